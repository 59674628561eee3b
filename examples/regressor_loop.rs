//! Runs the leg regressor in a loop (for profilers): `cargo run --release --example regressor_loop`.
use nalgebra::DMatrix;
use physid::dynamics::{regressor, Data};
use physid::model::{cheetah3, random::random_state};

fn main() {
    let m = cheetah3::leg();
    let mut d = Data::new(&m);
    let mut y = DMatrix::zeros(3, m.layout().len);
    let states: Vec<_> = (0..64).map(|s| random_state(s, 3, 2.0)).collect();
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(200_000);
    let mut acc = 0.0;
    let t = std::time::Instant::now();
    for k in 0..n {
        let [q, qd, qdd] = &states[k % 64];
        regressor(&m, &mut d, q, qd, qdd, &mut y);
        acc += y[(0, 0)];
    }
    println!(
        "{:.1} ns per regressor ({acc:.3})",
        t.elapsed().as_nanos() as f64 / n as f64
    );
}
