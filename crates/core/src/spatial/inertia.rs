//! Inertial parameters of one rigid body and their physical-consistency conditions
//! (Wensing, Kim & Slotine, RA-L 2018, §II–V).
//!
//! `π = [m, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz]`: mass (kg), first mass moment `h = m c`
//! (kg m, `c` the CoM in the body frame), rotational inertia `Ī` about the **body frame origin**
//! (kg m²), all in the body frame.

use super::{skew, Ellipsoid, Force, Motion, Transform};
use nalgebra::{Matrix3, Matrix4, Matrix6, SVector, SymmetricEigen, Vector3};

/// The ten inertial parameters of one body, in the paper's order (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct InertialParams(pub SVector<f64, 10>);

/// A malformed parameter vector, e.g. from a file.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ParamError {
    /// A non-finite number.
    #[error("parameter {index} ({name}) is not finite: {value}")]
    NotFinite {
        /// Position in the ten-vector.
        index: usize,
        /// Its name in the paper's order.
        name: &'static str,
        /// The value found.
        value: f64,
    },
}

/// Names of the ten parameters in the paper's order.
pub const PARAM_NAMES: [&str; 10] = [
    "m", "hx", "hy", "hz", "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz",
];

/// The spatial inertia in its operational form `(m, h, Ī)`, for the dynamics algorithms.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RigidInertia {
    /// Mass (kg).
    pub m: f64,
    /// First mass moment `m c` (kg m).
    pub h: Vector3<f64>,
    /// Rotational inertia about the frame origin (kg m²).
    pub ibar: Matrix3<f64>,
}

impl RigidInertia {
    /// `I v`: momentum of a body moving with spatial velocity `v` (RBDA eq. 2.63).
    #[inline]
    pub fn mul_motion(&self, v: &Motion) -> Force {
        Force::new(
            self.ibar * v.ang + self.h.cross(&v.lin),
            v.lin * self.m - self.h.cross(&v.ang),
        )
    }
    /// The same inertia in the parent frame A, given `x = B_X_A` and `self` in B coordinates:
    /// `Xᵀ I X` (RBDA eq. 2.66). With `y = Eᵀ h`: `h_A = y + m r` and
    /// `Ī_A = Eᵀ Ī E − S(y) S(r) − S(r) S(y) − m S(r) S(r)`; valid for any mass, including zero.
    /// `S(r) S(y) = (S(y) S(r))ᵀ` (both skew), taken as the transpose: the same products summed
    /// in the same order, so the same numbers.
    pub fn expressed_in_parent(&self, x: &Transform) -> RigidInertia {
        let y = x.e.tr_mul(&self.h);
        let (sy, sr) = (skew(&y), skew(&x.r));
        let sy_sr = sy * sr;
        RigidInertia {
            m: self.m,
            h: y + x.r * self.m,
            ibar: x.e.tr_mul(&self.ibar) * x.e - sy_sr - sy_sr.transpose() - sr * sr * self.m,
        }
    }

    /// The sum of two inertias given in the same frame.
    pub fn add(&self, o: &RigidInertia) -> RigidInertia {
        RigidInertia {
            m: self.m + o.m,
            h: self.h + o.h,
            ibar: self.ibar + o.ibar,
        }
    }
}

/// How well one parameter vector satisfies the nested consistency conditions.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct ConsistencyReport {
    /// Mass (kg).
    pub mass: f64,
    /// Smallest eigenvalue of the 6×6 spatial inertia `I(π)`; `> 0` is semi-consistency.
    pub min_eig_spatial: f64,
    /// Smallest eigenvalue of the 4×4 pseudo-inertia `J(π)`; `> 0` is full consistency.
    pub min_eig_pseudo: f64,
    /// `tr(J Q)` for the bounding ellipsoid (kg); `>= 0` with `J > 0` means the density can
    /// live inside it. `None` without an ellipsoid.
    pub trace_jq: Option<f64>,
    /// `tr(J Q) / m`: one minus the mass-averaged squared normalized radius (dimensionless).
    pub trace_jq_per_mass: Option<f64>,
    /// Smallest eigenvalue of the CoM-in-ellipsoid LMI `C(π)`.
    pub min_eig_com: Option<f64>,
}

impl ConsistencyReport {
    /// `I(π) > 0`.
    pub fn semi_consistent(&self) -> bool {
        self.min_eig_spatial > 0.0
    }
    /// `J(π) > 0`.
    pub fn consistent(&self) -> bool {
        self.min_eig_pseudo > 0.0
    }
    /// `J > 0`, `tr(J Q) >= 0` and `C(π) >= 0` (false without an ellipsoid).
    pub fn in_ellipsoid(&self) -> bool {
        self.consistent()
            && self.trace_jq.is_some_and(|t| t >= 0.0)
            && self.min_eig_com.is_some_and(|c| c >= 0.0)
    }
}

impl InertialParams {
    /// From the ten numbers in the paper's order, rejecting non-finite values.
    pub fn from_slice(p: &[f64; 10]) -> Result<Self, ParamError> {
        for (index, &value) in p.iter().enumerate() {
            if !value.is_finite() {
                return Err(ParamError::NotFinite {
                    index,
                    name: PARAM_NAMES[index],
                    value,
                });
            }
        }
        Ok(Self(SVector::from_column_slice(p)))
    }

    /// From mass (kg), CoM `c` (m) and rotational inertia about the CoM `ic` (kg m²), all in
    /// the body frame. Uses the parallel-axis theorem `Ī = I_C + m S(c) S(c)ᵀ`.
    pub fn from_mass_com_inertia(m: f64, c: &Vector3<f64>, ic: &Matrix3<f64>) -> Self {
        let sc = skew(c);
        Self::from_parts(m, &(c * m), &(ic + m * sc * sc.transpose()))
    }

    /// From `m`, `h` and `Ī` about the origin.
    pub fn from_parts(m: f64, h: &Vector3<f64>, ibar: &Matrix3<f64>) -> Self {
        let i = ibar;
        Self(SVector::from([
            m,
            h.x,
            h.y,
            h.z,
            i[(0, 0)],
            0.5 * (i[(0, 1)] + i[(1, 0)]),
            0.5 * (i[(0, 2)] + i[(2, 0)]),
            i[(1, 1)],
            0.5 * (i[(1, 2)] + i[(2, 1)]),
            i[(2, 2)],
        ]))
    }

    /// The zero body (massless).
    pub fn zero() -> Self {
        Self(SVector::zeros())
    }

    /// Mass (kg).
    pub fn mass(&self) -> f64 {
        self.0[0]
    }
    /// First mass moment `h = m c` (kg m).
    pub fn h(&self) -> Vector3<f64> {
        Vector3::new(self.0[1], self.0[2], self.0[3])
    }
    /// Rotational inertia about the frame origin (kg m²).
    pub fn ibar(&self) -> Matrix3<f64> {
        let p = &self.0;
        Matrix3::new(p[4], p[5], p[6], p[5], p[7], p[8], p[6], p[8], p[9])
    }
    /// Centre of mass (m); `None` for a massless body.
    pub fn com(&self) -> Option<Vector3<f64>> {
        (self.mass() > 0.0).then(|| self.h() / self.mass())
    }
    /// Rotational inertia about the CoM (kg m²); `None` for a massless body.
    pub fn inertia_about_com(&self) -> Option<Matrix3<f64>> {
        let c = self.com()?;
        let sc = skew(&c);
        Some(self.ibar() - self.mass() * sc * sc.transpose())
    }
    /// Principal moments about the CoM (ascending) and the principal axes (columns).
    pub fn principal_moments(&self) -> Option<(Vector3<f64>, Matrix3<f64>)> {
        let eig = SymmetricEigen::new(self.inertia_about_com()?);
        let mut idx = [0usize, 1, 2];
        idx.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
        let vals = Vector3::new(
            eig.eigenvalues[idx[0]],
            eig.eigenvalues[idx[1]],
            eig.eigenvalues[idx[2]],
        );
        let col = |k: usize| -> Vector3<f64> { eig.eigenvectors.column(idx[k]).into_owned() };
        let axes = Matrix3::from_columns(&[col(0), col(1), col(2)]);
        Some((vals, axes))
    }

    /// The operational spatial inertia.
    pub fn rigid(&self) -> RigidInertia {
        RigidInertia {
            m: self.mass(),
            h: self.h(),
            ibar: self.ibar(),
        }
    }

    /// The 6×6 spatial inertia `I(π) = [[Ī, S(h)], [S(h)ᵀ, m 1]]` (paper eq. 3).
    pub fn spatial_matrix(&self) -> Matrix6<f64> {
        let mut i = Matrix6::zeros();
        let sh = skew(&self.h());
        i.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.ibar());
        i.fixed_view_mut::<3, 3>(0, 3).copy_from(&sh);
        i.fixed_view_mut::<3, 3>(3, 0).copy_from(&sh.transpose());
        i.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(Matrix3::identity() * self.mass()));
        i
    }

    /// Second moments `Σ = tr(Ī)/2 · 1 − Ī` (kg m²), the density-weighted `∫ x xᵀ ρ`.
    pub fn second_moments(&self) -> Matrix3<f64> {
        let ibar = self.ibar();
        Matrix3::identity() * (0.5 * ibar.trace()) - ibar
    }

    /// The pseudo-inertia `J(π) = [[Σ, h], [hᵀ, m]]` (paper eq. 13).
    pub fn pseudo_inertia(&self) -> Matrix4<f64> {
        let mut j = Matrix4::zeros();
        let h = self.h();
        j.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&self.second_moments());
        j.fixed_view_mut::<3, 1>(0, 3).copy_from(&h);
        j.fixed_view_mut::<1, 3>(3, 0).copy_from(&h.transpose());
        j[(3, 3)] = self.mass();
        j
    }

    /// The inverse of [`pseudo_inertia`](Self::pseudo_inertia): `Ī = tr(Σ) 1 − Σ`.
    pub fn from_pseudo_inertia(j: &Matrix4<f64>) -> Self {
        let sigma: Matrix3<f64> = j.fixed_view::<3, 3>(0, 0).into();
        let sigma = 0.5 * (sigma + sigma.transpose());
        let h = Vector3::new(
            0.5 * (j[(0, 3)] + j[(3, 0)]),
            0.5 * (j[(1, 3)] + j[(3, 1)]),
            0.5 * (j[(2, 3)] + j[(3, 2)]),
        );
        Self::from_parts(
            j[(3, 3)],
            &h,
            &(Matrix3::identity() * sigma.trace() - sigma),
        )
    }

    /// The same body described in frame B, where `x = B_X_A` and `self` is given in frame A.
    pub fn transformed(&self, x: &Transform) -> Self {
        let m = self.mass();
        if m == 0.0 {
            // A massless body may still carry rotational inertia (a limit of zero mass): rotate.
            let ibar = x.e * self.ibar() * x.e.transpose();
            return Self::from_parts(0.0, &Vector3::zeros(), &ibar);
        }
        let c_b = x.point_to_b(&(self.h() / m));
        let ic_a = self.inertia_about_com().unwrap_or_else(Matrix3::zeros);
        Self::from_mass_com_inertia(m, &c_b, &(x.e * ic_a * x.e.transpose()))
    }

    /// Thicken a (possibly flat) mass distribution: `Σ_C ← Σ_C + m d² 1`, which adds
    /// `2 m d²` to each diagonal moment. `d` (m) is the added rms extent along every axis.
    pub fn thickened(&self, d: f64) -> Self {
        let mut p = *self;
        let add = 2.0 * self.mass() * d * d;
        p.0[4] += add;
        p.0[7] += add;
        p.0[9] += add;
        p
    }

    /// Smallest eigenvalue of `I(π)` (mixed units; the paper's semi-consistency margin).
    pub fn min_eig_spatial(&self) -> f64 {
        SymmetricEigen::new(self.spatial_matrix()).eigenvalues.min()
    }

    /// Smallest eigenvalue of `J(π)` (the paper's full-consistency margin).
    pub fn min_eig_pseudo(&self) -> f64 {
        SymmetricEigen::new(self.pseudo_inertia()).eigenvalues.min()
    }

    /// All consistency margins, with the ellipsoid conditions if one is given.
    pub fn consistency(&self, ellipsoid: Option<&Ellipsoid>) -> ConsistencyReport {
        let trace_jq = ellipsoid.map(|e| (self.pseudo_inertia() * e.q_matrix()).trace());
        ConsistencyReport {
            mass: self.mass(),
            min_eig_spatial: self.min_eig_spatial(),
            min_eig_pseudo: self.min_eig_pseudo(),
            trace_jq,
            trace_jq_per_mass: trace_jq.map(|t| t / self.mass()),
            min_eig_com: ellipsoid.map(|e| {
                SymmetricEigen::new(e.com_lmi(self.mass(), &self.h()))
                    .eigenvalues
                    .min()
            }),
        }
    }

    /// pinocchio's order (`Inertia::toDynamicParameters`):
    /// `[m, hx, hy, hz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]`.
    pub fn to_pinocchio(&self) -> [f64; 10] {
        let p = &self.0;
        [p[0], p[1], p[2], p[3], p[4], p[5], p[7], p[6], p[8], p[9]]
    }
    /// From pinocchio's order.
    pub fn from_pinocchio(v: &[f64; 10]) -> Result<Self, ParamError> {
        Self::from_slice(&[v[0], v[1], v[2], v[3], v[4], v[5], v[7], v[6], v[8], v[9]])
    }
    /// Cheetah-Software's and the authors' MATLAB order:
    /// `[m, hx, hy, hz, Ixx, Iyy, Izz, Iyz, Ixz, Ixy]`.
    pub fn to_cheetah(&self) -> [f64; 10] {
        let p = &self.0;
        [p[0], p[1], p[2], p[3], p[4], p[7], p[9], p[8], p[6], p[5]]
    }
    /// From Cheetah-Software's order.
    pub fn from_cheetah(v: &[f64; 10]) -> Result<Self, ParamError> {
        Self::from_slice(&[v[0], v[1], v[2], v[3], v[4], v[9], v[8], v[5], v[7], v[6]])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spatial::rot_axis_angle;

    /// `S(r) S(y)` is `(S(y) S(r))ᵀ` entry for entry (the transform of an inertia takes it so):
    /// on vectors of mixed signs and magnitudes, including zeros.
    #[test]
    fn the_product_of_two_skew_matrices_reversed_is_its_transpose_exactly() {
        let vs = [
            Vector3::new(0.3, -1.7e-3, 2.2),
            Vector3::new(-0.0, 5.5, -0.125),
            Vector3::new(1e-9, -3.3e4, 0.0),
            Vector3::new(-0.7, 0.11, -0.013),
        ];
        for y in &vs {
            for r in &vs {
                let (sy, sr) = (skew(y), skew(r));
                assert_eq!(sr * sy, (sy * sr).transpose(), "{y} {r}");
            }
        }
    }

    /// Point masses: the exact parameters of a known density.
    fn point_masses(pts: &[(f64, Vector3<f64>)]) -> InertialParams {
        let mut m = 0.0;
        let mut h = Vector3::zeros();
        let mut ibar = Matrix3::zeros();
        for (mi, x) in pts {
            m += mi;
            h += x * *mi;
            let sx = skew(x);
            ibar += *mi * sx * sx.transpose();
        }
        InertialParams::from_parts(m, &h, &ibar)
    }

    fn body() -> InertialParams {
        point_masses(&[
            (0.4, Vector3::new(0.1, 0.02, -0.05)),
            (0.3, Vector3::new(-0.03, 0.08, 0.01)),
            (0.2, Vector3::new(0.0, -0.04, 0.12)),
            (0.5, Vector3::new(0.05, 0.05, 0.05)),
        ])
    }

    #[test]
    fn pseudo_inertia_is_the_density_moment_matrix() {
        // J = Σ m_k [x_k;1][x_k;1]ᵀ for point masses: an independent definition.
        let pts = [
            (0.4, Vector3::new(0.1, 0.02, -0.05)),
            (0.3, Vector3::new(-0.03, 0.08, 0.01)),
        ];
        let mut j = Matrix4::zeros();
        for (m, x) in &pts {
            let v = nalgebra::Vector4::new(x.x, x.y, x.z, 1.0);
            j += *m * v * v.transpose();
        }
        assert!((point_masses(&pts).pseudo_inertia() - j).norm() < 1e-15);
    }

    #[test]
    fn conversions_round_trip() {
        let p = body();
        assert!((InertialParams::from_pseudo_inertia(&p.pseudo_inertia()).0 - p.0).norm() < 1e-15);
        let q = InertialParams::from_mass_com_inertia(
            p.mass(),
            &p.com().unwrap(),
            &p.inertia_about_com().unwrap(),
        );
        assert!((q.0 - p.0).norm() < 1e-15);
        let pin = InertialParams::from_pinocchio(&p.to_pinocchio()).unwrap();
        let che = InertialParams::from_cheetah(&p.to_cheetah()).unwrap();
        assert_eq!(pin, p);
        assert_eq!(che, p);
        // The named positions of the other orders.
        assert_eq!(p.to_pinocchio()[6], p.ibar()[(1, 1)]);
        assert_eq!(p.to_pinocchio()[7], p.ibar()[(0, 2)]);
        assert_eq!(p.to_cheetah()[6], p.ibar()[(2, 2)]);
        assert_eq!(p.to_cheetah()[9], p.ibar()[(0, 1)]);
    }

    #[test]
    fn spatial_matrix_is_momentum_operator() {
        let p = body();
        let v = Motion::new(Vector3::new(0.4, -0.2, 1.0), Vector3::new(0.3, 0.9, -0.5));
        let f = p.rigid().mul_motion(&v);
        assert!((f.to_vec6() - p.spatial_matrix() * v.to_vec6()).norm() < 1e-15);
    }

    #[test]
    fn transform_matches_spatial_congruence() {
        // I_B = X* I_A X⁻¹ = X^{-T} I_A X^{-1}.
        let p = body();
        let x = Transform::from_pose(
            &rot_axis_angle(&Vector3::new(0.2, 1.0, 0.3).normalize(), 0.9),
            &Vector3::new(0.2, -0.1, 0.3),
        );
        let xi = x.to_matrix().try_inverse().unwrap();
        let expect = xi.transpose() * p.spatial_matrix() * xi;
        assert!((p.transformed(&x).spatial_matrix() - expect).norm() < 1e-14);
    }

    #[test]
    fn congruence_to_parent_matches_matrix_form() {
        let p = body();
        let x = Transform::from_pose(
            &rot_axis_angle(&Vector3::new(-0.5, 1.0, 0.3).normalize(), 1.3),
            &Vector3::new(0.3, 0.1, -0.2),
        );
        let xm = x.to_matrix();
        let expect = xm.transpose() * p.spatial_matrix() * xm;
        let got = p.rigid().expressed_in_parent(&x);
        let got = InertialParams::from_parts(got.m, &got.h, &got.ibar).spatial_matrix();
        assert!((got - expect).norm() < 1e-14);
        // And it is the inverse of `transformed`.
        let back = p.transformed(&x.inverse());
        assert!((back.spatial_matrix() - expect).norm() < 1e-14);
    }

    #[test]
    fn consistency_of_real_and_unphysical_bodies() {
        let p = body();
        let r = p.consistency(None);
        assert!(r.semi_consistent() && r.consistent());
        // Violate the triangle inequality (Izz > Ixx + Iyy about the CoM) but keep I(π) > 0:
        // semi-consistent, not consistent. The thin rod about its axis is the limit.
        let bad = InertialParams::from_mass_com_inertia(
            1.0,
            &Vector3::zeros(),
            &Matrix3::from_diagonal(&Vector3::new(0.1, 0.1, 0.3)),
        );
        let rb = bad.consistency(None);
        assert!(rb.semi_consistent(), "{rb:?}");
        assert!(!rb.consistent(), "{rb:?}");
        // Principal moments of that body.
        let (pm, _) = bad.principal_moments().unwrap();
        assert!((pm - Vector3::new(0.1, 0.1, 0.3)).norm() < 1e-14);
    }

    #[test]
    fn thickening_adds_isotropic_covariance() {
        let p = body();
        let d = 0.01;
        let t = p.thickened(d);
        let dj = t.pseudo_inertia() - p.pseudo_inertia();
        let expect = Matrix4::from_diagonal(&nalgebra::Vector4::new(1.0, 1.0, 1.0, 0.0))
            * (p.mass() * d * d);
        assert!((dj - expect).norm() < 1e-15);
    }

    #[test]
    fn non_finite_parameters_are_named() {
        let mut v = [1.0; 10];
        v[7] = f64::NAN;
        let e = InertialParams::from_slice(&v).unwrap_err();
        assert!(e.to_string().contains("Iyy"), "{e}");
    }
}
