//! Allocator speed over N = 100, 1000, 10 000 (M = 5, paper distribution, fixed seeds).
//!
//! Run with `cargo bench -p afg-baseline`. The table in docs/baselines.md comes from
//! `cargo xtask bench-baselines`, which times the same methods on the same instances.

use afg_baseline::Method;
use afg_game::GeneratorConfig;
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};

fn allocators(c: &mut Criterion) {
    let mut group = c.benchmark_group("allocate");
    group.sample_size(10);
    for n in [100, 1_000, 10_000] {
        let inst = GeneratorConfig::paper(n, 5, 7)
            .generate()
            .expect("valid generator");
        for method in [Method::Opt, Method::Da, Method::DaBalanced, Method::Greedy] {
            let alloc = method.allocator(0);
            group.bench_with_input(BenchmarkId::new(method.name(), n), &inst, |b, inst| {
                b.iter(|| alloc.allocate(inst).expect("allocates"))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, allocators);
criterion_main!(benches);
