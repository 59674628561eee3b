//! A description's own uncertainty carried in its sidecar: `identify --out-urdf` writes the
//! fit's information matrix ([`crate::ident::information`]) as the sidecar's `[information]`
//! table, and `diagnose` reads it back as the prior on the description
//! (`diagnose::Options::description_information`), so a description that is itself an
//! identified model is held as firmly as its data determined it, and no firmer.

use super::data::Notice;
use super::ApiError;
use crate::ident::information::SidecarInformation;
use crate::model::Model;
use nalgebra::DMatrix;
use std::path::{Path, PathBuf};

/// The stated relative uncertainty the ladder adds to a sidecar's information when
/// `--description-uncertainty` is not given (what the data of the identification did not
/// determine is held this loosely).
pub const STATED_WITH_INFORMATION: f64 = 0.05;

/// The information a description's sidecar carries, mapped onto `model`'s parameters (rows of
/// parameters the sidecar does not name are zero: nothing known beyond the stated
/// uncertainty). `robot` is the `--robot` argument: a sidecar itself, or a URDF with its
/// sidecar beside it (`arm.urdf` → `arm.physid.toml`). `None` (with a warning saying why) when
/// the sidecar has no `[information]` table, names parameters the model does not have, or was
/// written for other parameter values than the description's; an error naming the file and
/// field when the table is malformed.
pub fn for_description(robot: &str, model: &Model) -> Result<DescriptionInformation, ApiError> {
    let none = DescriptionInformation {
        matrix: None,
        notices: vec![],
    };
    let Some(path) = sidecar_of(robot) else {
        return Ok(
            missing_sidecar(robot).map_or(none, |w| DescriptionInformation {
                matrix: None,
                notices: vec![w],
            }),
        );
    };
    let Some(table) = SidecarInformation::read(&path)? else {
        return Ok(none);
    };
    let shown = path.display();
    Ok(match table.onto(model) {
        Ok(matrix) => DescriptionInformation {
            matrix: Some(matrix),
            notices: vec![Notice::note(format!(
                "{shown}: the description's uncertainty from its identification's information matrix ({} samples, residual RMS {:.3} N m)",
                table.samples, table.residual_rms
            ))],
        },
        Err(why) => DescriptionInformation {
            matrix: None,
            notices: vec![Notice::warning(format!(
                "{shown}: [information] not used: {why}"
            ))],
        },
    })
}

/// A warning when the URDF `robot` was written by `identify` with its information matrix in a
/// sidecar that is not beside it (copied without it): the diagnosis then holds the description
/// by the stated uncertainty alone, which can read a payload as a gain.
fn missing_sidecar(robot: &str) -> Option<Notice> {
    let path = Path::new(robot);
    if path.extension().and_then(|e| e.to_str()) != Some("urdf") {
        return None;
    }
    let text = std::fs::read_to_string(path).ok()?;
    text.contains(crate::io::SIDECAR_MARK).then(|| {
        Notice::warning(format!(
            "{robot}: written by physid identify with its information matrix in {}, which is not there (copied without it?): the description is held by --description-uncertainty alone; copy the sidecar beside it",
            crate::io::sidecar_path(path).display()
        ))
    })
}

/// What a description's sidecar gives the diagnosis: its information matrix on the model's
/// parameters, if any is usable, and the notes and warnings saying where it came from or why
/// it is not used.
pub struct DescriptionInformation {
    /// The information matrix (model parameters × model parameters), when usable.
    pub matrix: Option<DMatrix<f64>>,
    /// What to show the user.
    pub notices: Vec<Notice>,
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
    let DescriptionInformation {
        matrix,
        mut notices,
    } = for_description(robot, model)?;
    if let Some(info) = matrix {
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
    use crate::ident::information::Information;
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
        for_description(path.to_str().unwrap(), model)
            .map(|d| (d.matrix, d.notices))
            .map_err(|e| e.to_string())
    }

    #[test]
    fn the_table_reads_back_bit_for_bit_and_maps_names_onto_the_model() {
        let (model, info) = leg_table();
        let text = info.sidecar_table();
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
        let (m, _) = read(&reversed.sidecar_table(), &model).unwrap();
        assert_eq!(m.unwrap(), info.matrix);
        // Parameters the table does not name carry no information.
        let first = Information {
            names: info.names[..10].to_vec(),
            at: info.at.rows(0, 10).into_owned(),
            matrix: info.matrix.view((0, 0), (10, 10)).into_owned(),
            ..info.clone()
        };
        let m = read(&first.sidecar_table(), &model).unwrap().0.unwrap();
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
        assert_eq!(for_description("cheetah3", &model).unwrap().matrix, None);
        let dir = tempfile::tempdir().unwrap();
        let urdf = dir.path().join("arm.urdf");
        assert_eq!(
            for_description(urdf.to_str().unwrap(), &model)
                .unwrap()
                .matrix,
            None
        );
    }

    /// Each malformed version of a sidecar's information `text` (its matrix's first row
    /// `first_row`) with what the error must say.
    fn malformed_tables(text: &str, first_row: &str) -> Vec<(String, &'static str)> {
        vec![
            (
                text.replace("samples = 1234\n", ""),
                "missing field `samples`",
            ),
            (
                text.replace("samples = 1234\n", "samples = 1234\nweight = 2\n"),
                "unknown field `weight`",
            ),
            (
                text.replacen(first_row, "", 1),
                "matrix has 65 rows for 66 parameters",
            ),
            (
                text.replacen(first_row, &first_row.replacen("1e3, ", "", 1), 1),
                "matrix row 0 has 65 entries, expected 66",
            ),
            (
                text.replacen("at = [", "at = [1e0, ", 1),
                "at has 67 values for 66 parameters",
            ),
            (
                text.replacen(first_row, &first_row.replacen("1e3", "nan", 1), 1),
                "matrix[0][0] is not finite",
            ),
            (
                text.replacen(first_row, &first_row.replacen("1e3", "-1e3", 1), 1),
                "matrix[0][0] = -1000 is negative",
            ),
            (
                text.replacen(first_row, &first_row.replacen("5e-4", "6e-4", 1), 1),
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
            (
                text.replace("samples = 1234\n", "samples = 0\n"),
                "samples = 0: an information matrix comes from at least one sample",
            ),
        ]
    }

    /// The leg's table with its matrix `m`, as text.
    fn with_matrix(info: &Information, m: DMatrix<f64>) -> String {
        Information {
            matrix: m,
            ..info.clone()
        }
        .sidecar_table()
    }

    #[test]
    fn a_table_no_identification_can_give_is_refused_saying_why() {
        let (model, info) = leg_table();
        let p = info.names.len();
        // Positive diagonal, symmetric, indefinite: [[1000, 1e5], [1e5, 1000]] in one corner.
        let mut indefinite = info.matrix.clone();
        (indefinite[(0, 1)], indefinite[(1, 0)]) = (1e5, 1e5);
        let cases = [
            (with_matrix(&info, indefinite), "not positive semidefinite"),
            (with_matrix(&info, DMatrix::zeros(p, p)), "matrix is zero"),
            (
                with_matrix(&info, &info.matrix * 1e300),
                "beyond any robot's",
            ),
        ];
        for (text, expected) in cases {
            let err = read(&text, &model).expect_err(expected);
            assert!(
                err.contains("leg.physid.toml") && err.contains(expected),
                "{expected}: {err}"
            );
        }
        // The intact table, and one ten times larger (more samples of the same motion), pass.
        assert!(read(&with_matrix(&info, &info.matrix * 10.0), &model).is_ok());
    }

    #[test]
    fn a_malformed_table_is_refused_naming_the_file_and_the_field() {
        let (model, info) = leg_table();
        let text = info.sidecar_table();
        let first_row = text
            .lines()
            .find(|l| l.starts_with("  ["))
            .unwrap()
            .to_string();
        let cases = malformed_tables(&text, &first_row);
        for (bad, expected) in cases {
            let err = read(&bad, &model).expect_err(expected);
            assert!(err.contains("leg.physid.toml"), "{err}");
            assert!(err.contains(expected), "expected {expected:?} in {err}");
        }
    }

    #[test]
    fn information_of_another_model_or_other_values_is_not_used_and_says_why() {
        let (model, info) = leg_table();
        let text = info.sidecar_table();
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
        let (m, notices) = read(&moved.sidecar_table(), &model).unwrap();
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
        std::fs::write(&path, info.sidecar_table()).unwrap();
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
