//! The D2Q9 BGK solver (the paper's equations 1–5): pull streaming and collision fused in one
//! pass over two lattices; half-way bounce-back at walls half a cell outside the boundary nodes;
//! the moving lid by Ladd's rule `fᵢ = f*_ī + 6wᵢρ cᵢ·u_w`; a periodic channel with Guo's body
//! force; a per-cell relaxation time from the strain rate of the non-equilibrium moments.

// The kernel walks the nine directions indexing several arrays (populations, equilibria, C, W)
// by the same i: a range loop says that most plainly.
#![allow(clippy::needless_range_loop)]

use crate::lattice::{C, OPP, W, equilibrium};
use crate::rheology::{Fluid, tau_of};

/// Walls and driving: the three walls are no-slip; the top one moves at `lid_u` (cavity), or the
/// domain is periodic in x and driven by a body force (channel, lid still).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Boundaries {
    pub lid_u: f64,
    pub periodic_x: bool,
    pub force_x: f64,
}

impl Boundaries {
    pub fn cavity(lid_u: f64) -> Boundaries {
        Boundaries {
            lid_u,
            periodic_x: false,
            force_x: 0.0,
        }
    }
    pub fn channel(force_x: f64) -> Boundaries {
        Boundaries {
            lid_u: 0.0,
            periodic_x: true,
            force_x,
        }
    }
}

/// The lattice and its fluid.
#[derive(Debug, Clone)]
pub struct Solver {
    pub nx: usize,
    pub ny: usize,
    pub fluid: Fluid,
    pub bounds: Boundaries,
    pub tau_min: f64,
    pub tau_max: f64,
    /// Post-collision populations, direction-major: `f[i·n + y·nx + x]`.
    f: Vec<f64>,
    g: Vec<f64>,
    /// Relaxation time of each cell (from the previous step: the lagged scheme).
    tau: Vec<f64>,
    pub steps: u64,
    /// Threads for the Newtonian interior (1 = one core).
    pub threads: usize,
}

impl Solver {
    /// A fluid at rest (ρ = 1) on `nx × ny` nodes. τ starts at the value of ν at a unit-ish shear
    /// rate, clamped.
    pub fn new(
        nx: usize,
        ny: usize,
        fluid: Fluid,
        bounds: Boundaries,
        tau_min: f64,
        tau_max: f64,
    ) -> Solver {
        let n = nx * ny;
        let mut f = vec![0.0; 9 * n];
        for i in 0..9 {
            f[i * n..(i + 1) * n].fill(W[i]);
        }
        let tau0 = tau_of(fluid.viscosity(1e-3)).clamp(tau_min, tau_max);
        Solver {
            nx,
            ny,
            fluid,
            bounds,
            tau_min,
            tau_max,
            g: f.clone(),
            f,
            tau: vec![tau0; n],
            steps: 0,
            threads: 1,
        }
    }

    fn n(&self) -> usize {
        self.nx * self.ny
    }

    /// One time step over every node.
    pub fn step(&mut self) {
        let (nx, ny, n) = (self.nx as isize, self.ny as isize, self.n());
        let b = self.bounds;
        let fluid = self.fluid;
        let (tmin, tmax) = (self.tau_min, self.tau_max);
        let newtonian_tau = match fluid {
            Fluid::Newtonian { nu } => Some(tau_of(nu).clamp(tmin, tmax)),
            _ => None,
        };
        let f = &self.f;
        let g = &mut self.g;
        let tau = &mut self.tau;
        // Newtonian without a body force: interior rows by the vectorisable row kernel.
        let fast = match newtonian_tau {
            Some(t) if b.force_x == 0.0 && nx >= 3 && ny >= 3 => Some(1.0 / t),
            _ => None,
        };
        if let Some(omega) = fast {
            let (nxu, nyu, len) = (nx as usize, ny as usize, nx as usize - 2);
            // Interior rows 1 .. ny−1, split into `threads` bands; each band gets its own
            // mutable window of every direction.
            let bands = self.threads.clamp(1, nyu - 2);
            let mut windows: Vec<Vec<&mut [f64]>> =
                (0..bands).map(|_| Vec::with_capacity(9)).collect();
            let mut starts = vec![1usize];
            for k in 1..bands {
                starts.push(1 + (nyu - 2) * k / bands);
            }
            starts.push(nyu - 1);
            for dir in g.chunks_mut(n) {
                let mut rest = &mut dir[nxu..(nyu - 1) * nxu];
                for (k, w) in windows.iter_mut().enumerate() {
                    let (band, tail) = rest.split_at_mut((starts[k + 1] - starts[k]) * nxu);
                    w.push(band);
                    rest = tail;
                }
            }
            let run_band = |y0: usize, y1: usize, band: &mut Vec<&mut [f64]>| {
                for y in y0..y1 {
                    let start = y * nxu + 1;
                    let src: [&[f64]; 9] = std::array::from_fn(|i| {
                        let from =
                            (start as isize - (C[i].1 as isize * nx + C[i].0 as isize)) as usize;
                        &f[i * n + from..i * n + from + len]
                    });
                    let local = (y - y0) * nxu + 1;
                    let mut it = band.iter_mut();
                    let mut out: [&mut [f64]; 9] = std::array::from_fn(|_| {
                        it.next()
                            .map(|d| &mut d[local..local + len])
                            .unwrap_or_default()
                    });
                    bgk_row(&src, &mut out, omega);
                }
            };
            if bands == 1 {
                run_band(starts[0], starts[1], &mut windows[0]);
            } else {
                std::thread::scope(|scope| {
                    for (k, w) in windows.iter_mut().enumerate() {
                        let (y0, y1) = (starts[k], starts[k + 1]);
                        let run = &run_band;
                        scope.spawn(move || run(y0, y1, w));
                    }
                });
            }
        }
        for y in 0..ny {
            let inner_row = y > 0 && y < ny - 1;
            for x in 0..nx {
                if fast.is_some() && inner_row && x > 0 && x < nx - 1 {
                    continue;
                }
                let cell = (y * nx + x) as usize;
                let mut fi = [0.0f64; 9];
                if inner_row && x > 0 && x < nx - 1 {
                    for i in 0..9 {
                        let src = cell as isize - (C[i].1 as isize * nx + C[i].0 as isize);
                        fi[i] = f[i * n + src as usize];
                    }
                } else {
                    for i in 0..9 {
                        let (mut sx, sy) = (x - C[i].0 as isize, y - C[i].1 as isize);
                        if b.periodic_x {
                            sx = sx.rem_euclid(nx);
                        }
                        if sx < 0 || sx >= nx || sy < 0 || sy >= ny {
                            // Half-way bounce-back; the lid adds the momentum of the moving wall.
                            let mut v = f[OPP[i] * n + cell];
                            if sy >= ny {
                                v += 6.0 * W[i] * C[i].0 as f64 * b.lid_u;
                            }
                            fi[i] = v;
                        } else {
                            fi[i] = f[i * n + (sy * nx + sx) as usize];
                        }
                    }
                }
                let rho: f64 = fi.iter().sum();
                let jx = fi[1] - fi[3] + fi[5] - fi[6] - fi[7] + fi[8] + 0.5 * b.force_x;
                let jy = fi[2] - fi[4] + fi[5] + fi[6] - fi[7] - fi[8];
                let (ux, uy) = (jx / rho, jy / rho);
                let mut feq = [0.0f64; 9];
                for i in 0..9 {
                    feq[i] = equilibrium(i, rho, ux, uy);
                }
                let t = match newtonian_tau {
                    Some(t) => t,
                    None => {
                        // Π^neq = Σ cᵢcᵢ(fᵢ − fᵢᵉᑫ); γ̇ = 3/(2ρτ)·√(2 Π:Π) with last step's τ.
                        let (mut pxx, mut pyy, mut pxy) = (0.0, 0.0, 0.0);
                        for i in 1..9 {
                            let d = fi[i] - feq[i];
                            let (cx, cy) = (C[i].0 as f64, C[i].1 as f64);
                            pxx += cx * cx * d;
                            pyy += cy * cy * d;
                            pxy += cx * cy * d;
                        }
                        let t_old = tau[cell];
                        let gamma = 1.5 / (rho * t_old)
                            * (2.0 * (pxx * pxx + pyy * pyy + 2.0 * pxy * pxy)).sqrt();
                        let t = tau_of(fluid.viscosity(gamma)).clamp(tmin, tmax);
                        tau[cell] = t;
                        t
                    }
                };
                let omega = 1.0 / t;
                if b.force_x != 0.0 {
                    // Guo: Fᵢ = (1 − ω/2) wᵢ [3(cᵢ − u) + 9(cᵢ·u)cᵢ]·F.
                    let pre = 1.0 - 0.5 * omega;
                    for i in 0..9 {
                        let (cx, cy) = (C[i].0 as f64, C[i].1 as f64);
                        let cu = cx * ux + cy * uy;
                        let fx = 3.0 * (cx - ux) + 9.0 * cu * cx;
                        g[i * n + cell] =
                            fi[i] - omega * (fi[i] - feq[i]) + pre * W[i] * fx * b.force_x;
                    }
                } else {
                    for i in 0..9 {
                        g[i * n + cell] = fi[i] - omega * (fi[i] - feq[i]);
                    }
                }
            }
        }
        std::mem::swap(&mut self.f, &mut self.g);
        self.steps += 1;
    }
}

/// BGK collision of one run of interior nodes, written so the compiler can vectorise across x:
/// straight-line arithmetic on nine source and nine destination slices of equal length.
#[inline(never)]
fn bgk_row(src: &[&[f64]; 9], dst: &mut [&mut [f64]; 9], omega: f64) {
    let len = src[0].len();
    let [s0, s1, s2, s3, s4, s5, s6, s7, s8] = src.map(|s| &s[..len]);
    let [d0, d1, d2, d3, d4, d5, d6, d7, d8] = dst.each_mut().map(|d| &mut d[..len]);
    let (w0, w1, w2) = (4.0 / 9.0, 1.0 / 9.0, 1.0 / 36.0);
    for x in 0..len {
        let (f0, f1, f2, f3, f4, f5, f6, f7, f8) = (
            s0[x], s1[x], s2[x], s3[x], s4[x], s5[x], s6[x], s7[x], s8[x],
        );
        let rho = f0 + f1 + f2 + f3 + f4 + f5 + f6 + f7 + f8;
        let inv = 1.0 / rho;
        let ux = (f1 - f3 + f5 - f6 - f7 + f8) * inv;
        let uy = (f2 - f4 + f5 + f6 - f7 - f8) * inv;
        let usq = 1.5 * (ux * ux + uy * uy);
        let eq = |w: f64, cu: f64| w * rho * (1.0 + 3.0 * cu + 4.5 * cu * cu - usq);
        d0[x] = f0 - omega * (f0 - eq(w0, 0.0));
        d1[x] = f1 - omega * (f1 - eq(w1, ux));
        d2[x] = f2 - omega * (f2 - eq(w1, uy));
        d3[x] = f3 - omega * (f3 - eq(w1, -ux));
        d4[x] = f4 - omega * (f4 - eq(w1, -uy));
        d5[x] = f5 - omega * (f5 - eq(w2, ux + uy));
        d6[x] = f6 - omega * (f6 - eq(w2, -ux + uy));
        d7[x] = f7 - omega * (f7 - eq(w2, -ux - uy));
        d8[x] = f8 - omega * (f8 - eq(w2, ux - uy));
    }
}

impl Solver {
    /// Density and velocity of node (x, y), from the post-collision populations (which have the
    /// same density and momentum as the pre-collision ones, less half the force).
    pub fn macroscopic(&self, x: usize, y: usize) -> (f64, f64, f64) {
        let (n, cell) = (self.n(), y * self.nx + x);
        let fi: Vec<f64> = (0..9).map(|i| self.f[i * n + cell]).collect();
        let rho: f64 = fi.iter().sum();
        let jx = fi[1] - fi[3] + fi[5] - fi[6] - fi[7] + fi[8] + 0.5 * self.bounds.force_x;
        let jy = fi[2] - fi[4] + fi[5] + fi[6] - fi[7] - fi[8];
        (rho, jx / rho, jy / rho)
    }

    /// The velocity field, row by row from the bottom: (u, v).
    pub fn velocity(&self) -> (Vec<f64>, Vec<f64>) {
        let mut u = Vec::with_capacity(self.n());
        let mut v = Vec::with_capacity(self.n());
        for y in 0..self.ny {
            for x in 0..self.nx {
                let (_, a, b) = self.macroscopic(x, y);
                u.push(a);
                v.push(b);
            }
        }
        (u, v)
    }

    /// Fraction of cells whose relaxation time sits at a clamp (for non-Newtonian fluids).
    pub fn clamped_fraction(&self) -> f64 {
        if self.fluid.is_newtonian() {
            return 0.0;
        }
        let at = self
            .tau
            .iter()
            .filter(|t| **t <= self.tau_min + 1e-12 || **t >= self.tau_max - 1e-12)
            .count();
        at as f64 / self.n() as f64
    }

    /// Runs until the velocity changes by less than `tol` (max over cells, relative to `scale`)
    /// over `every` steps, or `max_steps`. Returns the steps taken and the last change.
    pub fn run_to_convergence(
        &mut self,
        every: u64,
        tol: f64,
        max_steps: u64,
        scale: f64,
        mut progress: impl FnMut(u64, f64),
    ) -> (u64, f64) {
        let mut last = self.velocity();
        let mut change = f64::INFINITY;
        while self.steps < max_steps {
            for _ in 0..every {
                self.step();
            }
            let now = self.velocity();
            change = now
                .0
                .iter()
                .zip(&last.0)
                .chain(now.1.iter().zip(&last.1))
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max)
                / scale;
            progress(self.steps, change);
            last = now;
            if change < tol {
                break;
            }
        }
        (self.steps, change)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn row_kernel_equals_the_general_path() {
        // A power law with n = 1 is Newtonian but goes through the general per-cell path.
        let mut fast = Solver::new(
            17,
            13,
            Fluid::Newtonian { nu: 0.05 },
            Boundaries::cavity(0.1),
            0.5001,
            10.0,
        );
        let mut general = Solver::new(
            17,
            13,
            Fluid::PowerLaw { k: 0.05, n: 1.0 },
            Boundaries::cavity(0.1),
            0.5001,
            10.0,
        );
        let mut two = fast.clone();
        two.threads = 2;
        for _ in 0..200 {
            fast.step();
            general.step();
            two.step();
        }
        assert_eq!(fast.f, two.f, "two threads give the same lattice");
        let worst = fast
            .f
            .iter()
            .zip(&general.f)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-13, "{worst}");
    }
}
