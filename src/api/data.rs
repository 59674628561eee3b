//! The data an entry point identifies from: each file's runs in memory, or a large CSV with
//! q̇ and q̈ streamed from disk (memory independent of its length); parts of files as
//! [`Span`]s; torque errors summed over them.

use super::ApiError;
use crate::ident::{analysis, NormalEquations};
use crate::io::{samples, DataOptions, LoadedData};
use crate::model::Model;
use crate::trajectory::Trajectory;
use nalgebra::DVector;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// CSV files above this size with `ddq` columns are streamed when no effect terms are asked
/// for; smaller files are read once into memory.
pub const STREAM_ABOVE_BYTES: u64 = 64 << 20;

/// One file of identification data.
pub enum Data {
    /// Loaded and prepared samples.
    Memory(Box<LoadedData>),
    /// A streamable CSV.
    Csv {
        /// The file.
        path: PathBuf,
        /// The robot's joint names, in its order (the columns read).
        joints: Vec<String>,
        /// Its sample count.
        samples: usize,
    },
}

/// Samples `range` (indices of the file as read) of the file `file` of a data set.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Span {
    /// Index of the file in the data set.
    pub file: usize,
    /// Its samples, `[start, end)`.
    pub range: Range<usize>,
}

impl Data {
    /// Opens `paths` (read together): large CSV files with `dq` and `ddq` columns stream
    /// (unless `in_memory`, or joints are locked), the others are loaded and prepared with one
    /// cutoff ([`crate::io::load_all`]).
    pub fn open_all(
        paths: &[&Path],
        model: &Model,
        read: &DataOptions,
        in_memory: bool,
    ) -> Result<Vec<Data>, ApiError> {
        let mut streamed = vec![];
        for path in paths {
            let large = std::fs::metadata(path).is_ok_and(|m| m.len() > STREAM_ABOVE_BYTES);
            streamed.push(
                !in_memory
                    && large
                    && read.prepare.lock.is_empty()
                    && path.extension().and_then(|e| e.to_str()) == Some("csv")
                    && samples::csv_streamable(path)?,
            );
        }
        let loaded_paths: Vec<&Path> = paths
            .iter()
            .zip(&streamed)
            .filter(|(_, s)| !**s)
            .map(|(p, _)| *p)
            .collect();
        let mut loaded = crate::io::load_all(&loaded_paths, model, read)?.into_iter();
        let joints: Vec<String> = model.bodies.iter().map(|b| b.joint_name.clone()).collect();
        paths
            .iter()
            .zip(streamed)
            .map(|(path, s)| {
                Ok(if s {
                    let samples = samples::stream_csv(path, &joints, 0..0, &mut |_, _| {})?;
                    Data::Csv {
                        path: path.to_path_buf(),
                        joints: joints.clone(),
                        samples,
                    }
                } else {
                    Data::Memory(Box::new(
                        loaded
                            .next()
                            .expect("one loaded file per path not streamed"),
                    ))
                })
            })
            .collect()
    }

    /// Samples in the file as read.
    pub fn len(&self) -> usize {
        match self {
            Data::Memory(d) => d.report.samples_read,
            Data::Csv { samples, .. } => *samples,
        }
    }

    /// Whether the file holds no sample.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The pipeline's report (none for a streamed file).
    pub fn report(&self) -> Option<&crate::prepare::Report> {
        match self {
            Data::Memory(d) => Some(&d.report),
            Data::Csv { .. } => None,
        }
    }

    /// Joints locked by the pipeline (their rows are not fitted).
    pub fn locked(&self, m: &Model) -> Vec<usize> {
        let names = self.report().map_or(&[][..], |r| &r.locked[..]);
        m.bodies
            .iter()
            .enumerate()
            .filter(|(_, b)| names.contains(&b.joint_name))
            .map(|(j, _)| j)
            .collect()
    }

    /// The runs' samples whose index in the file lies in `r` (in memory; none when streamed).
    pub fn pieces(&self, r: &Range<usize>) -> Vec<Trajectory> {
        match self {
            Data::Memory(d) => d
                .runs
                .iter()
                .filter_map(|run| run.within(r))
                .map(|run| run.trajectory)
                .collect(),
            Data::Csv { .. } => vec![],
        }
    }

    /// Samples of `r` that the fit and the scores use.
    pub fn used(&self, r: &Range<usize>) -> usize {
        match self {
            Data::Memory(_) => self.pieces(r).iter().map(Trajectory::len).sum(),
            Data::Csv { .. } => r.len(),
        }
    }

    /// The model's normal equations over the samples `r`, the `excluded` joints' rows left out.
    pub fn normal_equations(
        &self,
        m: &Model,
        r: Range<usize>,
        excluded: &[usize],
    ) -> Result<NormalEquations, ApiError> {
        Ok(match self {
            Data::Memory(_) => {
                let mut ne = NormalEquations::new(m.dof(), m.layout().len)
                    .excluding(excluded)
                    .finish();
                for t in self.pieces(&r) {
                    ne = ne.merged(&NormalEquations::from_trajectory_excluding(
                        m,
                        &t,
                        0..t.len(),
                        excluded,
                    ));
                }
                ne
            }
            Data::Csv { path, joints, .. } => {
                NormalEquations::from_stream(m, |sink| samples::stream_csv(path, joints, r, sink))?
                    .0
            }
        })
    }

    /// The squared torque errors of `theta` over the samples `r`.
    pub fn squared_errors(
        &self,
        m: &Model,
        theta: &DVector<f64>,
        r: Range<usize>,
    ) -> Result<SquaredErrors, ApiError> {
        Ok(match self {
            Data::Memory(_) => {
                let mut acc = SquaredErrors::new(m.dof());
                for t in self.pieces(&r) {
                    let (per, _) = analysis::rms_error(m, theta, &t, 0..t.len());
                    acc = acc + SquaredErrors::from_rms(&per, t.len());
                }
                acc
            }
            Data::Csv { path, joints, .. } => {
                let (per, _) = analysis::rms_error_stream(m, theta, |sink| {
                    samples::stream_csv(path, joints, r.clone(), sink)
                })?;
                SquaredErrors::from_rms(&per, r.len())
            }
        })
    }
}

/// The joints any data file locks (union, in joint order).
pub fn locked_joints(m: &Model, data: &[Data]) -> Vec<usize> {
    let mut out: Vec<usize> = data.iter().flat_map(|d| d.locked(m)).collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// The spans' samples in memory (each file's runs within its range).
pub fn in_memory(data: &[Data], spans: &[Span]) -> Vec<Trajectory> {
    spans
        .iter()
        .flat_map(|s| data[s.file].pieces(&s.range))
        .collect()
}

impl std::ops::Add for SquaredErrors {
    type Output = Self;
    /// Both sums together.
    fn add(mut self, other: SquaredErrors) -> Self {
        for (a, b) in self.sum.iter_mut().zip(&other.sum) {
            *a += b;
        }
        self.samples += other.samples;
        self
    }
}

/// Sums of squared torque errors per joint over several runs (N² m²).
#[derive(Clone, Debug)]
pub struct SquaredErrors {
    sum: Vec<f64>,
    samples: usize,
}

impl SquaredErrors {
    /// Nothing summed yet, for `n` joints.
    pub fn new(n: usize) -> Self {
        Self {
            sum: vec![0.0; n],
            samples: 0,
        }
    }

    /// The sums behind per-joint RMS values `rms` (N m) over `samples` samples.
    pub fn from_rms(rms: &[f64], samples: usize) -> Self {
        Self {
            sum: rms.iter().map(|r| r * r * samples as f64).collect(),
            samples,
        }
    }

    /// Per-joint RMS (N m; `None` for the `locked` joints, whose torque is not fitted) and the
    /// RMS over the other joints.
    pub fn rms(&self, locked: &[usize]) -> (Vec<Option<f64>>, f64) {
        let k = self.samples.max(1) as f64;
        let per = (0..self.sum.len())
            .map(|j| (!locked.contains(&j)).then(|| (self.sum[j] / k).sqrt()))
            .collect();
        let fitted: Vec<f64> = (0..self.sum.len())
            .filter(|j| !locked.contains(j))
            .map(|j| self.sum[j])
            .collect();
        let all = (fitted.iter().sum::<f64>() / (k * fitted.len().max(1) as f64)).sqrt();
        (per, all)
    }
}
