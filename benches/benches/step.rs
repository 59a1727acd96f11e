//! Whole explicit steps of the solver on a 10^5-element elastic block, at 1
//! and 2 threads. Throughput is in element-updates per second.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use fdem_benches::block;
use fdem_solver::Simulation;

fn steps(c: &mut Criterion) {
    let spec = block(316, 158);
    let m = spec.triangles.len() as u64;
    let mut g = c.benchmark_group("step_1e5");
    g.throughput(Throughput::Elements(m));
    g.sample_size(20);
    for threads in [1, 2] {
        let mut sim = Simulation::new(spec.clone(), threads).unwrap();
        g.bench_function(format!("threads_{threads}"), |b| b.iter(|| sim.step(1).unwrap()));
    }
    g.finish();
}

criterion_group!(benches, steps);
criterion_main!(benches);
