//! What a student looks for in a flow field: where the vortex turns, where the clay stands,
//! the streamlines, and — for flow pushed through a channel — the analytic profile with its plug.
//! Fields are row-major from the bottom row, one value per cell; positions are in cells, the
//! centre of cell (i, j) at (i + ½, j + ½).

/// Eye of the main recirculation, normalised to 0..1: the extremum of the stream function
/// `ψ(x, y) = ∫₀^y u dy'` (ψ = 0 on the walls). `u` is row-major from the bottom row. ψ is summed
/// up each column, so it is known on the cell faces (y = 0, 1, …, ny) at the column centres
/// (x = ½, 3⁄2, …); the extremum is refined between them by a parabola through its neighbours in
/// each direction (sub-cell accuracy: a benchmark wants the centre to a fraction of a cell).
pub fn vortex_centre(u: &[f64], nx: usize, ny: usize) -> (f64, f64) {
    // psi[x][f]: ψ at face f (0 ..= ny) of column x.
    let psi: Vec<Vec<f64>> = (0..nx)
        .map(|x| {
            let mut column = Vec::with_capacity(ny + 1);
            let mut sum = 0.0;
            column.push(0.0);
            for y in 0..ny {
                sum += u[y * nx + x];
                column.push(sum);
            }
            column
        })
        .collect();
    let mut best = (0.0f64, nx / 2, ny / 2);
    for (x, column) in psi.iter().enumerate() {
        for (f, &p) in column.iter().enumerate() {
            if p.abs() > best.0.abs() {
                best = (p, x, f);
            }
        }
    }
    let (_, bx, bf) = best;
    // The vertex of the parabola through (−1, a), (0, b), (1, c): (a − c)/(2(a − 2b + c)).
    let vertex = |a: f64, b: f64, c: f64| {
        let d = a - 2.0 * b + c;
        if d.abs() > 1e-300 {
            (0.5 * (a - c) / d).clamp(-0.5, 0.5)
        } else {
            0.0
        }
    };
    let dy = if bf > 0 && bf < ny {
        vertex(psi[bx][bf - 1], psi[bx][bf], psi[bx][bf + 1])
    } else {
        0.0
    };
    let dx = if bx > 0 && bx + 1 < nx {
        vertex(psi[bx - 1][bf], psi[bx][bf], psi[bx + 1][bf])
    } else {
        0.0
    };
    (
        (bx as f64 + 0.5 + dx) / nx as f64,
        (bf as f64 + dy) / ny as f64,
    )
}

/// Cells of the lower-left and lower-right quarters slower than `threshold`: the dead zones.
pub fn dead_cells(u: &[f64], v: &[f64], nx: usize, ny: usize, threshold: f64) -> (usize, usize) {
    let slow = |x: usize, y: usize| u[y * nx + x].hypot(v[y * nx + x]) < threshold;
    let count = |xs: std::ops::Range<usize>| {
        (0..ny / 2)
            .flat_map(|y| xs.clone().map(move |x| (x, y)))
            .filter(|&(x, y)| slow(x, y))
            .count()
    };
    (count(0..nx / 2), count(nx / 2..nx))
}

/// Share of cells whose shear stress `|σ| = ν·γ̇` ([`crate::Solver::shear_stresses`]) stays below
/// the yield stress `tau0` (same units): the von Mises criterion for where a yield-stress slurry
/// stands still or moves as a rigid plug. Zero without a yield stress.
pub fn unyielded_fraction(stress: &[f64], tau0: f64) -> f64 {
    if tau0 <= 0.0 || stress.is_empty() {
        return 0.0;
    }
    stress.iter().filter(|&&s| s < tau0).count() as f64 / stress.len() as f64
}

/// The colour of a speed given as a fraction of the reference speed: dark blue (still) to
/// yellow (1 and above), on a square-root scale so that slow regions stay distinguishable.
pub fn speed_colour(fraction: f64) -> [u8; 3] {
    let s = fraction.clamp(0.0, 1.0).sqrt();
    [
        (255.0 * s) as u8,
        (40.0 + 180.0 * s) as u8,
        (40.0 + 120.0 * (1.0 - s)) as u8,
    ]
}

/// The velocity at (x, y) by bilinear interpolation between cell centres (clamped at the edges).
pub fn velocity_at(u: &[f64], v: &[f64], nx: usize, ny: usize, x: f64, y: f64) -> (f64, f64) {
    let fx = (x - 0.5).clamp(0.0, (nx - 1) as f64);
    let fy = (y - 0.5).clamp(0.0, (ny - 1) as f64);
    let (i, j) = (
        (fx as usize).min(nx.saturating_sub(2)),
        (fy as usize).min(ny.saturating_sub(2)),
    );
    let (a, b) = (fx - i as f64, fy - j as f64);
    let (i1, j1) = ((i + 1).min(nx - 1), (j + 1).min(ny - 1));
    let mix = |f: &[f64]| {
        f[j * nx + i] * (1.0 - a) * (1.0 - b)
            + f[j * nx + i1] * a * (1.0 - b)
            + f[j1 * nx + i] * (1.0 - a) * b
            + f[j1 * nx + i1] * a * b
    };
    (mix(u), mix(v))
}

/// Streamlines through a `seeds × seeds` grid of starting points: traced backwards and forwards
/// with the midpoint rule (RK2) in steps of 0.4 cells, up to 400 steps each way, until they leave
/// the domain, reach still fluid (slower than `still`) or close on their start. Each line is a
/// list of points in cells.
pub fn streamlines(
    u: &[f64],
    v: &[f64],
    nx: usize,
    ny: usize,
    seeds: usize,
    still: f64,
) -> Vec<Vec<(f64, f64)>> {
    let trace = |start: (f64, f64), sign: f64| {
        let mut line = vec![];
        let (mut x, mut y) = start;
        for k in 0..400 {
            let (a, b) = velocity_at(u, v, nx, ny, x, y);
            let speed = a.hypot(b);
            if speed < still {
                break;
            }
            let h = sign * 0.4 / speed;
            let (a2, b2) = velocity_at(u, v, nx, ny, x + 0.5 * h * a, y + 0.5 * h * b);
            x += h * a2;
            y += h * b2;
            if x < 0.0 || y < 0.0 || x > nx as f64 || y > ny as f64 {
                break;
            }
            line.push((x, y));
            if k > 10 && (x - start.0).hypot(y - start.1) < 0.3 {
                break;
            }
        }
        line
    };
    let mut lines = vec![];
    for sy in 0..seeds {
        for sx in 0..seeds {
            let start = (
                (sx as f64 + 0.5) * nx as f64 / seeds as f64,
                (sy as f64 + 0.5) * ny as f64 / seeds as f64,
            );
            let mut line = trace(start, -1.0);
            line.reverse();
            line.push(start);
            line.extend(trace(start, 1.0));
            if line.len() > 1 {
                lines.push(line);
            }
        }
    }
    lines
}

/// Pressure-driven flow of a Herschel–Bulkley fluid between plates `2h` apart (plane
/// Poiseuille), with the stress `τ = G·|y|` growing from the centre line: still sheared where
/// `G|y| > τ₀`, a rigid plug of half-width `y₀ = τ₀/G` around the centre. Outside the plug
/// `u(y) = n/(n+1)·(G/K)^(1/n)·[(h − y₀)^((n+1)/n) − (|y| − y₀)^((n+1)/n)]`, inside `u(y₀)`
/// (y from the centre line; consistent units, stresses over density in lattice units).
/// Covers Newtonian (n = 1, τ₀ = 0), power-law (τ₀ = 0) and Bingham (n = 1) fluids; zero if
/// the fluid does not yield (`y₀ ≥ h`).
pub fn plane_poiseuille(tau0: f64, k: f64, n: f64, g: f64, h: f64, y: f64) -> f64 {
    let y0 = tau0 / g;
    if y0 >= h {
        return 0.0;
    }
    let a = (n + 1.0) / n;
    let yy = y.abs().clamp(y0, h);
    n / (n + 1.0) * (g / k).powf(1.0 / n) * ((h - y0).powf(a) - (yy - y0).powf(a))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn poiseuille_profiles() {
        // Newtonian: the parabola G/(2K)·(h² − y²).
        for y in [-2.0, 0.0, 1.5, 3.0] {
            let want = 0.5 / (2.0 * 0.1) * (9.0 - y * y);
            assert!((plane_poiseuille(0.0, 0.1, 1.0, 0.5, 3.0, y) - want).abs() < 1e-12);
        }
        // Bingham: flat inside |y| < y₀ = 1, the parabola shifted outside.
        let plug = plane_poiseuille(0.5, 0.1, 1.0, 0.5, 3.0, 0.0);
        assert_eq!(plane_poiseuille(0.5, 0.1, 1.0, 0.5, 3.0, 0.7), plug);
        assert!((plug - 0.5 / 0.2 * 4.0).abs() < 1e-12);
        assert_eq!(plane_poiseuille(0.5, 0.1, 1.0, 0.5, 3.0, 3.0), 0.0);
        // Too little pressure to yield: no flow.
        assert_eq!(plane_poiseuille(2.0, 0.1, 1.0, 0.5, 3.0, 0.0), 0.0);
    }

    #[test]
    fn streamlines_follow_the_flow() {
        let (nx, ny) = (30, 30);
        // Uniform flow to the right: straight lines that leave through the right side.
        let (u, v) = (vec![1.0; nx * ny], vec![0.0; nx * ny]);
        let lines = streamlines(&u, &v, nx, ny, 3, 1e-6);
        assert_eq!(lines.len(), 9);
        for line in &lines {
            let y0 = line[0].1;
            assert!(line.iter().all(|p| (p.1 - y0).abs() < 1e-9));
            assert!(line[0].0 < 0.5 && line.last().unwrap().0 > nx as f64 - 0.5);
        }
        // Solid rotation about the centre: circles that close on their start.
        let c = 15.0;
        let mut u = vec![0.0; nx * ny];
        let mut v = vec![0.0; nx * ny];
        for j in 0..ny {
            for i in 0..nx {
                let (x, y) = (i as f64 + 0.5, j as f64 + 0.5);
                u[j * nx + i] = -(y - c);
                v[j * nx + i] = x - c;
            }
        }
        let lines = streamlines(&u, &v, nx, ny, 3, 1e-6);
        for line in lines.iter().filter(|l| l.len() > 20) {
            let r0 = (line[0].0 - c).hypot(line[0].1 - c);
            for p in line {
                let r = (p.0 - c).hypot(p.1 - c);
                assert!((r - r0).abs() < 0.05 * r0.max(1.0), "radius {r} vs {r0}");
            }
            assert!(line.len() < 800, "a circle closes before the step limit");
        }
        // Still fluid: no lines.
        assert!(streamlines(&[0.0; 4], &[0.0; 4], 2, 2, 2, 1e-6).is_empty());
    }

    #[test]
    fn cell_vortex_centre_and_still_corners() {
        // u = −(y − 6)·sin(π x/nx) above y = 2, still below: ψ peaks at y = 6, x = nx/2 (found
        // between the cells by the parabolas).
        let (nx, ny) = (20, 10);
        let mut u = vec![0.0; nx * ny];
        let v = vec![0.0; nx * ny];
        for y in 2..ny {
            for x in 0..nx {
                let s = (std::f64::consts::PI * (x as f64 + 0.5) / nx as f64).sin();
                u[y * nx + x] = -(y as f64 + 0.5 - 6.0) * s;
            }
        }
        let (x, y) = vortex_centre(&u, nx, ny);
        assert!((x - 0.5).abs() < 1e-9, "x = {x}");
        assert!((y - 0.6).abs() < 1e-9, "y = {y}");
        assert_eq!(dead_cells(&u, &v, nx, ny, 1e-9), (20, 20));
    }

    #[test]
    fn unyielded_cells_are_those_below_the_yield_stress() {
        let stress = [0.5, 1.5, 0.99, 2.0];
        assert_eq!(unyielded_fraction(&stress, 1.0), 0.5);
        assert_eq!(unyielded_fraction(&stress, 0.0), 0.0);
        assert_eq!(unyielded_fraction(&[], 1.0), 0.0);
    }
}
