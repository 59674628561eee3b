//! The CSV format of joint data ([`Trajectory`]) of docs/scenario-format.md ("Outputs of `physid simulate`"):
//! a header row, then `t, q1..qn, dq1..dqn, [ddq1..ddqn,] tau1..taun` (s, rad, rad/s, rad/s²,
//! N m). Extra columns are ignored on reading (the KUKA logs carry set-points too). Columns may
//! instead be named by joint, `q_<joint>, dq_<joint>, [ddq_<joint>,] tau_<joint>`, in any order:
//! they are matched to the robot's joints by name.

use super::IoError;
pub use crate::prepare::Logged;
use physid_core::trajectory::SAMPLE_GROUPS;
pub use physid_core::trajectory::{SampleError, SampleRef, SampleSink, Trajectory};
use std::path::Path;

/// Shortest text that reads back as the same `f64`, in exponent form for very small or large
/// magnitudes.
fn num(x: f64) -> String {
    let a = x.abs();
    if a != 0.0 && !(1e-4..1e15).contains(&a) {
        format!("{x:e}")
    } else {
        x.to_string()
    }
}

/// CSV text of a trajectory (full precision, so reading it back gives the same numbers).
pub fn to_csv(tr: &Trajectory) -> String {
    let n = tr.dof();
    let mut w = csv::Writer::from_writer(vec![]);
    let mut header = vec!["t".to_string()];
    let groups: Vec<&str> = if tr.qdd.is_some() {
        vec!["q", "dq", "ddq", "tau"]
    } else {
        vec!["q", "dq", "tau"]
    };
    for g in &groups {
        header.extend((1..=n).map(|j| format!("{g}{j}")));
    }
    w.write_record(&header).expect("writing to memory");
    for k in 0..tr.len() {
        let mut rec = vec![num(tr.t[k])];
        let mut add = |v: &[f64]| rec.extend(v.iter().map(|&x| num(x)));
        add(tr.q_at(k));
        add(tr.qd_at(k));
        if let Some(a) = tr.qdd_at(k) {
            add(a);
        }
        add(tr.tau_at(k));
        w.write_record(&rec).expect("writing to memory");
    }
    String::from_utf8(w.into_inner().expect("in memory")).expect("CSV is UTF-8")
}

/// Writes a reference trajectory (what a controller is to follow) as CSV, atomically: `t`, then
/// `q_<joint>`, `dq_<joint>`, `ddq_<joint>` per joint (s, rad, rad/s, rad/s²), no torques.
pub fn write_reference_csv(path: &Path, tr: &Trajectory) -> Result<(), IoError> {
    let mut w = csv::Writer::from_writer(vec![]);
    let mut header = vec!["t".to_string()];
    for g in ["q", "dq", "ddq"] {
        header.extend(tr.joint_names.iter().map(|j| format!("{g}_{j}")));
    }
    w.write_record(&header).expect("writing to memory");
    for k in 0..tr.len() {
        let mut rec = vec![num(tr.t[k])];
        rec.extend(tr.q_at(k).iter().map(|&x| num(x)));
        rec.extend(tr.qd_at(k).iter().map(|&x| num(x)));
        rec.extend(tr.qdd_at(k).unwrap_or(&[]).iter().map(|&x| num(x)));
        w.write_record(&rec).expect("writing to memory");
    }
    let bytes = w.into_inner().expect("in memory");
    super::write_atomic(path, &bytes)
}

/// Writes a trajectory as CSV, atomically.
pub fn write_csv(path: &Path, tr: &Trajectory) -> Result<(), IoError> {
    super::write_atomic(path, to_csv(tr).as_bytes())
}

/// Column positions of a CSV in the physid format, from its header, in the robot's joint order.
struct Columns {
    header: Vec<String>,
    t: usize,
    q: Vec<usize>,
    /// Velocity columns, if the file has them (else the pipeline derives q̇).
    dq: Option<Vec<usize>>,
    ddq: Option<Vec<usize>>,
    tau: Vec<usize>,
    /// The joints' names: the robot's for named columns (or when given), else `joint1..n`.
    names: Vec<String>,
    /// Joints named in the columns that the robot does not have (left out).
    ignored: Vec<String>,
}

impl Columns {
    /// A log of no samples with these columns' joints (q̇ and q̈ where the file has them).
    fn empty_log(&self) -> Logged {
        Logged {
            joint_names: self.names.clone(),
            t: vec![],
            q: vec![],
            qd: self.dq.is_some().then(Vec::new),
            qdd: self.ddq.is_some().then(Vec::new),
            tau: vec![],
        }
    }

    /// The columns of each group of a streamed sample (q, q̇, q̈, τ): a file without q̇ or q̈
    /// cannot be streamed (they are derived over each run).
    fn sample_groups(&self, path: &Path) -> Result<[Vec<usize>; 4], IoError> {
        let bad = |m: &str| IoError::invalid(path, m);
        let ddq = (self.ddq.clone())
            .ok_or_else(|| bad("no ddq columns: streaming needs accelerations"))?;
        let dq =
            (self.dq.clone()).ok_or_else(|| bad("no dq columns: streaming needs velocities"))?;
        Ok([self.q.clone(), dq, ddq, self.tau.clone()])
    }

    /// Reads the header. Columns are numbered (`q1, q2, …`: the joint count is the number of
    /// `q` columns, taken in the robot's order) or named by joint (`q_<joint>`, `dq_<joint>`,
    /// `ddq_<joint>`, `tau_<joint>`: matched to `robot`'s joints by name, in any order).
    fn parse<R: std::io::Read>(
        r: &mut csv::Reader<R>,
        path: &Path,
        robot: Option<&[String]>,
    ) -> Result<Columns, IoError> {
        let bad = |m: String| IoError::invalid(path, m);
        let header: Vec<String> = r
            .headers()
            .map_err(|e| bad(format!("header: {e}")))?
            .iter()
            .map(str::to_string)
            .collect();
        check_unique(&header, path)?;
        let col = |name: &str| header.iter().position(|h| h == name);
        let t = col("t").ok_or_else(|| bad("missing column t".into()))?;
        let JointKeys {
            keys,
            names,
            ignored,
        } = joint_keys(&header, robot, path)?;
        let need = |g: &str| -> Result<Vec<usize>, IoError> {
            keys.iter()
                .map(|k| {
                    col(&format!("{g}{k}")).ok_or_else(|| {
                        bad(format!("missing column {g}{k} ({} joints)", keys.len()))
                    })
                })
                .collect()
        };
        let (q, tau) = (need("q")?, need("tau")?);
        let optional = |g: &str| -> Result<Option<Vec<usize>>, IoError> {
            if keys.iter().any(|k| col(&format!("{g}{k}")).is_some()) {
                Ok(Some(need(g)?))
            } else {
                Ok(None)
            }
        };
        let (dq, ddq) = (optional("dq")?, optional("ddq")?);
        Ok(Columns {
            t,
            q,
            dq,
            ddq,
            tau,
            header,
            names,
            ignored,
        })
    }
}

/// The joints of a CSV header.
struct JointKeys {
    /// Column suffixes: `_<joint>` for named columns `q_<joint>`, else `1..n` for `q1..qn`.
    keys: Vec<String>,
    /// The joints' names (the robot's when given).
    names: Vec<String>,
    /// Named joints the robot does not have.
    ignored: Vec<String>,
}

/// A header names each column physid reads (`t`, `q…`, `dq…`, `ddq…`, `tau…`) once.
fn check_unique(header: &[String], path: &Path) -> Result<(), IoError> {
    let read = |h: &String| h == "t" || ["q", "dq", "ddq", "tau"].iter().any(|g| h.starts_with(g));
    match super::first_repeat(header, read) {
        Some((j, i)) => Err(IoError::invalid(
            path,
            format!(
                "column {} appears twice (columns {} and {}, counting from 1)",
                header[i],
                j + 1,
                i + 1
            ),
        )),
        None => Ok(()),
    }
}

/// Whether `h` is a numbered position column `qK` with `K > n`.
fn numbered_beyond(h: &str, n: usize) -> bool {
    h.strip_prefix('q')
        .and_then(|k| k.parse::<usize>().ok())
        .is_some_and(|k| k > n)
}

/// The joints of a CSV header, checked against the robot's when given.
fn joint_keys(
    header: &[String],
    robot: Option<&[String]>,
    path: &Path,
) -> Result<JointKeys, IoError> {
    let bad = |m: String| IoError::invalid(path, m);
    let col = |name: &str| header.iter().position(|h| h == name);
    let named: Vec<String> = header
        .iter()
        .filter_map(|h| h.strip_prefix("q_").map(str::to_string))
        .collect();
    if col("q1").is_none() && !named.is_empty() {
        let names = robot.map_or_else(|| named.clone(), <[String]>::to_vec);
        if let Some(missing) = names.iter().find(|j| !named.contains(j)) {
            return Err(bad(format!(
                "no column q_{missing} for the robot's joint '{missing}' (the file names {})",
                named.join(", ")
            )));
        }
        let ignored = named.into_iter().filter(|j| !names.contains(j)).collect();
        let keys: Vec<String> = names.iter().map(|j| format!("_{j}")).collect();
        Ok(JointKeys {
            keys,
            names,
            ignored,
        })
    } else {
        let n = (1..)
            .take_while(|j| col(&format!("q{j}")).is_some())
            .count();
        if let Some(after) = header.iter().find(|h| numbered_beyond(h, n)) {
            return Err(bad(format!(
                "column {after} without q{}: numbered columns run q1..qn without a gap",
                n + 1
            )));
        }
        if n == 0 {
            return Err(bad(
                "no q1 or q_<joint> column: expected a header `t, q1..qn, dq1..dqn, [ddq1..ddqn,] tau1..taun` or columns named q_<joint>, dq_<joint>, …"
                    .into(),
            ));
        }
        if let Some(r) = robot.filter(|r| r.len() != n) {
            return Err(bad(format!(
                "the file has {n} joints (q columns), the robot has {}",
                r.len()
            )));
        }
        let names = robot.map_or_else(
            || (1..=n).map(|j| format!("joint{j}")).collect(),
            <[String]>::to_vec,
        );
        Ok(JointKeys {
            keys: (1..=n).map(|j| j.to_string()).collect(),
            names,
            ignored: vec![],
        })
    }
}

/// Reads a trajectory from CSV, its joints in `robot`'s order when given (named columns matched
/// by name; numbered ones must be as many), else as the file has them (`joint1..n` for numbered
/// columns). The file must have velocity columns and increasing time; logs as robots write them
/// go through [`read_csv_logged`] and the pipeline instead. Errors name the file, the line and
/// the column.
pub fn read_csv(path: &Path, robot: Option<&[String]>) -> Result<Trajectory, IoError> {
    let (logged, _) = read_csv_logged(path, robot)?;
    let bad = |m: String| IoError::invalid(path, m);
    let qd = logged
        .qd
        .ok_or_else(|| bad("no dq columns (velocities)".into()))?;
    let tr = Trajectory {
        joint_names: logged.joint_names,
        t: logged.t,
        q: logged.q,
        qd,
        qdd: logged.qdd,
        tau: logged.tau,
        starts: vec![],
        margins: Default::default(),
    };
    tr.validate().map_err(|e| bad(e.to_string()))?;
    Ok(tr)
}

/// A CSV reader of the file at `path` whose header names are trimmed of spaces; a record's
/// fields are read as bytes and only the columns used are decoded ([`number`]).
fn reader(path: &Path) -> Result<csv::Reader<std::io::BufReader<std::fs::File>>, IoError> {
    let file = std::fs::File::open(path).map_err(|source| IoError::Fs {
        path: path.to_path_buf(),
        source,
    })?;
    Ok(records(std::io::BufReader::with_capacity(1 << 16, file)))
}

/// Field `col` of `rec` as a number, its text trimmed of spaces; the text when it is not one
/// (a field that is not UTF-8 shown with replacement characters).
fn number(rec: &csv::ByteRecord, col: usize) -> Result<f64, String> {
    let bytes = rec.get(col).unwrap_or(b"");
    // A plain decimal number (the common case) parsed straight from its bytes, correctly
    // rounded as `str::parse` does; anything else as before.
    if let Ok(v) = fast_float2::parse::<f64, _>(bytes.trim_ascii()) {
        return Ok(v);
    }
    match std::str::from_utf8(bytes).map(str::trim) {
        Ok(text) => text.parse().map_err(|_| text.to_string()),
        Err(_) => Err(String::from_utf8_lossy(bytes).trim().to_string()),
    }
}

/// Reads a CSV as logged (velocity and acceleration columns optional, time stamps as written),
/// its joints in `robot`'s order when given, and the joints named in the file that the robot
/// lacks. Each value is checked (finite, within range), naming the line and column; the time
/// stamps' order and gaps are the pipeline's ([`crate::prepare`]).
///
/// A large file without quotes is cut at line ends into parts read side by side (the current
/// rayon pool) and joined in order: the same samples as one pass. Where a part fails, the file
/// is read again in one pass, whose message names the line as it stands in the file.
pub fn read_csv_logged(
    path: &Path,
    robot: Option<&[String]>,
) -> Result<(Logged, Vec<String>), IoError> {
    let bytes = std::fs::read(path).map_err(|source| IoError::Fs {
        path: path.to_path_buf(),
        source,
    })?;
    let mut r = records(&bytes[..]);
    let c = Columns::parse(&mut r, path, robot)?;
    let body = &bytes[r.position().byte() as usize..];
    let parts = line_parts(body);
    if parts.len() > 1 {
        use rayon::prelude::*;
        let read: Result<Vec<Logged>, IoError> = (parts.par_iter())
            .map(|part| read_rows(&mut records_without_header(part), &c, path, true))
            .collect();
        if let Ok(read) = read {
            return Ok((joined(&c, read), c.ignored));
        }
    }
    let out = read_rows(&mut r, &c, path, false)?;
    Ok((out, c.ignored))
}

/// Bytes per part of a file read side by side ([`read_csv_logged`]); a smaller file is one part.
const PART_BYTES: usize = 1 << 20;

/// `body` (a CSV's records after its header) cut at line ends into up to one part per thread
/// of at least [`PART_BYTES`]; one part where a quote could hold a line end.
fn line_parts(body: &[u8]) -> Vec<&[u8]> {
    let wanted = rayon::current_num_threads()
        .min(body.len() / PART_BYTES)
        .max(1);
    if wanted == 1 || body.contains(&b'"') {
        return vec![body];
    }
    let mut parts = vec![];
    let mut start = 0;
    for i in 1..wanted {
        let aim = (body.len() * i / wanted).max(start);
        let Some(nl) = body[aim..].iter().position(|&b| b == b'\n') else {
            break;
        };
        parts.push(&body[start..aim + nl + 1]);
        start = aim + nl + 1;
    }
    parts.push(&body[start..]);
    parts
}

/// A CSV reader of a log from `source`: its headers trimmed (values are trimmed by
/// [`number`]), as every reader of logs here.
fn records<R: std::io::Read>(source: R) -> csv::Reader<R> {
    csv::ReaderBuilder::new()
        .trim(csv::Trim::Headers)
        .from_reader(source)
}

/// A CSV reader of records only (a part of a file after its header).
fn records_without_header(bytes: &[u8]) -> csv::Reader<&[u8]> {
    csv::ReaderBuilder::new()
        .has_headers(false)
        .from_reader(bytes)
}

/// The parts' samples joined in order.
fn joined(c: &Columns, parts: Vec<Logged>) -> Logged {
    let mut out = c.empty_log();
    for part in parts {
        out.t.extend(part.t);
        out.q.extend(part.q);
        out.tau.extend(part.tau);
        if let (Some(all), Some(v)) = (out.qd.as_mut(), part.qd) {
            all.extend(v);
        }
        if let (Some(all), Some(v)) = (out.qdd.as_mut(), part.qdd) {
            all.extend(v);
        }
    }
    out
}

/// The samples of the records `r` reads, each value checked (lines numbered from the file's
/// second). `part`: `r` reads a part of the file (its records must have the header's width,
/// and an empty part is no error).
fn read_rows<R: std::io::Read>(
    r: &mut csv::Reader<R>,
    c: &Columns,
    path: &Path,
    part: bool,
) -> Result<Logged, IoError> {
    let bad = |m: String| IoError::invalid(path, m);
    let mut out = c.empty_log();
    let mut rec = csv::ByteRecord::new();
    let mut k = 0usize;
    while r
        .read_byte_record(&mut rec)
        .map_err(|e| bad(format!("line {}: {e}", k + 2)))?
    {
        let line = k + 2;
        if part && rec.len() != c.header.len() {
            return Err(bad(format!("line {line}: not the header's width")));
        }
        let value = |col: usize, group: &str, t: Option<f64>| -> Result<f64, IoError> {
            let v = number(&rec, col).map_err(|s| {
                bad(format!(
                    "line {line}, column '{}': '{s}' is not a number",
                    c.header[col]
                ))
            })?;
            physid_core::trajectory::check_value(k, t.unwrap_or(v), group, &c.header[col], v)
                .map_err(|e| bad(format!("line {line}: {e}")))?;
            Ok(v)
        };
        let t = value(c.t, "t", None)?;
        out.t.push(t);
        for &col in &c.q {
            out.q.push(value(col, "q", Some(t))?);
        }
        if let (Some(cols), Some(v)) = (&c.dq, out.qd.as_mut()) {
            for &col in cols {
                v.push(value(col, "dq", Some(t))?);
            }
        }
        if let (Some(cols), Some(v)) = (&c.ddq, out.qdd.as_mut()) {
            for &col in cols {
                v.push(value(col, "ddq", Some(t))?);
            }
        }
        for &col in &c.tau {
            out.tau.push(value(col, "tau", Some(t))?);
        }
        k += 1;
    }
    if k == 0 && !part {
        return Err(bad("no samples".into()));
    }
    Ok(out)
}

/// Checks sample `k`'s time `t` (s, column `name`): finite, and after the previous `prev`.
fn check_time(k: usize, t: f64, prev: f64, name: &str) -> Result<(), String> {
    physid_core::trajectory::check_value(k, t, "t", name, t)
        .map_err(|e| format!("line {}: {e}", k + 2))?;
    if t <= prev {
        return Err(format!(
            "sample {k}: time {t} s does not increase (previous {prev} s)"
        ));
    }
    Ok(())
}

/// Streams a CSV with `ddq` columns sample by sample without loading it, checking each sample
/// (finite values, increasing time) as it goes; `f(k, sample)` sees samples `range` only, the
/// joints in `robot`'s order.
/// Returns the number of samples in the file. Memory does not grow with the file.
pub fn stream_csv(
    path: &Path,
    robot: &[String],
    range: std::ops::Range<usize>,
    f: &mut SampleSink,
) -> Result<usize, IoError> {
    let bad = |m: String| IoError::invalid(path, m);
    let mut r = reader(path)?;
    let c = Columns::parse(&mut r, path, Some(robot))?;
    let n = robot.len();
    let header = &c.header;
    let t_col = c.t;
    let cols = c.sample_groups(path)?;
    let mut vals = vec![0.0; 4 * n];
    let mut prev = f64::NEG_INFINITY;
    let mut rec = csv::ByteRecord::new();
    let mut k = 0usize;
    while r
        .read_byte_record(&mut rec)
        .map_err(|e| bad(format!("line {}: {e}", k + 2)))?
    {
        let get = |c: usize| -> Result<f64, IoError> {
            let v = number(&rec, c).map_err(|s| {
                bad(format!(
                    "line {}, column '{}': '{s}' is not a number",
                    k + 2,
                    header[c]
                ))
            })?;
            Ok(v)
        };
        // The value of column `c` in group `g` (t, q, dq, ddq, tau), checked like a trajectory's.
        let checked = |g: &str, c: usize, t: f64| -> Result<f64, IoError> {
            let v = get(c)?;
            physid_core::trajectory::check_value(k, t, g, &header[c], v)
                .map_err(|e| bad(format!("line {}: {e}", k + 2)))?;
            Ok(v)
        };
        let t = get(t_col)?;
        check_time(k, t, prev, &header[t_col]).map_err(bad)?;
        prev = t;
        if range.contains(&k) {
            for (g, cs) in cols.iter().enumerate() {
                for (j, &c) in cs.iter().enumerate() {
                    vals[g * n + j] = checked(SAMPLE_GROUPS[g], c, t)?;
                }
            }
            f(k, &SampleRef::packed(t, &vals));
        }
        k += 1;
    }
    if k == 0 {
        return Err(bad("no samples".into()));
    }
    Ok(k)
}

/// Whether a CSV's header has `dq` and `ddq` columns (so it can be streamed: nothing to derive).
pub fn csv_streamable(path: &Path) -> Result<bool, IoError> {
    let mut r = reader(path)?;
    let c = Columns::parse(&mut r, path, None)?;
    Ok(c.dq.is_some() && c.ddq.is_some())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A log of `rows` samples of two joints (t, q, τ), `edit` applied to each line.
    fn log(rows: usize, edit: impl Fn(usize, String) -> String) -> String {
        let mut text = String::from("t,q1,q2,tau1,tau2\n");
        for k in 0..rows {
            let t = k as f64 * 1e-3;
            let line = format!(
                "{t},{},{},{},{}",
                (0.7 * t).sin() + 1e-13 * k as f64,
                -0.3 * t,
                12.5 * (1.3 * t).cos(),
                -3.25 + t
            );
            text.push_str(&edit(k, line));
            text.push('\n');
        }
        text
    }

    fn read(text: &str) -> Result<Logged, IoError> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("log.csv");
        std::fs::write(&path, text).unwrap();
        read_csv_logged(&path, None).map(|(l, _)| l)
    }

    /// The message of reading `text` on `threads` workers, after the file's path.
    fn message(threads: usize, text: &str) -> String {
        let err = on(threads, || read(text)).unwrap_err().to_string();
        err.split_once("log.csv: ").unwrap().1.to_string()
    }

    /// A pool of `threads` workers running `f`.
    fn on<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads);
        pool.build().unwrap().install(f)
    }

    #[test]
    fn a_field_reads_as_the_standard_library_parses_it() {
        let fields = [
            "0",
            "-0",
            "1.5",
            " 2.25 ",
            "+3",
            "1e-300",
            "4.9e-324",
            "1.7976931348623157e308",
            "-1.1762644894566798e-13",
            "0.1",
            ".5",
            "5.",
            "1E5",
            "inf",
            "-Infinity",
            "NaN",
            "1e",
            "e5",
            "--1",
            "1.2.3",
            "0x10",
            "1_0",
            "",
            " ",
            "\u{a0}7\u{a0}",
            "1e400",
            "abc",
        ];
        for f in fields {
            let rec = csv::ByteRecord::from(vec![f]);
            let want = f.trim().parse::<f64>();
            match (number(&rec, 0), want) {
                (Ok(v), Ok(w)) => assert!(
                    v.to_bits() == w.to_bits() || (v.is_nan() && w.is_nan()),
                    "{f:?}: {v} vs {w}"
                ),
                (Err(text), Err(_)) => assert_eq!(text, f.trim(), "{f:?}"),
                (got, want) => panic!("{f:?}: {got:?} vs {want:?}"),
            }
        }
    }

    #[test]
    fn a_large_log_read_in_parts_side_by_side_is_the_log_read_in_one_pass() {
        let text = log(60_000, |_, l| l);
        assert!(text.len() > 3 * PART_BYTES, "{} bytes", text.len());
        let one = on(1, || read(&text)).unwrap();
        for threads in [2, 3, 4] {
            let parts = on(threads, || line_parts(text.as_bytes()).len());
            assert!(parts > 1, "{threads} threads: {parts} part");
            let side_by_side = on(threads, || read(&text)).unwrap();
            assert_eq!(side_by_side.t.len(), 60_000);
            assert_eq!(side_by_side.t, one.t);
            assert_eq!(side_by_side.q, one.q);
            assert_eq!(side_by_side.tau, one.tau);
        }
        // With Windows line ends and a last line without its end, the same samples.
        let crlf = text.replace('\n', "\r\n");
        let crlf = on(4, || read(crlf.trim_end())).unwrap();
        assert_eq!((crlf.t, crlf.q, crlf.tau), (one.t, one.q, one.tau));
    }

    #[test]
    fn a_bad_value_or_a_short_line_in_a_later_part_names_its_line_in_the_file() {
        let bad = log(60_000, |k, l| {
            if k == 50_000 {
                format!("{},x", l.rsplit_once(',').unwrap().0)
            } else {
                l
            }
        });
        let err = on(4, || read(&bad)).unwrap_err().to_string();
        assert!(err.contains("line 50002, column 'tau2': 'x"), "{err}");
        let short = log(60_000, |k, l| {
            if k == 45_000 {
                l.rsplit_once(',').unwrap().0.to_string()
            } else {
                l
            }
        });
        let one = message(1, &short);
        assert_eq!(message(4, &short), one);
        assert!(one.contains("line 45002"), "{one}");
        // A truncated last line, as a recorder killed mid-write leaves it.
        let cut = log(60_000, |_, l| l);
        let cut = &cut[..cut.len() - 9];
        assert_eq!(message(4, cut), message(1, cut));
    }
}
