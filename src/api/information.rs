//! A description's own uncertainty carried in its sidecar: `identify --out-urdf` writes the
//! fit's information matrix ([`crate::ident::information`]) as the sidecar's `[information]`
//! table, and `diagnose` reads it back as the prior on the description
//! (`diagnose::Options::description_information`), so a description that is itself an
//! identified model is held as firmly as its data determined it, and no firmer.

use super::data::Notice;
use super::ApiError;
use crate::ident::information::Information;
use crate::io::IoError;
use crate::model::Model;
use nalgebra::DMatrix;
use serde::Deserialize;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// The stated relative uncertainty the ladder adds to a sidecar's information when
/// `--description-uncertainty` is not given (what the data of the identification did not
/// determine is held this loosely).
pub const STATED_WITH_INFORMATION: f64 = 0.05;

/// Largest relative change of a parameter between the sidecar's `at` and the description read
/// (the URDF's text form of `m`, `c`, `I_c` rounds the last bits of `π`): beyond it the
/// description was edited after it was identified and the information is not its own.
const SAME_PARAMETER: f64 = 1e-6;

/// The `[information]` table of a sidecar (TOML), numbers in shortest round-trip form.
pub fn sidecar_table(info: &Information) -> String {
    let mut s = String::from(
        "\n# The identification's information matrix over the parameters below: YᵀY / (s² τ_c)\n# over its training samples (s: residual RMS, τ_c: residual correlation time in\n# samples). physid diagnose reads it as the description's uncertainty (docs/diagnose.md).\n[information]\n",
    );
    let list = |v: &mut dyn Iterator<Item = String>| v.collect::<Vec<String>>().join(", ");
    let _ = writeln!(s, "samples = {}", info.samples);
    let _ = writeln!(s, "residual_rms = {:e}", info.residual_rms);
    let _ = writeln!(s, "correlation_samples = {:e}", info.correlation_samples);
    let names = list(&mut info.names.iter().map(|n| format!("{n:?}")));
    let _ = writeln!(s, "parameters = [{names}]");
    let _ = writeln!(
        s,
        "at = [{}]",
        list(&mut info.at.iter().map(|x| format!("{x:e}")))
    );
    s.push_str("matrix = [\n");
    for row in info.matrix.row_iter() {
        let _ = writeln!(
            s,
            "  [{}],",
            list(&mut row.iter().map(|x| format!("{x:e}")))
        );
    }
    s.push_str("]\n");
    s
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Table {
    samples: usize,
    residual_rms: f64,
    correlation_samples: f64,
    parameters: Vec<String>,
    at: Vec<f64>,
    matrix: Vec<Vec<f64>>,
}

/// The information a description's sidecar carries, mapped onto `model`'s parameters (rows of
/// parameters the sidecar does not name are zero: nothing known beyond the stated
/// uncertainty). `robot` is the `--robot` argument: a sidecar itself, or a URDF with its
/// sidecar beside it (`arm.urdf` → `arm.physid.toml`). `None` (with a warning saying why) when
/// the sidecar has no `[information]` table, names parameters the model does not have, or was
/// written for other parameter values than the description's; an error naming the file and
/// field when the table is malformed.
pub fn for_description(
    robot: &str,
    model: &Model,
) -> Result<(Option<DMatrix<f64>>, Vec<Notice>), ApiError> {
    let Some(path) = sidecar_of(robot) else {
        return Ok((None, vec![]));
    };
    let text = crate::io::read_to_string(&path)?;
    #[derive(Deserialize)]
    struct Doc {
        information: Option<toml::Value>,
    }
    let bad = |m: String| ApiError::from(IoError::invalid(&path, m));
    let doc: Doc = toml::from_str(&text).map_err(|e| bad(e.to_string().trim_end().into()))?;
    let Some(value) = doc.information else {
        return Ok((None, vec![]));
    };
    let table: Table = value
        .try_into()
        .map_err(|e: toml::de::Error| bad(format!("[information]: {}", e.message())))?;
    check(&table).map_err(|m| bad(format!("[information]: {m}")))?;
    let shown = path.display();
    match onto(&table, model) {
        Ok(matrix) => Ok((
            Some(matrix),
            vec![Notice::note(format!(
                "{shown}: the description's uncertainty from its identification's information matrix ({} samples, residual RMS {:.3} N m)",
                table.samples, table.residual_rms
            ))],
        )),
        Err(why) => Ok((
            None,
            vec![Notice::warning(format!(
                "{shown}: [information] not used: {why}"
            ))],
        )),
    }
}

/// The sidecar of a `--robot` argument: a TOML file itself, or the one beside a URDF.
fn sidecar_of(robot: &str) -> Option<PathBuf> {
    let path = Path::new(robot);
    match path.extension().and_then(|e| e.to_str()) {
        Some("toml") => Some(path.to_path_buf()),
        Some("urdf") => Some(crate::io::sidecar_path(path)).filter(|p| p.is_file()),
        _ => None,
    }
}

/// The table's own consistency: sizes, finite numbers, a symmetric matrix with a non-negative
/// diagonal, distinct names.
fn check(t: &Table) -> Result<(), String> {
    let p = t.parameters.len();
    if t.at.len() != p {
        return Err(format!("at has {} values for {p} parameters", t.at.len()));
    }
    if t.matrix.len() != p {
        return Err(format!(
            "matrix has {} rows for {p} parameters",
            t.matrix.len()
        ));
    }
    if let Some((i, row)) = t.matrix.iter().enumerate().find(|(_, r)| r.len() != p) {
        return Err(format!(
            "matrix row {i} has {} entries, expected {p}",
            row.len()
        ));
    }
    if let Some(i) = t.at.iter().position(|x| !x.is_finite()) {
        return Err(format!("at[{i}] is not finite"));
    }
    for (i, row) in t.matrix.iter().enumerate() {
        if let Some(j) = row.iter().position(|x| !x.is_finite()) {
            return Err(format!("matrix[{i}][{j}] is not finite"));
        }
        if row[i] < 0.0 {
            return Err(format!("matrix[{i}][{i}] = {} is negative", row[i]));
        }
    }
    let scale = (0..p).map(|i| t.matrix[i][i]).fold(0.0, f64::max);
    for i in 0..p {
        for j in 0..i {
            if (t.matrix[i][j] - t.matrix[j][i]).abs() > 1e-9 * scale {
                return Err(format!(
                    "matrix is not symmetric: [{i}][{j}] = {} but [{j}][{i}] = {}",
                    t.matrix[i][j], t.matrix[j][i]
                ));
            }
        }
    }
    let mut seen = std::collections::HashSet::new();
    if let Some(dup) = t.parameters.iter().find(|n| !seen.insert(n.as_str())) {
        return Err(format!("parameter {dup:?} named twice"));
    }
    if !(t.correlation_samples.is_finite() && t.correlation_samples >= 1.0) {
        return Err(format!(
            "correlation_samples = {} must be at least 1",
            t.correlation_samples
        ));
    }
    if !(t.residual_rms.is_finite() && t.residual_rms > 0.0) {
        return Err(format!(
            "residual_rms = {} must be positive",
            t.residual_rms
        ));
    }
    Ok(())
}

/// The table's matrix on `model`'s parameters, or why it does not describe this model.
fn onto(t: &Table, model: &Model) -> Result<DMatrix<f64>, String> {
    let names = model.parameter_names();
    let values = model.parameters();
    let mut col = Vec::with_capacity(t.parameters.len());
    for (k, name) in t.parameters.iter().enumerate() {
        let Some(c) = names.iter().position(|n| n == name) else {
            return Err(format!(
                "it names {name:?}, which the robot as loaded does not have (rotors or joints changed since it was identified?)"
            ));
        };
        let (a, b) = (t.at[k], values[c]);
        if (a - b).abs() > SAME_PARAMETER * a.abs().max(b.abs()).max(1e-3) {
            return Err(format!(
                "it was computed at {name} = {a:e}, the description has {b:e}: the description was changed after it was identified"
            ));
        }
        col.push(c);
    }
    let mut m = DMatrix::zeros(names.len(), names.len());
    for (i, &ci) in col.iter().enumerate() {
        for (j, &cj) in col.iter().enumerate() {
            m[(ci, cj)] = t.matrix[i][j];
        }
    }
    Ok(m)
}

/// Gives `opts` the information of the description `robot`'s sidecar ([`for_description`]):
/// its prior then holds what the description's own data determined, plus
/// [`STATED_WITH_INFORMATION`] when no relative uncertainty was stated (which turns the ladder
/// from the description on). Baseline runs, when given, replace it with their own. Returns the
/// notes and warnings to show.
pub fn apply(
    robot: &str,
    model: &Model,
    opts: &mut crate::diagnose::Options,
) -> Result<Vec<Notice>, ApiError> {
    let (information, mut notices) = for_description(robot, model)?;
    if let Some(info) = information {
        opts.description_information = Some(info);
        if opts.description_uncertainty.is_none() {
            opts.description_uncertainty = Some(STATED_WITH_INFORMATION);
            notices.push(Notice::note(format!(
                "description uncertainty: its information matrix plus {} % stated (--description-uncertainty to change)",
                100.0 * STATED_WITH_INFORMATION
            )));
        }
    }
    Ok(notices)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DVector;

    /// A sidecar table for the leg with a symmetric matrix of distinct entries.
    fn leg_table() -> (Model, Information) {
        let model = crate::model::cheetah3::leg();
        let p = model.layout().len;
        let matrix = DMatrix::from_fn(p, p, |i, j| {
            if i == j {
                1e3 + i as f64 / 7.0
            } else {
                1.0 / (1.0 + (i + j) as f64) * 1e-3
            }
        });
        let info = Information {
            names: model.parameter_names(),
            at: model.parameters(),
            matrix,
            samples: 1234,
            residual_rms: 0.1,
            correlation_samples: 3.5,
        };
        (model, info)
    }

    fn read(text: &str, model: &Model) -> Result<(Option<DMatrix<f64>>, Vec<Notice>), String> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("leg.physid.toml");
        std::fs::write(&path, text).unwrap();
        for_description(path.to_str().unwrap(), model).map_err(|e| e.to_string())
    }

    #[test]
    fn the_table_reads_back_bit_for_bit_and_maps_names_onto_the_model() {
        let (model, info) = leg_table();
        let text = sidecar_table(&info);
        let (m, notices) = read(&text, &model).unwrap();
        assert_eq!(m.unwrap(), info.matrix);
        assert!(notices[0].text.contains("1234 samples"), "{}", notices[0]);
        // Listed in another order, the same matrix lands on the same rows.
        let p = info.names.len();
        let order: Vec<usize> = (0..p).rev().collect();
        let reversed = Information {
            names: order.iter().map(|&i| info.names[i].clone()).collect(),
            at: DVector::from_iterator(p, order.iter().map(|&i| info.at[i])),
            matrix: DMatrix::from_fn(p, p, |i, j| info.matrix[(order[i], order[j])]),
            ..info.clone()
        };
        let (m, _) = read(&sidecar_table(&reversed), &model).unwrap();
        assert_eq!(m.unwrap(), info.matrix);
        // Parameters the table does not name carry no information.
        let first = Information {
            names: info.names[..10].to_vec(),
            at: info.at.rows(0, 10).into_owned(),
            matrix: info.matrix.view((0, 0), (10, 10)).into_owned(),
            ..info.clone()
        };
        let m = read(&sidecar_table(&first), &model).unwrap().0.unwrap();
        assert_eq!(m.view((0, 0), (10, 10)), info.matrix.view((0, 0), (10, 10)));
        assert_eq!(m.view((10, 10), (p - 10, p - 10)).abs().max(), 0.0);
    }

    #[test]
    fn a_sidecar_without_the_table_or_a_robot_without_a_sidecar_gives_nothing() {
        let (model, _) = leg_table();
        assert_eq!(
            read("[robot]\nbuiltin = \"cheetah3\"\n", &model).unwrap().0,
            None
        );
        assert_eq!(for_description("cheetah3", &model).unwrap().0, None);
        let dir = tempfile::tempdir().unwrap();
        let urdf = dir.path().join("arm.urdf");
        assert_eq!(
            for_description(urdf.to_str().unwrap(), &model).unwrap().0,
            None
        );
    }

    #[test]
    fn a_malformed_table_is_refused_naming_the_file_and_the_field() {
        let (model, info) = leg_table();
        let text = sidecar_table(&info);
        let first_row = text
            .lines()
            .find(|l| l.starts_with("  ["))
            .unwrap()
            .to_string();
        let cases: Vec<(String, &str)> = vec![
            (
                text.replace("samples = 1234\n", ""),
                "missing field `samples`",
            ),
            (
                text.replace("samples = 1234\n", "samples = 1234\nweight = 2\n"),
                "unknown field `weight`",
            ),
            (
                text.replacen(&first_row, "", 1),
                "matrix has 65 rows for 66 parameters",
            ),
            (
                text.replacen(&first_row, &first_row.replacen("1e3, ", "", 1), 1),
                "matrix row 0 has 65 entries, expected 66",
            ),
            (
                text.replacen("at = [", "at = [1e0, ", 1),
                "at has 67 values for 66 parameters",
            ),
            (
                text.replacen(&first_row, &first_row.replacen("1e3", "nan", 1), 1),
                "matrix[0][0] is not finite",
            ),
            (
                text.replacen(&first_row, &first_row.replacen("1e3", "-1e3", 1), 1),
                "matrix[0][0] = -1000 is negative",
            ),
            (
                text.replacen(&first_row, &first_row.replacen("5e-4", "6e-4", 1), 1),
                "matrix is not symmetric: [1][0]",
            ),
            (
                text.replace("residual_rms = 1e-1", "residual_rms = 0e0"),
                "residual_rms = 0 must be positive",
            ),
            (
                text.replace("correlation_samples = 3.5e0", "correlation_samples = 5e-1"),
                "correlation_samples = 0.5 must be at least 1",
            ),
            (
                text.replacen("\"thigh.hx\"", "\"thigh.m\"", 1),
                "parameter \"thigh.m\" named twice",
            ),
            (
                text.replace("[information]", "[information]\n[information]"),
                "leg.physid.toml",
            ),
        ];
        for (bad, expected) in cases {
            let err = read(&bad, &model).expect_err(expected);
            assert!(err.contains("leg.physid.toml"), "{err}");
            assert!(err.contains(expected), "expected {expected:?} in {err}");
        }
    }

    #[test]
    fn information_of_another_model_or_other_values_is_not_used_and_says_why() {
        let (model, info) = leg_table();
        let text = sidecar_table(&info);
        let renamed = text.replacen("\"thigh.m\"", "\"femur.m\"", 1);
        let (m, notices) = read(&renamed, &model).unwrap();
        assert_eq!(m, None);
        assert!(
            notices[0].warning
                && notices[0]
                    .text
                    .contains("\"femur.m\", which the robot as loaded does not have"),
            "{}",
            notices[0]
        );
        let mut moved = info.clone();
        let c = info.names.iter().position(|n| n == "thigh.m").unwrap();
        moved.at[c] *= 1.01;
        let (m, notices) = read(&sidecar_table(&moved), &model).unwrap();
        assert_eq!(m, None);
        assert!(
            notices[0].warning && notices[0].text.contains("thigh.m"),
            "{}",
            notices[0]
        );
        assert!(
            notices[0].text.contains("changed after it was identified"),
            "{}",
            notices[0]
        );
    }

    #[test]
    fn apply_states_five_percent_only_when_nothing_was_stated() {
        let (model, info) = leg_table();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("leg.physid.toml");
        std::fs::write(&path, sidecar_table(&info)).unwrap();
        let arg = path.to_str().unwrap();
        let mut opts = crate::diagnose::Options::default();
        let notices = apply(arg, &model, &mut opts).unwrap();
        assert_eq!(opts.description_uncertainty, Some(STATED_WITH_INFORMATION));
        assert_eq!(opts.description_information.as_ref(), Some(&info.matrix));
        assert_eq!(notices.len(), 2);
        let mut opts = crate::diagnose::Options {
            description_uncertainty: Some(0.2),
            ..Default::default()
        };
        assert_eq!(apply(arg, &model, &mut opts).unwrap().len(), 1);
        assert_eq!(opts.description_uncertainty, Some(0.2));
    }
}
