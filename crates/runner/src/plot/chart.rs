//! Time-series figures: panels of lines against time over the shaded support phases, drawn as SVG.
//!
//! Text is laid out with plotters' fixed estimate (no font files are read), so the figures build the same
//! on any machine.

use std::path::Path;

use plotters::prelude::*;

use super::PlotError;

/// Points kept per series: longer series are decimated (every k-th sample) to keep the SVGs small.
pub const MAX_POINTS: usize = 800;

/// One line of a panel.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend entry (`None`: not in the legend, e.g. the second limit line).
    pub label: Option<String>,
    /// Line colour.
    pub color: RGBColor,
    /// Line width \[px\].
    pub width: u32,
    /// (time \[s\], value) pairs in time order.
    pub points: Vec<(f64, f64)>,
}

impl Series {
    /// A labelled line of width 2.
    pub fn new(label: impl Into<String>, color: RGBColor, points: Vec<(f64, f64)>) -> Self {
        Self {
            label: Some(label.into()),
            color,
            width: 2,
            points,
        }
    }
}

/// One chart of a figure.
#[derive(Debug, Clone)]
pub struct Panel {
    /// Caption.
    pub title: String,
    /// Y axis label, with its unit.
    pub y_label: String,
    /// Lines.
    pub series: Vec<Series>,
}

/// A support phase from `/events`: `[start, end)` \[s\] and its name.
#[derive(Debug, Clone, PartialEq)]
pub struct PhaseSpan {
    /// Start \[s\].
    pub start: f64,
    /// End \[s\].
    pub end: f64,
    /// `double_support`, `left_stance` or `right_stance`.
    pub phase: String,
}

/// The shading colour and legend name of a phase.
fn phase_style(phase: &str) -> (RGBColor, &'static str) {
    match phase {
        "double_support" => (RGBColor(190, 190, 190), "double support"),
        "left_stance" => (RGBColor(150, 190, 240), "left stance"),
        "right_stance" => (RGBColor(245, 190, 130), "right stance"),
        _ => (RGBColor(230, 230, 230), "other phase"),
    }
}

/// Every k-th point so that at most `max` remain (the last point is kept).
pub fn decimate(points: &[(f64, f64)], max: usize) -> Vec<(f64, f64)> {
    if points.len() <= max || max < 2 {
        return points.to_vec();
    }
    let k = points.len().div_ceil(max - 1);
    let mut out: Vec<_> = points.iter().step_by(k).copied().collect();
    if let Some(last) = points.last() {
        if out.last() != Some(last) {
            out.push(*last);
        }
    }
    out
}

fn range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    values
        .filter(|v| v.is_finite())
        .fold(None, |acc, v| match acc {
            None => Some((v, v)),
            Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
        })
}

/// The y range of a panel with a 5 % margin (a unit range around a constant).
fn padded(lo: f64, hi: f64) -> (f64, f64) {
    let span = hi - lo;
    if span <= 1e-12 * (1.0 + lo.abs()) {
        (lo - 0.5, hi + 0.5)
    } else {
        (lo - 0.05 * span, hi + 0.05 * span)
    }
}

fn err<E: std::fmt::Display>(e: E) -> PlotError {
    PlotError::Draw(e.to_string())
}

/// Draws `panels` in a grid of `cols` columns over a shared time axis, with the support phases shaded,
/// and writes the SVG to `path`.
pub fn draw_time_figure(
    path: &Path,
    title: &str,
    panels: &[Panel],
    cols: usize,
    phases: &[PhaseSpan],
) -> Result<(), PlotError> {
    let cols = cols.max(1);
    let rows = panels.len().div_ceil(cols).max(1);
    let width = if cols == 1 { 1000 } else { 600 * cols as u32 };
    let size = (width, 320 * rows as u32 + 40);
    let root = SVGBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let root = root.titled(title, ("sans-serif", 22)).map_err(err)?;
    let all_t = panels
        .iter()
        .flat_map(|p| p.series.iter())
        .flat_map(|s| s.points.iter().map(|p| p.0))
        .chain(phases.iter().flat_map(|p| [p.start, p.end]));
    let (t0, t1) = range(all_t).unwrap_or((0.0, 1.0));
    let t1 = if t1 > t0 { t1 } else { t0 + 1.0 };
    for (panel, area) in panels.iter().zip(root.split_evenly((rows, cols))) {
        draw_panel(&area, panel, (t0, t1), phases)?;
    }
    root.present().map_err(err)
}

fn draw_panel(
    area: &DrawingArea<SVGBackend<'_>, plotters::coord::Shift>,
    panel: &Panel,
    (t0, t1): (f64, f64),
    phases: &[PhaseSpan],
) -> Result<(), PlotError> {
    let (lo, hi) = range(
        panel
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1)),
    )
    .unwrap_or((0.0, 1.0));
    let (y0, y1) = padded(lo, hi);
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, ("sans-serif", 16))
        .margin(10)
        .x_label_area_size(38)
        .y_label_area_size(64)
        .build_cartesian_2d(t0..t1, y0..y1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("time [s]")
        .y_desc(panel.y_label.as_str())
        .max_light_lines(0)
        .draw()
        .map_err(err)?;
    let mut names: Vec<&str> = Vec::new();
    for p in phases {
        if !names.contains(&p.phase.as_str()) {
            names.push(&p.phase);
        }
    }
    for name in names {
        let (color, label) = phase_style(name);
        let fill = color.mix(0.35).filled();
        chart
            .draw_series(
                phases
                    .iter()
                    .filter(|p| p.phase == name)
                    .map(|p| Rectangle::new([(p.start, y0), (p.end, y1)], fill)),
            )
            .map_err(err)?
            .label(label)
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 16, y + 5)], fill));
    }
    for s in &panel.series {
        let style = s.color.stroke_width(s.width);
        let points = decimate(&s.points, MAX_POINTS);
        let drawn = chart
            .draw_series(LineSeries::new(points, style))
            .map_err(err)?;
        if let Some(label) = &s.label {
            drawn
                .label(label.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], style));
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font(("sans-serif", 12))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(err)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimation_keeps_the_ends_and_the_cap() {
        let pts: Vec<_> = (0..10_000).map(|i| (i as f64, i as f64)).collect();
        let d = decimate(&pts, 1000);
        assert!(d.len() <= 1000, "{}", d.len());
        assert!(d.len() > 900, "{}", d.len());
        assert_eq!(d.first(), pts.first());
        assert_eq!(d.last(), pts.last());
        assert_eq!(decimate(&pts[..5], 1000).len(), 5);
    }
}
