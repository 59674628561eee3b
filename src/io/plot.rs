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

/// Draws the series legend of `chart` (upper right, framed) the same way in every plot.
pub fn legend<'a, DB, CT>(chart: &mut ChartContext<'a, DB, CT>) -> Result<(), String>
where
    DB: DrawingBackend + 'a,
    CT: CoordTranslate,
{
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.85))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| e.to_string())
}
