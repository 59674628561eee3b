//! The paper's matrix inequalities as linear maps of `π`, in Clarabel's PSD-cone layout.
//!
//! `I(π)` (6×6), `J(π)` (4×4) and `C(π)` (4×4) are linear in `π`, so each is `Σ_k π_k M_k` with
//! `M_k = M(e_k)`. Clarabel's `PSDTriangleConeT(n)` takes the upper triangle column by column,
//! off-diagonal entries times √2: `svec(M) = [M00, √2 M01, M11, √2 M02, √2 M12, M22, …]`, so that
//! `svec(A)·svec(B) = tr(A B)`.

use nalgebra::{DMatrix, Dim, Matrix, RawStorage, RawStorageMut, SVector};
use physid_core::spatial::{Ellipsoid, InertialParams};

/// `svec` of a symmetric matrix (any nalgebra storage) in Clarabel's order (see the module
/// docs).
pub fn svec<R: Dim, C: Dim, S: RawStorage<f64, R, C>>(m: &Matrix<f64, R, C, S>) -> Vec<f64> {
    let n = m.nrows();
    let s2 = std::f64::consts::SQRT_2;
    let mut v = Vec::with_capacity(n * (n + 1) / 2);
    for j in 0..n {
        for i in 0..=j {
            v.push(if i == j {
                m[(i, j)]
            } else {
                s2 * 0.5 * (m[(i, j)] + m[(j, i)])
            });
        }
    }
    v
}

/// The inverse of [`svec`].
pub fn smat(v: &[f64], n: usize) -> DMatrix<f64> {
    let mut m = DMatrix::zeros(n, n);
    smat_into(v, &mut m);
    m
}

/// [`smat`] of a 4 × 4 block (a pseudo-inertia's), fixed-size.
pub fn smat4(v: &[f64]) -> nalgebra::Matrix4<f64> {
    let mut m = nalgebra::Matrix4::zeros();
    smat_into(v, &mut m);
    m
}

/// [`smat`] written into a square matrix of any nalgebra storage (a fixed-size one needs no
/// allocation).
pub fn smat_into<R: Dim, C: Dim, S: RawStorageMut<f64, R, C>>(
    v: &[f64],
    m: &mut Matrix<f64, R, C, S>,
) {
    let s2 = std::f64::consts::SQRT_2;
    let mut k = 0;
    for j in 0..m.ncols() {
        for i in 0..=j {
            let x = if i == j { v[k] } else { v[k] / s2 };
            m[(i, j)] = x;
            m[(j, i)] = x;
            k += 1;
        }
    }
}

/// Which matrix inequality.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lmi {
    /// `I(π)`, 6×6 (semi-consistency).
    Spatial,
    /// `J(π)`, 4×4 (full consistency).
    Pseudo,
    /// `C(π)` for an ellipsoid, 4×4 (CoM in the ellipsoid).
    Com(Ellipsoid),
}

impl Lmi {
    /// Matrix size.
    pub fn dim(&self) -> usize {
        match self {
            Lmi::Spatial => 6,
            Lmi::Pseudo | Lmi::Com(_) => 4,
        }
    }

    /// The matrix at `π`.
    pub fn matrix(&self, p: &InertialParams) -> DMatrix<f64> {
        match self {
            Lmi::Spatial => DMatrix::from_column_slice(6, 6, p.spatial_matrix().as_slice()),
            Lmi::Pseudo => DMatrix::from_column_slice(4, 4, p.pseudo_inertia().as_slice()),
            Lmi::Com(e) => DMatrix::from_column_slice(4, 4, e.com_lmi(p.mass(), &p.h()).as_slice()),
        }
    }

    /// `svec(M(e_k))` for the ten unit parameter vectors: column `k` of the linear map.
    pub fn basis(&self) -> Vec<Vec<f64>> {
        (0..10)
            .map(|k| {
                let mut e = SVector::<f64, 10>::zeros();
                e[k] = 1.0;
                svec(&self.matrix(&InertialParams(e)))
            })
            .collect()
    }
}

/// `tr(J(e_k) Q)` for the ten unit vectors: the linear form of `tr(J(π) Q)`.
pub fn trace_jq_form(e: &Ellipsoid) -> [f64; 10] {
    let q = e.q_matrix();
    std::array::from_fn(|k| {
        let mut v = SVector::<f64, 10>::zeros();
        v[k] = 1.0;
        (InertialParams(v).pseudo_inertia() * q).trace()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;
    use physid_core::model::random::random_body;
    use rand::SeedableRng;

    #[test]
    fn svec_and_smat_read_a_fixed_size_matrix_as_a_dynamic_one() {
        let v: Vec<f64> = (0..10).map(|k| 0.3 * k as f64 - 1.1).collect();
        let dynamic = smat(&v, 4);
        let mut fixed = nalgebra::Matrix4::zeros();
        smat_into(&v, &mut fixed);
        assert_eq!(fixed.as_slice(), dynamic.as_slice());
        assert_eq!(svec(&fixed), v);
        assert_eq!(svec(&dynamic), v);
    }

    #[test]
    fn svec_inner_product_is_the_trace_inner_product() {
        let a = DMatrix::from_fn(4, 4, |i, j| {
            (i + 2 * j) as f64 + if i == j { 1.0 } else { 0.0 }
        });
        let a = &a + a.transpose();
        let b = DMatrix::from_fn(4, 4, |i, j| ((i * j) as f64).sin());
        let b = &b + b.transpose();
        let sa = svec(&a);
        let sb = svec(&b);
        let dot: f64 = sa.iter().zip(&sb).map(|(x, y)| x * y).sum();
        assert!((dot - (&a * &b).trace()).abs() < 1e-12);
        assert!((smat(&sa, 4) - &a).norm() < 1e-14);
        // Clarabel's order: (0,0), (0,1), (1,1), (0,2), ...
        assert_eq!(sa[0], a[(0, 0)]);
        assert!((sa[1] - std::f64::consts::SQRT_2 * a[(0, 1)]).abs() < 1e-15);
        assert_eq!(sa[2], a[(1, 1)]);
    }

    #[test]
    fn basis_reconstructs_each_lmi_linearly() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let p = random_body(&mut rng, &Vector3::new(0.1, 0.0, -0.1), 0.1);
        let e = Ellipsoid::axis_aligned(Vector3::new(0.0, 0.0, -0.1), Vector3::new(0.2, 0.2, 0.3));
        for lmi in [Lmi::Spatial, Lmi::Pseudo, Lmi::Com(e)] {
            let basis = lmi.basis();
            let mut v = vec![0.0; basis[0].len()];
            for (k, col) in basis.iter().enumerate() {
                for (a, b) in v.iter_mut().zip(col) {
                    *a += p.0[k] * b;
                }
            }
            assert!(
                (smat(&v, lmi.dim()) - lmi.matrix(&p)).norm() < 1e-14,
                "{lmi:?}"
            );
        }
        let form = trace_jq_form(&e);
        let t: f64 = form.iter().zip(p.0.iter()).map(|(a, b)| a * b).sum();
        assert!((t - p.consistency(Some(&e)).trace_jq.unwrap()).abs() < 1e-14);
    }
}
