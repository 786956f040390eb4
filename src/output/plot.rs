//! Log-log convergence plots as SVG (plotters), written atomically.

use super::{write_atomic, OutputError};
use plotters::prelude::*;
use std::path::Path;

/// One curve of a log-log plot.
pub struct Series {
    /// Legend label.
    pub label: String,
    /// `(x, y)` points; non-positive values are skipped.
    pub points: Vec<(f64, f64)>,
    /// Dashed line (e.g. whole-plate norms next to interior ones).
    pub dashed: bool,
}

const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
];

/// Write a log-log plot of `series` to `path` (SVG, 900 x 600). Colours cycle per pair
/// of series so that a solid curve and the dashed one after it share a colour.
pub fn write_loglog_svg(path: &Path, title: &str, x_label: &str, y_label: &str, series: &[Series]) -> Result<(), OutputError> {
    let err = |e: String| OutputError::InvalidInput { path: path.to_path_buf(), detail: format!("plot: {e}") };
    let pts: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
        .collect();
    if pts.is_empty() {
        return Err(err("no positive finite points".into()));
    }
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for (x, y) in &pts {
        x0 = x0.min(*x);
        x1 = x1.max(*x);
        y0 = y0.min(*y);
        y1 = y1.max(*y);
    }
    let (x0, x1, y0, y1) = (x0 / 1.5, x1 * 1.5, y0 / 3.0, y1 * 3.0);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 600)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(|e| err(e.to_string()))?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
            .x_label_formatter(&|v| format!("{v:.0e}"))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .draw()
            .map_err(|e| err(e.to_string()))?;
        for (k, s) in series.iter().enumerate() {
            let colour = PALETTE[(k / 2) % PALETTE.len()];
            let data: Vec<(f64, f64)> = s.points.iter().copied().filter(|(x, y)| *x > 0.0 && *y > 0.0).collect();
            let style = ShapeStyle::from(&colour).stroke_width(2);
            let drawn = if s.dashed {
                chart.draw_series(DashedLineSeries::new(data.clone(), 8, 5, style))
            } else {
                chart.draw_series(LineSeries::new(data.clone(), style))
            };
            drawn
                .map_err(|e| err(e.to_string()))?
                .label(s.label.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
            chart.draw_series(data.iter().map(|p| Circle::new(*p, 3, colour.filled()))).map_err(|e| err(e.to_string()))?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::LowerRight)
            .draw()
            .map_err(|e| err(e.to_string()))?;
        root.present().map_err(|e| err(e.to_string()))?;
    }
    write_atomic(path, svg.as_bytes())
}
