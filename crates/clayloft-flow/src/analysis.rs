//! What a student looks for in a flow field: where the vortex turns, and where the clay stands.

/// Eye of the main recirculation, normalised to 0..1: the extremum of the stream function
/// `ψ(x, y) = ∫₀^y u dy'` (ψ = 0 on the walls). `u` is row-major from the bottom row.
pub fn vortex_centre(u: &[f64], nx: usize, ny: usize) -> (f64, f64) {
    let mut best = (0.0f64, nx / 2, ny / 2);
    for x in 0..nx {
        let mut psi = 0.0;
        for y in 0..ny {
            psi += u[y * nx + x];
            if psi.abs() > best.0.abs() {
                best = (psi, x, y);
            }
        }
    }
    (
        (best.1 as f64 + 0.5) / nx as f64,
        (best.2 as f64 + 0.5) / ny as f64,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cell_vortex_centre_and_still_corners() {
        // u = −(y − 6)·sin(π x/nx) above y = 2, still below: ψ peaks at y = 6, x = nx/2.
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
        assert!((x - 0.5).abs() <= 0.5 / nx as f64 + 1e-9, "x = {x}");
        assert!((y - 0.55).abs() < 1e-9, "y = {y}");
        assert_eq!(dead_cells(&u, &v, nx, ny, 1e-9), (20, 20));
    }
}
