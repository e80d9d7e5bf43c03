//! Figures as SVG with plotters: x–y panels (scatter points, fitted curves, lines), box plots and
//! the selection grid, laid out side by side in one file.
//!
//! Only finite values are drawn and every axis range is padded to a positive width, so no
//! coordinate in a file is ever NaN. A logarithmic y axis is drawn as log10(y) on a linear axis
//! with the ticks labelled in y (values ≤ 0 cannot be shown there and are counted in the title).

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

use toolconf_model::registry::AXES;
use toolconf_stats::{summary, Summary};

use super::figure_parts::wants_log;
use super::{write_atomically, ReproduceError};

pub use plotters::style::RGBColor as Colour;

pub const BLACK_: Colour = Colour(0, 0, 0);
pub const GOAL_GREY: Colour = Colour(90, 90, 90);

/// A labelled set of (x, y) values drawn as dots or as a line.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend entry ("" for none).
    pub label: String,
    pub colour: Colour,
    pub points: Vec<(f64, f64)>,
    pub dashed: bool,
}

impl Series {
    pub fn new(label: impl Into<String>, colour: Colour, points: Vec<(f64, f64)>) -> Self {
        Self {
            label: label.into(),
            colour,
            points,
            dashed: false,
        }
    }

    pub fn dashed(mut self) -> Self {
        self.dashed = true;
        self
    }
}

/// Where the legend goes.
#[derive(Debug, Clone, Copy)]
pub enum Legend {
    UpperRight,
    UpperLeft,
    LowerRight,
    LowerLeft,
}

/// An x–y panel: scatter series, line series, optional log y axis.
#[derive(Debug, Clone)]
pub struct XyPanel {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub dots: Vec<Series>,
    pub lines: Vec<Series>,
    pub log_y: bool,
    pub legend: Legend,
    /// Extra space above the data, as a fraction of its height (room for the legend).
    pub headroom: f64,
}

/// Every point's y value, across `series`.
pub fn all_y(series: &[Series]) -> Vec<f64> {
    series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1))
        .collect()
}

/// Points against confidence, no lines; log y where they span more than a factor 30.
pub fn scatter_panel(title: &str, x_label: &str, y_label: &str, dots: Vec<Series>) -> Panel {
    Panel::Xy(XyPanel {
        title: title.into(),
        x_label: x_label.into(),
        y_label: y_label.into(),
        log_y: wants_log(&all_y(&dots)),
        dots,
        lines: vec![],
        legend: Legend::UpperRight,
        headroom: 0.8,
    })
}

/// Means per level as `lines`, each mean drawn as a dot too; log y where they span more than a
/// factor 30.
pub fn means_panel(title: &str, x_label: &str, y_label: &str, lines: Vec<Series>) -> Panel {
    Panel::Xy(XyPanel {
        title: title.into(),
        x_label: x_label.into(),
        y_label: y_label.into(),
        dots: lines
            .iter()
            .map(|s| Series::new("", s.colour, s.points.clone()))
            .collect(),
        log_y: wants_log(&all_y(&lines)),
        lines,
        legend: Legend::UpperRight,
        headroom: 0.3,
    })
}

/// The tool's tip paths (`lines`, with start and goal points as `dots`) in the plane of the
/// robot's base axes `a` and `b`.
pub fn tip_path_panel(
    title: &str,
    (a, b): (usize, usize),
    dots: Vec<Series>,
    lines: Vec<Series>,
) -> Panel {
    Panel::Xy(XyPanel {
        title: title.into(),
        x_label: format!("tip {} [m]", AXES[a]),
        y_label: format!("tip {} [m]", AXES[b]),
        dots,
        lines,
        log_y: false,
        legend: Legend::UpperLeft,
        headroom: 0.6,
    })
}

/// Box plots side by side, one per group (Tukey whiskers at 1.5 IQR, outliers as rings), each
/// with its mean ± sd drawn beside it.
#[derive(Debug, Clone)]
pub struct BoxPanel {
    pub title: String,
    pub y_label: String,
    pub groups: Vec<(String, Colour, Vec<f64>)>,
}

/// A grid of coloured cells: `cells[row][column]` indexes `categories`; row 0 is drawn on top.
#[derive(Debug, Clone)]
pub struct GridPanel {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub cells: Vec<Vec<usize>>,
    pub categories: Vec<(String, Colour)>,
}

#[derive(Debug, Clone)]
pub enum Panel {
    Xy(XyPanel),
    Boxes(BoxPanel),
    Grid(GridPanel),
}

/// Draws `panels` in a row, each `panel_size` pixels, and returns the SVG text.
pub fn render(panels: &[Panel], panel_size: (u32, u32)) -> Result<String, String> {
    let mut svg = String::new();
    {
        let width = panel_size.0 * panels.len().max(1) as u32;
        let root = SVGBackend::with_string(&mut svg, (width, panel_size.1)).into_drawing_area();
        root.fill(&WHITE).map_err(text)?;
        let areas = root.split_evenly((1, panels.len().max(1)));
        for (panel, area) in panels.iter().zip(&areas) {
            match panel {
                Panel::Xy(p) => draw_xy(area, p)?,
                Panel::Boxes(p) => draw_boxes(area, p)?,
                Panel::Grid(p) => draw_grid(area, p)?,
            }
        }
        root.present().map_err(text)?;
    }
    Ok(svg)
}

/// Renders and writes `path` atomically; returns the SVG text for inlining.
pub fn save(
    path: &std::path::Path,
    panels: &[Panel],
    panel_size: (u32, u32),
) -> Result<String, ReproduceError> {
    let svg = render(panels, panel_size).map_err(|reason| ReproduceError::Plot {
        path: path.to_path_buf(),
        reason,
    })?;
    write_atomically(path, &svg)?;
    Ok(svg)
}

fn text(e: impl std::fmt::Display) -> String {
    e.to_string()
}

/// Tick label: short and exact enough (values within 1e-9 of 0 are 0, the rounding left by
/// tick arithmetic).
fn tick(v: f64) -> String {
    let a = v.abs();
    if a < 1e-9 || !v.is_finite() {
        "0".into()
    } else if (1e-2..1e5).contains(&a) {
        let s = format!("{v:.3}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        format!("{v:.1e}")
    }
}

/// Tick label of a log axis: two significant digits.
fn log_tick(v: f64) -> String {
    if !v.is_finite() || v <= 0.0 {
        return "0".into();
    }
    let magnitude = v.log10().floor();
    let rounded = (v / 10f64.powf(magnitude - 1.0)).round() * 10f64.powf(magnitude - 1.0);
    if (1e-2..1e5).contains(&rounded) {
        let decimals = (1.0 - magnitude).max(0.0) as usize;
        format!("{rounded:.decimals$}")
    } else {
        format!("{rounded:.1e}")
    }
}

/// [lo, hi] of the values, padded by 5 % (or ±0.5 when all are equal); (0, 1) if none.
pub fn padded_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(v), h.max(v))
        });
    if lo > hi {
        return (0.0, 1.0);
    }
    let width = hi - lo;
    if width <= 1e-12 * lo.abs().max(hi.abs()).max(1.0) {
        let pad = 0.5_f64.max(lo.abs() * 0.05);
        (lo - pad, hi + pad)
    } else {
        (lo - 0.05 * width, hi + 0.05 * width)
    }
}

fn legend_position(l: Legend) -> SeriesLabelPosition {
    match l {
        Legend::UpperRight => SeriesLabelPosition::UpperRight,
        Legend::UpperLeft => SeriesLabelPosition::UpperLeft,
        Legend::LowerRight => SeriesLabelPosition::LowerRight,
        Legend::LowerLeft => SeriesLabelPosition::LowerLeft,
    }
}

/// A chart on linear x and y axes of f64.
type Chart<'a, 'b, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// A series' points that can be drawn: finite, and on a log axis positive (as log10(y)); the
/// count of values ≤ 0 a log axis leaves out is added to `hidden`.
fn drawable(s: &Series, log: bool, hidden: &mut usize) -> Vec<(f64, f64)> {
    s.points
        .iter()
        .filter_map(|&(x, y)| {
            let y = if log {
                if y > 0.0 {
                    y.log10()
                } else {
                    *hidden += 1;
                    return None;
                }
            } else {
                y
            };
            (x.is_finite() && y.is_finite()).then_some((x, y))
        })
        .collect()
}

fn draw_xy<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &XyPanel) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let log = p.log_y;
    let mut hidden = 0usize;
    let dots: Vec<Vec<(f64, f64)>> = p
        .dots
        .iter()
        .map(|s| drawable(s, log, &mut hidden))
        .collect();
    let lines: Vec<Vec<(f64, f64)>> = p
        .lines
        .iter()
        .map(|s| drawable(s, log, &mut hidden))
        .collect();
    let all = || dots.iter().chain(&lines).flatten();
    let (x0, x1) = padded_range(all().map(|q| q.0));
    let (y0, y1) = padded_range(all().map(|q| q.1));
    let y1 = y1 + p.headroom.max(0.0) * (y1 - y0);
    let title = if hidden > 0 {
        format!("{} ({hidden} values ≤ 0 not shown)", p.title)
    } else {
        p.title.clone()
    };
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 15))
        .margin(10)
        .x_label_area_size(42)
        .y_label_area_size(64)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(text)?;
    let y_label = if log {
        format!("{} (log scale)", p.y_label)
    } else {
        p.y_label.clone()
    };
    let y_format = |v: &f64| {
        if log {
            log_tick(10f64.powf(*v))
        } else {
            tick(*v)
        }
    };
    chart
        .configure_mesh()
        .x_desc(p.x_label.as_str())
        .y_desc(y_label)
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&y_format)
        .max_light_lines(1)
        .light_line_style(Colour(240, 240, 240))
        .bold_line_style(Colour(215, 215, 215))
        .draw()
        .map_err(text)?;
    if draw_series(&mut chart, p, &dots, &lines)? {
        chart
            .configure_series_labels()
            .position(legend_position(p.legend))
            .background_style(WHITE.mix(0.85))
            .border_style(Colour(150, 150, 150))
            .label_font(("sans-serif", 12))
            .draw()
            .map_err(text)?;
    }
    Ok(())
}

/// The panel's lines, then its dots (`lines` and `dots` their drawable points); whether any has
/// a legend entry.
fn draw_series<DB: DrawingBackend>(
    chart: &mut Chart<'_, '_, DB>,
    p: &XyPanel,
    dots: &[Vec<(f64, f64)>],
    lines: &[Vec<(f64, f64)>],
) -> Result<bool, String>
where
    DB::ErrorType: 'static,
{
    let mut labelled = false;
    for (s, pts) in p.lines.iter().zip(lines) {
        let style = s.colour.stroke_width(2);
        let anno = if s.dashed {
            chart
                .draw_series(DashedLineSeries::new(pts.iter().copied(), 6, 4, style))
                .map_err(text)?
        } else {
            chart
                .draw_series(LineSeries::new(pts.iter().copied(), style))
                .map_err(text)?
        };
        if !s.label.is_empty() {
            labelled = true;
            anno.label(s.label.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style));
        }
    }
    for (s, pts) in p.dots.iter().zip(dots) {
        let fill = s.colour.mix(0.75).filled();
        let anno = chart
            .draw_series(pts.iter().map(|&q| Circle::new(q, 3, fill)))
            .map_err(text)?;
        if !s.label.is_empty() {
            labelled = true;
            anno.label(s.label.as_str())
                .legend(move |(x, y)| Circle::new((x + 9, y), 4, fill));
        }
    }
    Ok(labelled)
}

fn draw_boxes<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &BoxPanel) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let k = p.groups.len().max(1);
    let stats: Vec<_> = p
        .groups
        .iter()
        .map(|g| summary(&finite(&g.2)).ok())
        .collect();
    let (y0, y1) = padded_range(
        stats
            .iter()
            .flatten()
            .flat_map(|s| [s.min, s.max, s.mean - s.sd, s.mean + s.sd]),
    );
    let labels: Vec<String> = p.groups.iter().map(|g| g.0.clone()).collect();
    let mut chart = ChartBuilder::on(area)
        .caption(p.title.as_str(), ("sans-serif", 15))
        .margin(10)
        .x_label_area_size(42)
        .y_label_area_size(64)
        .build_cartesian_2d(0.5..k as f64 + 0.5, y0..y1)
        .map_err(text)?;
    let x_format = |v: &f64| {
        let i = v.round();
        if (v - i).abs() < 1e-6 && i >= 1.0 && i <= k as f64 {
            labels[i as usize - 1].clone()
        } else {
            String::new()
        }
    };
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(k)
        .x_label_formatter(&x_format)
        .y_desc(p.y_label.as_str())
        .y_label_formatter(&|v| tick(*v))
        .max_light_lines(0)
        .bold_line_style(Colour(215, 215, 215))
        .draw()
        .map_err(text)?;
    for (i, ((_, colour, values), s)) in p.groups.iter().zip(&stats).enumerate() {
        let Some(s) = s else { continue };
        draw_box(&mut chart, i as f64 + 1.0, *colour, &finite(values), s)?;
    }
    Ok(())
}

/// The finite values of `v`.
fn finite(v: &[f64]) -> Vec<f64> {
    v.iter().copied().filter(|x| x.is_finite()).collect()
}

/// One box at `x`: quartiles, whiskers to the last values within 1.5 IQR, the median, mean ±
/// sd beside it, and the values beyond the whiskers as circles.
fn draw_box<DB: DrawingBackend>(
    chart: &mut Chart<'_, '_, DB>,
    x: f64,
    colour: Colour,
    values: &[f64],
    s: &Summary,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let (l, r) = (x - 0.22, x + 0.22);
    let edge = colour.stroke_width(2);
    let iqr = s.q3 - s.q1;
    let inside = |v: &&f64| **v >= s.q1 - 1.5 * iqr && **v <= s.q3 + 1.5 * iqr;
    let lo = values.iter().filter(inside).fold(s.q1, |a, &v| a.min(v));
    let hi = values.iter().filter(inside).fold(s.q3, |a, &v| a.max(v));
    let mut shapes: Vec<PathElement<(f64, f64)>> = vec![
        PathElement::new(vec![(x, s.q3), (x, hi)], edge),
        PathElement::new(vec![(x, s.q1), (x, lo)], edge),
        PathElement::new(vec![(x - 0.1, hi), (x + 0.1, hi)], edge),
        PathElement::new(vec![(x - 0.1, lo), (x + 0.1, lo)], edge),
        PathElement::new(vec![(l, s.median), (r, s.median)], BLACK_.stroke_width(3)),
    ];
    // Mean ± sd beside the box.
    let m = x + 0.34;
    let sd_style = BLACK_.stroke_width(1);
    let (below, above) = (s.mean - s.sd, s.mean + s.sd);
    shapes.push(PathElement::new(vec![(m, below), (m, above)], sd_style));
    shapes.push(PathElement::new(
        vec![(m - 0.04, below), (m + 0.04, below)],
        sd_style,
    ));
    shapes.push(PathElement::new(
        vec![(m - 0.04, above), (m + 0.04, above)],
        sd_style,
    ));
    let corners = [(l, s.q1), (r, s.q3)];
    let fill = colour.mix(0.35).filled();
    chart
        .draw_series(std::iter::once(Rectangle::new(corners, fill)))
        .map_err(text)?;
    chart
        .draw_series(std::iter::once(Rectangle::new(corners, edge)))
        .map_err(text)?;
    chart.draw_series(shapes).map_err(text)?;
    let mean = TriangleMarker::new((m, s.mean), 5, BLACK_.filled());
    chart.draw_series(std::iter::once(mean)).map_err(text)?;
    chart
        .draw_series(
            values
                .iter()
                .filter(|v| !inside(v))
                .map(|&v| Circle::new((x, v), 3, colour.stroke_width(1))),
        )
        .map_err(text)?;
    Ok(())
}

fn draw_grid<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &GridPanel) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let rows = p.cells.len().max(1);
    let cols = p.cells.iter().map(Vec::len).max().unwrap_or(0).max(1);
    let (w, h) = area.dim_in_pixel();
    let (plot_area, legend_area) = area.split_vertically(h.saturating_sub(34));
    let mut chart = ChartBuilder::on(&plot_area)
        .caption(p.title.as_str(), ("sans-serif", 15))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(0.5..cols as f64 + 0.5, 0.5..rows as f64 + 0.5)
        .map_err(text)?;
    let int_label = |v: &f64, n: usize, flip: bool| {
        let i = v.round();
        if (v - i).abs() < 1e-6 && i >= 1.0 && i <= n as f64 {
            let i = i as usize;
            (if flip { n + 1 - i } else { i }).to_string()
        } else {
            String::new()
        }
    };
    chart
        .configure_mesh()
        .disable_mesh()
        .x_labels(cols)
        .y_labels(rows)
        .x_label_formatter(&|v| int_label(v, cols, false))
        .y_label_formatter(&|v| int_label(v, rows, true))
        .x_desc(p.x_label.as_str())
        .y_desc(p.y_label.as_str())
        .draw()
        .map_err(text)?;
    let border = Colour(120, 120, 120).stroke_width(1);
    for (r, row) in p.cells.iter().enumerate() {
        let y = (rows - r) as f64;
        for (c, &cat) in row.iter().enumerate() {
            let x = c as f64 + 1.0;
            let corners = [(x - 0.5, y - 0.5), (x + 0.5, y + 0.5)];
            let fill = p.categories.get(cat).map_or(WHITE, |c| c.1);
            chart
                .draw_series([
                    Rectangle::new(corners, fill.filled()),
                    Rectangle::new(corners, border),
                ])
                .map_err(text)?;
        }
    }
    // Legend strip: a swatch and a name per category.
    let step = (w as i32 - 40) / p.categories.len().max(1) as i32;
    for (i, (name, colour)) in p.categories.iter().enumerate() {
        let x = 40 + i as i32 * step;
        legend_area
            .draw(&Rectangle::new([(x, 8), (x + 16, 24)], colour.filled()))
            .map_err(text)?;
        legend_area
            .draw(&Rectangle::new(
                [(x, 8), (x + 16, 24)],
                BLACK_.stroke_width(1),
            ))
            .map_err(text)?;
        legend_area
            .draw(&Text::new(name.as_str(), (x + 22, 10), ("sans-serif", 13)))
            .map_err(text)?;
    }
    Ok(())
}

/// Blue (−1) through light grey (0) to red (+1), for signed values such as ΔT.
pub fn diverging(v: f64) -> Colour {
    let v = v.clamp(-1.0, 1.0);
    let grey = (190.0, 190.0, 190.0);
    let end = if v < 0.0 {
        (33.0, 102.0, 172.0)
    } else {
        (178.0, 24.0, 43.0)
    };
    let t = v.abs();
    let mix = |a: f64, b: f64| (a + (b - a) * t).round() as u8;
    Colour(mix(grey.0, end.0), mix(grey.1, end.1), mix(grey.2, end.2))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_short() {
        assert_eq!(tick(-2.2e-16), "0");
        assert_eq!(tick(0.25), "0.25");
        assert_eq!(tick(2.5e6), "2.5e6");
        assert_eq!(log_tick(31622.777), "32000");
        assert_eq!(log_tick(3.16227), "3.2");
        assert_eq!(log_tick(0.0316), "0.032");
        assert_eq!(log_tick(1e6), "1.0e6");
        assert_eq!(log_tick(100.0), "100");
    }

    #[test]
    fn constant_data_still_has_a_range() {
        let (lo, hi) = padded_range([4.6, 4.6, 4.6].into_iter());
        assert!(lo < 4.6 && hi > 4.6);
        assert_eq!(padded_range(std::iter::empty()), (0.0, 1.0));
        assert_eq!(padded_range([f64::NAN].into_iter()), (0.0, 1.0));
    }

    #[test]
    fn every_panel_kind_renders_without_nan() {
        let xy = Panel::Xy(XyPanel {
            title: "t".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            dots: vec![Series::new(
                "a",
                diverging(-0.5),
                vec![(1.0, 2.0), (1.0, 20.0)],
            )],
            lines: vec![Series::new("fit", BLACK_, vec![(1.0, 3.0), (1.0, 4.0)]).dashed()],
            log_y: true,
            legend: Legend::UpperRight,
            headroom: 0.2,
        });
        let boxes = Panel::Boxes(BoxPanel {
            title: "b".into(),
            y_label: "y".into(),
            groups: vec![
                ("F".into(), diverging(1.0), vec![1.0, 2.0, 3.0, 10.0]),
                ("J".into(), diverging(0.0), vec![1.0]),
            ],
        });
        let grid = Panel::Grid(GridPanel {
            title: "g".into(),
            x_label: "trial".into(),
            y_label: "tool".into(),
            cells: vec![vec![0, 1], vec![2, 3]],
            categories: vec![
                ("none".into(), Colour(255, 255, 255)),
                ("F".into(), Colour(200, 200, 200)),
                ("J".into(), Colour(100, 100, 100)),
                ("both".into(), BLACK_),
            ],
        });
        let svg = render(&[xy, boxes, grid], (300, 250)).unwrap();
        assert!(svg.starts_with("<svg"));
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
    }
}
