//! Writes N noise-free samples of the Cheetah leg (random states, τ = RNEA + friction, with q̈)
//! as CSV, streaming, for memory measurements of `physid identify` on long files:
//! `cargo run --release --example synthetic_csv -- N OUT.csv`
use physid::dynamics::{rnea_with_friction, Data};
use physid::model::{cheetah3, random::random_state};
use std::io::Write;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|a| a.parse().ok()).expect("N");
    let out = std::fs::File::create(args.get(2).expect("OUT.csv")).expect("create");
    let mut w = std::io::BufWriter::new(out);
    let m = cheetah3::leg();
    let mut d = Data::new(&m);
    writeln!(w, "t,q1,q2,q3,dq1,dq2,dq3,ddq1,ddq2,ddq3,tau1,tau2,tau3").unwrap();
    for k in 0..n {
        let [q, qd, qdd] = random_state(k as u64, 3, 2.0);
        let tau = rnea_with_friction(&m, &mut d, &q, &qd, &qdd);
        let row: Vec<String> = [k as f64 * 1e-3]
            .iter()
            .chain(&q)
            .chain(&qd)
            .chain(&qdd)
            .chain(tau.iter())
            .map(|x| format!("{x:e}"))
            .collect();
        writeln!(w, "{}", row.join(",")).unwrap();
    }
}
