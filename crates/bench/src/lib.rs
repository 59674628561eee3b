//! The diagnosis's benchmarks, scored against what was injected: the simulated blind benchmark
//! ([`blind`]: cases with withheld effects, diagnosed from files only), the semi-real benchmark
//! ([`semireal`]: real runs as the base, a description identified on another run, one change
//! injected per case) and the generalization benchmark ([`generalize`]: the semi-real cases on
//! robots simulated as real robots, some held out of every tuning decision and scored apart).
//! Equations, scores and their reading in docs/diagnose.md.
//!
//! A floor of physid (docs/architecture.md §6) of its own crate, `physid-bench`, standing on
//! the experiment floor for its tables; the `physid` crate re-exports it as `physid::bench`.
#![warn(missing_docs)]

pub mod blind;
pub mod generalize;
pub mod semireal;
