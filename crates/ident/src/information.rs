//! The information an identification carries about its parameters: `𝓘 = w YᵀY` with
//! `w = 1/(s² τ_c)`, `s²` the fit's residual mean square (N m)² and `τ_c` the residual's
//! correlation time in samples (its long-run variance over its variance, by batch means). A
//! description identified on data is known as well as those data determined it: `𝓘` is the
//! precision of that estimate, and the diagnosis's prior on the description
//! (`diagnose::Options::description_information`) when it is written into the exported URDF's
//! sidecar.
//!
//! The residual is read one sample at a time ([`ResidualStats::push`]), so a file streamed from
//! disk gives its information in flat memory.

use nalgebra::{DMatrix, DVector};
use physid_core::model::Model;
use physid_io::IoError;
use serde::Deserialize;
use std::fmt::Write;
use std::path::Path;

/// Length of a batch of the batch means (s): long against the correlation of a residual left by
/// friction and filtering, short against a run.
pub const BATCH_SECONDS: f64 = 1.0;

/// Running statistics of a fit's residual `Y θ − τ` (N m), joint by joint: its mean square and
/// its batch means over [`BATCH_SECONDS`] (a batch also ends where the stamps step back or jump
/// past a batch, i.e. at the start of the next run or a gap).
#[derive(Clone, Debug)]
pub struct ResidualStats {
    /// `Σ r²` per joint.
    sum_sq: Vec<f64>,
    /// Residuals counted per joint (non-finite entries, e.g. locked joints, are not).
    count: Vec<usize>,
    /// The open batch's `Σ r` per joint.
    batch_sum: Vec<f64>,
    /// `Σ (Σ_batch r)²` per joint over the closed batches.
    long: Vec<f64>,
    /// Stamp of the open batch's first sample and of the last sample (s).
    batch_start: Option<f64>,
    last_t: f64,
}

impl ResidualStats {
    /// No samples yet, for `n` joints.
    pub fn new(n: usize) -> Self {
        ResidualStats {
            sum_sq: vec![0.0; n],
            count: vec![0; n],
            batch_sum: vec![0.0; n],
            long: vec![0.0; n],
            batch_start: None,
            last_t: f64::NEG_INFINITY,
        }
    }

    /// Adds the residual `r` (N m, one per joint) of the sample stamped `t` (s); entries that
    /// are not finite are left out (a joint whose torque is not fitted).
    pub fn push(&mut self, t: f64, r: &[f64]) {
        let ends = self
            .batch_start
            .is_some_and(|t0| t - t0 >= BATCH_SECONDS || t <= self.last_t);
        if ends {
            self.close_batch();
        }
        if self.batch_start.is_none() {
            self.batch_start = Some(t);
        }
        self.last_t = t;
        for (j, &rj) in r.iter().enumerate().filter(|(_, v)| v.is_finite()) {
            self.sum_sq[j] += rj * rj;
            self.count[j] += 1;
            self.batch_sum[j] += rj;
        }
    }

    fn close_batch(&mut self) {
        for (long, s) in self.long.iter_mut().zip(self.batch_sum.iter_mut()) {
            *long += *s * *s;
            *s = 0.0;
        }
        self.batch_start = None;
    }

    /// Joint-samples counted.
    pub fn joint_samples(&self) -> usize {
        self.count.iter().sum()
    }

    /// `s²`: the residual's mean square over every joint-sample counted ((N m)²; NaN without
    /// any).
    pub fn mean_square(&self) -> f64 {
        self.sum_sq.iter().sum::<f64>() / self.joint_samples() as f64
    }

    /// `τ_c`: `Σ_batches (Σ r)² / Σ r²` pooled over the joints (samples per independent sample,
    /// at least 1; 1 for a residual that is zero).
    pub fn correlation_samples(&self) -> f64 {
        let mut long: f64 = self.long.iter().sum();
        long += self.batch_sum.iter().map(|s| s * s).sum::<f64>();
        let var: f64 = self.sum_sq.iter().sum();
        if var > 0.0 {
            (long / var).max(1.0)
        } else {
            1.0
        }
    }
}

/// An identification's information matrix over the model's parameters.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Information {
    /// The parameters' names (`Model::parameter_names`), one per row and column.
    pub names: Vec<String>,
    /// The parameters it was computed at (the identified values; their units).
    pub at: DVector<f64>,
    /// `𝓘 = YᵀY / (s² τ_c)` (the inverse of the parameters' covariance, in their units).
    pub matrix: DMatrix<f64>,
    /// Samples fitted.
    pub samples: usize,
    /// `s` (N m).
    pub residual_rms: f64,
    /// `τ_c` (samples).
    pub correlation_samples: f64,
}

/// Why an information matrix could not be formed.
#[derive(Clone, Debug, PartialEq, thiserror::Error, serde::Serialize, serde::Deserialize)]
pub enum InformationError {
    /// No residual was counted.
    #[error("no residual to weigh the data by (no samples fitted)")]
    NoSamples,
    /// The fit is exact: the data give no noise level to weigh them by.
    #[error(
        "the fit leaves no residual (RMS {0} N m): the data give no noise level to weigh them by"
    )]
    NoResidual(f64),
    /// Names, values and `YᵀY` of different sizes.
    #[error("{names} names, {at} values and a {rows}×{cols} YᵀY do not match")]
    Shape {
        /// Names given.
        names: usize,
        /// Values given.
        at: usize,
        /// Rows of `YᵀY`.
        rows: usize,
        /// Columns of `YᵀY`.
        cols: usize,
    },
}

impl Information {
    /// `YᵀY / (s² τ_c)` from the fit's normal equations `yty` over `samples` samples, at the
    /// parameters `at` named `names`, with the residual statistics `stats` of the same fit.
    pub fn new(
        names: Vec<String>,
        at: DVector<f64>,
        yty: &DMatrix<f64>,
        samples: usize,
        stats: &ResidualStats,
    ) -> Result<Self, InformationError> {
        let p = names.len();
        if at.len() != p || yty.nrows() != p || yty.ncols() != p {
            return Err(InformationError::Shape {
                names: p,
                at: at.len(),
                rows: yty.nrows(),
                cols: yty.ncols(),
            });
        }
        if stats.joint_samples() == 0 {
            return Err(InformationError::NoSamples);
        }
        let s2 = stats.mean_square();
        if !(s2 > 0.0 && s2.is_finite()) {
            return Err(InformationError::NoResidual(s2.sqrt()));
        }
        let tau_c = stats.correlation_samples();
        Ok(Information {
            names,
            at,
            matrix: yty / (s2 * tau_c),
            samples,
            residual_rms: s2.sqrt(),
            correlation_samples: tau_c,
        })
    }
}

/// Largest relative change of a parameter between the sidecar's `at` and the description read
/// (the URDF's text form of `m`, `c`, `I_c` rounds the last bits of `π`): beyond it the
/// description was edited after it was identified and the information is not its own.
const SAME_PARAMETER: f64 = 1e-6;

impl Information {
    /// The `[information]` table of a sidecar (TOML), numbers in shortest round-trip form.
    pub fn sidecar_table(&self) -> String {
        let mut s = String::from(
            "\n# The identification's information matrix over the parameters below: YᵀY / (s² τ_c)\n# over its training samples (s: residual RMS, τ_c: residual correlation time in\n# samples). physid diagnose reads it as the description's uncertainty (docs/diagnose.md).\n[information]\n",
        );
        let list = |v: &mut dyn Iterator<Item = String>| v.collect::<Vec<String>>().join(", ");
        let _ = writeln!(s, "samples = {}", self.samples);
        let _ = writeln!(s, "residual_rms = {:e}", self.residual_rms);
        let _ = writeln!(s, "correlation_samples = {:e}", self.correlation_samples);
        let names = list(&mut self.names.iter().map(|n| format!("{n:?}")));
        let _ = writeln!(s, "parameters = [{names}]");
        let _ = writeln!(
            s,
            "at = [{}]",
            list(&mut self.at.iter().map(|x| format!("{x:e}")))
        );
        s.push_str("matrix = [\n");
        for row in self.matrix.row_iter() {
            let _ = writeln!(
                s,
                "  [{}],",
                list(&mut row.iter().map(|x| format!("{x:e}")))
            );
        }
        s.push_str("]\n");
        s
    }
}

/// The `[information]` table as a sidecar holds it (read by [`SidecarInformation::read`]).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SidecarInformation {
    /// Samples the identification fitted.
    pub samples: usize,
    /// Its residual RMS (N m).
    pub residual_rms: f64,
    correlation_samples: f64,
    parameters: Vec<String>,
    at: Vec<f64>,
    matrix: Vec<Vec<f64>>,
}

impl SidecarInformation {
    /// The `[information]` table of the sidecar at `path`, checked ([`check`]); `None` when it
    /// has none; an error naming the file and the field when it is malformed.
    pub fn read(path: &Path) -> Result<Option<Self>, IoError> {
        let text = physid_io::read_to_string(path)?;
        #[derive(Deserialize)]
        struct Doc {
            information: Option<toml::Value>,
        }
        let bad = |m: String| IoError::invalid(path, m);
        let doc: Doc = toml::from_str(&text).map_err(|e| bad(e.to_string().trim_end().into()))?;
        let Some(value) = doc.information else {
            return Ok(None);
        };
        let table: SidecarInformation = value
            .try_into()
            .map_err(|e: toml::de::Error| bad(format!("[information]: {}", e.message())))?;
        check(&table).map_err(|m| bad(format!("[information]: {m}")))?;
        Ok(Some(table))
    }

    /// The table's matrix on `model`'s parameters, or why it does not describe this model.
    pub fn onto(&self, model: &Model) -> Result<DMatrix<f64>, String> {
        let names = model.parameter_names();
        let values = model.parameters();
        let mut col = Vec::with_capacity(self.parameters.len());
        for (k, name) in self.parameters.iter().enumerate() {
            let Some(c) = names.iter().position(|n| n == name) else {
                return Err(format!(
                    "it names {name:?}, which the robot as loaded does not have (rotors or joints changed since it was identified?)"
                ));
            };
            let (a, b) = (self.at[k], values[c]);
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
                m[(ci, cj)] = self.matrix[i][j];
            }
        }
        Ok(m)
    }
}

/// The most a regressor column's RMS over an identification's samples can be (N m per unit
/// parameter): accelerations of 10³ rad/s² on a 10 m lever are 10⁴; a table that implies 10⁶
/// was scaled or corrupted after it was written.
const MAX_REGRESSOR_RMS: f64 = 1e6;

/// What the matrix says, checked against what an identification can give (largest diagonal
/// `scale`): information from at least one sample, positive semidefinite (an indefinite matrix
/// gives negative variances, and the ladder then claims payloads the intact table does not),
/// not zero, and of a size samples of a robot can give (`YᵀY = I s² τ_c`).
fn check_content(t: &SidecarInformation, scale: f64) -> Result<(), String> {
    if t.samples == 0 {
        return Err("samples = 0: an information matrix comes from at least one sample".into());
    }
    if scale == 0.0 {
        return Err("matrix is zero: it carries no information (rewrite the sidecar with physid identify --out-urdf, or remove the table)".into());
    }
    let p = t.parameters.len();
    let m = DMatrix::from_fn(p, p, |i, j| t.matrix[i][j] / scale);
    let min = m.symmetric_eigenvalues().min();
    if min < -1e-9 {
        return Err(format!(
            "matrix is not positive semidefinite (smallest eigenvalue {:e}, largest diagonal {scale:e}): an information matrix never is; the table was edited or corrupted",
            min * scale
        ));
    }
    let rms = (scale * t.residual_rms.powi(2) * t.correlation_samples / t.samples as f64).sqrt();
    if rms.is_finite() && rms > MAX_REGRESSOR_RMS {
        return Err(format!(
            "matrix implies a regressor column of RMS {rms:e} over {} samples at residual_rms {:e}, beyond any robot's ({MAX_REGRESSOR_RMS:e}): the table was scaled or corrupted",
            t.samples, t.residual_rms
        ));
    }
    Ok(())
}

/// The table's own consistency: sizes, finite numbers, a symmetric matrix with a non-negative
/// diagonal, distinct names, a content an identification can give ([`check_content`]).
fn check(t: &SidecarInformation) -> Result<(), String> {
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
    check_content(t, scale)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// White noise of unit variance at 100 Hz.
    fn white(seconds: f64, seed: u64) -> Vec<(f64, f64)> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        (0..(seconds * 100.0) as usize)
            .map(|k| {
                let u: f64 = rng.random_range(-1.0..1.0);
                (k as f64 * 0.01, u * 3f64.sqrt())
            })
            .collect()
    }

    #[test]
    fn white_noise_has_a_correlation_time_near_one_and_its_variance_as_mean_square() {
        let mut stats = ResidualStats::new(1);
        for (t, r) in white(400.0, 1) {
            stats.push(t, &[r]);
        }
        assert!(
            (stats.mean_square() - 1.0).abs() < 0.02,
            "{}",
            stats.mean_square()
        );
        // Batch means of 100 samples over 400 batches: τ_c = 1 within a few 1/√400.
        let tc = stats.correlation_samples();
        assert!((tc - 1.0).abs() < 0.15, "{tc}");
    }

    #[test]
    fn a_residual_held_for_ten_samples_counts_ten_times_fewer_samples() {
        // Each white value repeated 10 times: τ_c = 10 (batches of 100 hold 10 whole blocks).
        let mut stats = ResidualStats::new(1);
        for (k, (_, r)) in white(40.0, 2).into_iter().enumerate() {
            for i in 0..10 {
                stats.push((10 * k + i) as f64 * 0.01, &[r]);
            }
        }
        let tc = stats.correlation_samples();
        assert!((tc - 10.0).abs() < 1.5, "{tc}");
    }

    #[test]
    fn a_batch_ends_where_a_run_starts_again_and_locked_joints_are_not_counted() {
        let mut stats = ResidualStats::new(2);
        // Two runs of 0.5 s each, stamps restarting: two batches of +1, −1 residuals, which
        // would cancel within one batch.
        for k in 0..50 {
            stats.push(k as f64 * 0.01, &[1.0, f64::NAN]);
        }
        for k in 0..50 {
            stats.push(k as f64 * 0.01, &[-1.0, f64::NAN]);
        }
        assert_eq!(stats.joint_samples(), 100);
        assert!((stats.correlation_samples() - 50.0).abs() < 1e-12);
        assert!((stats.mean_square() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn the_information_is_yty_over_the_weighted_noise_and_refuses_what_cannot_weigh() {
        let mut stats = ResidualStats::new(1);
        for (t, r) in white(50.0, 3) {
            stats.push(t, &[2.0 * r]);
        }
        let yty = DMatrix::from_row_slice(2, 2, &[4.0, 1.0, 1.0, 3.0]);
        let names = vec!["a.m".to_string(), "a.hx".to_string()];
        let info = Information::new(names.clone(), DVector::zeros(2), &yty, 5000, &stats).unwrap();
        let w = 1.0 / (stats.mean_square() * stats.correlation_samples());
        assert!((info.matrix[(0, 1)] - w).abs() < 1e-15 * w);
        assert!((info.residual_rms - 2.0).abs() < 0.1);
        let err = Information::new(names.clone(), DVector::zeros(3), &yty, 1, &stats);
        assert!(matches!(err, Err(InformationError::Shape { at: 3, .. })));
        let empty = ResidualStats::new(1);
        let err = Information::new(names.clone(), DVector::zeros(2), &yty, 0, &empty);
        assert_eq!(err, Err(InformationError::NoSamples));
        let mut exact = ResidualStats::new(1);
        exact.push(0.0, &[0.0]);
        let err = Information::new(names, DVector::zeros(2), &yty, 1, &exact);
        assert!(matches!(err, Err(InformationError::NoResidual(_))));
    }
}
