//! Accuracy and cost of the integration step: a scenario at 1, 2 and 4 steps per control
//! period of RK4 and of Ralston's third-order method against 16 RK4 substeps (sensor noise and
//! quantization off, the velocity feedback the truth, so that only the integration differs),
//! beside the error budget of a tenth of the scenario's torque noise.
//!
//! `cargo run --release --example substeps [SCENARIO.toml …]` (default: the shell experiment)
fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let paths = if args.is_empty() {
        vec!["scenarios/cheetah3_shell.toml".to_string()]
    } else {
        args
    };
    for path in paths {
        report(std::path::Path::new(&path));
    }
}

fn report(path: &std::path::Path) {
    let (mut sc, m, _) = physid::sim::scenario::load(path).unwrap();
    let budget = sc.sensors.torque_noise / 10.0;
    sc.sensors.torque_noise = 0.0;
    sc.sensors.encoder_noise = 0.0;
    sc.sensors.encoder_step = 0.0;
    sc.sensors.velocity_feedback = physid::sim::scenario::VelocityFeedback::True;
    sc.simulation.duration = sc.simulation.duration.min(10.0);
    let seconds = sc.simulation.duration;
    let mut run = |s: usize, method: physid::sim::Method| {
        sc.simulation.substeps = s;
        sc.simulation.integrator = Some(method);
        let t = std::time::Instant::now();
        let r = physid::sim::run(&m, &sc, &mut |_| {}).unwrap();
        (r, t.elapsed().as_secs_f64())
    };
    let (reference, _) = run(16, physid::sim::Method::Rk4);
    println!(
        "{}: {seconds} s, budget {budget:.1e} N m (a tenth of the torque noise)",
        path.display()
    );
    let methods = [physid::sim::Method::Rk4, physid::sim::Method::Ralston3];
    for (method, s) in methods.into_iter().flat_map(|m| [1, 2, 4].map(|s| (m, s))) {
        let (r, wall) = run(s, method);
        let max_diff = |a: &[f64], b: &[f64]| {
            a.iter()
                .zip(b)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max)
        };
        let dq = max_diff(&r.truth.q, &reference.truth.q);
        let dtau = max_diff(&r.truth.tau, &reference.truth.tau);
        let verdict = if dtau <= budget { "within" } else { "OVER" };
        println!(
            "  {:<8} x{s}: max |dq| {dq:.2e} rad, max |dtau| {dtau:.2e} N m vs RK4 x16 \
             ({verdict} budget); {:.0}x real time",
            method.name(),
            seconds / wall
        );
    }
}
