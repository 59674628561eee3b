//! The CSV format of a floating-base robot's log (docs/floating-base.md, "Logs"): the joint
//! columns of [`crate::samples`] (`t`, `q_<joint>`, optional `dq_<joint>`, `tau_<joint>`) and
//!
//! - the trunk's pose in the world: `base_x, base_y, base_z` (m) and the unit quaternion
//!   `base_qw, base_qx, base_qy, base_qz` of its orientation (trunk axes in world coordinates);
//! - the trunk's twist in trunk coordinates, as an IMU's gyro and a state estimator give it:
//!   `base_wx, base_wy, base_wz` (rad/s) and `base_vx, base_vy, base_vz` (m/s, the velocity of
//!   the trunk frame's origin);
//! - per foot, optionally, the ground's force on it in world coordinates
//!   `force_<foot>_x, _y, _z` (N) and whether it is in contact, `contact_<foot>` (0 or 1).
//!
//! Every value is checked on reading, naming the file, the line and the column.

use super::IoError;
use crate::prepare::Logged;
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use physid_core::spatial::Motion;
use std::path::Path;

/// How far a quaternion's norm may stray from 1 before the line is refused.
pub const QUATERNION_NORM_TOLERANCE: f64 = 0.01;

/// A floating-base log as written: the joints' samples and, per sample, the trunk's pose and
/// twist and the feet's forces and contacts.
#[derive(Clone, Debug, PartialEq)]
pub struct FloatingLog {
    /// The joints' time stamps, positions, velocities (if logged) and torques.
    pub joints: Logged,
    /// The trunk's orientation per sample (its axes in world coordinates).
    pub rotation: Vec<Matrix3<f64>>,
    /// The trunk origin's position per sample (world, m).
    pub position: Vec<Vector3<f64>>,
    /// The trunk's twist `[ω; v]` per sample, trunk coordinates (rad/s, m/s).
    pub twist: Vec<Motion>,
    /// Foot names, in the order of `force` and `contact`.
    pub feet: Vec<String>,
    /// The ground's force on each foot, `feet.len()` per sample (world, N), if logged.
    pub force: Option<Vec<Vector3<f64>>>,
    /// Each foot's contact state, `feet.len()` per sample, if logged.
    pub contact: Option<Vec<bool>>,
    /// The IMU's accelerometer at the trunk frame's origin, if logged: the specific force
    /// `Rᵀ (p̈ − g)` per sample, trunk coordinates (m/s²; `+9.81` up at rest).
    pub accel: Option<Vec<Vector3<f64>>>,
}

impl FloatingLog {
    /// Samples.
    pub fn len(&self) -> usize {
        self.joints.len()
    }

    /// No samples.
    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }
}

/// The trunk's column names, in order.
const BASE: [&str; 13] = [
    "base_x", "base_y", "base_z", "base_qw", "base_qx", "base_qy", "base_qz", "base_wx", "base_wy",
    "base_wz", "base_vx", "base_vy", "base_vz",
];

/// The accelerometer's column names, in order (optional, all three or none).
const ACCEL: [&str; 3] = ["base_ax", "base_ay", "base_az"];

/// Shortest text that reads back as the same `f64`.
fn num(x: f64) -> String {
    format!("{x:?}")
}

/// CSV text of `log` (full precision).
pub fn to_csv(log: &FloatingLog) -> String {
    let j = &log.joints;
    let mut header = vec!["t".to_string()];
    let mut groups = vec![("q", Some(&j.q))];
    groups.push(("dq", j.qd.as_ref()));
    groups.push(("tau", Some(&j.tau)));
    for (g, v) in &groups {
        if v.is_some() {
            header.extend(j.joint_names.iter().map(|n| format!("{g}_{n}")));
        }
    }
    header.extend(BASE.iter().map(|s| s.to_string()));
    if log.accel.is_some() {
        header.extend(ACCEL.iter().map(|s| s.to_string()));
    }
    for foot in &log.feet {
        if log.force.is_some() {
            header.extend(["x", "y", "z"].map(|c| format!("force_{foot}_{c}")));
        }
        if log.contact.is_some() {
            header.push(format!("contact_{foot}"));
        }
    }
    let mut out = header.join(",");
    out.push('\n');
    for k in 0..log.len() {
        out.push_str(&row(log, &groups, k).join(","));
        out.push('\n');
    }
    out
}

/// The fields of sample `k`.
fn row(log: &FloatingLog, groups: &[(&str, Option<&Vec<f64>>)], k: usize) -> Vec<String> {
    let n = log.joints.dof();
    let mut rec = vec![num(log.joints.t[k])];
    for (_, v) in groups {
        if let Some(v) = v {
            rec.extend(v[k * n..(k + 1) * n].iter().map(|&x| num(x)));
        }
    }
    let q = UnitQuaternion::from_matrix(&log.rotation[k]);
    let (p, w) = (log.position[k], &log.twist[k]);
    let base = [
        p.x, p.y, p.z, q.w, q.i, q.j, q.k, w.ang.x, w.ang.y, w.ang.z, w.lin.x, w.lin.y, w.lin.z,
    ];
    rec.extend(base.iter().map(|&x| num(x)));
    if let Some(accel) = &log.accel {
        rec.extend(accel[k].iter().map(|&x| num(x)));
    }
    let f = log.feet.len();
    for i in 0..f {
        if let Some(force) = &log.force {
            rec.extend(force[k * f + i].iter().map(|&x| num(x)));
        }
        if let Some(contact) = &log.contact {
            rec.push(if contact[k * f + i] { "1" } else { "0" }.into());
        }
    }
    rec
}

/// Writes `log` as CSV at `path`, atomically.
pub fn write_csv(path: &Path, log: &FloatingLog) -> Result<(), IoError> {
    super::write_atomic(path, to_csv(log).as_bytes())
}

/// Reads a floating-base log: the joint columns matched to `joints` by name
/// ([`crate::samples::read_csv_logged`]), the trunk's thirteen columns (all required), the
/// accelerometer's three where the file has them (all or none), and per
/// foot of `feet` the force columns and the contact column where the file has them (a foot's
/// three force columns all or none; every foot alike). Errors name the file, the line and the
/// column.
pub fn read_csv(path: &Path, joints: &[String], feet: &[String]) -> Result<FloatingLog, IoError> {
    let (logged, _) = crate::samples::read_csv_logged(path, Some(joints))?;
    let bad = |m: String| IoError::invalid(path, m);
    let mut r = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_path(path)
        .map_err(|e| bad(e.to_string()))?;
    let header: Vec<String> = r
        .headers()
        .map_err(|e| bad(format!("line 1: {e}")))?
        .iter()
        .map(str::to_string)
        .collect();
    let cols = FloatingColumns::find(&header, feet).map_err(bad)?;
    let mut log = FloatingLog {
        joints: logged,
        rotation: vec![],
        position: vec![],
        twist: vec![],
        feet: feet.to_vec(),
        force: cols.force.as_ref().map(|_| vec![]),
        contact: cols.contact.as_ref().map(|_| vec![]),
        accel: cols.accel.map(|_| vec![]),
    };
    for (k, rec) in r.records().enumerate() {
        let line = k + 2;
        let rec = rec.map_err(|e| bad(format!("line {line}: {e}")))?;
        cols.read(&rec, &header, &mut log)
            .map_err(|m| bad(format!("line {line}, {m}")))?;
    }
    if log.rotation.len() != log.len() {
        return Err(bad(format!(
            "{} samples of the trunk for {} of the joints",
            log.rotation.len(),
            log.len()
        )));
    }
    Ok(log)
}

/// Where the trunk's and the feet's columns are.
struct FloatingColumns {
    base: [usize; 13],
    accel: Option<[usize; 3]>,
    force: Option<Vec<[usize; 3]>>,
    contact: Option<Vec<usize>>,
}

impl FloatingColumns {
    /// The columns of `header`; `Err` names what is missing.
    fn find(header: &[String], feet: &[String]) -> Result<Self, String> {
        let at = |name: &str| header.iter().position(|h| h == name);
        let base = BASE.map(at);
        if let Some(i) = base.iter().position(Option::is_none) {
            return Err(format!(
                "no column '{}': a floating-base log has the trunk's pose and twist ({})",
                BASE[i],
                BASE.join(", ")
            ));
        }
        let force: Vec<[Option<usize>; 3]> = feet
            .iter()
            .map(|f| ["x", "y", "z"].map(|c| at(&format!("force_{f}_{c}"))))
            .collect();
        let contact: Vec<Option<usize>> =
            feet.iter().map(|f| at(&format!("contact_{f}"))).collect();
        let accel = ACCEL.map(at);
        if !(accel.complete() || accel.absent()) {
            let missing = accel
                .iter()
                .position(Option::is_none)
                .expect("not complete");
            return Err(format!(
                "no column '{}': an accelerometer has three columns ({})",
                ACCEL[missing],
                ACCEL.join(", ")
            ));
        }
        let accel = accel
            .complete()
            .then(|| accel.map(|c| c.expect("complete")));
        Ok(Self {
            base: base.map(|b| b.expect("checked")),
            accel,
            force: all_or_none(&force, feet, "force_{foot}_x, _y and _z")?
                .map(|v| v.into_iter().map(|c| c.map(|i| i.expect("all"))).collect()),
            contact: all_or_none(&contact, feet, "contact_{foot}")?
                .map(|v| v.into_iter().map(|c| c.expect("all")).collect()),
        })
    }

    /// Reads one record into `log`; `Err` names the column at fault.
    fn read(
        &self,
        rec: &csv::StringRecord,
        header: &[String],
        log: &mut FloatingLog,
    ) -> Result<(), String> {
        let value = |col: usize| -> Result<f64, String> {
            let text = rec.get(col).unwrap_or("");
            match text.parse::<f64>() {
                Ok(v) if v.is_finite() && v.abs() <= 1e6 => Ok(v),
                Ok(v) => Err(format!(
                    "column '{}': {v} is not a finite value",
                    header[col]
                )),
                Err(_) => Err(format!(
                    "column '{}': '{text}' is not a number",
                    header[col]
                )),
            }
        };
        let b: Vec<f64> = self
            .base
            .iter()
            .map(|&c| value(c))
            .collect::<Result<_, _>>()?;
        let quat = nalgebra::Quaternion::new(b[3], b[4], b[5], b[6]);
        if (quat.norm() - 1.0).abs() > QUATERNION_NORM_TOLERANCE {
            return Err(format!(
                "columns 'base_qw'..'base_qz': the quaternion's norm is {:.4}, not 1 (a unit quaternion w, x, y, z)",
                quat.norm()
            ));
        }
        let rot = UnitQuaternion::from_quaternion(quat).to_rotation_matrix();
        log.rotation.push(rot.into_inner());
        log.position.push(Vector3::new(b[0], b[1], b[2]));
        log.twist.push(Motion::new(
            Vector3::new(b[7], b[8], b[9]),
            Vector3::new(b[10], b[11], b[12]),
        ));
        if let (Some(c), Some(out)) = (&self.accel, log.accel.as_mut()) {
            out.push(Vector3::new(value(c[0])?, value(c[1])?, value(c[2])?));
        }
        if let (Some(cols), Some(out)) = (&self.force, log.force.as_mut()) {
            for c in cols {
                out.push(Vector3::new(value(c[0])?, value(c[1])?, value(c[2])?));
            }
        }
        if let (Some(cols), Some(out)) = (&self.contact, log.contact.as_mut()) {
            for &c in cols {
                out.push(match value(c)? {
                    0.0 => false,
                    1.0 => true,
                    v => return Err(format!("column '{}': {v} is not 0 or 1", header[c])),
                });
            }
        }
        Ok(())
    }
}

/// `Some` of every foot's columns when every foot has them, `None` when none has; `Err` names
/// the first foot that lacks what another has (`what` describes the columns).
fn all_or_none<T: Clone + Complete>(
    found: &[T],
    feet: &[String],
    what: &str,
) -> Result<Option<Vec<T>>, String> {
    let complete: Vec<bool> = found.iter().map(Complete::complete).collect();
    let absent: Vec<bool> = found.iter().map(Complete::absent).collect();
    if absent.iter().all(|&a| a) {
        return Ok(None);
    }
    match complete.iter().position(|&c| !c) {
        None => Ok(Some(found.to_vec())),
        Some(i) => Err(format!(
            "foot '{}' lacks some of its columns {what} that other feet have",
            feet[i]
        )),
    }
}

/// Whether a foot's columns are all there, or none.
trait Complete {
    fn complete(&self) -> bool;
    fn absent(&self) -> bool;
}

impl Complete for Option<usize> {
    fn complete(&self) -> bool {
        self.is_some()
    }
    fn absent(&self) -> bool {
        self.is_none()
    }
}

impl Complete for [Option<usize>; 3] {
    fn complete(&self) -> bool {
        self.iter().all(Option::is_some)
    }
    fn absent(&self) -> bool {
        self.iter().all(Option::is_none)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A two-joint, two-foot log of `m` samples with everything logged.
    fn log(m: usize) -> FloatingLog {
        let t: Vec<f64> = (0..m).map(|k| 0.001 * k as f64).collect();
        let rot = |k: usize| {
            physid_core::spatial::rot_axis_angle(&Vector3::new(0.6, 0.0, 0.8), 0.1 * k as f64)
        };
        FloatingLog {
            joints: Logged {
                joint_names: vec!["a".into(), "b".into()],
                t: t.clone(),
                q: t.iter().flat_map(|&x| [x.sin(), 0.3 - x]).collect(),
                qd: None,
                qdd: None,
                tau: t.iter().flat_map(|&x| [1.0 + x, -2.5 * x]).collect(),
            },
            rotation: (0..m).map(rot).collect(),
            position: t.iter().map(|&x| Vector3::new(x, -x, 0.45)).collect(),
            twist: t
                .iter()
                .map(|&x| Motion::new(Vector3::new(x, 0.1, -0.2), Vector3::new(0.0, x, 1e-3)))
                .collect(),
            feet: vec!["left".into(), "right".into()],
            force: Some(
                (0..2 * m)
                    .map(|i| Vector3::new(0.1 * i as f64, -1.0, 200.0 - i as f64))
                    .collect(),
            ),
            contact: Some((0..2 * m).map(|i| i % 3 != 0).collect()),
            accel: Some(
                t.iter()
                    .map(|&x| Vector3::new(0.2 * x, -0.1, 9.81 + x))
                    .collect(),
            ),
        }
    }

    fn written(text: &str) -> (tempfile::TempDir, std::path::PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("log.csv");
        std::fs::write(&path, text).unwrap();
        (dir, path)
    }

    fn read(text: &str) -> Result<FloatingLog, String> {
        let (_dir, path) = written(text);
        let feet = ["left".to_string(), "right".to_string()];
        read_csv(&path, &["a".into(), "b".into()], &feet).map_err(|e| e.to_string())
    }

    #[test]
    fn a_log_reads_back_as_written() {
        let want = log(7);
        let got = read(&to_csv(&want)).unwrap();
        assert_eq!(got.joints, want.joints);
        assert_eq!((&got.position, &got.twist), (&want.position, &want.twist));
        assert_eq!((&got.force, &got.contact), (&want.force, &want.contact));
        assert_eq!(got.accel, want.accel);
        for (a, b) in got.rotation.iter().zip(&want.rotation) {
            assert!((a - b).abs().max() < 1e-15, "{a} {b}");
        }
        // Without the feet's columns, neither forces nor contacts; without the accelerometer's,
        // no accelerometer.
        let bare = FloatingLog {
            force: None,
            contact: None,
            accel: None,
            ..want
        };
        let got = read(&to_csv(&bare)).unwrap();
        assert_eq!((got.force, got.contact, got.accel), (None, None, None));
    }

    #[test]
    fn a_bad_log_is_refused_naming_the_line_and_the_column() {
        let text = to_csv(&log(4));
        let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
        let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
        let with = |line: usize, name: &str, value: &str| -> String {
            let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
            let mut fields: Vec<String> = lines[line - 1].split(',').map(str::to_string).collect();
            fields[col(name)] = value.into();
            lines[line - 1] = fields.join(",");
            lines.join("\n") + "\n"
        };
        let cases = [
            (
                with(3, "base_vy", "NaN"),
                "line 3, column 'base_vy': NaN is not a finite value",
            ),
            (
                with(2, "base_qw", "3"),
                "line 2, columns 'base_qw'..'base_qz': the quaternion's norm",
            ),
            (
                with(4, "contact_right", "2"),
                "line 4, column 'contact_right': 2 is not 0 or 1",
            ),
            (
                with(5, "force_left_z", "x"),
                "line 5, column 'force_left_z': 'x' is not a number",
            ),
            (with(1, "base_wz", "omega_z"), "no column 'base_wz'"),
            (
                with(1, "base_ay", "acc_y"),
                "no column 'base_ay': an accelerometer has three columns",
            ),
            (
                with(3, "base_az", "inf"),
                "line 3, column 'base_az': inf is not a finite value",
            ),
            (
                with(1, "force_right_y", "f"),
                "foot 'right' lacks some of its columns force_{foot}_x, _y and _z",
            ),
        ];
        for (text, said) in cases {
            let err = read(&text).unwrap_err();
            assert!(
                err.contains(said) && err.contains("log.csv"),
                "{said}: {err}"
            );
        }
    }
}
