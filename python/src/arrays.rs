//! Array-likes in, numpy arrays out: joint quantities as `(samples, n)`, one sample as `(n,)`.

use crate::errors::*;
use numpy::{IntoPyArray, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;

/// Joint values given as an array-like, read once: sample-major, with their sample count and
/// whether they were one sample (shape `(n,)`, answered with one sample as pinocchio does).
pub(crate) struct Joints {
    pub(crate) values: Vec<f64>,
    pub(crate) samples: usize,
    pub(crate) one: bool,
}

/// An array-like of joint values as [`Joints`]: anything `numpy.asarray` reads as real numbers
/// (numpy arrays of any integer or float dtype, nested lists, pandas and polars frames), of
/// shape `(samples, n)` or one sample `(n,)`.
pub(crate) fn samples(name: &str, a: &Bound<'_, PyAny>, n: usize) -> PyResult<Joints> {
    let (values, shape) = real(name, a)?;
    let (samples, one) = match shape[..] {
        [m] if m == n => (1, true),
        [s, m] if m == n => (s, false),
        _ => {
            return Err(exception(format!(
            "{name} has shape {shape:?}: give (samples, {n}) or ({n},) for the robot's {n} joints"
        )))
        }
    };
    Ok(Joints {
        values,
        samples,
        one,
    })
}

/// An array-like of real numbers (anything `numpy.asarray` reads as integers or floats) read
/// once as float64, in C order, with its shape; other values are a `TypeError` naming `name`.
fn real(name: &str, a: &Bound<'_, PyAny>) -> PyResult<(Vec<f64>, Vec<usize>)> {
    let array = a.py().import("numpy")?.call_method1("asarray", (a,))?;
    let dtype = array.getattr("dtype")?;
    let kind: String = dtype.getattr("kind")?.extract()?;
    if !matches!(kind.as_str(), "i" | "u" | "f") {
        return Err(PyTypeError::new_err(format!(
            "{name}: an array of real numbers is needed, not one of dtype {dtype}"
        )));
    }
    let array: PyReadonlyArrayDyn<'_, f64> =
        array.call_method1("astype", ("float64",))?.extract()?;
    let view = array.as_array();
    Ok((view.iter().copied().collect(), view.shape().to_vec()))
}

/// A table of samples of any number of joints: sample-major values, `(samples, joints)`.
pub(crate) struct Table {
    pub(crate) values: Vec<f64>,
    pub(crate) samples: usize,
    pub(crate) joints: usize,
}

/// An array-like of shape `(samples, joints)` as a [`Table`] (at least one sample and joint).
pub(crate) fn table(name: &str, a: &Bound<'_, PyAny>) -> PyResult<Table> {
    let (values, shape) = real(name, a)?;
    match shape[..] {
        [samples, joints] if samples > 0 && joints > 0 => Ok(Table {
            values,
            samples,
            joints,
        }),
        _ => Err(exception(format!(
            "{name} has shape {shape:?}: give (samples, joints), one row per sample"
        ))),
    }
}

/// A one-dimensional array-like of real numbers.
pub(crate) fn vector(name: &str, a: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    let (values, shape) = real(name, a)?;
    match shape[..] {
        [_] => Ok(values),
        _ => Err(exception(format!(
            "{name} has shape {shape:?}: give one value per sample"
        ))),
    }
}

/// Positions, velocities and accelerations as flat sample-major vectors, q's sample count (the
/// library checks that the others have as many), and whether q was one sample.
pub(crate) struct States {
    pub(crate) q: Vec<f64>,
    pub(crate) qd: Vec<f64>,
    pub(crate) qdd: Vec<f64>,
    pub(crate) samples: usize,
    pub(crate) one: bool,
}

pub(crate) fn states(
    q: &Bound<'_, PyAny>,
    qd: &Bound<'_, PyAny>,
    qdd: &Bound<'_, PyAny>,
    n: usize,
) -> PyResult<States> {
    let q = samples("q", q, n)?;
    Ok(States {
        qd: samples("qd", qd, n)?.values,
        qdd: samples("qdd", qdd, n)?.values,
        samples: q.samples,
        one: q.one,
        q: q.values,
    })
}

/// `values` shaped `(samples, rest…)`, or `(rest…)` for one sample given as one.
pub(crate) fn shaped<'py>(
    py: Python<'py>,
    values: Vec<f64>,
    samples: usize,
    one: bool,
    rest: &[usize],
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let shape: Vec<usize> = if one {
        rest.to_vec()
    } else {
        std::iter::once(samples)
            .chain(rest.iter().copied())
            .collect()
    };
    values.into_pyarray(py).reshape(shape)
}
