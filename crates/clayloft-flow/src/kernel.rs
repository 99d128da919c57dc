//! The kernel: pull streaming and collision of a run of nodes (the interior of a band, or the
//! gathered wall nodes), written as straight-line arithmetic over nine source and nine
//! destination slices so that the compiler vectorises it across the run. The same code is compiled three times — for AVX-512, for AVX2 and for
//! the baseline — and the widest the CPU has is chosen at run time, so the binary stays portable.
//! No fused multiply–adds are used, so every variant gives the same numbers bit for bit.

use crate::collision::{
    CHUNK, Relaxation, moments, relax_towards_equilibrium, shear_rate_squared,
    single_precision_rate,
};
use crate::lattice::{Stored, shift, unshift};

/// Writes the nine populations of node x.
macro_rules! store {
    ($f:expr, $x:expr, $($d:ident),+) => {{
        let mut i = 0;
        $(
            $d[$x] = shift(i, $f[i]);
            i += 1;
        )+
        let _ = i;
    }};
}

/// One run of interior nodes: the nine populations pulled from their upwind neighbours
/// (`src[i][x]` is the population arriving at node x in direction i), where to write the
/// post-collision populations, and the nodes' relaxation rates ω = 1/τ of the last step and of
/// this one (used only when τ varies from node to node).
pub struct Row<'a> {
    pub src: [&'a [Stored]; 9],
    pub dst: [&'a mut [Stored]; 9],
    pub omega_old: &'a [f64],
    pub omega_new: &'a mut [f64],
}

/// Streams and collides one row.
pub fn sweep<R: Relaxation, const FORCED: bool>(row: Row<'_>, relax: &R, force_x: f64) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU has AVX-512F, the only feature the function enables.
            return unsafe { sweep_avx512::<R, FORCED>(row, relax, force_x) };
        }
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2 (and so AVX), the features the function enables.
            return unsafe { sweep_avx2::<R, FORCED>(row, relax, force_x) };
        }
    }
    sweep_body::<R, FORCED>(row, relax, force_x)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn sweep_avx512<R: Relaxation, const FORCED: bool>(row: Row<'_>, relax: &R, force_x: f64) {
    sweep_body::<R, FORCED>(row, relax, force_x)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn sweep_avx2<R: Relaxation, const FORCED: bool>(row: Row<'_>, relax: &R, force_x: f64) {
    sweep_body::<R, FORCED>(row, relax, force_x)
}

/// Unpacks the row into separate slice arguments: each `&`/`&mut` argument tells the compiler
/// that it overlaps no other, so the vectorised loop needs no run-time overlap checks (with the
/// nineteen slices in a struct it would need more checks than it is willing to emit).
#[inline(always)]
fn sweep_body<R: Relaxation, const FORCED: bool>(row: Row<'_>, relax: &R, force_x: f64) {
    let Row {
        src,
        dst,
        omega_old,
        omega_new,
    } = row;
    let [s0, s1, s2, s3, s4, s5, s6, s7, s8] = src;
    let [d0, d1, d2, d3, d4, d5, d6, d7, d8] = dst;
    sweep_slices::<R, FORCED>(
        [s0, s1, s2, s3, s4, s5, s6, s7, s8],
        d0,
        d1,
        d2,
        d3,
        d4,
        d5,
        d6,
        d7,
        d8,
        omega_old,
        omega_new,
        relax,
        force_x,
    )
}

#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn sweep_slices<R: Relaxation, const FORCED: bool>(
    src: [&[Stored]; 9],
    d0: &mut [Stored],
    d1: &mut [Stored],
    d2: &mut [Stored],
    d3: &mut [Stored],
    d4: &mut [Stored],
    d5: &mut [Stored],
    d6: &mut [Stored],
    d7: &mut [Stored],
    d8: &mut [Stored],
    omega_old: &[f64],
    omega_new: &mut [f64],
    relax: &R,
    force_x: f64,
) {
    let len = omega_new.len();
    // Slices of one known length: the loops below then need no bounds checks.
    let [s0, s1, s2, s3, s4, s5, s6, s7, s8] = src.map(|s| &s[..len]);
    let [d0, d1, d2, d3, d4, d5, d6, d7, d8] =
        [d0, d1, d2, d3, d4, d5, d6, d7, d8].map(|d| &mut d[..len]);
    let omega_old = &omega_old[..len];
    // A macro rather than a closure: closures are not always inlined, and a call stops the
    // vectoriser.
    macro_rules! load {
        ($x:expr) => {
            [
                unshift(0, s0[$x]),
                unshift(1, s1[$x]),
                unshift(2, s2[$x]),
                unshift(3, s3[$x]),
                unshift(4, s4[$x]),
                unshift(5, s5[$x]),
                unshift(6, s6[$x]),
                unshift(7, s7[$x]),
                unshift(8, s8[$x]),
            ]
        };
    }
    if !R::PER_NODE {
        // One τ: a single pass.
        let omega = relax.omega_at(0.0);
        for x in 0..len {
            let mut f = load!(x);
            let node = moments::<FORCED>(&f, force_x);
            relax_towards_equilibrium::<FORCED>(&mut f, node.rho, node.ux, node.uy, omega, force_x);
            store!(f, x, d0, d1, d2, d3, d4, d5, d6, d7, d8);
        }
        return;
    }
    // τ per node: three short passes over chunks that stay in the L1 cache — moments and shear
    // rate, then τ (the logarithm and exponentials), then the collision. One long pass would
    // chain several hundred cycles of dependent arithmetic per node, more than the processor can
    // overlap across nodes; short passes let it run many nodes' chains side by side.
    let mut rho = [0.0; CHUNK];
    let mut ux = [0.0; CHUNK];
    let mut uy = [0.0; CHUNK];
    let mut gamma_sq = [0.0f32; CHUNK];
    let mut start = 0;
    while start < len {
        let m = CHUNK.min(len - start);
        for k in 0..m {
            let f = load!(start + k);
            let node = moments::<FORCED>(&f, force_x);
            (rho[k], ux[k], uy[k]) = (node.rho, node.ux, node.uy);
            gamma_sq[k] = single_precision_rate(shear_rate_squared(&f, node, omega_old[start + k]));
        }
        relax.omega_at_each(&gamma_sq[..m], &mut omega_new[start..start + m]);
        for k in 0..m {
            let x = start + k;
            let mut f = load!(x);
            let omega = omega_new[x];
            relax_towards_equilibrium::<FORCED>(&mut f, rho[k], ux[k], uy[k], omega, force_x);
            store!(f, x, d0, d1, d2, d3, d4, d5, d6, d7, d8);
        }
        start += m;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::{ConstantRate, ShearDependent};
    use crate::lattice::{W, equilibrium};
    use crate::rheology::Fluid;

    /// A row of 1000 nodes in gently varying states, run through `sweep` by `variant`.
    fn run(
        variant: fn(Row<'_>, &ShearDependent, f64),
        law: &ShearDependent,
    ) -> (Vec<Stored>, Vec<f64>) {
        let len = 1000;
        let src: Vec<Vec<Stored>> = (0..9)
            .map(|i| {
                (0..len)
                    .map(|x| {
                        let t = x as f64 * 0.01;
                        let f =
                            equilibrium(i, 1.0 + 0.01 * t.sin(), 0.05 * t.cos(), 0.03 * t.sin());
                        shift(i, f + 1e-4 * W[i] * (t * (i + 1) as f64).sin())
                    })
                    .collect()
            })
            .collect();
        let omega_old: Vec<f64> = (0..len)
            .map(|x| 1.0 + 0.5 * (x as f64 * 0.1).sin())
            .collect();
        let mut dst = vec![vec![0.0 as Stored; len]; 9];
        let mut omega_new = vec![0.0; len];
        let mut it = dst.iter_mut();
        let row = Row {
            src: std::array::from_fn(|i| &src[i][..]),
            dst: std::array::from_fn(|_| &mut it.next().unwrap()[..]),
            omega_old: &omega_old,
            omega_new: &mut omega_new,
        };
        variant(row, law, 1e-5);
        (dst.concat(), omega_new)
    }

    #[test]
    fn every_instruction_set_gives_the_same_numbers() {
        let law = ShearDependent::of(
            Fluid::HerschelBulkley {
                tau0: 2e-5,
                k: 0.02,
                n: 0.5,
                m: 1e4,
            },
            0.51,
            10.0,
        )
        .unwrap();
        let baseline = run(sweep_body::<ShearDependent, true>, &law);
        assert!(baseline.1.iter().all(|w| *w > 0.09 && *w < 1.97));
        #[cfg(target_arch = "x86_64")]
        {
            if std::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU has AVX2.
                let avx2 = run(|r, l, f| unsafe { sweep_avx2::<_, true>(r, l, f) }, &law);
                assert!(avx2 == baseline, "AVX2 differs from the baseline");
            }
            if std::is_x86_feature_detected!("avx512f") {
                // SAFETY: the CPU has AVX-512F.
                let avx512 = run(|r, l, f| unsafe { sweep_avx512::<_, true>(r, l, f) }, &law);
                assert!(avx512 == baseline, "AVX-512 differs from the baseline");
            }
        }
    }

    #[test]
    fn constant_rate_of_one_lands_on_the_equilibrium() {
        let src = [[0.01 as Stored; 4]; 9];
        let mut dst = vec![vec![0.0 as Stored; 4]; 9];
        let mut it = dst.iter_mut();
        let row = Row {
            src: std::array::from_fn(|i| &src[i][..]),
            dst: std::array::from_fn(|_| &mut it.next().unwrap()[..]),
            omega_old: &[1.0; 4],
            omega_new: &mut [1.0; 4],
        };
        sweep::<ConstantRate, false>(row, &ConstantRate(1.0), 0.0);
        // ρ = 1 + 9·0.01, u = 0: every direction relaxes to wᵢρ, stored as wᵢ(ρ − 1).
        for (i, d) in dst.iter().enumerate() {
            let want = shift(i, W[i] * 1.09);
            assert!(
                d.iter().all(|v| (v - want).abs() < 1e-7),
                "{i}: {d:?} vs {want}"
            );
        }
    }
}
