//! Horizontal grouped bars on a categorical axis: the report's residual per segment. Each
//! category is a row labelled in full on the left (the hand-written chart this replaces put
//! numeric ticks under categories and cut their labels), one bar per series in each row.

use super::plot::{DrawResult, W, color, wrap};
use crate::render::num;
use plotters::coord::ranged1d::{IntoSegmentedCoord, SegmentValue};
use plotters::prelude::*;

/// One group of bars: its legend name, colour and one value per category.
pub(super) struct BarSeries {
    /// Legend name.
    pub(super) name: String,
    /// Colour.
    pub(super) color: String,
    /// One value per category (non-finite: no bar).
    pub(super) values: Vec<f64>,
}

/// Horizontal grouped bars: one row per category (labelled in full on the left, first on top),
/// one bar per series in each row, values along the bottom axis labelled `value_label`.
pub(super) fn bars(
    title: &str,
    value_label: &str,
    categories: &[String],
    series: &[BarSeries],
) -> String {
    let n = categories.len();
    let top = series
        .iter()
        .flat_map(|s| s.values.iter())
        .filter(|v| v.is_finite())
        .fold(0.0f64, |m, v| m.max(*v));
    let points = series
        .iter()
        .flat_map(|s| s.values.iter())
        .filter(|v| v.is_finite())
        .count();
    let label_px = categories
        .iter()
        .map(|c| c.chars().count())
        .max()
        .unwrap_or(8) as u32
        * 7
        + 16;
    let height = (70 + 22 * n.max(1) * series.len().max(1)).clamp(200, 900) as u32;
    let mut buf = String::new();
    let drawn = draw_bars(
        &mut buf,
        (W as u32, height),
        label_px,
        title,
        value_label,
        categories,
        series,
        if top > 0.0 { top * 1.1 } else { 1.0 },
    );
    wrap(buf, drawn, title, points, "")
}

#[allow(clippy::too_many_arguments)]
fn draw_bars(
    buf: &mut String,
    size: (u32, u32),
    label_px: u32,
    title: &str,
    value_label: &str,
    categories: &[String],
    series: &[BarSeries],
    top: f64,
) -> DrawResult {
    let n = categories.len() as i32;
    let root = SVGBackend::with_string(buf, size).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 15))
        .margin(8)
        .x_label_area_size(40)
        .y_label_area_size(label_px)
        .build_cartesian_2d(0.0..top, (0..n).into_segmented())?;
    let step = top / 20.0;
    let fx = |v: &f64| num::tick(*v, step);
    // Row k from the top is segment n−1−k, so the first category is on top.
    let fy = |v: &SegmentValue<i32>| match v {
        SegmentValue::CenterOf(k) => usize::try_from(n - 1 - k)
            .ok()
            .and_then(|i| categories.get(i))
            .cloned()
            .unwrap_or_default(),
        _ => String::new(),
    };
    chart
        .configure_mesh()
        .disable_y_mesh()
        .y_labels(categories.len())
        .x_desc(value_label)
        .x_label_formatter(&fx)
        .y_label_formatter(&fy)
        .light_line_style(RGBColor(245, 245, 245))
        .label_style(("sans-serif", 11))
        .axis_desc_style(("sans-serif", 12))
        .draw()?;
    let nb = series.len().max(1) as f64;
    for (k, _) in categories.iter().enumerate() {
        let row = n - 1 - k as i32;
        let (_, y_lo) = chart.backend_coord(&(0.0, SegmentValue::Exact(row)));
        let (_, y_hi) = chart.backend_coord(&(0.0, SegmentValue::Exact(row + 1)));
        let (top_px, bottom_px) = (y_lo.min(y_hi) as f64, y_lo.max(y_hi) as f64);
        let inner = 0.8 * (bottom_px - top_px);
        let bh = inner / nb;
        for (j, s) in series.iter().enumerate() {
            let Some(v) = s.values.get(k).copied().filter(|v| v.is_finite()) else {
                continue;
            };
            let (x0, _) = chart.backend_coord(&(0.0, SegmentValue::Exact(row)));
            let (x1, _) = chart.backend_coord(&(v.min(top), SegmentValue::Exact(row)));
            let y0 = top_px + 0.1 * (bottom_px - top_px) + bh * j as f64;
            root.draw(&Rectangle::new(
                [(x0, y0 as i32), (x1.max(x0 + 1), (y0 + bh - 1.0) as i32)],
                color(&s.color).filled(),
            ))?;
        }
    }
    for s in series {
        let col = color(&s.color);
        chart
            .draw_series(std::iter::empty::<Circle<(f64, SegmentValue<i32>), i32>>())?
            .label(s.name.as_str())
            .legend(move |(x, y)| Rectangle::new([(x, y - 4), (x + 14, y + 4)], col.filled()));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(200, 200, 200))
        .label_font(("sans-serif", 11))
        .draw()?;
    root.present()?;
    Ok(())
}
