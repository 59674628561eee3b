//! Bounding ellipsoids of bodies (paper §V).

use nalgebra::{Matrix3, Matrix4, Vector3};

/// The ellipsoid `S = {x : (x − x_s)ᵀ Q_s⁻¹ (x − x_s) ≤ 1}` in a body frame (m).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Ellipsoid {
    /// Centre `x_s` (m).
    pub center: Vector3<f64>,
    /// Shape `Q_s = R diag(a²) Rᵀ` (m²), with `a` the semi-axes.
    pub qs: Matrix3<f64>,
}

impl Ellipsoid {
    /// An axis-aligned ellipsoid with the given semi-axes (m).
    pub fn axis_aligned(center: Vector3<f64>, semi_axes: Vector3<f64>) -> Self {
        Self {
            center,
            qs: Matrix3::from_diagonal(&semi_axes.component_mul(&semi_axes)),
        }
    }

    /// A sphere of radius `r` (m).
    pub fn sphere(center: Vector3<f64>, r: f64) -> Self {
        Self::axis_aligned(center, Vector3::repeat(r))
    }

    /// The semi-axes (m), ascending, and whether `Q_s` is positive definite.
    pub fn semi_axes(&self) -> Vector3<f64> {
        let mut e = nalgebra::SymmetricEigen::new(self.qs).eigenvalues;
        e.as_mut_slice().sort_by(f64::total_cmp);
        e.map(|x| x.max(0.0).sqrt())
    }

    /// The 4×4 `Q` with `S = {x : [x;1]ᵀ Q [x;1] ≥ 0}`:
    /// `Q = [[−Q_s⁻¹, Q_s⁻¹ x_s], [x_sᵀ Q_s⁻¹, 1 − x_sᵀ Q_s⁻¹ x_s]]`.
    pub fn q_matrix(&self) -> Matrix4<f64> {
        let qi = self
            .qs
            .try_inverse()
            .unwrap_or_else(|| Matrix3::from_diagonal_element(f64::INFINITY));
        let b = qi * self.center;
        let mut q = Matrix4::zeros();
        q.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-qi));
        q.fixed_view_mut::<3, 1>(0, 3).copy_from(&b);
        q.fixed_view_mut::<1, 3>(3, 0).copy_from(&b.transpose());
        q[(3, 3)] = 1.0 - self.center.dot(&b);
        q
    }

    /// The CoM-in-ellipsoid LMI `C(π) = [[m, (h − m x_s)ᵀ], [h − m x_s, m Q_s]]` (paper eq. 22).
    pub fn com_lmi(&self, m: f64, h: &Vector3<f64>) -> Matrix4<f64> {
        let d = h - self.center * m;
        let mut c = Matrix4::zeros();
        c[(0, 0)] = m;
        c.fixed_view_mut::<1, 3>(0, 1).copy_from(&d.transpose());
        c.fixed_view_mut::<3, 1>(1, 0).copy_from(&d);
        c.fixed_view_mut::<3, 3>(1, 1).copy_from(&(self.qs * m));
        c
    }

    /// Whether the point `x` lies in the ellipsoid.
    pub fn contains(&self, x: &Vector3<f64>) -> bool {
        let v = nalgebra::Vector4::new(x.x, x.y, x.z, 1.0);
        (v.transpose() * self.q_matrix() * v)[0] >= 0.0
    }

    /// The axis-aligned ellipsoid around `points` (m, one frame), each semi-axis `margin` (m)
    /// beyond the ellipsoid through the corners of their bounding box (half-extents times
    /// `√d`, `d` the box's non-degenerate dimensions: a segment's ellipsoid reaches its ends).
    pub fn around_points(points: &[Vector3<f64>], margin: f64) -> Self {
        let first = points.first().copied().unwrap_or_else(Vector3::zeros);
        let (lo, hi) = points
            .iter()
            .fold((first, first), |(lo, hi), p| (lo.inf(p), hi.sup(p)));
        let half = (hi - lo) / 2.0;
        let d = half.iter().filter(|&&e| e > 1e-9).count().max(1) as f64;
        Self::axis_aligned((lo + hi) / 2.0, half * d.sqrt() + Vector3::repeat(margin))
    }

    /// The same ellipsoid scaled about its centre by `s` (semi-axes times `s`).
    pub fn scaled(&self, s: f64) -> Self {
        Self {
            center: self.center,
            qs: self.qs * (s * s),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spatial::InertialParams;

    #[test]
    fn q_matrix_describes_the_set() {
        let e =
            Ellipsoid::axis_aligned(Vector3::new(0.0, 0.0, -0.17), Vector3::new(0.05, 0.06, 0.2));
        assert!(e.contains(&Vector3::new(0.0, 0.0, -0.17)));
        assert!(e.contains(&Vector3::new(0.049, 0.0, -0.17)));
        assert!(!e.contains(&Vector3::new(0.051, 0.0, -0.17)));
        assert!(e.contains(&Vector3::new(0.0, 0.0, 0.029)));
        assert!(!e.contains(&Vector3::new(0.0, 0.0, 0.031)));
        assert!((e.semi_axes() - Vector3::new(0.05, 0.06, 0.2)).norm() < 1e-15);
    }

    #[test]
    fn trace_jq_separates_inside_from_outside_mass() {
        let e = Ellipsoid::sphere(Vector3::zeros(), 0.1);
        // Two point masses on the surface: tr(JQ) = 0 exactly, J singular.
        let on = |r: f64| {
            let x = Vector3::new(r, 0.0, 0.0);
            let s = crate::spatial::skew(&x);
            InertialParams::from_parts(2.0, &Vector3::zeros(), &(2.0 * s * s.transpose()))
        };
        let r_in = on(0.09).consistency(Some(&e));
        let r_edge = on(0.1).consistency(Some(&e));
        let r_out = on(0.11).consistency(Some(&e));
        assert!(r_in.trace_jq.unwrap() > 0.0);
        assert!(r_edge.trace_jq.unwrap().abs() < 1e-15);
        assert!(r_out.trace_jq.unwrap() < 0.0);
        // The CoM is at the centre in all three: C(π) alone cannot tell them apart.
        assert!(r_out.min_eig_com.unwrap() >= 0.0);
        // tr(JQ)/m = 1 − r²/R² for mass at radius r.
        assert!((r_in.trace_jq_per_mass.unwrap() - (1.0 - 0.81)).abs() < 1e-12);
    }
}
