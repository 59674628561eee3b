//! Identification: recovery of the identifiable parameter combinations on noise-free data under
//! every constraint set, constraints that hold (checked independently of the solver) on noisy
//! data, agreement of the direct and cone solutions, and clear errors.

mod common;

use nalgebra::{DMatrix, DVector, SymmetricEigen};
use physid::dynamics::{regressor, rnea_with_friction, Data};
use physid::ident::{self, analysis, ConstraintSet, NormalEquations, Options, SolveStatus};
use physid::model::{cheetah3, random::random_state, Model};
use physid::trajectory::Trajectory;

/// Noise-free samples with exact `sign` friction: τ = Y θ exactly.
fn exact_data(m: &Model, count: usize, seed: u64) -> Trajectory {
    let mut d = Data::new(m);
    let names = m.joint_names();
    let mut tr = Trajectory::new(names, true);
    for k in 0..count {
        let [q, qd, qdd] = random_state(seed * 100_000 + k as u64, m.dof(), 2.0);
        let tau = rnea_with_friction(m, &mut d, &q, &qd, &qdd);
        tr.push(k as f64 * 1e-3, &q, &qd, Some(&qdd), tau.as_slice());
    }
    tr
}

/// A prior 30% off the truth (a "CAD" estimate), so recovery is not handed over by the prior.
fn perturbed_prior(m: &Model) -> DVector<f64> {
    let theta = m.parameters();
    let [r, _, _] = random_state(99, theta.len(), 0.3);
    DVector::from_iterator(
        theta.len(),
        theta.iter().zip(&r).map(|(t, e)| t * (1.0 + e)),
    )
}

/// Relative error of `a − b` on the identifiable subspace of the normal matrix.
fn identifiable_error(ne: &NormalEquations, a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    let p = a.len();
    let d: Vec<f64> = (0..p)
        .map(|i| 1.0 / ne.yty[(i, i)].sqrt().max(1e-300))
        .collect();
    let hs = DMatrix::from_fn(p, p, |i, j| d[i] * ne.yty[(i, j)] * d[j]);
    let eig = SymmetricEigen::new(hs);
    let lmax = eig.eigenvalues.max();
    let (mut num, mut den) = (0.0, 0.0);
    for k in 0..p {
        if eig.eigenvalues[k] > 1e-6 * lmax {
            let v = eig.eigenvectors.column(k);
            let proj = |x: &DVector<f64>| (0..p).map(|i| v[i] * x[i] / d[i]).sum::<f64>();
            num += (proj(a) - proj(b)).powi(2);
            den += proj(b).powi(2);
        }
    }
    (num / den).sqrt()
}

#[test]
fn every_constraint_set_recovers_the_identifiable_parameters_from_clean_data() {
    let m = cheetah3::leg();
    let train = exact_data(&m, 2000, 1);
    let valid = exact_data(&m, 500, 2);
    let ne = NormalEquations::from_trajectory(&m, &train, 0..train.len());
    let truth = m.parameters();
    let prior = perturbed_prior(&m);
    for set in ConstraintSet::ALL {
        let mut o = Options::new(set);
        o.prior_weight = 1e-9;
        let r = ident::identify(&m, &ne, &prior, &o).unwrap();
        let err = identifiable_error(&ne, &r.theta, &truth);
        let (rms, overall) = analysis::rms_error(&m, &r.theta, &valid, 0..valid.len());
        eprintln!(
            "{set:?}: identifiable-subspace error {err:.2e}, validation RMS {rms:?} N m, {} it",
            r.solver.iterations
        );
        assert!(err < 1e-4, "{set:?}: {err:e}");
        assert!(overall < 1e-3, "{set:?}: validation RMS {overall:e}");
        assert!(
            r.constraints_hold,
            "{set:?}: the truth satisfies the set, so must the estimate"
        );
        assert!(
            matches!(
                r.solver.status,
                SolveStatus::Direct | SolveStatus::Interior | SolveStatus::Solved
            ),
            "{:?}",
            r.solver
        );
    }
}

#[test]
fn direct_and_cone_least_squares_agree() {
    let m = cheetah3::leg();
    let train = exact_data(&m, 800, 3);
    let ne = NormalEquations::from_trajectory(&m, &train, 0..train.len());
    let prior = perturbed_prior(&m);
    let mut o = Options::new(ConstraintSet::None);
    o.prior_weight = 1e-4;
    let direct = ident::identify(&m, &ne, &prior, &o).unwrap();
    o.force_cone_solver = true;
    let cone = ident::identify(&m, &ne, &prior, &o).unwrap();
    let rel = (&direct.theta - &cone.theta).norm() / direct.theta.norm();
    assert!(rel < 1e-6, "direct vs cone: {rel:e}");
    assert!((direct.objective - cone.objective).abs() < 1e-9 * (1.0 + direct.objective.abs()));
}

#[test]
fn noisy_data_constrained_estimates_satisfy_their_constraints_and_ols_does_not() {
    let path = common::root().join("scenarios/cheetah3_shell.toml");
    let (mut sc, m, _) = physid::sim::scenario::load(&path).unwrap();
    sc.simulation.duration = 4.0;
    let rec = physid::sim::run(&m, &sc, &mut |_| {}).unwrap();
    let data = &rec.processed;
    let prior = perturbed_prior(&m);
    let mut ols_violations = 0;
    for (start, len) in [(0, 150), (1000, 150), (2000, 150)] {
        let ne = NormalEquations::from_trajectory(&m, data, start..start + len);
        for set in ConstraintSet::ALL {
            let r = ident::identify(&m, &ne, &prior, &Options::new(set)).unwrap();
            // Independent check: eigenvalues recomputed from the parameters.
            let theta = &r.theta;
            let ok = ident::bodies(&m).iter().all(|(_, c, e)| {
                let p = physid::spatial::InertialParams(theta.fixed_rows::<10>(*c).into_owned());
                let rep = p.consistency(e.as_ref());
                match set {
                    ConstraintSet::None => true,
                    ConstraintSet::Semi => rep.min_eig_spatial > 0.0,
                    ConstraintSet::Consistent => rep.min_eig_pseudo > 0.0,
                    ConstraintSet::Ellipsoid => {
                        rep.min_eig_pseudo > 0.0
                            && rep.trace_jq.unwrap() >= -1e-9
                            && rep.min_eig_com.unwrap() >= -1e-9
                    }
                }
            });
            assert!(
                ok && r.constraints_hold,
                "{set:?} on samples {start}..: constraints violated"
            );
            if set != ConstraintSet::None {
                assert!(
                    r.viscous.iter().chain(&r.coulomb).all(|f| *f >= -1e-9),
                    "{set:?}: negative friction"
                );
            }
            if set == ConstraintSet::None
                && !ident::constraints_hold(&m, theta, ConstraintSet::Consistent)
            {
                ols_violations += 1;
            }
        }
    }
    assert!(
        ols_violations >= 2,
        "least squares on 150 noisy samples should usually be inconsistent ({ols_violations}/3)"
    );
}

#[test]
fn bad_identification_requests_are_clear_errors() {
    let m = cheetah3::leg();
    let tr = exact_data(&m, 5, 4);
    let ne = NormalEquations::from_trajectory(&m, &tr, 0..5);
    let mut o = Options::new(ConstraintSet::Consistent);
    o.prior_weight = 0.0;
    let e = ident::identify(&m, &ne, &m.parameters(), &o)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("5 samples") && e.contains("66 parameters"),
        "{e}"
    );
    let bare = m.without_rotors();
    let mut bodies = bare.bodies().to_vec();
    bodies[1].bounding = None;
    let no_ell = Model::new("x", bodies, bare.gravity()).unwrap();
    let tr2 = exact_data(&no_ell, 100, 5);
    let ne2 = NormalEquations::from_trajectory(&no_ell, &tr2, 0..100);
    let e = ident::identify(
        &no_ell,
        &ne2,
        &no_ell.parameters(),
        &Options::new(ConstraintSet::Ellipsoid),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("'thigh'") && e.contains("ellipsoid"), "{e}");
    let _ = regressor;
}

#[test]
fn log_det_regularizer_recovers_clean_data_and_pulls_to_the_prior() {
    use physid::ident::Regularizer;
    let m = cheetah3::leg();
    let train = exact_data(&m, 1500, 6);
    let ne = NormalEquations::from_trajectory(&m, &train, 0..train.len());
    let truth = m.parameters();
    // A consistent prior: each body's truth thickened differently, friction scaled.
    let mut prior = truth.clone();
    for (k, (_, c, _)) in ident::bodies(&m).iter().enumerate() {
        let p = physid::spatial::InertialParams(truth.fixed_rows::<10>(*c).into_owned())
            .thickened(0.005 * (1 + k % 3) as f64);
        prior.rows_mut(*c, 10).copy_from(&(p.0 * 1.2));
    }
    // Small weight: the data decide the identifiable part.
    let mut o = Options::new(ConstraintSet::None);
    o.regularizer = Regularizer::LogDet;
    o.prior_weight = 1e-7;
    let r = ident::identify(&m, &ne, &prior, &o).unwrap();
    let err = identifiable_error(&ne, &r.theta, &truth);
    assert!(err < 1e-4, "identifiable error {err:e}");
    // The divergence's domain is J ≻ 0: physically consistent even without constraints.
    assert!(ident::constraints_hold(
        &m,
        &r.theta,
        ConstraintSet::Consistent
    ));
    let b = ident::bregman_logdet(&m, &r.theta, &prior).unwrap();
    assert!(b.is_finite() && b > 0.0, "{b}");
    // Heavy weight on almost no data: the estimate collapses onto the prior (d = 0 there).
    // Measured: relative distance 6e-2 at w = 1, 1.3e-2 at 1e2, 2e-4 at 1e4 (beyond ~1e6 the
    // program is so badly scaled that Clarabel stops at AlmostSolved).
    let few = NormalEquations::from_trajectory(&m, &train, 0..3);
    o.prior_weight = 1e4;
    let r = ident::identify(&m, &few, &prior, &o).unwrap();
    assert_eq!(r.solver.status, SolveStatus::Solved);
    let rel = (&r.theta - &prior).norm() / prior.norm();
    assert!(rel < 1e-3, "heavy prior: {rel:e}");
    assert!(ident::bregman_logdet(&m, &r.theta, &prior).unwrap() < 1e-4);
}

#[test]
fn extra_columns_are_free_unless_declared_non_negative() {
    // τ = Y θ − 0.5 r for a column r outside the model: free, its coefficient is −0.5; declared
    // non-negative, it stops at 0 (and even `none` then goes through the cone solver).
    let m = cheetah3::leg();
    let tr = exact_data(&m, 400, 3);
    let (n, p) = (m.dof(), m.layout().len);
    let mut ne = NormalEquations::new(n, p + 1);
    let mut z = DMatrix::zeros(n, p + 1);
    physid::ident::normal::for_each_regressor(&m, &tr, 0..tr.len(), &mut |k, y| {
        z.columns_mut(0, p).copy_from(y);
        let r: Vec<f64> = (0..n).map(|j| ((k * 7 + j * 3) as f64).sin()).collect();
        let tau: Vec<f64> = (0..n).map(|j| tr.tau_at(k)[j] - 0.5 * r[j]).collect();
        for j in 0..n {
            z[(j, p)] = r[j];
        }
        ne.add(&z, &tau);
    });
    let ne = ne.finish();
    let mut prior = DVector::zeros(p + 1);
    prior.rows_mut(0, p).copy_from(&m.parameters());
    for set in [ConstraintSet::None, ConstraintSet::Consistent] {
        let mut o = Options::new(set);
        let free = ident::identify(&m, &ne, &prior, &o).unwrap();
        assert!(
            (free.theta[p] + 0.5).abs() < 1e-6,
            "{set:?}: {}",
            free.theta[p]
        );
        o.nonnegative = vec![p];
        let held = ident::identify(&m, &ne, &prior, &o).unwrap();
        assert!(
            held.theta[p] > -1e-7 && held.theta[p] < 1e-3,
            "{set:?}: {}",
            held.theta[p]
        );
        assert_ne!(held.solver.status, SolveStatus::Direct);
    }
    // A non-negative index outside θ is a named error, not a panic.
    let mut o = Options::new(ConstraintSet::Consistent);
    o.nonnegative = vec![p + 1];
    assert!(ident::identify(&m, &ne, &prior, &o).is_err());
}

#[test]
fn base_parameters_are_the_identifiable_combinations_with_errors() {
    // The leg with rotors on clean data: the base parameters span the regressor's row space
    // (one per rank), each dependent column is the combination of base columns they state, and
    // their values at the truth and at any θ that differs by a null direction agree.
    let m = cheetah3::leg();
    let tr = exact_data(&m, 400, 3);
    let ne = NormalEquations::from_trajectory(&m, &tr, 0..tr.len());
    let truth = m.parameters();
    let idf = analysis::identifiability(&m, &ne, &truth);
    assert_eq!(idf.base.len(), idf.rank);
    assert_eq!(idf.rank, 38, "the leg's structural rank on rich motion");
    assert_eq!(idf.unidentifiable_total, idf.parameters - idf.rank);
    // Listed once each: no two null directions the same line.
    let mut lines = idf.unidentifiable.clone();
    lines.sort();
    lines.dedup();
    assert_eq!(lines.len(), idf.unidentifiable.len());
    // The world-mounted ab/ad rotor's mass never enters the torques.
    assert!(
        idf.unidentifiable
            .iter()
            .any(|u| u.starts_with("abad_rotor:")
                && u.contains(" m,")
                && u.ends_with("(never excited)")),
        "{:?}",
        idf.unidentifiable
    );
    // Y θ = Σ_i Y_{b_i} β_i for every θ: check on the samples with a θ moved along the null
    // space (the truth plus a random vector projected out of the row space).
    let names = m.parameter_names();
    let col = |name: &str| names.iter().position(|n| n == name).unwrap();
    let beta = |theta: &DVector<f64>| -> Vec<f64> {
        idf.base
            .iter()
            .map(|b| {
                b.terms
                    .iter()
                    .map(|t| t.coefficient * theta[col(&t.parameter)])
                    .sum()
            })
            .collect()
    };
    let mut d = Data::new(&m);
    let mut y = DMatrix::zeros(m.dof(), truth.len());
    let k = 17;
    regressor(
        &m,
        &mut d,
        tr.q_at(k),
        tr.qd_at(k),
        tr.qdd_at(k).unwrap(),
        &mut y,
    );
    let at_base = |b: &[f64]| -> DVector<f64> {
        let mut tau = DVector::zeros(m.dof());
        for (bp, v) in idf.base.iter().zip(b) {
            tau += y.column(col(&bp.terms[0].parameter)) * *v;
        }
        tau
    };
    let tau = &y * &truth;
    let err = (at_base(&beta(&truth)) - &tau).norm() / tau.norm();
    assert!(err < 1e-9, "Y θ against Y_b β: {err:e}");
    // Values reported at θ, and exact data leave tiny standard errors.
    for (bp, v) in idf.base.iter().zip(beta(&truth)) {
        assert!(
            (bp.value - v).abs() <= 1e-12 * v.abs().max(1.0),
            "{}",
            bp.expression
        );
        assert!(bp.standard_error.is_finite());
    }
    // A parameter that is not identifiable alone has no finite standard error.
    assert!(idf.standard_errors[col("abad_rotor.m")].is_infinite());
}

/// `Σ YᵀY`, `Σ Yᵀτ`, `Σ ‖τ‖²` over the samples `range` of `tr`, one dense product per sample,
/// the rows of `excluded` joints zeroed: the reference the streaming assembly is checked
/// against.
fn dense_sums(
    m: &Model,
    tr: &Trajectory,
    range: std::ops::Range<usize>,
    excluded: &[usize],
) -> (DMatrix<f64>, DVector<f64>, f64) {
    let p = m.layout().len;
    let (mut yty, mut ytt, mut tt) = (DMatrix::<f64>::zeros(p, p), DVector::zeros(p), 0.0);
    physid::ident::normal::for_each_regressor(m, tr, range, &mut |k, y| {
        let mut y = y.clone();
        let mut tau = DVector::from_column_slice(tr.tau_at(k));
        for &j in excluded {
            y.row_mut(j).fill(0.0);
            tau[j] = 0.0;
        }
        yty += y.transpose() * &y;
        ytt += y.transpose() * &tau;
        tt += tau.norm_squared();
    });
    (yty, ytt, tt)
}

#[test]
fn the_parallel_assembly_is_the_same_whatever_the_thread_count_and_matches_one_pass() {
    // The normal equations are summed in fixed chunks in parallel: bit for bit the same sums
    // on one thread and on four, and the same as one sequential pass over the samples up to
    // rounding (a different order of additions).
    let m = cheetah3::leg();
    let tr = exact_data(&m, 5000, 3);
    let pool = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
    };
    let one = pool(1).install(|| NormalEquations::from_trajectory(&m, &tr, 100..4900));
    let four = pool(4).install(|| NormalEquations::from_trajectory(&m, &tr, 100..4900));
    assert_eq!(one.yty, four.yty);
    assert_eq!(one.ytt, four.ytt);
    assert_eq!((one.tt, one.samples), (four.tt, four.samples));
    assert_eq!(one.samples, 4800);
    let (yty, _, _) = dense_sums(&m, &tr, 100..4900, &[]);
    let scale = yty.amax();
    assert!(
        (&one.yty - &yty).amax() <= 1e-12 * scale,
        "{:e}",
        (&one.yty - &yty).amax() / scale
    );
    assert!(one.yty.iter().all(|x| x.is_finite()));
    assert_eq!(one.yty, one.yty.transpose());
}

#[test]
fn the_joint_by_joint_assembly_matches_dense_sums_on_trees_with_a_joint_left_out() {
    // The assembly sums each joint's rows over the columns its subtree can touch; on branched
    // trees with rotors, with a joint's rows excluded, it must give the dense sums of
    // `Σ Yᵀ Y`, `Σ Yᵀ τ`, `Σ ‖τ‖²` over the rows kept, up to rounding.
    for seed in [3, 11] {
        let m = physid::model::random::random_tree(seed, 7);
        let tr = exact_data(&m, 700, seed);
        let excluded = [2];
        let ne = NormalEquations::from_trajectory_excluding(&m, &tr, 0..tr.len(), &excluded);
        let n = m.dof();
        let (yty, ytt, tt) = dense_sums(&m, &tr, 0..tr.len(), &excluded);
        let rel = |a: f64, scale: f64| a / scale;
        assert!(
            rel((&ne.yty - &yty).amax(), yty.amax()) <= 1e-12,
            "seed {seed}"
        );
        assert!(
            rel((&ne.ytt - &ytt).amax(), ytt.amax()) <= 1e-12,
            "seed {seed}"
        );
        assert!(rel((ne.tt - tt).abs(), tt) <= 1e-12, "seed {seed}");
        assert_eq!(ne.samples, 700);
        assert_eq!(ne.rows_per_sample(), n - 1);
        assert_eq!(ne.yty, ne.yty.transpose());
    }
}

#[test]
fn with_its_constraints_inactive_every_set_reaches_the_least_squares_optimum() {
    // Clean data of the leg: the least-squares optimum (with the prior's pull) lies strictly
    // inside every set, up to the margin ε of the matrix inequalities. Where it clears the
    // margin too the set returns it without the cone solver (status `Interior`; the semi set
    // here, while a rotor's pseudo-inertia has its least eigenvalue inside ε), and every solve,
    // the cone solver's forced too, must end at its objective to the solver's absolute gap tolerance
    // (1e-8 N² m²). That objective (3.5e-7) is tiny beside Σ τ² / n_s (26); the cone program is
    // solved about the unconstrained minimizer so that the solver's tolerances apply to the
    // excess over it (semi: 1.4e-9 above). Solved about the origin instead, semi stopped 2.8e-8
    // above it, 8 % of the objective.
    let m = cheetah3::leg();
    let train = exact_data(&m, 2000, 4);
    let ne = NormalEquations::from_trajectory(&m, &train, 0..train.len());
    let prior = perturbed_prior(&m);
    let direct = ident::identify(&m, &ne, &prior, &Options::new(ConstraintSet::None)).unwrap();
    let scale = ne.tt / ne.samples as f64;
    assert!(direct.objective > 0.0 && direct.objective < 1e-4 * scale);
    for set in [
        ConstraintSet::Semi,
        ConstraintSet::Consistent,
        ConstraintSet::Ellipsoid,
    ] {
        let fast = ident::identify(&m, &ne, &prior, &Options::new(set)).unwrap();
        assert!(fast.constraints_hold, "{set:?}");
        if set == ConstraintSet::Semi {
            assert_eq!(fast.solver.status, SolveStatus::Interior);
        }
        if fast.solver.status == SolveStatus::Interior {
            assert_eq!(fast.theta, direct.theta, "{set:?}: not the direct optimum");
        }
        assert!((fast.objective - direct.objective).abs() <= 1e-8, "{set:?}");
        let mut forced = Options::new(set);
        forced.force_cone_solver = true;
        let r = ident::identify(&m, &ne, &prior, &forced).unwrap();
        assert_eq!(r.solver.status, SolveStatus::Solved, "{set:?}");
        let excess = r.objective - direct.objective;
        eprintln!(
            "{set:?}: objective {:e}, direct {:e}, Σ τ²/n_s {scale:e}",
            r.objective, direct.objective
        );
        assert!(
            excess.abs() <= 1e-8,
            "{set:?}: {excess:e} above the direct optimum"
        );
    }
}

#[test]
fn an_unconstrained_optimum_outside_the_set_goes_to_the_cone_solver() {
    // 150 noisy samples: least squares is inconsistent (as in the noisy-data test), so the consistent
    // set's optimum lies on its boundary and must come from the cone solver, with J ≻ 0 held.
    let path = common::root().join("scenarios/cheetah3_shell.toml");
    let (mut sc, m, _) = physid::sim::scenario::load(&path).unwrap();
    sc.simulation.duration = 1.0;
    let rec = physid::sim::run(&m, &sc, &mut |_| {}).unwrap();
    let ne = NormalEquations::from_trajectory(&m, &rec.processed, 0..150);
    let prior = perturbed_prior(&m);
    let ls = ident::identify(&m, &ne, &prior, &Options::new(ConstraintSet::None)).unwrap();
    assert!(!ident::constraints_hold(
        &m,
        &ls.theta,
        ConstraintSet::Consistent
    ));
    let r = ident::identify(&m, &ne, &prior, &Options::new(ConstraintSet::Consistent)).unwrap();
    assert_eq!(r.solver.status, SolveStatus::Solved);
    assert!(r.constraints_hold);
    assert!(r.objective > ls.objective);
}
