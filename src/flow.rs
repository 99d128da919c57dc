//! `clayloft flow`: runs the extruder-flow simulation (SPEC §10) and writes what a student needs
//! to look at it: the velocity fields and centre-line profiles as CSV, a picture of the speed
//! with streamlines, the vortex centre and the dead zones.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clayloft_flow::analysis;
use clayloft_flow::groove::{Groove, MATERIALS, Material, material};
use clayloft_flow::{Boundaries, Fluid, Solver};
use indicatif::{ProgressBar, ProgressStyle};

use crate::Failure;

/// Options of `clayloft flow`.
#[derive(clap::Args, Debug)]
pub struct FlowOptions {
    /// cavity (Ghia benchmark, normalised), groove (the screw groove, physical units) or
    /// channel (pushed through a slot by pressure: the plug of a yield-stress slurry).
    #[arg(long, default_value = "groove")]
    pub case: String,
    /// Lattice cells across the width.
    #[arg(long, default_value_t = 120)]
    pub cells: usize,
    /// Reynolds number of the cavity case.
    #[arg(long, default_value_t = 100.0)]
    pub re: f64,
    /// Bingham number of the cavity case: a Bingham plastic in creeping flow instead of a
    /// Newtonian fluid at --re (the viscoplastic benchmark; 0 = Newtonian Stokes flow).
    #[arg(long, value_name = "BN")]
    pub bingham: Option<f64>,
    /// Screw speed, revolutions per minute.
    #[arg(long, default_value_t = 45.0)]
    pub rpm: f64,
    /// Screw diameter, mm.
    #[arg(long = "diameter", value_name = "MM", default_value_t = 20.0)]
    pub diameter_mm: f64,
    /// Groove width, mm.
    #[arg(long = "width", value_name = "MM", default_value_t = 4.0)]
    pub width_mm: f64,
    /// Groove depth, mm (for the channel: its gap).
    #[arg(long = "depth", value_name = "MM", default_value_t = 4.0)]
    pub depth_mm: f64,
    /// newtonian, clay-paste or ceramic-slurry.
    #[arg(long, default_value = "ceramic-slurry")]
    pub material: String,
    /// Yield stress τ₀, Pa (instead of the material's).
    #[arg(long, value_name = "PA")]
    pub yield_stress: Option<f64>,
    /// Consistency K, Pa·s^n (instead of the material's).
    #[arg(long, value_name = "K")]
    pub consistency: Option<f64>,
    /// Flow index n (instead of the material's): below 1 shear-thinning.
    #[arg(long, value_name = "N")]
    pub flow_index: Option<f64>,
    /// Pressure gradient along the channel, MPa/m.
    #[arg(long, value_name = "MPA_PER_M", default_value_t = 0.5)]
    pub pressure_gradient: f64,
    /// Stop after this many time steps, converged or not.
    #[arg(long, default_value_t = 400_000)]
    pub max_steps: u64,
    /// Threads for the solver (bands of rows; 2 uses both cores of a two-core machine).
    #[arg(long, default_value_t = 1)]
    pub threads: usize,
    /// Folder for the velocity fields, profiles and picture.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

/// What a case sets up: the solver, the velocity scale in lattice units (the lid, the wall, or
/// the channel's centre speed), millimetres per cell (None: normalised), and the factor from
/// lattice velocity to m/s.
struct Setup {
    solver: Solver,
    scale_lu: f64,
    cell_mm: Option<f64>,
    to_ms: f64,
    /// For the channel: the analytic profile in lattice units, and the plug half-width in mm.
    channel: Option<Channel>,
    /// The yield stress in lattice units (0 without one): cells below it are unyielded.
    yield_stress: f64,
}

struct Channel {
    exact: Vec<f64>,
    /// The yield stress in lattice units, and the analytic plug half-width in mm.
    tau0_lu: f64,
    plug_half_mm: f64,
    gap_mm: f64,
}

pub fn flow(o: FlowOptions) -> Result<ExitCode, Failure> {
    if !(8..=1024).contains(&o.cells) {
        return Err(Failure(format!(
            "--cells {}: must lie in 8 … 1024",
            o.cells
        )));
    }
    if !(1..=64).contains(&o.threads) {
        return Err(Failure(format!(
            "--threads {}: must lie in 1 … 64",
            o.threads
        )));
    }
    let mut setup = match o.case.as_str() {
        "cavity" => cavity(&o)?,
        "groove" => groove(&o, material_of(&o)?)?,
        "channel" => channel(&o, material_of(&o)?)?,
        other => {
            return Err(Failure(format!(
                "--case {other}: choose cavity, groove or channel"
            )));
        }
    };
    std::fs::create_dir_all(&o.out)
        .map_err(|e| Failure(format!("{}: cannot create: {e}", o.out.display())))?;
    let solver = &mut setup.solver;
    solver.threads = o.threads;
    let bar = ProgressBar::new(o.max_steps);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} steps {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    // Momentum needs about N²/ν steps to cross the lattice: never call it converged before
    // twice that (ν of the reference viscosity).
    let nu_ref = match solver.fluid {
        Fluid::Newtonian { nu } => nu,
        _ => 1.0 / 6.0,
    };
    // (Leaving at least one check of convergence within --max-steps.)
    let min_steps = ((2.0 * (solver.ny * solver.ny) as f64 / nu_ref) as u64)
        .min(o.max_steps.saturating_sub(1000));
    let started = std::time::Instant::now();
    while solver.steps < min_steps {
        solver.advance(1000.min(min_steps - solver.steps));
        bar.set_position(solver.steps);
    }
    let (steps, change) =
        solver.run_to_convergence(1000, 1e-6, o.max_steps, setup.scale_lu, |s, c| {
            bar.set_position(s);
            bar.set_message(format!("change {c:.1e}"));
        });
    bar.finish_and_clear();
    let converged = change < 1e-6;
    let lups =
        (steps * (solver.nx * solver.ny) as u64) as f64 / started.elapsed().as_secs_f64().max(1e-9);
    let state = if converged {
        format!(
            "converged after {steps} steps (velocity change {change:.1e} of the velocity scale per 1000 steps)"
        )
    } else if change.is_finite() {
        format!(
            "stopped unconverged after {steps} steps (velocity change {change:.1e} of the velocity scale per 1000 steps)"
        )
    } else {
        format!(
            "stopped after {steps} steps, before the first check of convergence (raise --max-steps)"
        )
    };
    println!(
        "{state}; {:.1} % of cells at the relaxation-time clamp; {:.0} million lattice updates/s on {} thread(s)",
        solver.clamped_fraction() * 100.0,
        lups / 1e6,
        solver.bands(),
    );
    let (u, v) = solver.velocity();
    let (nx, ny) = (solver.nx, solver.ny);
    write_outputs(&o.out, nx, ny, &u, &v, setup.scale_lu, setup.to_ms)?;
    if let Some(c) = &setup.channel {
        report_channel(solver, c, &u, setup.to_ms);
        println!("wrote channel results to {}", o.out.display());
        return Ok(ExitCode::SUCCESS);
    }
    let (cx, cy) = analysis::vortex_centre(&u, nx, ny);
    let (left, right) = analysis::dead_cells(&u, &v, nx, ny, 0.01 * setup.scale_lu);
    match setup.cell_mm {
        Some(d) => {
            println!(
                "vortex centre: x={:.2} mm, y={:.2} mm",
                cx * nx as f64 * d,
                cy * ny as f64 * d
            );
            println!(
                "dead zones (slower than 1 % of the wall): lower left {:.2} mm², lower right {:.2} mm²",
                left as f64 * d * d,
                right as f64 * d * d
            );
        }
        None => {
            println!("vortex centre: x={cx:.4}, y={cy:.4}");
            println!(
                "dead zones (slower than 1 % of the lid): lower left {:.2} %, lower right {:.2} % of the cavity",
                100.0 * left as f64 / (nx * ny) as f64,
                100.0 * right as f64 / (nx * ny) as f64
            );
        }
    }
    if setup.yield_stress > 0.0 {
        let unyielded = analysis::unyielded_fraction(&solver.shear_stresses(), setup.yield_stress);
        println!(
            "unyielded (shear stress below the yield stress): {:.1} % of the cells",
            100.0 * unyielded
        );
    }
    println!("wrote {} results to {}", o.case, o.out.display());
    Ok(ExitCode::SUCCESS)
}

/// The lid-driven cavity at `--re`, normalised (the Ghia et al. benchmark), or with `--bingham`
/// a Bingham plastic in creeping flow.
fn cavity(o: &FlowOptions) -> Result<Setup, Failure> {
    if let Some(bn) = o.bingham {
        if !(bn.is_finite() && (0.0..=1000.0).contains(&bn)) {
            return Err(Failure(format!("--bingham {bn}: must lie in 0 … 1000")));
        }
        let (solver, tau0) = clayloft_flow::cavity::bingham(o.cells, bn, 1.0 / 6.0);
        println!(
            "Bingham lid-driven cavity, Bn = {bn}, creeping flow (lattice Re = {}), {} × {} lattice",
            clayloft_flow::groove::LATTICE_REYNOLDS,
            o.cells,
            o.cells
        );
        let lid = solver.bounds.lid_u;
        return Ok(Setup {
            solver,
            scale_lu: lid,
            cell_mm: None,
            to_ms: 1.0 / lid,
            channel: None,
            yield_stress: tau0,
        });
    }
    if !(0.01..=5000.0).contains(&o.re) {
        return Err(Failure(format!("--re {}: must lie in 0.01 … 5000", o.re)));
    }
    let lid = 0.1;
    let nu = lid * o.cells as f64 / o.re;
    let solver = Solver::new(
        o.cells,
        o.cells,
        Fluid::Newtonian { nu },
        Boundaries::cavity(lid),
        0.5001,
        1000.0,
    );
    println!(
        "lid-driven cavity, Re = {}, {} × {} lattice, τ = {:.3}",
        o.re,
        o.cells,
        o.cells,
        3.0 * nu + 0.5
    );
    Ok(Setup {
        solver,
        scale_lu: lid,
        cell_mm: None,
        to_ms: 1.0 / lid,
        channel: None,
        yield_stress: 0.0,
    })
}

/// The material preset with the user's overrides, checked.
fn material_of(o: &FlowOptions) -> Result<Material, Failure> {
    let mut m: Material = material(&o.material).ok_or_else(|| {
        let names: Vec<&str> = MATERIALS.iter().map(|m| m.name).collect();
        Failure(format!(
            "--material {}: unknown (choose {})",
            o.material,
            names.join(", ")
        ))
    })?;
    if let Some(t) = o.yield_stress {
        m.tau0 = t;
    }
    if let Some(k) = o.consistency {
        m.k = k;
    }
    if let Some(n) = o.flow_index {
        m.n = n;
    }
    for (name, v, lo, hi) in [
        ("--rpm", o.rpm, 0.1, 1000.0),
        ("--diameter", o.diameter_mm, 1.0, 500.0),
        ("--width", o.width_mm, 0.1, 100.0),
        ("--depth", o.depth_mm, 0.1, 100.0),
        ("--pressure-gradient", o.pressure_gradient, 1e-3, 1e4),
        ("--yield-stress", m.tau0, 0.0, 1e5),
        ("--consistency", m.k, 1e-3, 1e6),
        ("--flow-index", m.n, 0.1, 2.0),
    ] {
        if !(v.is_finite() && (lo..=hi).contains(&v)) {
            return Err(Failure(format!("{name} {v}: must lie in {lo} … {hi}")));
        }
    }
    println!(
        "material {} (τ₀ = {} Pa, K = {} Pa·sⁿ, n = {}, ρ = {} kg/m³): {}",
        m.name, m.tau0, m.k, m.n, m.rho, m.source
    );
    Ok(m)
}

/// The screw groove in physical units, converted through the Reynolds number.
fn groove(o: &FlowOptions, m: Material) -> Result<Setup, Failure> {
    let g = Groove {
        width_m: o.width_mm * 1e-3,
        depth_m: o.depth_mm * 1e-3,
        screw_diameter_m: o.diameter_mm * 1e-3,
        rpm: o.rpm,
        material: m,
    };
    let l = g.to_lattice(o.cells, 1.0);
    println!(
        "groove {} × {} mm, screw Ø {} mm at {} rpm: barrel wall {:.4} m/s, shear rate U/H = {:.2}/s",
        o.width_mm,
        o.depth_mm,
        o.diameter_mm,
        o.rpm,
        l.lid_speed,
        g.shear_rate()
    );
    println!(
        "Reynolds number Re = U·H/ν(U/H) = {:.3e} (creeping flow: solved at lattice Re = {}); Bingham number τ₀/(K·(U/H)ⁿ) = {:.2}; lattice {} × {}, Δx = {:.1} µm",
        l.reynolds,
        clayloft_flow::groove::LATTICE_REYNOLDS,
        l.bingham,
        l.nx,
        l.ny,
        l.dx * 1e6,
    );
    Ok(Setup {
        solver: l.solver(),
        scale_lu: l.lid_u,
        cell_mm: Some(l.dx * 1e3),
        to_ms: l.lid_speed / l.lid_u,
        channel: None,
        yield_stress: l.yield_stress(),
    })
}

/// Clay pushed by pressure through a slot `--depth` wide (the flow along the barrel and into
/// the nozzle). Without inertia the profile depends only on the flow index n and on how far the
/// yield zone reaches, y₀/h = τ₀/(G·h); the lattice reproduces those two numbers with a centre
/// speed of 0.02 and a wall viscosity of 0.1, and the analytic centre speed in m/s scales it back.
fn channel(o: &FlowOptions, m: Material) -> Result<Setup, Failure> {
    let g_phys = o.pressure_gradient * 1e6; // MPa/m → Pa/m
    let h_phys = o.depth_mm * 1e-3 / 2.0;
    let y0_phys = m.tau0 / g_phys;
    println!(
        "channel {} mm wide, pressure gradient {} MPa/m: wall stress G·h = {:.0} Pa",
        o.depth_mm,
        o.pressure_gradient,
        g_phys * h_phys
    );
    if y0_phys >= h_phys {
        return Err(Failure(format!(
            "--pressure-gradient {}: the slurry does not yield (its yield stress {} Pa needs more than {:.3} MPa/m across {} mm)",
            o.pressure_gradient,
            m.tau0,
            m.tau0 / h_phys / 1e6,
            o.depth_mm
        )));
    }
    let beta = y0_phys / h_phys;
    let (n, ny, nx) = (m.n, o.cells, 4);
    let h = ny as f64 / 2.0;
    let a = (n + 1.0) / n;
    let u_max = 0.02;
    // u_max = n/(n+1)·(G/K)^(1/n)·(h(1−β))^a, and ν at the wall = G·h/γ̇_w = 0.1.
    let g_over_k = (u_max * (n + 1.0) / n / (h * (1.0 - beta)).powf(a)).powf(n);
    let gamma_wall = (g_over_k * h * (1.0 - beta)).powf(1.0 / n);
    let g = 0.1 * gamma_wall / h;
    let k = g / g_over_k;
    let tau0 = g * beta * h;
    let fluid = if tau0 > 0.0 {
        Fluid::HerschelBulkley {
            tau0,
            k,
            n,
            m: 50.0 * h / u_max,
        }
    } else if n == 1.0 {
        Fluid::Newtonian { nu: k }
    } else {
        Fluid::PowerLaw { k, n }
    };
    let exact: Vec<f64> = (0..ny)
        .map(|j| analysis::plane_poiseuille(tau0, k, n, g, h, j as f64 + 0.5 - h))
        .collect();
    let u_phys =
        analysis::plane_poiseuille(m.tau0 / m.rho, m.k / m.rho, n, g_phys / m.rho, h_phys, 0.0);
    let nu_wall =
        g_phys * h_phys / m.rho / ((g_phys * h_phys - m.tau0) / m.k).max(1e-30).powf(1.0 / n);
    println!(
        "centre speed {:.4} m/s, Reynolds number ρ·U·h/η_wall = {:.3e} (parallel flow: inertia plays no part); plug half-width y₀ = τ₀/G = {:.3} mm of {:.3} mm; lattice {nx} × {ny} (periodic along the channel)",
        u_phys,
        u_phys * h_phys / nu_wall,
        y0_phys * 1e3,
        h_phys * 1e3
    );
    Ok(Setup {
        solver: Solver::new(nx, ny, fluid, Boundaries::channel(g), 0.505, 10.0),
        scale_lu: u_max,
        cell_mm: Some(o.depth_mm / ny as f64),
        to_ms: u_phys / u_max,
        channel: Some(Channel {
            exact,
            tau0_lu: tau0,
            plug_half_mm: y0_phys * 1e3,
            gap_mm: o.depth_mm,
        }),
        yield_stress: tau0,
    })
}

/// The channel's profile against the analytic one, the plug, and the flow rate.
fn report_channel(solver: &Solver, c: &Channel, u: &[f64], to_ms: f64) {
    let (nx, ny) = (solver.nx, solver.ny);
    let column: Vec<f64> = (0..ny).map(|y| u[y * nx + nx / 2]).collect();
    let peak = c.exact.iter().cloned().fold(0.0, f64::max);
    let worst = column
        .iter()
        .zip(&c.exact)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let (_, at_limit) = solver.clamped_fractions();
    let cell_mm = c.gap_mm / ny as f64;
    // The plug: rows of the middle column whose shear stress stays below the yield stress.
    let stress = solver.shear_stresses();
    let plug_rows = (0..ny)
        .filter(|&y| stress[y * nx + nx / 2] < c.tau0_lu)
        .count();
    let flow: f64 = column.iter().sum::<f64>() * to_ms * cell_mm; // m/s · mm = mm·m/s
    println!(
        "profile within {:.1} % of the analytic Herschel–Bulkley profile (of the centre speed)",
        100.0 * worst / peak
    );
    if worst > 0.1 * peak {
        println!(
            "  (the lattice is too coarse for this profile — a thin sheared layer or a strongly shear-thinning slurry: try more --cells)"
        );
    }
    if c.tau0_lu > 0.0 {
        println!(
            "plug (stress below the yield stress): half-width {:.3} mm; analytic y₀ = τ₀/G = {:.3} mm",
            plug_rows as f64 * cell_mm / 2.0,
            c.plug_half_mm
        );
    }
    println!(
        "{:.0} % of the gap at the viscosity limit (barely sheared: the plug, and for n < 1 its edges)",
        at_limit * 100.0
    );
    println!("flow rate {:.1} mm³/s per mm of channel width", flow * 1e3);
}

fn write_csv(path: &Path, text: String) -> Result<(), Failure> {
    clayloft_core::atomic::write_atomically(path, |w| w.write_all(text.as_bytes()))?;
    Ok(())
}

fn write_outputs(
    dir: &Path,
    nx: usize,
    ny: usize,
    u: &[f64],
    v: &[f64],
    lid: f64,
    to_ms: f64,
) -> Result<(), Failure> {
    for (name, field) in [("u.csv", u), ("v.csv", v)] {
        let mut s = (0..nx)
            .map(|x| format!("x{x}"))
            .collect::<Vec<_>>()
            .join(",");
        s.push('\n');
        for y in 0..ny {
            s += &(0..nx)
                .map(|x| format!("{:.6e}", field[y * nx + x] * to_ms))
                .collect::<Vec<_>>()
                .join(",");
            s.push('\n');
        }
        write_csv(&dir.join(name), s)?;
    }
    let mut s = String::from("y,u\n");
    for y in 0..ny {
        let val = 0.5 * (u[y * nx + (nx - 1) / 2] + u[y * nx + nx / 2]) / lid;
        s += &format!("{:.6},{:.6}\n", (y as f64 + 0.5) / ny as f64, val);
    }
    write_csv(&dir.join("centerline_u.csv"), s)?;
    let mut s = String::from("x,v\n");
    for x in 0..nx {
        let val = 0.5 * (v[((ny - 1) / 2) * nx + x] + v[(ny / 2) * nx + x]) / lid;
        s += &format!("{:.6},{:.6}\n", (x as f64 + 0.5) / nx as f64, val);
    }
    write_csv(&dir.join("centerline_v.csv"), s)?;
    speed_png(&dir.join("speed.png"), nx, ny, u, v, lid)
}

/// Speed (dark blue → yellow) with white streamlines ([`analysis::streamlines`]). A periodic
/// channel only a few cells long is repeated along its length so the picture is not a sliver.
fn speed_png(
    path: &Path,
    nx: usize,
    ny: usize,
    u: &[f64],
    v: &[f64],
    scale: f64,
) -> Result<(), Failure> {
    let (nx, u, v) = if nx * 4 < ny {
        let wide = ny / 2;
        let tile = |f: &[f64]| -> Vec<f64> {
            (0..ny)
                .flat_map(|y| (0..wide).map(move |x| (x, y)))
                .map(|(x, y)| f[y * nx + x % nx])
                .collect()
        };
        (wide, tile(u), tile(v))
    } else {
        (nx, u.to_vec(), v.to_vec())
    };
    let px = (480 / nx.max(ny)).max(1);
    let (w, h) = ((nx * px) as u32, (ny * px) as u32);
    let mut img = image::RgbImage::from_fn(w, h, |x, y| {
        let (fx, fy) = (
            (x as f64 + 0.5) / px as f64,
            ny as f64 - (y as f64 + 0.5) / px as f64,
        );
        let (a, b) = analysis::velocity_at(&u, &v, nx, ny, fx, fy);
        image::Rgb(analysis::speed_colour(a.hypot(b) / scale))
    });
    for line in analysis::streamlines(&u, &v, nx, ny, 8, 1e-6 * scale) {
        for (x, y) in line {
            let (ix, iy) = ((x * px as f64) as u32, ((ny as f64 - y) * px as f64) as u32);
            if ix < w && iy < h {
                img.put_pixel(ix, iy, image::Rgb([245, 245, 245]));
            }
        }
    }
    let mut bytes = Vec::new();
    img.write_to(
        &mut std::io::Cursor::new(&mut bytes),
        image::ImageFormat::Png,
    )
    .map_err(|e| Failure(format!("{}: cannot encode: {e}", path.display())))?;
    clayloft_core::atomic::write_atomically(path, |w| w.write_all(&bytes))?;
    Ok(())
}
