//! Accuracy and cost of the integration step: the shell experiment at 1, 2 and 4 RK4 substeps
//! per 1 ms control period against 16 substeps (noise off, so only integration differs).
//! `cargo run --release --example substeps`
fn main() {
    let path = std::path::Path::new("scenarios/cheetah3_shell.toml");
    let (mut sc, m, _) = physid::sim::scenario::load(path).unwrap();
    sc.sensors.torque_noise = 0.0;
    sc.sensors.encoder_step = 0.0;
    sc.sensors.velocity_feedback = physid::sim::scenario::VelocityFeedback::True;
    sc.simulation.duration = 10.0;
    let mut run = |s: usize| {
        sc.simulation.substeps = s;
        let t = std::time::Instant::now();
        let r = physid::sim::run(&m, &sc, &mut |_| {}).unwrap();
        (r, t.elapsed().as_secs_f64())
    };
    let (reference, _) = run(16);
    for s in [1, 2, 4] {
        let (r, wall) = run(s);
        let dq = r
            .truth
            .q
            .iter()
            .zip(&reference.truth.q)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let dt = r
            .truth
            .tau
            .iter()
            .zip(&reference.truth.tau)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        println!("substeps {s}: max |dq| {dq:.2e} rad, max |dtau| {dt:.2e} N m vs 16 substeps; {:.0}x real time", 10.0 / wall);
    }
}
