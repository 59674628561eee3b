//! The sample-size experiment: results independent of the thread count, and the paper's
//! qualitative result tested with statistics over seeds (a small version of
//! scenarios/sample_size.toml).

mod common;

use physid::experiment::{self, median_iqr, ExperimentSpec, Row};
use physid::ident::ConstraintSet;

fn setup() -> (physid::sim::scenario::Scenario, physid::model::Model) {
    let path = common::root().join("scenarios/sample_size.toml");
    let (sc, m, _) = physid::sim::scenario::load(&path).unwrap();
    (sc, m)
}

fn run(spec: &ExperimentSpec, threads: usize) -> Vec<Row> {
    let (sc, m) = setup();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| experiment::run(&m, &sc, spec, &|_, _| {}))
        .unwrap()
}

fn median(rows: &[Row], n_s: usize, set: ConstraintSet) -> f64 {
    let v: Vec<f64> = rows
        .iter()
        .filter(|r| r.n_s == n_s && r.constraints == set)
        .map(|r| r.val_rms_overall)
        .collect();
    median_iqr(&v).1
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let spec = ExperimentSpec {
        seeds: 3,
        sizes: Some(vec![30, 300]),
        validation: 500,
        ..Default::default()
    };
    let a = run(&spec, 1);
    let b = run(&spec, 2);
    assert_eq!(a.len(), 3 * 2 * 4);
    for (x, y) in a.iter().zip(&b) {
        // Everything but the wall-clock solve time is bit-identical (compared as text, because
        // the CoM error of a body identified with non-positive mass is NaN).
        let strip = |r: &Row| {
            format!(
                "{:?}",
                Row {
                    solve_s: 0.0,
                    ..r.clone()
                }
            )
        };
        assert_eq!(strip(x), strip(y));
    }
}

#[test]
fn tighter_constraints_generalize_better_from_few_samples_and_the_gap_closes() {
    let spec = ExperimentSpec {
        seeds: 8,
        sizes: Some(vec![20, 150, 6000]),
        validation: 4000,
        ..Default::default()
    };
    let rows = run(&spec, 2);
    use ConstraintSet::*;
    for n in [20, 150] {
        let m: Vec<f64> = [None, Semi, Consistent, Ellipsoid]
            .iter()
            .map(|&s| median(&rows, n, s))
            .collect();
        eprintln!("n_s {n}: median validation RMS none {:.1}, semi {:.1}, consistent {:.1}, ellipsoid {:.1} N m", m[0], m[1], m[2], m[3]);
        assert!(m[2] <= m[1] && m[1] <= m[0], "ordering at n_s = {n}: {m:?}");
        // Not by a hair: least squares is at least 10× worse than the physically consistent sets.
        assert!(m[0] > 10.0 * m[2] && m[0] > 10.0 * m[3], "{m:?}");
        if n == 20 {
            // At the smallest size the ellipsoid set is clearly the best (measured 58.6 vs 270.7).
            assert!(m[3] <= m[2], "ordering at n_s = {n}: {m:?}");
        } else {
            // By 150 samples ellipsoid and consistent tie (measured 33.9 vs 32.5 N m over 8
            // seeds, 4 %): the ellipsoid set is not meaningfully worse.
            assert!(m[3] <= 1.1 * m[2], "ordering at n_s = {n}: {m:?}");
        }
    }
    // Constrained results are physically consistent in every seed; least squares in none.
    let frac = |n: usize, s: ConstraintSet| {
        rows.iter()
            .filter(|r| r.n_s == n && r.constraints == s && r.consistent)
            .count()
    };
    assert_eq!(frac(20, Consistent), 8);
    assert_eq!(frac(20, Ellipsoid), 8);
    assert_eq!(frac(20, None), 0);
    // With 6000 samples the sets agree to 1 % and the error is of the paper's order (1.46 N m).
    let big: Vec<f64> = [None, Semi, Consistent, Ellipsoid]
        .iter()
        .map(|&s| median(&rows, 6000, s))
        .collect();
    let (lo, hi) = big
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
    assert!(hi / lo < 1.01, "{big:?}");
    assert!((0.8..2.0).contains(&lo), "{big:?}");
}

#[test]
fn polars_summary_and_pivot_match_a_direct_computation() {
    use physid::experiment::tables;
    let spec = ExperimentSpec {
        seeds: 4,
        sizes: Some(vec![40, 400]),
        validation: 400,
        ..Default::default()
    };
    let rows = run(&spec, 2);
    let joints = vec!["a".to_string(), "b".to_string(), "c".to_string()];
    let long = tables::long_table(&rows, &joints).unwrap();
    assert_eq!(long.height(), 4 * 2 * 4);
    let summary = tables::summary(&long).unwrap();
    assert_eq!(summary.height(), 2 * 4);
    let get = |name: &str, i: usize| {
        summary
            .column(name)
            .unwrap()
            .get(i)
            .unwrap()
            .try_extract::<f64>()
            .unwrap()
    };
    let mut i = 0;
    for n in [40usize, 400] {
        for set in ConstraintSet::ALL {
            let v: Vec<f64> = rows
                .iter()
                .filter(|r| r.n_s == n && r.constraints == set)
                .map(|r| r.val_rms_overall)
                .collect();
            let (q1, med, q3) = median_iqr(&v);
            assert!(
                (get("val_rms_median", i) - med).abs() <= 1e-12 * med,
                "{n} {set:?}"
            );
            assert!(
                (get("val_rms_q25", i) - q1).abs() <= 1e-12 * q1
                    && (get("val_rms_q75", i) - q3).abs() <= 1e-12 * q3
            );
            i += 1;
        }
    }
    let p = tables::pivot(
        &summary,
        "val_rms_median",
        &["none", "semi", "consistent", "ellipsoid"],
    )
    .unwrap();
    assert_eq!(p.shape(), (2, 5));
    let names: Vec<String> = p.get_column_names().iter().map(|s| s.to_string()).collect();
    assert_eq!(names, ["n_s", "none", "semi", "consistent", "ellipsoid"]);
    let cell = p
        .column("ellipsoid")
        .unwrap()
        .get(1)
        .unwrap()
        .try_extract::<f64>()
        .unwrap();
    assert!((cell - get("val_rms_median", 7)).abs() < 1e-15);
}

#[test]
fn random_windows_and_per_body_errors() {
    use physid::experiment::{tables, Windows};
    let spec = ExperimentSpec {
        seeds: 2,
        sizes: Some(vec![50, 500]),
        validation: 300,
        windows: Windows::Random,
        ..Default::default()
    };
    let a = run(&spec, 2);
    let b = run(&spec, 1);
    let first = run(
        &ExperimentSpec {
            windows: Windows::First,
            ..spec.clone()
        },
        2,
    );
    let key = |r: &Row| {
        format!(
            "{:?}",
            Row {
                solve_s: 0.0,
                ..r.clone()
            }
        )
    };
    assert_eq!(
        a.iter().map(key).collect::<Vec<_>>(),
        b.iter().map(key).collect::<Vec<_>>(),
        "random windows must be deterministic"
    );
    assert!(
        a.iter()
            .zip(&first)
            .any(|(x, y)| x.val_rms_overall != y.val_rms_overall),
        "random windows should differ from the first window"
    );
    // Six bodies (3 links, 3 rotors), four errors each; their mean is the row's mean error.
    let (_, m) = setup();
    let names: Vec<String> = physid::ident::bodies(&m)
        .into_iter()
        .map(|(n, _, _)| n)
        .collect();
    assert_eq!(names.len(), 6);
    for r in &a {
        assert_eq!(r.body_errors.len(), 6);
        let mean_j = r.body_errors.iter().map(|e| e[3]).sum::<f64>() / 6.0;
        assert!((mean_j - r.j_err).abs() <= 1e-12 * r.j_err.abs().max(1.0));
    }
    let joints = vec!["a".to_string(), "b".to_string(), "c".to_string()];
    let long = tables::long_table_with_bodies(&a, &joints, &names).unwrap();
    assert!(long.column("j_err_shank").is_ok() && long.column("mass_err_knee_rotor").is_ok());
}
