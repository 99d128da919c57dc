//! Lattice updates per second, 120 × 120 (the groove lattice): one core, then two threads
//! (bands of rows that meet at a barrier after every step; 50 steps per sample).

use clayloft_flow::{Boundaries, Fluid, Solver};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};

const STEPS: u64 = 50;

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("lbm_120x120");
    g.throughput(Throughput::Elements(120 * 120 * STEPS));
    for (name, fluid) in [
        ("newtonian", Fluid::Newtonian { nu: 0.1 }),
        (
            "herschel_bulkley",
            Fluid::HerschelBulkley {
                tau0: 1e-5,
                k: 0.05,
                n: 0.4,
                m: 1e4,
            },
        ),
    ] {
        let mut s = Solver::new(120, 120, fluid, Boundaries::cavity(0.05), 0.51, 10.0);
        s.advance(200);
        g.bench_function(name, |b| b.iter(|| s.advance(STEPS)));
        s.threads = 2;
        g.bench_function(format!("{name}_two_threads"), |b| {
            b.iter(|| s.advance(STEPS))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
