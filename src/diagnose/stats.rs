//! Order statistics the diagnosis's steps share (a leaf: it imports nothing of the diagnosis).

/// The median of `v` (values ordered by `f64::total_cmp`, a NaN above every number); 0 for no
/// values.
pub(crate) fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let m = s.len();
    if m == 0 {
        0.0
    } else if m % 2 == 1 {
        s[m / 2]
    } else {
        0.5 * (s[m / 2 - 1] + s[m / 2])
    }
}

/// `v` less its median: per-joint torque gains as the diagnosis reports them (a gain common to
/// every joint is a scale of all inertial parameters, so only the joints' differences are
/// identifiable).
pub(crate) fn relative_to_median(v: &[f64]) -> Vec<f64> {
    let m = median(v);
    v.iter().map(|x| x - m).collect()
}
