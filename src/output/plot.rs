//! Log-log plots (plotters, SVG), written atomically: convergence curves
//! ([`write_loglog_svg`], and with a PNG rendered from it by resvg
//! [`write_loglog_plot`]) and cost-accuracy fronts ([`write_front_plot`], SVG and PNG).
//!
//! Both axes are logarithmic and labelled at every power of ten inside the (widened)
//! data range, so a plot spanning 1e-9 to 1 carries ten readable labels.

use super::{write_atomic, OutputError};
use plotters::coord::ranged1d::{KeyPointHint, Ranged, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::ops::Range;
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

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
];

/// A logarithmic axis over whole decades `[10^a, 10^b]` (`b >= a + 1`) covering the
/// data range `lo..hi`, with its tick marks at every power of ten.
#[derive(Clone, Debug)]
struct DecadeAxis {
    range: Range<f64>,
    ticks: Vec<f64>,
}

impl DecadeAxis {
    /// The decades around `lo..hi` (both positive and finite).
    fn covering(lo: f64, hi: f64) -> Self {
        let a = lo.log10().floor() as i32;
        let b = (hi.log10().ceil() as i32).max(a + 1);
        DecadeAxis { range: 10f64.powi(a)..10f64.powi(b), ticks: (a..=b).map(|k| 10f64.powi(k)).collect() }
    }
}

impl Ranged for DecadeAxis {
    type FormatOption = plotters::coord::ranged1d::NoDefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let (a, b) = (self.range.start.log10(), self.range.end.log10());
        let t = (value.max(f64::MIN_POSITIVE).log10() - a) / (b - a);
        limit.0 + (t * (limit.1 - limit.0) as f64).round() as i32
    }

    fn key_points<Hint: KeyPointHint>(&self, _hint: Hint) -> Vec<f64> {
        self.ticks.clone()
    }

    fn range(&self) -> Range<f64> {
        self.range.clone()
    }
}

impl ValueFormatter<f64> for DecadeAxis {
    fn format(value: &f64) -> String {
        decade_label(*value)
    }
}

/// `10^k` as a short label: `0.01`, `0.1`, `1`, `10`, `100`, else `1e-3`, `1e4`.
pub(crate) fn decade_label(v: f64) -> String {
    let k = v.log10().round() as i32;
    match k {
        -2..=2 => format!("{}", 10f64.powi(k)),
        _ => format!("1e{k}"),
    }
}

/// The decade axes around all positive finite `(x, y)` of `points`; `None` without any.
fn axes_of(points: impl Iterator<Item = (f64, f64)>) -> Option<(DecadeAxis, DecadeAxis)> {
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for (x, y) in points.filter(|&(x, y)| positive(x) && positive(y)) {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    (x1 > 0.0).then(|| (DecadeAxis::covering(x0, x1), DecadeAxis::covering(y0, y1)))
}

fn positive(v: f64) -> bool {
    v > 0.0 && v.is_finite()
}

/// The plotting error of `path` as an output error.
fn plot_error(path: &Path) -> impl Fn(String) -> OutputError + '_ {
    move |e| OutputError::InvalidInput { path: path.to_path_buf(), detail: format!("plot: {e}") }
}

/// The palette index of each of `series`: a dashed curve right after a solid one
/// takes its colour (so such a pair shares a colour), any other curve the next one.
fn colours(series: &[Series]) -> Vec<usize> {
    let mut next = 0;
    let mut after_solid = false;
    series
        .iter()
        .map(|s| {
            if !(s.dashed && after_solid) {
                next += 1;
            }
            after_solid = !s.dashed;
            (next - 1) % PALETTE.len()
        })
        .collect()
}

/// Write a log-log plot of `series` to `path` (SVG, 900 x 600). A solid curve and the
/// dashed one after it share a colour; the legend draws each line as it is drawn
/// (dashed or solid).
pub fn write_loglog_svg(path: &Path, title: &str, x_label: &str, y_label: &str, series: &[Series]) -> Result<(), OutputError> {
    let svg = loglog_svg(path, title, (x_label, y_label), series)?;
    write_atomic(path, svg.as_bytes())
}

/// [`write_loglog_svg`] to `svg_path`, and the same plot as a PNG rendered from it to
/// `png_path`. Returns a note when the PNG has no text (no system font found).
pub fn write_loglog_plot(
    svg_path: &Path,
    png_path: &Path,
    title: &str,
    (x_label, y_label): (&str, &str),
    series: &[Series],
) -> Result<Option<String>, OutputError> {
    let svg = loglog_svg(svg_path, title, (x_label, y_label), series)?;
    write_atomic(svg_path, svg.as_bytes())?;
    svg_to_png(&svg, png_path)
}

/// The SVG text of [`write_loglog_svg`] (errors name `path`).
fn loglog_svg(path: &Path, title: &str, (x_label, y_label): (&str, &str), series: &[Series]) -> Result<String, OutputError> {
    let err = plot_error(path);
    let (xs, ys) = axes_of(series.iter().flat_map(|s| s.points.iter().copied())).ok_or_else(|| err("no positive finite points".into()))?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 600)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(xs, ys)
            .map_err(|e| err(e.to_string()))?;
        chart.configure_mesh().x_desc(x_label).y_desc(y_label).draw().map_err(|e| err(e.to_string()))?;
        for (s, c) in series.iter().zip(colours(series)) {
            let colour = PALETTE[c];
            let data: Vec<(f64, f64)> = s.points.iter().copied().filter(|&(x, y)| positive(x) && positive(y)).collect();
            let style = ShapeStyle::from(&colour).stroke_width(2);
            let drawn = if s.dashed {
                chart.draw_series(DashedLineSeries::new(data.clone(), 8, 5, style))
            } else {
                chart.draw_series(LineSeries::new(data.clone(), style))
            };
            let dashed = s.dashed;
            drawn.map_err(|e| err(e.to_string()))?.label(s.label.clone()).legend(move |(x, y)| {
                // A dashed sample for a dashed curve: two strokes with a gap.
                let second = if dashed { (x + 13, x + 22) } else { (x, x + 22) };
                EmptyElement::at((0, 0))
                    + PathElement::new(vec![(x, y), (if dashed { x + 8 } else { x + 22 }, y)], style)
                    + PathElement::new(vec![(second.0, y), (second.1, y)], style)
            });
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
    Ok(svg)
}

/// A group of points of one colour in a front plot.
pub struct PointGroup {
    /// Legend label.
    pub label: String,
    /// `(cost, error)` points whose error is exact: filled circles.
    pub exact: Vec<(f64, f64)>,
    /// `(cost, error)` points whose error is estimated: hollow circles, larger.
    pub estimated: Vec<(f64, f64)>,
}

/// One panel of a front plot: groups of points and the front as a step line.
pub struct FrontPanel {
    /// Panel caption.
    pub title: String,
    /// Axis labels.
    pub x_label: String,
    pub y_label: String,
    /// The point groups (one colour each).
    pub groups: Vec<PointGroup>,
    /// The front points (any order): drawn by cost as a staircase, the error of a
    /// front point holding until a costlier one improves it.
    pub front: Vec<(f64, f64)>,
}

/// Draw one panel into `area`.
fn draw_front_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panel: &FrontPanel,
    err: &dyn Fn(String) -> OutputError,
) -> Result<(), OutputError> {
    let all = panel.groups.iter().flat_map(|g| g.exact.iter().chain(g.estimated.iter()).copied());
    let Some((xs, ys)) = axes_of(all) else {
        // An empty panel (no run finished): its caption says so.
        area.titled(&format!("{}: no finished run", panel.title), ("sans-serif", 18)).map_err(|e| err(e.to_string()))?;
        return Ok(());
    };
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(65)
        .build_cartesian_2d(xs, ys)
        .map_err(|e| err(e.to_string()))?;
    chart.configure_mesh().x_desc(&panel.x_label).y_desc(&panel.y_label).draw().map_err(|e| err(e.to_string()))?;
    let mut front = panel.front.clone();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut steps = Vec::new();
    for (k, &(x, y)) in front.iter().enumerate() {
        if k > 0 {
            steps.push((x, front[k - 1].1));
        }
        steps.push((x, y));
    }
    let line = ShapeStyle::from(&BLACK.mix(0.6)).stroke_width(1);
    chart
        .draw_series(LineSeries::new(steps, line))
        .map_err(|e| err(e.to_string()))?
        .label("front")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], line));
    for (k, g) in panel.groups.iter().enumerate() {
        let colour = PALETTE[k % PALETTE.len()];
        let exact = g.exact.iter().copied().filter(|&(x, y)| positive(x) && positive(y));
        chart.draw_series(exact.map(|p| Circle::new(p, 4, colour.filled()))).map_err(|e| err(e.to_string()))?;
        let estimated = g.estimated.iter().copied().filter(|&(x, y)| positive(x) && positive(y));
        chart
            .draw_series(estimated.map(|p| Circle::new(p, 6, colour.stroke_width(2))))
            .map_err(|e| err(e.to_string()))?
            .label(g.label.clone())
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, colour.filled()));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| err(e.to_string()))?;
    Ok(())
}

/// Write `panels` side by side (each 700 x 560) as an SVG to `svg_path` and as a PNG
/// rendered from it to `png_path`. Filled circles are exact errors, larger hollow
/// circles estimated ones. Returns a note when the PNG has no text (no system font found).
pub fn write_front_plot(svg_path: &Path, png_path: &Path, title: &str, panels: &[FrontPanel]) -> Result<Option<String>, OutputError> {
    let err = plot_error(svg_path);
    let width = 700 * panels.len().max(1) as u32;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width, 600)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
        let root = root.titled(title, ("sans-serif", 20)).map_err(|e| err(e.to_string()))?;
        for (area, panel) in root.split_evenly((1, panels.len().max(1))).iter().zip(panels) {
            draw_front_panel(area, panel, &err)?;
        }
        root.present().map_err(|e| err(e.to_string()))?;
    }
    write_atomic(svg_path, svg.as_bytes())?;
    svg_to_png(&svg, png_path)
}

/// Render `svg` to a PNG file at its own size (resvg, system fonts; the generic
/// `sans-serif` is mapped to the first installed sans-serif family). Returns a note
/// when no font was found, so the PNG has no text.
pub fn svg_to_png(svg: &str, path: &Path) -> Result<Option<String>, OutputError> {
    use resvg::{tiny_skia, usvg};
    let err = plot_error(path);
    let mut fonts = usvg::fontdb::Database::new();
    fonts.load_system_fonts();
    let sans = fonts
        .faces()
        .flat_map(|f| f.families.iter().map(|(name, _)| name.clone()))
        .find(|n| n.contains("Sans") && !n.contains("Mono"))
        .or_else(|| fonts.faces().find_map(|f| f.families.first().map(|(n, _)| n.clone())));
    let note = match &sans {
        Some(family) => {
            fonts.set_sans_serif_family(family.clone());
            None
        }
        None => Some(format!("{}: no system font found, the PNG has no text (the SVG beside it has)", path.display())),
    };
    let options = usvg::Options { fontdb: std::sync::Arc::new(fonts), ..usvg::Options::default() };
    let tree = usvg::Tree::from_str(svg, &options).map_err(|e| err(e.to_string()))?;
    let size = tree.size().to_int_size();
    let mut pixmap = tiny_skia::Pixmap::new(size.width(), size.height()).ok_or_else(|| err("empty image".into()))?;
    pixmap.fill(tiny_skia::Color::WHITE);
    resvg::render(&tree, tiny_skia::Transform::default(), &mut pixmap.as_mut());
    let png = pixmap.encode_png().map_err(|e| err(e.to_string()))?;
    write_atomic(path, &png)?;
    Ok(note)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decades_cover_the_data_with_a_label_each() {
        let a = DecadeAxis::covering(3e-9, 0.4);
        assert_eq!(a.ticks.len(), 10, "1e-9 .. 1: ten decades");
        assert!((a.range.start - 1e-9).abs() < 1e-24 && (a.range.end - 1.0).abs() < 1e-15);
        let labels: Vec<String> = a.ticks.iter().map(|&t| decade_label(t)).collect();
        assert_eq!(labels[..3], ["1e-9", "1e-8", "1e-7"]);
        assert_eq!(labels[7..], ["0.01", "0.1", "1"]);
        // Data within one decade still gets two labelled ends.
        assert_eq!(DecadeAxis::covering(2.0, 3.0).ticks, vec![1.0, 10.0]);
    }

    #[test]
    fn loglog_svg_labels_every_decade_and_dashes_the_legend() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.svg");
        let series = vec![
            Series { label: "interior".into(), points: vec![(0.4, 0.3), (0.1, 2e-3), (0.025, 4e-6)], dashed: false },
            Series { label: "whole plate".into(), points: vec![(0.4, 0.5), (0.1, 1e-2), (0.025, 1e-4)], dashed: true },
        ];
        write_loglog_svg(&path, "t", "x", "y", &series).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        for label in ["0.01", "0.1", "1e-3", "1e-4", "1e-5", "1e-6"] {
            // plotters writes each label on a line of its own inside <text>.
            assert!(svg.contains(&format!("\n{label}\n</text>")), "label {label} missing");
        }
    }

    /// A dashed curve right after a solid one shares its colour; any other curve
    /// takes a new one.
    #[test]
    fn dashed_curves_share_the_colour_of_the_solid_one_before_them() {
        let s = |dashed| Series { label: String::new(), points: Vec::new(), dashed };
        assert_eq!(colours(&[s(false), s(true), s(false), s(true)]), [0, 0, 1, 1]);
        assert_eq!(colours(&[s(false), s(false), s(true), s(true)]), [0, 1, 1, 2]);
        assert_eq!(colours(&[s(true), s(true), s(false), s(true)]), [0, 1, 2, 2]);
    }

    #[test]
    fn loglog_plot_writes_svg_and_png() {
        let dir = tempfile::tempdir().unwrap();
        let (svg, png) = (dir.path().join("c.svg"), dir.path().join("c.png"));
        let series = vec![Series { label: "e_inf(u)".into(), points: vec![(0.1, 1e-2), (0.05, 2.5e-3)], dashed: false }];
        write_loglog_plot(&svg, &png, "convergence", ("h", "error"), &series).unwrap();
        assert_eq!(&std::fs::read(&png).unwrap()[1..4], b"PNG");
        assert!(std::fs::read_to_string(&svg).unwrap().contains("e_inf(u)"));
    }

    #[test]
    fn front_plot_writes_svg_and_png() {
        let dir = tempfile::tempdir().unwrap();
        let (svg, png) = (dir.path().join("f.svg"), dir.path().join("f.png"));
        let panel = FrontPanel {
            title: "sigma".into(),
            x_label: "seconds".into(),
            y_label: "e_inf".into(),
            groups: vec![PointGroup { label: "a".into(), exact: vec![(0.1, 1e-2), (1.0, 1e-4)], estimated: vec![(0.1, 1.1e-2)] }],
            front: vec![(0.1, 1e-2), (1.0, 1e-4)],
        };
        write_front_plot(&svg, &png, "front", &[panel]).unwrap();
        let bytes = std::fs::read(&png).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
        assert!(std::fs::read_to_string(&svg).unwrap().contains("\n1e-4\n</text>"));
    }
}
