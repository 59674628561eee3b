//! The effect library, identification side: each unmodelled effect offered to the
//! identification as extra regressor columns `E_k` next to the rigid-body regressor `Y_k`, so
//! that `τ_k ≈ Y_k θ + E_k c` (equations and units in `docs/diagnose.md`). Linear effects are
//! columns of the data; nonlinear ones are linearized about the nominal model `θ̂₀` (gain, tilt,
//! delay), searched over a one-dimensional grid (Stribeck velocity, cogging harmonic), each
//! grid point a [`Variant`], or both (compliance and backlash: a secant of `θ̂₀`'s prediction at
//! the grid's shift).
//!
//! What each kind's columns are is its row of [`super::kinds`], reading the per-data state of
//! [`super::context`]; this module holds the variants and the loop over samples
//! ([`Context::for_each_row`]).

pub use super::context::Context;
use super::context::{Sample, Scratch};
pub use super::Kind;
use nalgebra::DMatrix;
use physid_core::dynamics::regressor;
use physid_core::trajectory::Trajectory;
use serde::Serialize;

/// Whether a joint moving at `qd` (rad/s) is slower than `min_speed`: its rows are left out of
/// every fit and error of the diagnosis.
pub fn slow(qd: f64, min_speed: f64) -> bool {
    qd.abs() < min_speed
}

/// A consumer of augmented rows: `(sample, Z_k, τ_k)`.
pub type RowSink<'f> = dyn FnMut(usize, &DMatrix<f64>, &[f64]) + 'f;

/// An effect kind at one point of its grid (`param` = Stribeck velocity or cogging harmonic).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct Variant {
    /// The kind.
    pub kind: Kind,
    /// The grid value (0 for kinds without one).
    pub param: f64,
}

/// Every variant of `kinds`.
pub fn variants(kinds: &[Kind], n: usize) -> Vec<Variant> {
    kinds
        .iter()
        .flat_map(|&kind| {
            kind.grid(n)
                .into_iter()
                .map(move |param| Variant { kind, param })
        })
        .collect()
}

impl Context<'_> {
    /// Calls `f(k, Z_k, τ_k)` for every sample `k` in `range` with `Z_k = [Y_k | E_k]`, the
    /// effect columns of `variants` in order after the model's. Rows of joints slower than
    /// `min_speed` (rad/s) are zero in `Z_k` and `τ_k` (friction near zero speed is outside the
    /// model); [`slow`] tells which.
    pub fn for_each_row(
        &self,
        tr: &Trajectory,
        range: std::ops::Range<usize>,
        variants: &[Variant],
        min_speed: f64,
        f: &mut RowSink,
    ) {
        let model = self.model;
        let n = model.dof();
        let p0 = model.layout().len;
        let extra: usize = variants.iter().map(|v| v.kind.columns(n)).sum();
        let mut z = DMatrix::zeros(n, p0 + extra);
        let mut scratch = Scratch::new(self);
        let mut y = DMatrix::zeros(n, p0);
        let mut tau_m = vec![0.0; n];
        for k in range {
            let (q, qd, qdd, tau) = (
                tr.q_at(k),
                tr.qd_at(k),
                tr.qdd_at(k).expect("q̈ present"),
                tr.tau_at(k),
            );
            z.fill(0.0);
            regressor(model, &mut scratch.data, q, qd, qdd, &mut y);
            z.columns_mut(0, p0).copy_from(&y);
            let mut c = p0;
            for v in variants {
                let sample = Sample {
                    k,
                    n,
                    q,
                    qd,
                    qdd,
                    param: v.param,
                };
                (v.kind.spec().fill)(self, &sample, &mut scratch, &mut z, c);
                c += v.kind.columns(n);
            }
            tau_m.copy_from_slice(tau);
            for j in 0..n {
                if slow(qd[j], min_speed) {
                    z.row_mut(j).fill(0.0);
                    tau_m[j] = 0.0;
                }
            }
            f(k, &z, &tau_m);
        }
    }
}

/// The names of `kinds` joined by ", ".
pub fn names(kinds: &[Kind]) -> String {
    kinds.iter().map(Kind::name).collect::<Vec<_>>().join(", ")
}
