//! `clayloft flow`: runs the extruder-flow simulation (SPEC §10) and writes what a student needs
//! to look at it: the velocity fields and centre-line profiles as CSV, a picture of the speed
//! with streamlines, the vortex centre and the dead zones.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clayloft_flow::groove::{Groove, MATERIALS, Material, material};
use clayloft_flow::{Boundaries, Fluid, Solver};
use indicatif::{ProgressBar, ProgressStyle};

use crate::Failure;

/// Options of `clayloft flow`.
pub struct FlowOptions {
    pub case: String,
    pub cells: usize,
    pub re: f64,
    pub rpm: f64,
    pub diameter_mm: f64,
    pub width_mm: f64,
    pub depth_mm: f64,
    pub material: String,
    pub yield_stress: Option<f64>,
    pub consistency: Option<f64>,
    pub flow_index: Option<f64>,
    pub max_steps: u64,
    pub out: PathBuf,
}

pub fn flow(o: FlowOptions) -> Result<ExitCode, Failure> {
    if !(8..=1024).contains(&o.cells) {
        return Err(Failure(format!(
            "--cells {}: must lie in 8 … 1024",
            o.cells
        )));
    }
    std::fs::create_dir_all(&o.out)
        .map_err(|e| Failure(format!("{}: cannot create: {e}", o.out.display())))?;
    // (solver, lid speed in lattice units, metres per cell or None for normalised, scale to m/s)
    let (mut solver, lid_lu, cell_mm, to_ms, title) = match o.case.as_str() {
        "cavity" => {
            if !(0.01..=5000.0).contains(&o.re) {
                return Err(Failure(format!("--re {}: must lie in 0.01 … 5000", o.re)));
            }
            let lid = 0.1;
            let nu = lid * o.cells as f64 / o.re;
            let s = Solver::new(
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
            (s, lid, None, 1.0 / lid, "cavity".to_string())
        }
        "groove" => {
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
                ("--yield-stress", m.tau0, 0.0, 1e5),
                ("--consistency", m.k, 1e-3, 1e6),
                ("--flow-index", m.n, 0.1, 2.0),
            ] {
                if !(v.is_finite() && (lo..=hi).contains(&v)) {
                    return Err(Failure(format!("{name} {v}: must lie in {lo} … {hi}")));
                }
            }
            let g = Groove {
                width_m: o.width_mm * 1e-3,
                depth_m: o.depth_mm * 1e-3,
                screw_diameter_m: o.diameter_mm * 1e-3,
                rpm: o.rpm,
                material: m,
            };
            let l = g.to_lattice(o.cells, 1.0);
            println!(
                "groove {} × {} mm, screw Ø {} mm at {} rpm: barrel wall {:.4} m/s",
                o.width_mm, o.depth_mm, o.diameter_mm, o.rpm, l.lid_speed
            );
            println!(
                "material {} (τ₀ = {} Pa, K = {} Pa·sⁿ, n = {}, ρ = {} kg/m³): {}",
                m.name, m.tau0, m.k, m.n, m.rho, m.source
            );
            println!(
                "Reynolds number Re = U·H/ν(U/H) = {:.3e} (Stokes flow); lattice {} × {}, Δx = {:.1} µm, Δt = {:.3e} s, wall {:.3e} lattice units",
                l.reynolds,
                l.nx,
                l.ny,
                l.dx * 1e6,
                l.dt,
                l.lid_u
            );
            let s = Solver::new(l.nx, l.ny, l.fluid, Boundaries::cavity(l.lid_u), 0.51, 10.0);
            (
                s,
                l.lid_u,
                Some(l.dx * 1e3),
                l.dx / l.dt,
                "groove".to_string(),
            )
        }
        other => return Err(Failure(format!("--case {other}: choose cavity or groove"))),
    };
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
    let min_steps = ((2.0 * (solver.ny * solver.ny) as f64 / nu_ref) as u64).min(o.max_steps);
    for k in 0..min_steps {
        solver.step();
        if k % 1000 == 0 {
            bar.set_position(k);
        }
    }
    let (steps, change) = solver.run_to_convergence(1000, 1e-6, o.max_steps, lid_lu, |s, c| {
        bar.set_position(s);
        bar.set_message(format!("change {c:.1e}"));
    });
    bar.finish_and_clear();
    let converged = change < 1e-6;
    println!(
        "{} after {steps} steps (velocity change {change:.1e} of the wall speed per 1000 steps); {:.1} % of cells at the relaxation-time clamp",
        if converged {
            "converged"
        } else {
            "stopped unconverged"
        },
        solver.clamped_fraction() * 100.0
    );
    let (u, v) = solver.velocity();
    let (nx, ny) = (solver.nx, solver.ny);
    write_outputs(&o.out, nx, ny, &u, &v, lid_lu, to_ms)?;
    let (cx, cy) = clayloft_flow::analysis::vortex_centre(&u, nx, ny);
    let (left, right) = clayloft_flow::analysis::dead_cells(&u, &v, nx, ny, 0.01 * lid_lu);
    match cell_mm {
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
    println!("wrote {title} results to {}", o.out.display());
    Ok(ExitCode::SUCCESS)
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

/// Speed (dark blue → yellow) with white streamlines traced from a grid of seeds (RK2 on the
/// bilinear velocity field).
fn speed_png(
    path: &Path,
    nx: usize,
    ny: usize,
    u: &[f64],
    v: &[f64],
    lid: f64,
) -> Result<(), Failure> {
    let px = (480 / nx.max(ny)).max(1);
    let (w, h) = ((nx * px) as u32, (ny * px) as u32);
    let at = |fx: f64, fy: f64, f: &[f64]| {
        let (x0, y0) = (
            (fx - 0.5).clamp(0.0, nx as f64 - 1.001),
            (fy - 0.5).clamp(0.0, ny as f64 - 1.001),
        );
        let (i, j) = (x0 as usize, y0 as usize);
        let (a, b) = (x0 - i as f64, y0 - j as f64);
        let g = |x: usize, y: usize| f[y.min(ny - 1) * nx + x.min(nx - 1)];
        g(i, j) * (1.0 - a) * (1.0 - b)
            + g(i + 1, j) * a * (1.0 - b)
            + g(i, j + 1) * (1.0 - a) * b
            + g(i + 1, j + 1) * a * b
    };
    let mut img = image::RgbImage::from_fn(w, h, |x, y| {
        let (fx, fy) = (
            (x as f64 + 0.5) / px as f64,
            ny as f64 - (y as f64 + 0.5) / px as f64,
        );
        let s = (at(fx, fy, u).hypot(at(fx, fy, v)) / lid)
            .clamp(0.0, 1.0)
            .powf(0.5);
        image::Rgb([
            (255.0 * s) as u8,
            (40.0 + 180.0 * s) as u8,
            (120.0 * (1.0 - s) + 40.0) as u8,
        ])
    });
    let seeds = 8;
    for sy in 0..seeds {
        for sx in 0..seeds {
            let (mut x, mut y) = (
                (sx as f64 + 0.5) * nx as f64 / seeds as f64,
                (sy as f64 + 0.5) * ny as f64 / seeds as f64,
            );
            for _ in 0..400 {
                let (a, b) = (at(x, y, u), at(x, y, v));
                let sp = a.hypot(b);
                if sp < 1e-6 * lid {
                    break;
                }
                let step = 0.4 / sp;
                let (mx, my) = (x + 0.5 * step * a, y + 0.5 * step * b);
                let (a2, b2) = (at(mx, my, u), at(mx, my, v));
                x += step * a2;
                y += step * b2;
                if x < 0.0 || y < 0.0 || x >= nx as f64 || y >= ny as f64 {
                    break;
                }
                let (ix, iy) = ((x * px as f64) as u32, ((ny as f64 - y) * px as f64) as u32);
                if ix < w && iy < h {
                    img.put_pixel(ix, iy, image::Rgb([245, 245, 245]));
                }
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
