//! The interior row kernel: pull streaming and collision of a run of interior nodes, written as
//! straight-line arithmetic over nine source and nine destination slices so that the compiler
//! vectorises it across x. The same code is compiled three times — for AVX-512, for AVX2 and for
//! the baseline — and the widest the CPU has is chosen at run time, so the binary stays portable.
//! No fused multiply–adds are used, so every variant gives the same numbers bit for bit.

use crate::collision::{CHUNK, Relaxation, moments, relax_towards_equilibrium, shear_rate};

/// Writes the nine populations of node x.
macro_rules! store {
    ($f:expr, $x:expr, $($d:ident),+) => {{
        let mut i = 0;
        $(
            $d[$x] = $f[i];
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
    pub src: [&'a [f64]; 9],
    pub dst: [&'a mut [f64]; 9],
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
    src: [&[f64]; 9],
    d0: &mut [f64],
    d1: &mut [f64],
    d2: &mut [f64],
    d3: &mut [f64],
    d4: &mut [f64],
    d5: &mut [f64],
    d6: &mut [f64],
    d7: &mut [f64],
    d8: &mut [f64],
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
                s0[$x], s1[$x], s2[$x], s3[$x], s4[$x], s5[$x], s6[$x], s7[$x], s8[$x],
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
    let mut gamma = [0.0; CHUNK];
    let mut start = 0;
    while start < len {
        let m = CHUNK.min(len - start);
        for k in 0..m {
            let f = load!(start + k);
            let node = moments::<FORCED>(&f, force_x);
            (rho[k], ux[k], uy[k]) = (node.rho, node.ux, node.uy);
            gamma[k] = shear_rate(&f, node, omega_old[start + k]);
        }
        relax.omega_at_each(&gamma[..m], &mut omega_new[start..start + m]);
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
