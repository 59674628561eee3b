//! The paper's problem timed in-library, side by side in one process: the Cheetah-3 leg's 66
//! parameters from 10,000 samples of the shell experiment, `ellipsoid` set. The assembly
//! (regressor + normal equations) runs on one thread and on every core, alternated, each
//! followed by the solve; medians of 31 rounds.
//!
//! `cargo run --release --example paper_problem`

use physid::ident::{self, ConstraintSet, NormalEquations, Options};
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/cheetah3_shell.toml");
    let (mut sc, m, _) = physid::sim::scenario::load(std::path::Path::new(path)).unwrap();
    sc.simulation.duration = 10.0;
    let rec = physid::sim::run(&m, &sc, &mut |_| {}).unwrap();
    let data = &rec.processed;
    let prior = m.parameters();
    let opts = Options::new(ConstraintSet::Ellipsoid);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let pools: Vec<(usize, rayon::ThreadPool)> = [1, cores]
        .into_iter()
        .map(|t| {
            (
                t,
                rayon::ThreadPoolBuilder::new()
                    .num_threads(t)
                    .build()
                    .unwrap(),
            )
        })
        .collect();
    let mut times = vec![(vec![], vec![]); pools.len()];
    let mut objective = vec![0.0; pools.len()];
    for _ in 0..31 {
        for (i, (_, pool)) in pools.iter().enumerate() {
            let t0 = Instant::now();
            let ne = pool.install(|| NormalEquations::from_trajectory(&m, data, 0..data.len()));
            let t1 = Instant::now();
            let id = ident::identify(&m, &ne, &prior, &opts).unwrap();
            let t2 = Instant::now();
            times[i].0.push((t1 - t0).as_secs_f64() * 1e3);
            times[i].1.push((t2 - t1).as_secs_f64() * 1e3);
            objective[i] = id.objective;
        }
    }
    println!(
        "paper problem: {} samples, {} parameters, ellipsoid",
        data.len(),
        m.layout().len
    );
    for (i, (threads, _)) in pools.iter().enumerate() {
        let (a, s) = (median(times[i].0.clone()), median(times[i].1.clone()));
        println!(
            "  {threads} thread(s): assembly {a:.2} ms, solve {s:.2} ms, end to end {:.2} ms (objective {:.12e})",
            a + s,
            objective[i]
        );
    }
}
