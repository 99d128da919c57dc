//! Lattice updates per second on one core, 120 × 120 (the groove lattice).

use clayloft_flow::{Boundaries, Fluid, Solver};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("lbm_120x120");
    g.throughput(Throughput::Elements(120 * 120 * 10));
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
        for _ in 0..200 {
            s.step();
        }
        g.bench_function(name, |b| {
            b.iter(|| {
                for _ in 0..10 {
                    s.step();
                }
            })
        });
        s.threads = 2;
        g.bench_function(format!("{name}_two_threads"), |b| {
            b.iter(|| {
                for _ in 0..10 {
                    s.step();
                }
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
