//! Simulation speed: one simulated second of the paper's shell experiment (1 kHz control,
//! closed loop, sensors, processing) per iteration, in physid (RK4 at 4 and 1 steps per
//! period, Ralston's third order at 1) and in rapier (4 substeps) side by side. Real-time
//! factor = 1 s / time per iteration.
//!
//! `cargo bench --bench simulation`

use criterion::{criterion_group, criterion_main, Criterion};
use physid::sim::scenario::Engine;
use physid::sim::Method;
use std::hint::black_box;

fn benches(c: &mut Criterion) {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/cheetah3_shell.toml");
    let (mut sc, m, _) = physid::sim::scenario::load(std::path::Path::new(path)).unwrap();
    sc.simulation.duration = 1.0;
    let mut g = c.benchmark_group("shell experiment, 1 simulated second");
    for (label, engine, method, substeps) in [
        ("physid RK4 x4", Engine::Physid, Some(Method::Rk4), 4),
        ("physid RK4 x1", Engine::Physid, Some(Method::Rk4), 1),
        (
            "physid Ralston3 x1",
            Engine::Physid,
            Some(Method::Ralston3),
            1,
        ),
        ("rapier x4", Engine::Rapier, None, 4),
    ] {
        sc.simulation.engine = engine;
        sc.simulation.integrator = method;
        sc.simulation.substeps = substeps;
        g.bench_function(label, |b| {
            b.iter(|| black_box(physid::sim::run(&m, &sc, &mut |_| {}).unwrap().truth.len()))
        });
    }
    g.finish();
}

criterion_group! {
    name = simulation;
    config = Criterion::default().sample_size(10).measurement_time(std::time::Duration::from_secs(5)).warm_up_time(std::time::Duration::from_millis(500));
    targets = benches
}
criterion_main!(simulation);
