//! The look every physid plot shares (plotters, SVG): one palette and one legend style, so
//! the experiment's and the diagnosis's figures read alike.

use plotters::prelude::*;

/// The plots' palette (Tableau 10 order: blue, red, green, purple, orange, cyan, brown, grey).
pub const PALETTE: [(u8, u8, u8); 8] = [
    (31, 119, 180),
    (214, 39, 40),
    (44, 160, 44),
    (148, 103, 189),
    (255, 127, 14),
    (23, 190, 207),
    (140, 86, 75),
    (127, 127, 127),
];

/// Colour `k` of [`PALETTE`], cycling.
pub fn colour(k: usize) -> RGBColor {
    let (r, g, b) = PALETTE[k % PALETTE.len()];
    RGBColor(r, g, b)
}

/// How a legend entry is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mark {
    /// A filled square (bars).
    Bar,
    /// A line segment (curves).
    Line,
}

/// Width (px) of the legend column [`legend_outside`] draws into.
pub const LEGEND_WIDTH: u32 = 190;

/// Draws a legend into `area` (a column beside the chart, so that it never covers data): one
/// entry per `(name, colour, mark)`, top down.
pub fn legend_outside<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    entries: &[(String, RGBColor, Mark)],
) -> Result<(), String> {
    let font = ("sans-serif", 13).into_font().color(&BLACK);
    for (i, (name, c, mark)) in entries.iter().enumerate() {
        let y = 60 + 22 * i as i32;
        match mark {
            Mark::Bar => area
                .draw(&Rectangle::new([(8, y - 6), (22, y + 6)], c.filled()))
                .map_err(|e| e.to_string())?,
            Mark::Line => area
                .draw(&PathElement::new(vec![(4, y), (26, y)], c.stroke_width(2)))
                .map_err(|e| e.to_string())?,
        }
        area.draw(&Text::new(name.clone(), (32, y - 7), font.clone()))
            .map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// A tick label for a positive axis value: integers without decimals, small values with up to
/// three significant digits, large ones in exponent form (`1e4`).
pub fn tick(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if !(1e-3..1e5).contains(&a) {
        format!("{v:.0e}")
    } else if (v - v.round()).abs() < 1e-9 * a.max(1.0) {
        format!("{}", v.round() as i64)
    } else {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// The top of a bar plot's value axis (the largest finite value, at least 10⁻⁹) and the room
/// below it (pixels) for the longest of `labels`, written downwards.
fn bar_extent(labels: &[String], series: &[(String, Vec<f64>)]) -> (f64, u32) {
    let ymax = series
        .iter()
        .flat_map(|(_, v)| v.iter().copied())
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max)
        .max(1e-9);
    let longest = labels.iter().map(|l| l.chars().count()).max().unwrap_or(0);
    (ymax, (12 + 7 * longest).clamp(40, 220) as u32)
}

/// The legend of grouped bars: each series' name in its colour.
fn bar_entries(series: &[(String, Vec<f64>)]) -> Vec<(String, RGBColor, Mark)> {
    series
        .iter()
        .enumerate()
        .map(|(s, (name, _))| (name.clone(), colour(s), Mark::Bar))
        .collect()
}

/// Grouped bars: one group per label (written below the axis), one bar per series, from zero;
/// the legend in a column beside the chart.
pub fn grouped_bars(
    title: &str,
    ylabel: &str,
    labels: &[String],
    series: &[(String, Vec<f64>)],
) -> Result<String, String> {
    let err = |e: &dyn std::fmt::Display| e.to_string();
    let (ymax, label_area) = bar_extent(labels, series);
    let groups = labels.len();
    let per = series.len().max(1);
    let mut svg = String::new();
    {
        let width = (140 + 60 * groups * per).clamp(640, 1400) as u32 + LEGEND_WIDTH;
        let root = SVGBackend::with_string(&mut svg, (width, 480 + label_area)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let (plot_area, legend_area) = root.split_horizontally(width - LEGEND_WIDTH);
        let mut chart = ChartBuilder::on(&plot_area)
            .caption(title, ("sans-serif", 18))
            .margin(15)
            .x_label_area_size(label_area)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..groups as f64, 0.0..ymax * 1.08)
            .map_err(|e| err(&e))?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(0)
            .y_label_formatter(&|v| format!("{v:.2}"))
            .y_desc(ylabel)
            .draw()
            .map_err(|e| err(&e))?;
        let w = 0.8 / per as f64;
        for (s, (_, vals)) in series.iter().enumerate() {
            let c = colour(s);
            chart
                .draw_series(vals.iter().enumerate().map(|(g, v)| {
                    let x0 = g as f64 + 0.1 + s as f64 * w;
                    Rectangle::new([(x0, 0.0), (x0 + w * 0.9, v.max(0.0))], c.filled())
                }))
                .map_err(|e| err(&e))?;
        }
        // Group labels under the axis, at each group's centre, written downwards.
        let style = ("sans-serif", 12)
            .into_font()
            .transform(FontTransform::Rotate90)
            .color(&BLACK);
        for (g, l) in labels.iter().enumerate() {
            let (px, py) = chart.backend_coord(&(g as f64 + 0.5, 0.0));
            plot_area
                .draw(&Text::new(l.clone(), (px - 6, py + 8), style.clone()))
                .map_err(|e| err(&e))?;
        }
        legend_outside(&legend_area, &bar_entries(series))?;
        root.present().map_err(|e| err(&e))?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_read_as_numbers_people_write() {
        assert_eq!(tick(10.0), "10");
        assert_eq!(tick(1000.0), "1000");
        assert_eq!(tick(0.25), "0.25");
        assert_eq!(tick(0.5), "0.5");
        assert_eq!(tick(1e6), "1e6");
        assert_eq!(tick(2e-4), "2e-4");
    }
}
