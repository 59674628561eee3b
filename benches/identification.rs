//! The paper's identification problem: the Cheetah-3 leg (3 links + 3 rotors + 6 friction
//! terms = 66 parameters), 10,000 samples of the simulated shell experiment, `ellipsoid` set.
//! Reported: end to end (regressor, streaming assembly, solve) and the parts.
//!
//! `cargo bench --bench identification`

use criterion::{criterion_group, criterion_main, Criterion};
use physid::ident::{self, ConstraintSet, NormalEquations, Options};
use std::hint::black_box;

fn benches(c: &mut Criterion) {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/cheetah3_shell.toml");
    let (mut sc, m, _) = physid::sim::scenario::load(std::path::Path::new(path)).unwrap();
    sc.simulation.duration = 10.0;
    let rec = physid::sim::run(&m, &sc, &mut |_| {}).unwrap();
    let data = &rec.processed;
    let prior = m.parameters();
    let mut g = c.benchmark_group("paper problem, 10k samples, 66 parameters");
    g.bench_function("regressor only (10k samples)", |b| {
        let mut d = physid::dynamics::Data::new(&m);
        let mut y = nalgebra::DMatrix::zeros(3, 66);
        b.iter(|| {
            for k in 0..data.len() {
                physid::dynamics::regressor(
                    &m,
                    &mut d,
                    data.q_at(k),
                    data.qd_at(k),
                    data.qdd_at(k).unwrap(),
                    &mut y,
                );
            }
            black_box(y[(0, 0)])
        })
    });
    g.bench_function("assembly (regressor + normal equations)", |b| {
        b.iter(|| black_box(NormalEquations::from_trajectory(&m, data, 0..data.len()).tt))
    });
    let ne = NormalEquations::from_trajectory(&m, data, 0..data.len());
    for set in ConstraintSet::ALL {
        g.bench_function(format!("solve only, {}", set.name()), |b| {
            b.iter(|| {
                black_box(
                    ident::identify(&m, &ne, &prior, &Options::new(set))
                        .unwrap()
                        .objective,
                )
            })
        });
    }
    g.bench_function("end to end, ellipsoid", |b| {
        b.iter(|| {
            let ne = NormalEquations::from_trajectory(&m, data, 0..data.len());
            black_box(
                ident::identify(&m, &ne, &prior, &Options::new(ConstraintSet::Ellipsoid))
                    .unwrap()
                    .objective,
            )
        })
    });
    g.finish();
}

criterion_group! {
    name = identification;
    config = Criterion::default().sample_size(20).measurement_time(std::time::Duration::from_secs(3)).warm_up_time(std::time::Duration::from_millis(500));
    targets = benches
}
criterion_main!(identification);
