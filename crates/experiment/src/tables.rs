//! Tables of an experiment with polars: the long table (one row per seed × n_s × set), the
//! summary over seeds (median and interquartile range per n_s × set), and its pivot (n_s rows,
//! one column per constraint set). Parquet and CSV, written atomically.

use super::Row;
use physid_io::IoError;
use polars::prelude::*;
use std::path::Path;

/// The long table; `bodies` names the per-body error columns (links then rotors), e.g.
/// `mass_err_thigh`, `com_err_m_thigh`, `inertia_err_thigh`, `j_err_thigh`.
pub fn long_table_with_bodies(
    rows: &[Row],
    joints: &[String],
    bodies: &[String],
) -> PolarsResult<DataFrame> {
    let mut df = long_table(rows, joints)?;
    for (b, name) in bodies.iter().enumerate() {
        for (k, what) in ["mass_err", "com_err_m", "inertia_err", "j_err"]
            .iter()
            .enumerate()
        {
            let v: Vec<f64> = rows
                .iter()
                .map(|r| r.body_errors.get(b).map_or(f64::NAN, |e| e[k]))
                .collect();
            df.with_column(Series::new(format!("{what}_{name}").into(), v).into_column())?;
        }
    }
    Ok(df)
}

/// The columns that say which cell a row is: its seed, training size and constraint set.
fn key_columns(rows: &[Row]) -> Vec<Column> {
    vec![
        Series::new(
            "seed".into(),
            rows.iter().map(|r| r.seed).collect::<Vec<u64>>(),
        )
        .into_column(),
        Series::new(
            "n_s".into(),
            rows.iter().map(|r| r.n_s as u64).collect::<Vec<u64>>(),
        )
        .into_column(),
        Series::new(
            "constraints".into(),
            rows.iter()
                .map(|r| r.constraints.name())
                .collect::<Vec<&str>>(),
        )
        .into_column(),
    ]
}

/// The long table.
pub fn long_table(rows: &[Row], joints: &[String]) -> PolarsResult<DataFrame> {
    let f = |name: &str, v: Vec<f64>| Series::new(name.into(), v).into_column();
    let mut cols = key_columns(rows);
    for (j, name) in joints.iter().enumerate() {
        cols.push(f(
            &format!("val_rms_{name}"),
            rows.iter().map(|r| r.val_rms[j]).collect(),
        ));
    }
    cols.push(f(
        "val_rms",
        rows.iter().map(|r| r.val_rms_overall).collect(),
    ));
    cols.push(f(
        "train_rms",
        rows.iter().map(|r| r.train_rms_overall).collect(),
    ));
    cols.push(f(
        "val_truth_rms",
        rows.iter().map(|r| r.val_truth_rms).collect(),
    ));
    cols.push(f("mass_err", rows.iter().map(|r| r.mass_err).collect()));
    cols.push(f("com_err_m", rows.iter().map(|r| r.com_err).collect()));
    cols.push(f(
        "inertia_err",
        rows.iter().map(|r| r.inertia_err).collect(),
    ));
    cols.push(f("j_err", rows.iter().map(|r| r.j_err).collect()));
    cols.push(
        Series::new(
            "consistent".into(),
            rows.iter().map(|r| r.consistent).collect::<Vec<bool>>(),
        )
        .into_column(),
    );
    cols.push(
        Series::new(
            "status".into(),
            rows.iter()
                .map(|r| r.status.as_str())
                .collect::<Vec<&str>>(),
        )
        .into_column(),
    );
    cols.push(f(
        "solve_ms",
        rows.iter().map(|r| r.solve_s * 1e3).collect(),
    ));
    DataFrame::new_infer_height(cols)
}

/// A per-group statistic of one column (booleans count as 0 and 1; nulls are skipped).
#[derive(Clone, Copy, Debug)]
pub enum Stat {
    /// The group's row count (the column is not read).
    Count,
    /// The arithmetic mean.
    Mean,
    /// The median (the mean of the two middle values of an even count).
    Median,
    /// The quantile at this fraction, interpolated linearly between order statistics.
    Quantile(f64),
}

/// One row per group of `df`'s rows by the columns `keys` (first-appearance order): the key
/// values and one column per `(column, statistic, name)` of `aggs`.
pub fn group_stats(
    df: &DataFrame,
    keys: &[&str],
    aggs: &[(&str, Stat, &str)],
) -> PolarsResult<DataFrame> {
    Groups::of(df, keys)?.agg(df, aggs)
}

/// A table's rows grouped by key columns, groups in first-appearance order.
struct Groups {
    /// One row per group: its key values.
    keys: DataFrame,
    /// The row indices of each group.
    rows: Vec<IdxCa>,
}

impl Groups {
    /// Groups the rows of `df` by the columns `keys` (polars' stable group-by).
    fn of(df: &DataFrame, keys: &[&str]) -> PolarsResult<Self> {
        let by = df.group_by_stable(keys.iter().copied())?;
        let rows = by
            .get_groups()
            .iter()
            .map(|g| match g {
                GroupsIndicator::Idx((_, idx)) => IdxCa::from_vec("".into(), idx.to_vec()),
                GroupsIndicator::Slice([first, len]) => {
                    IdxCa::from_vec("".into(), (first..first + len).collect())
                }
            })
            .collect();
        Ok(Self {
            keys: DataFrame::new_infer_height(by.keys())?,
            rows,
        })
    }

    /// The key columns and one column per `(column, statistic, name)` of the rows of `df`.
    fn agg(&self, df: &DataFrame, aggs: &[(&str, Stat, &str)]) -> PolarsResult<DataFrame> {
        let mut out = self.keys.clone();
        for &(column, stat, name) in aggs {
            out.with_column(self.stat(df, column, stat)?.with_name(name.into()))?;
        }
        Ok(out)
    }

    /// `stat` of `column` in each group.
    fn stat(&self, df: &DataFrame, column: &str, stat: Stat) -> PolarsResult<Column> {
        if let Stat::Count = stat {
            let n: Vec<IdxSize> = self.rows.iter().map(|r| r.len() as IdxSize).collect();
            return Ok(Series::new("".into(), n).into_column());
        }
        let values = df.column(column)?.cast(&DataType::Float64)?;
        let values = values.f64()?;
        let per_group = self
            .rows
            .iter()
            .map(|rows| {
                let group = values.take(rows)?;
                Ok(match stat {
                    Stat::Mean => group.mean(),
                    Stat::Median => group.median(),
                    Stat::Quantile(p) => group.quantile(p, QuantileMethod::Linear)?,
                    Stat::Count => unreachable!("counted above"),
                })
            })
            .collect::<PolarsResult<Vec<Option<f64>>>>()?;
        Ok(Series::new("".into(), per_group).into_column())
    }
}

/// Median and quartiles over seeds per (n_s, set), in first-appearance order.
pub fn summary(long: &DataFrame) -> PolarsResult<DataFrame> {
    summary_by(long, &[])
}

/// Adds constant string columns (a sweep's grid values) to a table.
pub fn with_constants(mut df: DataFrame, columns: &[(String, String)]) -> PolarsResult<DataFrame> {
    let h = df.height();
    for (name, value) in columns.iter().rev() {
        df.insert_column(
            0,
            Series::new(name.as_str().into(), vec![value.as_str(); h]).into_column(),
        )?;
    }
    Ok(df)
}

/// Column `name` of `df` as numbers (cast to f64; nulls are NaN).
pub fn floats(df: &DataFrame, name: &str) -> PolarsResult<Vec<f64>> {
    Ok(df
        .column(name)?
        .cast(&DataType::Float64)?
        .f64()?
        .iter()
        .map(|v| v.unwrap_or(f64::NAN))
        .collect())
}

/// Column `name` of `df` as text, one string per row (nulls are empty).
pub fn strings(df: &DataFrame, name: &str) -> PolarsResult<Vec<String>> {
    let col = df.column(name)?;
    Ok((0..df.height())
        .map(|i| {
            col.get(i)
                .map(|v| v.str_value().to_string())
                .unwrap_or_default()
        })
        .collect())
}

/// The rows of `df` whose string column `column` equals `value`.
pub fn filter_eq(df: &DataFrame, column: &str, value: &str) -> PolarsResult<DataFrame> {
    let mask = df.column(column)?.str()?.equal(value);
    df.filter(&mask)
}

/// Stacks tables with the same columns.
pub fn concat(tables: Vec<DataFrame>) -> PolarsResult<DataFrame> {
    let mut it = tables.into_iter();
    let mut acc = it
        .next()
        .ok_or_else(|| PolarsError::NoData("no tables".into()))?;
    for t in it {
        acc.vstack_mut(&t)?;
    }
    Ok(acc)
}

/// Median and quartiles over seeds per (`keys`…, n_s, set), in first-appearance order.
pub fn summary_by(long: &DataFrame, keys: &[&str]) -> PolarsResult<DataFrame> {
    use Stat::{Count, Mean, Median, Quantile};
    let mut by = keys.to_vec();
    by.extend(["n_s", "constraints"]);
    group_stats(
        long,
        &by,
        &[
            ("", Count, "seeds"),
            ("val_rms", Quantile(0.25), "val_rms_q25"),
            ("val_rms", Median, "val_rms_median"),
            ("val_rms", Quantile(0.75), "val_rms_q75"),
            ("val_truth_rms", Quantile(0.25), "val_truth_rms_q25"),
            ("val_truth_rms", Median, "val_truth_rms_median"),
            ("val_truth_rms", Quantile(0.75), "val_truth_rms_q75"),
            ("j_err", Quantile(0.25), "j_err_q25"),
            ("j_err", Median, "j_err_median"),
            ("j_err", Quantile(0.75), "j_err_q75"),
            ("consistent", Mean, "consistent_fraction"),
            ("solve_ms", Median, "solve_ms_median"),
        ],
    )
}

/// The n_s × set table of one summary column: one row per training size (first-appearance
/// order), one column per set (the first matching row's value; null where none).
pub fn pivot(summary: &DataFrame, value: &str, sets: &[&str]) -> PolarsResult<DataFrame> {
    let sizes = Groups::of(summary, &["n_s"])?;
    let constraints = strings(summary, "constraints")?;
    let values = summary.column(value)?.cast(&DataType::Float64)?;
    let values = values.f64()?;
    let mut out = sizes.keys.clone();
    for set in sets {
        let cell: Vec<Option<f64>> = sizes
            .rows
            .iter()
            .map(|rows| {
                rows.into_no_null_iter()
                    .find(|&i| constraints[i as usize] == *set)
                    .and_then(|i| values.get(i as usize))
            })
            .collect();
        out.with_column(Series::new((*set).into(), cell).into_column())?;
    }
    Ok(out)
}

fn polars_err(path: &Path, e: PolarsError) -> IoError {
    IoError::Invalid {
        path: path.to_path_buf(),
        message: format!("writing table: {e}"),
    }
}

/// Writes through `write` into a temporary file beside `path`, then renames it into place.
fn write_atomically(
    path: &Path,
    write: impl FnOnce(&std::fs::File) -> PolarsResult<()>,
) -> Result<(), IoError> {
    let tmp = physid_io::new_temp_beside(path)?;
    write(tmp.as_file()).map_err(|e| polars_err(path, e))?;
    tmp.persist(path).map_err(|e| IoError::Fs {
        path: path.to_path_buf(),
        source: e.error,
    })?;
    Ok(())
}

/// Writes a table as Parquet, atomically.
pub fn write_parquet(path: &Path, df: &mut DataFrame) -> Result<(), IoError> {
    write_parquet_with(path, df, &[])
}

/// [`write_parquet`] with more file-level key-value metadata (e.g. `physid.provenance`).
pub fn write_parquet_with(
    path: &Path,
    df: &mut DataFrame,
    extra: &[(String, String)],
) -> Result<(), IoError> {
    let mut kv = parquet_metadata(df);
    kv.extend(extra.iter().cloned());
    let metadata = KeyValueMetadata::from_static(kv);
    write_atomically(path, |f| {
        ParquetWriter::new(f)
            .with_key_value_metadata(Some(metadata.clone()))
            .finish(df)
            .map(|_| ())
    })
}

/// The unit of a column physid writes, by its name (`None`: a label, a count or a flag).
pub fn unit_of(column: &str) -> Option<&'static str> {
    let c = column;
    let starts = |p: &str| c.starts_with(p);
    if starts("val_rms")
        || starts("train_rms")
        || starts("val_truth_rms")
        || starts("rms_")
        || c == "visible_gap"
        || c == "noise_floor"
    {
        Some("N m")
    } else if starts("com_err_m") {
        Some("m")
    } else if starts("mass_err")
        || starts("inertia_err")
        || starts("j_err")
        || c == "magnitude_error"
        || c == "gap_closed"
        || c.ends_with("_fraction")
        || c == "top1"
    {
        Some("1 (relative)")
    } else if starts("solve_ms") {
        Some("ms")
    } else if c == "n_s" {
        Some("samples")
    } else {
        None
    }
}

/// File-level key-value metadata of every physid Parquet table: the writer and version, and
/// each column's unit (`physid.units`, a JSON object) where it has one.
fn parquet_metadata(df: &DataFrame) -> Vec<(String, String)> {
    let units: serde_json::Map<String, serde_json::Value> = df
        .get_column_names()
        .iter()
        .filter_map(|n| unit_of(n).map(|u| (n.to_string(), u.into())))
        .collect();
    vec![
        (
            "physid.writer".into(),
            format!("physid {}", env!("CARGO_PKG_VERSION")),
        ),
        (
            "physid.units".into(),
            serde_json::Value::Object(units).to_string(),
        ),
    ]
}

/// The file-level key-value metadata of a Parquet file.
pub fn parquet_key_values(path: &Path) -> Result<Vec<(String, String)>, IoError> {
    let f = std::fs::File::open(path).map_err(|source| IoError::Fs {
        path: path.to_path_buf(),
        source,
    })?;
    let mut reader = ParquetReader::new(f);
    let meta = reader.get_metadata().map_err(|e| IoError::Invalid {
        path: path.to_path_buf(),
        message: format!("reading metadata: {e}"),
    })?;
    Ok(meta
        .key_value_metadata
        .iter()
        .flatten()
        .map(|kv| (kv.key.clone(), kv.value.clone().unwrap_or_default()))
        .collect())
}

/// Writes a table as CSV, atomically.
pub fn write_csv(path: &Path, df: &mut DataFrame) -> Result<(), IoError> {
    write_atomically(path, |f| CsvWriter::new(f).finish(df))
}

/// A table as CSV text, as [`write_csv`] writes it (for callers that hand it on in memory, e.g.
/// the Python package's DataFrames).
pub fn csv_text(df: &mut DataFrame) -> PolarsResult<String> {
    let mut bytes = vec![];
    CsvWriter::new(&mut bytes).finish(df)?;
    String::from_utf8(bytes).map_err(|e| PolarsError::ComputeError(e.to_string().into()))
}

/// Reads a Parquet table (for merging sweep shards and tests).
pub fn read_parquet(path: &Path) -> Result<DataFrame, IoError> {
    let f = std::fs::File::open(path).map_err(|source| IoError::Fs {
        path: path.to_path_buf(),
        source,
    })?;
    ParquetReader::new(f)
        .finish()
        .map_err(|e| IoError::Invalid {
            path: path.to_path_buf(),
            message: format!("reading table: {e}"),
        })
}

/// The n_s × set table of a summary quantity as "median [q25, q75]" strings.
pub fn pivot_with_iqr(summary: &DataFrame, value: &str, sets: &[&str]) -> PolarsResult<DataFrame> {
    let med = pivot(summary, &format!("{value}_median"), sets)?;
    let lo = pivot(summary, &format!("{value}_q25"), sets)?;
    let hi = pivot(summary, &format!("{value}_q75"), sets)?;
    let mut cols = vec![med.column("n_s")?.clone()];
    for set in sets {
        let f = |df: &DataFrame, i: usize| {
            df.column(set)
                .ok()
                .and_then(|c| c.get(i).ok())
                .and_then(|v| v.try_extract::<f64>().ok())
                .unwrap_or(f64::NAN)
        };
        let v: Vec<String> = (0..med.height())
            .map(|i| format!("{:.3} [{:.3}, {:.3}]", f(&med, i), f(&lo, i), f(&hi, i)))
            .collect();
        cols.push(Series::new((*set).into(), v).into_column());
    }
    DataFrame::new_infer_height(cols)
}

/// A Markdown table of a data frame (numbers to 3 significant decimals, missing values as
/// empty cells).
pub fn markdown(df: &DataFrame) -> String {
    let mut s = String::new();
    let names: Vec<String> = df
        .get_column_names()
        .iter()
        .map(|n| n.to_string())
        .collect();
    let header: Vec<String> = names.iter().map(|n| physid_io::md_cell(n)).collect();
    s += &format!(
        "| {} |\n|{}\n",
        header.join(" | "),
        "---|".repeat(names.len())
    );
    for i in 0..df.height() {
        let cells: Vec<String> = df
            .columns()
            .iter()
            .map(|c| match c.get(i) {
                Ok(AnyValue::Float64(x)) => format!("{x:.3}"),
                Ok(AnyValue::String(x)) => physid_io::md_cell(x),
                Ok(AnyValue::Null) => String::new(),
                Ok(v) => format!("{v}"),
                Err(_) => String::new(),
            })
            .collect();
        s += &format!("| {} |\n", cells.join(" | "));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markdown_writes_numbers_to_three_decimals_and_missing_values_as_empty_cells() {
        let df = df!(
            "case" => [0u64, 1],
            "kind" => [Some("gain"), None],
            "error" => [None, Some(0.12345)],
            "top1" => [Some(true), None],
        )
        .unwrap();
        assert_eq!(
            markdown(&df),
            "| case | kind | error | top1 |\n|---|---|---|---|\n| 0 | gain |  | true |\n| 1 |  | 0.123 |  |\n"
        );
    }
}
