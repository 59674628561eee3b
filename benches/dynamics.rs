//! Dynamics benchmarks: RNEA, the full regressor (66 columns for the leg with rotors), CRBA and
//! forward dynamics, side by side, on the Cheetah-3 leg and the KUKA LWR4+.
//!
//! `cargo bench --bench dynamics`. The regressor's cost is reported as a ratio to RNEA's.

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::DMatrix;
use physid::dynamics::{crba, forward_dynamics, regressor, rnea, Data};
use physid::model::random::random_state;
use physid::model::{cheetah3, Model};
use std::hint::black_box;

fn bench_model(c: &mut Criterion, label: &str, m: &Model) {
    let mut d = Data::new(m);
    let states: Vec<[Vec<f64>; 3]> = (0..64).map(|s| random_state(s, m.dof(), 2.0)).collect();
    let mut y = DMatrix::zeros(m.dof(), m.layout().len);
    let mut g = c.benchmark_group(label);
    let mut k = 0usize;
    let mut next = || {
        k = (k + 1) % states.len();
        k
    };
    g.bench_function("rnea", |b| {
        b.iter(|| {
            let [q, qd, qdd] = &states[next()];
            black_box(rnea(m, &mut d, q, qd, qdd)[0])
        })
    });
    g.bench_function(format!("regressor ({} columns)", m.layout().len), |b| {
        b.iter(|| {
            let [q, qd, qdd] = &states[next()];
            regressor(m, &mut d, q, qd, qdd, &mut y);
            black_box(y[(0, 0)])
        })
    });
    g.bench_function("crba", |b| {
        b.iter(|| {
            let [q, _, _] = &states[next()];
            black_box(crba(m, &mut d, q)[(0, 0)])
        })
    });
    g.bench_function("forward dynamics", |b| {
        b.iter(|| {
            let [q, qd, tau] = &states[next()];
            black_box(forward_dynamics(m, &mut d, q, qd, tau).unwrap()[0])
        })
    });
    g.finish();
}

fn benches(c: &mut Criterion) {
    bench_model(c, "cheetah3 leg with rotors", &cheetah3::leg());
    bench_model(
        c,
        "cheetah3 leg links only",
        &cheetah3::leg().without_rotors(),
    );
    let kuka = concat!(env!("CARGO_MANIFEST_DIR"), "/data/kuka_lwr4/kuka_lwr4.urdf");
    if let Ok(m) = physid::io::load_robot(kuka) {
        bench_model(c, "kuka lwr4", &m);
    }
}

criterion_group! {
    name = dynamics;
    config = Criterion::default().sample_size(50).measurement_time(std::time::Duration::from_secs(2)).warm_up_time(std::time::Duration::from_millis(500));
    targets = benches
}
criterion_main!(dynamics);
