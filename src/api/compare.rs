//! Experiment and sweep results compared (`physid compare`): the paired signed-rank test per
//! group, against a baseline folder or between two constraint sets of one result.

pub use crate::experiment::compare::{
    against_baseline, variants, CompareError, CompareOptions, Comparison, GroupResult, Outcome,
};
