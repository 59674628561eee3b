//! Plots of an experiment (plotters, SVG): a summary column versus n_s on log-log axes, one line
//! per constraint set (the median over seeds) with its interquartile band.

use physid_io::plot::{colour, legend_outside, tick, Mark, LEGEND_WIDTH};
use plotters::prelude::*;
use polars::prelude::*;
use std::path::Path;

/// Plots `{value}_median` with the `{value}_q25`..`{value}_q75` band against n_s per set.
pub fn plot_vs_ns(
    summary: &DataFrame,
    value: &str,
    sets: &[&str],
    title: &str,
    ylabel: &str,
    path: &Path,
) -> Result<(), physid_io::IoError> {
    plot_vs_ns_by(summary, "constraints", value, sets, title, ylabel, path)
}

/// The least and largest of the finite positive `values` (∞ and 0 when there are none): a log
/// axis's extent.
fn positive_extent<'v>(values: impl Iterator<Item = &'v f64>) -> (f64, f64) {
    values
        .copied()
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, 0.0), |(lo, hi), v| (lo.min(v), hi.max(v)))
}

/// The outline of the band between `lo` and `hi` over the points `idx` of `x`: along `lo`
/// forward, back along `hi`.
fn band(idx: &[usize], x: &[f64], (lo, hi): (&[f64], &[f64])) -> Vec<(f64, f64)> {
    idx.iter()
        .map(|&i| (x[i], lo[i]))
        .chain(idx.iter().rev().map(|&i| (x[i], hi[i])))
        .collect()
}

/// `n_s`, the lower quartile, median and upper quartile of a value, and each row's series.
type BandColumns = (Vec<f64>, [Vec<f64>; 3], Vec<String>);

/// The columns a plot against `n_s` reads from `summary`: `n_s`, the `value`'s lower quartile,
/// median and upper quartile, and the series each row belongs to; errors name the plot's `path`.
fn band_columns(
    summary: &DataFrame,
    series_column: &str,
    value: &str,
    path: &Path,
) -> Result<BandColumns, physid_io::IoError> {
    let err = |e: polars::error::PolarsError| physid_io::IoError::invalid(path, e.to_string());
    let get = |name: &str| super::tables::floats(summary, name).map_err(err);
    let quartiles = [
        get(&format!("{value}_q25"))?,
        get(&format!("{value}_median"))?,
        get(&format!("{value}_q75"))?,
    ];
    let series = super::tables::strings(summary, series_column).map_err(err)?;
    Ok((get("n_s")?, quartiles, series))
}

/// A chart with both axes logarithmic, drawn as SVG.
type LogLogChart<'a, 'b> =
    ChartContext<'a, SVGBackend<'b>, Cartesian2d<LogCoord<f64>, LogCoord<f64>>>;

/// A log-log chart against `n_s` on `area`: the x axis from 0.9 `xmin` to 1.1 `xmax`, the
/// y axis over the whole decades around `ymin..ymax` (every axis then carries a labelled tick
/// at each end), the mesh drawn.
fn log_log_chart<'a, 'b>(
    area: &'a DrawingArea<SVGBackend<'b>, plotters::coord::Shift>,
    title: &str,
    ylabel: &str,
    [(xmin, xmax), (ymin, ymax)]: [(f64, f64); 2],
) -> Result<LogLogChart<'a, 'b>, String> {
    let decades = 0.99 * 10f64.powf(ymin.log10().floor())..1.01 * 10f64.powf(ymax.log10().ceil());
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 20))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(75)
        .build_cartesian_2d((xmin * 0.9..xmax * 1.1).log_scale(), decades.log_scale())
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc("training samples n_s (count)")
        .y_desc(ylabel)
        .x_labels(12)
        .y_labels(12)
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .draw()
        .map_err(|e| e.to_string())?;
    Ok(chart)
}

/// [`plot_vs_ns`] with one line per value `series` of column `series_column`.
pub fn plot_vs_ns_by(
    summary: &DataFrame,
    series_column: &str,
    value: &str,
    sets: &[&str],
    title: &str,
    ylabel: &str,
    path: &Path,
) -> Result<(), physid_io::IoError> {
    let err = |m: String| physid_io::IoError::invalid(path, m);
    let (ns, [lo, med, hi], set_of) = band_columns(summary, series_column, value, path)?;
    let finite = |v: &f64| v.is_finite() && *v > 0.0;
    let (xmin, xmax) = positive_extent(ns.iter());
    let (ymin, ymax) = positive_extent(lo.iter().chain(&hi));
    let mut svg = String::new();
    {
        let width = 860 + LEGEND_WIDTH;
        let root = SVGBackend::with_string(&mut svg, (width, 540)).into_drawing_area();
        let draw = |e: String| err(format!("plot: {e}"));
        root.fill(&WHITE).map_err(|e| draw(e.to_string()))?;
        let (plot_area, legend_area) = root.split_horizontally(860);
        let extent = [(xmin, xmax), (ymin, ymax)];
        let mut chart = log_log_chart(&plot_area, title, ylabel, extent).map_err(draw)?;
        let mut entries = vec![];
        for (k, set) in sets.iter().enumerate() {
            // Loosest to tightest: red, green, purple, blue (then orange, cyan).
            let named = colour([1, 2, 3, 0, 4, 5][k % 6]);
            let color = named.to_rgba();
            let idx: Vec<usize> = (0..ns.len())
                .filter(|&i| set_of[i] == *set && finite(&lo[i]) && finite(&hi[i]))
                .collect();
            let band = band(&idx, &ns, (&lo, &hi));
            chart
                .draw_series(std::iter::once(Polygon::new(band, color.mix(0.18))))
                .map_err(|e| draw(e.to_string()))?;
            chart
                .draw_series(LineSeries::new(
                    idx.iter().map(|&i| (ns[i], med[i])),
                    color.stroke_width(2),
                ))
                .map_err(|e| draw(e.to_string()))?;
            entries.push((set.to_string(), named, Mark::Line));
        }
        legend_outside(&legend_area, &entries).map_err(draw)?;
        root.present().map_err(|e| draw(e.to_string()))?;
    }
    physid_io::write_atomic(path, svg.as_bytes())
}
