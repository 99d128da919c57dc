//! The D2Q9 BGK solver (the paper's equations 1–5): pull streaming and collision fused in one
//! pass over two lattices; half-way bounce-back at walls half a cell outside the boundary nodes;
//! the moving lid by Ladd's rule `fᵢ = f*_ī + 6wᵢρ cᵢ·u_w`; a periodic channel with Guo's body
//! force; a per-node relaxation rate from the strain rate of the non-equilibrium moments
//! ([`crate::collision`]); time steps on one thread or on bands of rows ([`crate::parallel`]).

// The wall nodes walk the nine directions indexing several arrays (populations, C, W, OPP) by
// the same i: a range loop says that most plainly.
#![allow(clippy::needless_range_loop)]

use crate::collision::{ConstantRate, Relaxation, ShearDependent, moments, shear_rate_squared};
use crate::kernel::{self, Row};
use crate::lattice::{C, OPP, Stored, W, shift, unshift};
use crate::parallel::{SpinBarrier, band_starts};
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
    /// Post-collision populations in their stored form ([`Stored`]), direction-major:
    /// `f[i·n + y·nx + x]`; `g` is the lattice the next step writes.
    f: Vec<Stored>,
    g: Vec<Stored>,
    /// Relaxation rate ω = 1/τ of each node after the last step (read by the next: the lagged
    /// scheme), and the buffer the next step writes.
    omega: Vec<f64>,
    omega_next: Vec<f64>,
    pub steps: u64,
    /// Threads asked for (1 = one core): bands of rows that meet after every step. At most one
    /// per core is used ([`Solver::bands`]): the threads wait for each other after every step, so
    /// more than the machine can run at once would only take turns waiting.
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
        // At rest with ρ = 1 every population equals its weight: stored as 0.
        let f = vec![0.0; 9 * n];
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
            omega: vec![1.0 / tau0; n],
            omega_next: vec![1.0 / tau0; n],
            steps: 0,
            threads: 1,
        }
    }

    fn n(&self) -> usize {
        self.nx * self.ny
    }

    /// One time step over every node.
    pub fn step(&mut self) {
        self.advance(1);
    }

    /// `steps` time steps, on [`Solver::threads`] threads.
    pub fn advance(&mut self, steps: u64) {
        match ShearDependent::of(self.fluid, self.tau_min, self.tau_max) {
            Some(law) => self.advance_with(law, steps),
            None => {
                let nu = match self.fluid {
                    Fluid::Newtonian { nu } => nu,
                    _ => unreachable!("non-Newtonian fluids have a shear-dependent law"),
                };
                let tau = tau_of(nu).clamp(self.tau_min, self.tau_max);
                self.advance_with(ConstantRate(1.0 / tau), steps)
            }
        }
    }

    fn advance_with<R: Relaxation>(&mut self, relax: R, steps: u64) {
        if self.bounds.force_x != 0.0 {
            self.advance_monomorphic::<R, true>(relax, steps)
        } else {
            self.advance_monomorphic::<R, false>(relax, steps)
        }
    }

    fn advance_monomorphic<R: Relaxation, const FORCED: bool>(&mut self, relax: R, steps: u64) {
        let frame = Frame {
            nx: self.nx,
            ny: self.ny,
            bounds: self.bounds,
        };
        let starts = band_starts(self.ny, self.bands());
        let bands = starts.len() - 1;
        if bands == 1 {
            let mut walls = WallNodes::new(&frame, 0..self.ny);
            for _ in 0..steps {
                let (src, dst) = split_directions(&self.f, &mut self.g, 0..self.ny, self.nx);
                let omega = (&self.omega[..], &mut self.omega_next[..]);
                frame.update_rows::<R, FORCED>(src, dst, omega, &mut walls, &relax);
                self.swap();
            }
        } else {
            let shared = SharedLattices {
                f: [self.f.as_mut_ptr(), self.g.as_mut_ptr()],
                omega: [self.omega.as_mut_ptr(), self.omega_next.as_mut_ptr()],
                n: self.n(),
                nx: self.nx,
            };
            let barrier = SpinBarrier::new(bands);
            let band = |k: usize| {
                let rows = starts[k]..starts[k + 1];
                let mut walls = WallNodes::new(&frame, rows.clone());
                for s in 0..steps {
                    // SAFETY: see `SharedLattices`; the barrier ends every step.
                    unsafe {
                        let (src, dst, omega) = shared.band((s % 2) as usize, rows.clone());
                        frame.update_rows::<R, FORCED>(src, dst, omega, &mut walls, &relax);
                    }
                    barrier.wait();
                }
            };
            std::thread::scope(|scope| {
                for k in 1..bands {
                    let band = &band;
                    scope.spawn(move || band(k));
                }
                band(0);
            });
            if steps % 2 == 1 {
                self.swap();
            }
        }
        self.steps += steps;
    }

    /// How many bands (threads) a step runs on: [`Solver::threads`], at most the machine's cores
    /// and the lattice's rows.
    pub fn bands(&self) -> usize {
        self.threads.clamp(1, cores()).min(self.ny.max(1))
    }

    /// The lattice just written becomes the one the next step reads.
    fn swap(&mut self) {
        std::mem::swap(&mut self.f, &mut self.g);
        std::mem::swap(&mut self.omega, &mut self.omega_next);
    }
}

/// The machine's cores, asked once (the query reads cgroup files: slow next to a small step).
fn cores() -> usize {
    static CORES: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}

/// The nine directions of the source lattice (whole) and of the destination rows `rows`.
fn split_directions<'a>(
    src: &'a [Stored],
    dst: &'a mut [Stored],
    rows: std::ops::Range<usize>,
    nx: usize,
) -> ([&'a [Stored]; 9], [&'a mut [Stored]; 9]) {
    let n = src.len() / 9;
    let mut dirs = dst.chunks_mut(n);
    (
        std::array::from_fn(|i| &src[i * n..(i + 1) * n]),
        std::array::from_fn(|_| {
            let d = dirs.next().expect("nine directions");
            &mut d[rows.start * nx..rows.end * nx]
        }),
    )
}

/// What a band update needs to know about the lattice besides its populations.
#[derive(Clone, Copy)]
struct Frame {
    nx: usize,
    ny: usize,
    bounds: Boundaries,
}

impl Frame {
    /// Streams from `src` (each direction whole) and collides the band's rows (`walls.rows`),
    /// writing them to `dst` (those rows of each direction); `omega` holds those rows' relaxation
    /// rates from the last step and receives the new ones.
    ///
    /// The interior of the band is one flat run from node (1, first interior row) to node
    /// (nx − 2, last interior row), so the vectorised kernel sees long runs with one remainder.
    /// The run also passes the side nodes x = 0 and x = nx − 1 of the rows in between, where the
    /// pull reads the neighbouring row's far side; those nodes, and the top and bottom rows, are
    /// then done again properly with [`Frame::pull_at_wall`] (each node's update reads only the
    /// last step, so doing one twice is harmless).
    fn update_rows<R: Relaxation, const FORCED: bool>(
        &self,
        src: [&[Stored]; 9],
        mut dst: [&mut [Stored]; 9],
        (omega_old, omega_new): (&[f64], &mut [f64]),
        walls: &mut WallNodes,
        relax: &R,
    ) {
        let rows = walls.rows.clone();
        let (nx, ny) = (self.nx, self.ny);
        let (first, last) = (rows.start.max(1), rows.end.min(ny - 1));
        if nx >= 3 && first < last {
            let start = first * nx + 1;
            let len = (last - 1) * nx + nx - 1 - start;
            let local = start - rows.start * nx;
            let pulled: [&[Stored]; 9] = std::array::from_fn(|i| {
                let from = start as isize - (C[i].1 as isize * nx as isize + C[i].0 as isize);
                &src[i][from as usize..from as usize + len]
            });
            let mut it = dst.iter_mut();
            let row = Row {
                src: pulled,
                dst: std::array::from_fn(|_| {
                    let d = it.next().expect("nine directions");
                    &mut d[local..local + len]
                }),
                omega_old: &omega_old[local..local + len],
                omega_new: &mut omega_new[local..local + len],
            };
            kernel::sweep::<R, FORCED>(row, relax, self.bounds.force_x);
        }
        // The nodes next to a wall: their pulled populations are gathered into scratch rows,
        // collided by the same kernel, and scattered back.
        let WallNodes {
            nodes,
            populations,
            rates,
            ..
        } = walls;
        let m = nodes.len();
        let (pulled, out) = populations.split_at_mut(9 * m);
        let (w_old, w_new) = rates.split_at_mut(m);
        for (k, &(x, y)) in nodes.iter().enumerate() {
            let f = self.pull_at_wall(&src, x, y);
            for i in 0..9 {
                pulled[i * m + k] = shift(i, f[i]);
            }
            w_old[k] = omega_old[(y - rows.start) * nx + x];
        }
        let mut out_dirs = out.chunks_mut(m.max(1));
        let row = Row {
            src: std::array::from_fn(|i| &pulled[i * m..(i + 1) * m]),
            dst: std::array::from_fn(|_| out_dirs.next().unwrap_or_default()),
            omega_old: w_old,
            omega_new: w_new,
        };
        kernel::sweep::<R, FORCED>(row, relax, self.bounds.force_x);
        for (k, &(x, y)) in nodes.iter().enumerate() {
            let local = (y - rows.start) * nx + x;
            for i in 0..9 {
                dst[i][local] = out[i * m + k];
            }
            omega_new[local] = if R::PER_NODE { w_new[k] } else { w_old[k] };
        }
    }

    /// The populations arriving at node (x, y) next to a wall (or the periodic seam): those that
    /// would come from outside bounce back half-way, `fᵢ = f*_ī`, and the lid adds the momentum
    /// of the moving wall, `6wᵢρ cᵢ·u_w` with ρ ≈ 1.
    #[inline(always)]
    fn pull_at_wall(&self, src: &[&[Stored]; 9], x: usize, y: usize) -> [f64; 9] {
        let (nx, ny) = (self.nx as isize, self.ny as isize);
        let b = self.bounds;
        let cell = y * self.nx + x;
        let mut f = [0.0; 9];
        for i in 0..9 {
            let mut sx = x as isize - C[i].0 as isize;
            let sy = y as isize - C[i].1 as isize;
            if b.periodic_x {
                sx = sx.rem_euclid(nx);
            }
            f[i] = if sx < 0 || sx >= nx || sy < 0 || sy >= ny {
                let mut v = unshift(OPP[i], src[OPP[i]][cell]);
                if sy >= ny {
                    v += 6.0 * W[i] * C[i].0 as f64 * b.lid_u;
                }
                v
            } else {
                unshift(i, src[i][(sy * nx + sx) as usize])
            };
        }
        f
    }
}

/// The nodes of a band next to a wall — the sides of the interior rows, and whole top and bottom
/// rows — and scratch rows for them, made once per stretch of steps.
struct WallNodes {
    rows: std::ops::Range<usize>,
    nodes: Vec<(usize, usize)>,
    /// Pulled populations, then the collided ones: 9 rows of `nodes.len()` each.
    populations: Vec<Stored>,
    /// Their old and new relaxation rates.
    rates: Vec<f64>,
}

impl WallNodes {
    fn new(frame: &Frame, rows: std::ops::Range<usize>) -> WallNodes {
        let (nx, ny) = (frame.nx, frame.ny);
        let mut nodes = Vec::with_capacity(2 * rows.len() + 2 * nx);
        for y in rows.clone() {
            if y > 0 && y + 1 < ny && nx >= 3 {
                nodes.extend([(0, y), (nx - 1, y)]);
            } else {
                nodes.extend((0..nx).map(|x| (x, y)));
            }
        }
        WallNodes {
            rows,
            populations: vec![0.0; 18 * nodes.len()],
            rates: vec![0.0; 2 * nodes.len()],
            nodes,
        }
    }
}

/// The two lattices and their relaxation rates, shared by the band threads of a stretch of steps.
///
/// In step s every thread reads the whole source lattice (index s mod 2) and its own rows of the
/// source ω, and writes only its own rows of the destination lattice and ω (index 1 − s mod 2);
/// nobody writes a source during the step, and the barrier that ends each step orders all writes
/// before the next step's reads. The pointers come from `&mut` borrows of the solver's vectors
/// that outlive the threads.
struct SharedLattices {
    f: [*mut Stored; 2],
    omega: [*mut f64; 2],
    n: usize,
    nx: usize,
}

// SAFETY: the threads' accesses are disjoint or read-only within a step, as described above.
unsafe impl Sync for SharedLattices {}

/// A band's view of the lattices in one step: source directions, destination rows, and its rows
/// of the old and new ω.
type BandView<'a> = (
    [&'a [Stored]; 9],
    [&'a mut [Stored]; 9],
    (&'a [f64], &'a mut [f64]),
);

impl SharedLattices {
    /// What the band `rows` reads and writes in a step whose source is lattice `src`.
    ///
    /// # Safety
    /// Bands held at the same time must not overlap and must have the same `src`.
    unsafe fn band(&self, src: usize, rows: std::ops::Range<usize>) -> BandView<'_> {
        let dst = 1 - src;
        let (n, start, len) = (self.n, rows.start * self.nx, rows.len() * self.nx);
        // SAFETY: all ranges lie inside the 9·n (or n) elements of the vectors; the caller
        // guarantees the aliasing rules above.
        unsafe {
            (
                std::array::from_fn(|i| std::slice::from_raw_parts(self.f[src].add(i * n), n)),
                std::array::from_fn(|i| {
                    std::slice::from_raw_parts_mut(self.f[dst].add(i * n + start), len)
                }),
                (
                    std::slice::from_raw_parts(self.omega[src].add(start), len),
                    std::slice::from_raw_parts_mut(self.omega[dst].add(start), len),
                ),
            )
        }
    }
}

impl Solver {
    /// Density and velocity of node (x, y), from the post-collision populations (which have the
    /// same density and momentum as the pre-collision ones, less half the force).
    pub fn macroscopic(&self, x: usize, y: usize) -> (f64, f64, f64) {
        let (n, cell) = (self.n(), y * self.nx + x);
        let fi: [f64; 9] = std::array::from_fn(|i| unshift(i, self.f[i * n + cell]));
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

    /// The magnitude of the (kinematic) shear stress at every node, row-major from the bottom:
    /// `|σ| = ν·γ̇`, with γ̇ from the non-equilibrium moments of the populations arriving at
    /// the node for the next step (as the next collision will see them) and ν = (1/ω − ½)/3
    /// from the node's relaxation rate. Where `|σ|` is below a slurry's yield stress, the slurry
    /// does not yield: the plug.
    pub fn shear_stresses(&self) -> Vec<f64> {
        let n = self.n();
        let frame = Frame {
            nx: self.nx,
            ny: self.ny,
            bounds: self.bounds,
        };
        let src: [&[Stored]; 9] = std::array::from_fn(|i| &self.f[i * n..(i + 1) * n]);
        let mut out = Vec::with_capacity(n);
        for y in 0..self.ny {
            for x in 0..self.nx {
                let omega = self.omega[y * self.nx + x];
                let f = frame.pull_at_wall(&src, x, y);
                let m = if self.bounds.force_x != 0.0 {
                    moments::<true>(&f, self.bounds.force_x)
                } else {
                    moments::<false>(&f, 0.0)
                };
                let gamma = shear_rate_squared(&f, m, omega).sqrt();
                out.push((1.0 / omega - 0.5) / 3.0 * gamma);
            }
        }
        out
    }

    /// Fractions of cells whose relaxation time sits at the lower and at the upper clamp (for
    /// non-Newtonian fluids; cells at the upper one are, for practical purposes, unyielded).
    pub fn clamped_fractions(&self) -> (f64, f64) {
        if self.fluid.is_newtonian() {
            return (0.0, 0.0);
        }
        let (mut low, mut high) = (0, 0);
        for w in &self.omega {
            let tau = 1.0 / w;
            low += usize::from(tau <= self.tau_min * (1.0 + 1e-6));
            high += usize::from(tau >= self.tau_max * (1.0 - 1e-6));
        }
        let n = self.n() as f64;
        (low as f64 / n, high as f64 / n)
    }

    /// Fraction of cells whose relaxation time sits at either clamp.
    pub fn clamped_fraction(&self) -> f64 {
        let (low, high) = self.clamped_fractions();
        low + high
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
            self.advance(every.min(max_steps - self.steps));
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
    use crate::collision::collide;

    /// One step done the plain way: every node pulled with [`Frame::pull_at_wall`] (which is
    /// also right for interior nodes) and collided by the scalar [`collide`], with the
    /// reference viscosity law of [`Fluid::viscosity`] and `std` maths.
    fn reference_step(s: &mut Solver) {
        let n = s.n();
        let frame = Frame {
            nx: s.nx,
            ny: s.ny,
            bounds: s.bounds,
        };
        let src: [&[Stored]; 9] = std::array::from_fn(|i| &s.f[i * n..(i + 1) * n]);
        let mut g = vec![0.0; 9 * n];
        let mut omega = vec![0.0; n];
        for y in 0..s.ny {
            for x in 0..s.nx {
                let cell = y * s.nx + x;
                let mut f = frame.pull_at_wall(&src, x, y);
                let law = ReferenceLaw(s.fluid, s.tau_min, s.tau_max);
                omega[cell] = if s.bounds.force_x != 0.0 {
                    collide::<_, true>(&mut f, &law, s.omega[cell], s.bounds.force_x)
                } else {
                    collide::<_, false>(&mut f, &law, s.omega[cell], 0.0)
                };
                for i in 0..9 {
                    g[i * n + cell] = shift(i, f[i]);
                }
            }
        }
        s.f = g;
        s.omega = omega;
        s.steps += 1;
    }

    #[derive(Clone, Copy)]
    struct ReferenceLaw(Fluid, f64, f64);

    impl Relaxation for ReferenceLaw {
        const PER_NODE: bool = true;
        fn omega_at(&self, gamma_sq: f64) -> f64 {
            1.0 / tau_of(self.0.viscosity(gamma_sq.sqrt())).clamp(self.1, self.2)
        }
    }

    fn worst_difference<T: Copy + Into<f64>>(a: &[T], b: &[T]) -> f64 {
        a.iter()
            .zip(b)
            .map(|(a, b)| ((*a).into() - (*b).into()).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn kernel_matches_the_plain_per_node_step() {
        let hb = Fluid::HerschelBulkley {
            tau0: 2e-5,
            k: 0.02,
            n: 0.5,
            m: 1e4,
        };
        for (fluid, bounds) in [
            (Fluid::Newtonian { nu: 0.05 }, Boundaries::cavity(0.1)),
            (hb, Boundaries::cavity(0.1)),
            (
                Fluid::PowerLaw { k: 0.05, n: 1.5 },
                Boundaries::channel(1e-5),
            ),
            (hb, Boundaries::channel(1e-5)),
        ] {
            // Wide enough for the flat interior run to span several kernel chunks.
            let mut fast = Solver::new(300, 13, fluid, bounds, 0.51, 10.0);
            let mut plain = fast.clone();
            let mut two = fast.clone();
            two.threads = 2;
            fast.advance(150);
            two.advance(150);
            for _ in 0..150 {
                reference_step(&mut plain);
            }
            assert_eq!(
                fast.f, two.f,
                "{fluid:?}: two threads give the same lattice"
            );
            assert_eq!(
                fast.omega, two.omega,
                "{fluid:?}: and the same relaxation rates"
            );
            let worst = worst_difference(&fast.f, &plain.f);
            // Single-precision storage: the two orders of arithmetic may round a population to
            // neighbouring floats (7·10⁻⁹ apart near 0.06); a real fault shows as 10⁻⁵ and more.
            assert!(
                worst < 1e-7,
                "{fluid:?} {bounds:?}: populations differ by {worst}"
            );
            if !fluid.is_newtonian() {
                let worst = worst_difference(&fast.omega, &plain.omega);
                assert!(worst < 1e-5, "{fluid:?}: ω differs by {worst}");
            }
            // Something happened: the lid or the force moved the fluid.
            let (u, _) = fast.velocity();
            assert!(u.iter().any(|u| u.abs() > 1e-4), "{fluid:?}: fluid at rest");
        }
    }

    #[test]
    fn channel_stress_grows_linearly_from_the_centre() {
        // Momentum balance of a channel: |σ| = G·|y| whatever the fluid.
        let (ny, g) = (20, 1e-5);
        for fluid in [
            Fluid::Newtonian { nu: 1.0 / 6.0 },
            Fluid::PowerLaw { k: 0.05, n: 0.6 },
        ] {
            let mut s = Solver::new(3, ny, fluid, Boundaries::channel(g), 0.505, 10.0);
            s.run_to_convergence(1000, 1e-7, 200_000, 1e-3, |_, _| {});
            let stress = s.shear_stresses();
            for y in [2, 5, 14, 17] {
                let want = g * (y as f64 + 0.5 - ny as f64 / 2.0).abs();
                let got = stress[y * 3 + 1];
                assert!(
                    (got - want).abs() < 0.03 * want,
                    "{fluid:?} row {y}: {got:e} vs {want:e}"
                );
            }
        }
    }

    #[test]
    fn threads_are_capped_and_step_limits_kept() {
        let mut s = Solver::new(
            10,
            6,
            Fluid::Newtonian { nu: 0.1 },
            Boundaries::cavity(0.05),
            0.51,
            10.0,
        );
        s.threads = 1000;
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        assert_eq!(s.bands(), cores.min(6));
        s.threads = 0;
        assert_eq!(s.bands(), 1);
        // The convergence loop stops at max_steps even between two of its checks.
        let (steps, change) = s.run_to_convergence(1000, 1e-30, 2500, 0.05, |_, _| {});
        assert_eq!((steps, s.steps), (2500, 2500));
        assert!(change.is_finite() && change > 0.0);
    }

    #[test]
    fn odd_and_even_stretches_on_several_threads_agree() {
        let mut one = Solver::new(
            40,
            31,
            Fluid::Newtonian { nu: 0.05 },
            Boundaries::cavity(0.1),
            0.51,
            10.0,
        );
        let mut three = one.clone();
        three.threads = 3;
        for steps in [1, 2, 7, 10] {
            one.advance(steps);
            three.advance(steps);
        }
        assert_eq!(one.f, three.f);
        assert_eq!(one.steps, 20);
    }

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
        let worst = worst_difference(&fast.f, &general.f);
        assert!(worst < 1e-7, "{worst}");
    }
}
