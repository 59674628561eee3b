//! The library's entry points per command, the floor the `physid` binary and the Python
//! package stand on: typed options in, a typed report out that is also the command's JSON
//! contract (docs/schemas/), errors as values naming the file, field or option at fault.
//!
//! One module per command: [`identify`] (its options, default constraint set, fit, scores,
//! ground-truth errors, the effects a diagnosis confirmed), [`diagnose`] (a diagnosis, or what
//! changed against baseline runs, and its report), [`simulate`], [`excite`] (a design and its
//! check in simulation), [`experiment`] (a scenario's sample-size experiment), [`sweep`],
//! [`compare`], [`model`] (a robot loaded and described), [`export`], [`dynamics`] (inverse
//! dynamics, mass matrices and regressors over many samples, shapes checked); with the data
//! they read ([`data`]: files or runs held in memory, streamed or loaded, spans of them), the
//! files they read and write ([`files`]), a description's information ([`information`]) and an
//! experiment's provenance ([`provenance`]). The types these take and return are re-exported
//! here, so that a caller (the Python package) needs no lower floor.

pub mod compare;
pub mod data;
pub mod diagnose;
pub mod dynamics;
pub mod excite;
pub mod experiment;
pub mod export;
pub mod files;
pub mod floating;
pub mod identify;
pub mod information;
pub mod model;
pub mod provenance;
pub mod simulate;
pub mod sweep;

use std::path::PathBuf;

// The error types an entry point's error may carry among its causes, and the trait naming an
// invalid option, for bindings that tell kinds of failure apart (the Python package).
pub use crate::ident::IdentError;
pub use crate::io::{IoError, MemoryLog};
pub use crate::options::OptionError;

// The types the entry points take and return, for callers that stand on this floor alone (the
// Python package).
pub use crate::ident::{bodies, ConstraintSet};
pub use crate::io::document;
pub use crate::model::floating::FloatingModel;
pub use crate::model::{Model, RotorModel};
pub use crate::prepare::Logged;
pub use crate::spatial::{openblas_kernels_for_this_cpu, ConsistencyReport, PARAM_NAMES};
pub use crate::trajectory::Trajectory;

/// An error of an entry point, naming what is at fault.
#[derive(Debug, thiserror::Error)]
pub enum ApiError {
    /// A file could not be read.
    #[error(transparent)]
    Io(#[from] crate::io::IoError),
    /// The identification failed (a non-finite problem, the solver).
    #[error(transparent)]
    Ident(#[from] crate::ident::IdentError),
    /// An array given to a batch routine has the wrong shape or a non-finite value.
    #[error(transparent)]
    Shape(#[from] dynamics::ShapeError),
    /// The diagnosis failed or its options are invalid.
    #[error(transparent)]
    Diagnose(#[from] crate::diagnose::DiagnoseError),
    /// The baseline runs could not be diagnosed and calibrated.
    #[error("diagnosing and calibrating the baseline (--baseline-data)")]
    Baseline {
        /// What failed.
        #[source]
        source: crate::diagnose::DiagnoseError,
    },
    /// No excitation can be designed with these settings for this robot.
    #[error(transparent)]
    Design(#[from] crate::sim::design::DesignError),
    /// An option of an entry point out of its range.
    #[error("{option} = {value}: expected {expected}")]
    InvalidOption {
        /// The option.
        option: &'static str,
        /// What it must be.
        expected: &'static str,
        /// The value given.
        value: f64,
    },
    /// A file-system operation on a result folder failed.
    #[error("{action} {}", path.display())]
    Fs {
        /// What was being done ("creating", "reading", "removing").
        action: &'static str,
        /// The file or folder.
        path: PathBuf,
        /// The operating-system error.
        #[source]
        source: std::io::Error,
    },
    /// A sweep cell failed.
    #[error("cell {id}")]
    Cell {
        /// The cell's id.
        id: String,
        /// What failed.
        #[source]
        source: Box<crate::experiment::sweep::SweepError>,
    },
    /// A table could not be built.
    #[error(transparent)]
    Table(#[from] polars::prelude::PolarsError),
    /// A designed scenario is not valid.
    #[error("the designed scenario: {0}")]
    Designed(String),
    /// The designed excitation could not be simulated.
    #[error("simulating the designed excitation")]
    DesignedSimulation {
        /// What failed.
        #[source]
        source: crate::sim::simulate::SimError,
    },
    /// A simulation failed (a scenario value, the integration).
    #[error("simulating {}", path.display())]
    Simulation {
        /// The scenario file.
        path: PathBuf,
        /// What failed.
        #[source]
        source: crate::sim::simulate::SimError,
    },
    /// A model could not be built (parameters of the wrong length).
    #[error(transparent)]
    Model(#[from] crate::model::ModelError),
    /// An option's value is not valid (the message names the option).
    #[error("{0}")]
    Options(String),
    /// Stopped by its caller before the end (Python's Ctrl-C): nothing more was written.
    #[error("cancelled")]
    Cancelled,
    /// A file's content is not what the option needs.
    #[error("{}: {message}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the field.
        message: String,
    },
}

impl ApiError {
    pub(crate) fn invalid_option(option: &'static str, expected: &'static str, value: f64) -> Self {
        ApiError::InvalidOption {
            option,
            expected,
            value,
        }
    }

    pub(crate) fn invalid(path: &std::path::Path, message: impl Into<String>) -> Self {
        ApiError::Invalid {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }
}

impl OptionError for ApiError {
    /// The invalid option of the identification or the diagnosis beneath, if that is the
    /// error.
    fn invalid_option(&self) -> Option<(&'static str, &'static str, f64)> {
        match self {
            ApiError::Ident(e) => e.invalid_option(),
            ApiError::Diagnose(e) => e.invalid_option(),
            ApiError::Design(e) => e.invalid_option(),
            ApiError::InvalidOption {
                option,
                expected,
                value,
            } => Some((option, expected, *value)),
            _ => None,
        }
    }
}
