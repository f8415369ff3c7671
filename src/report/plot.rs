//! The one plotting layer: every x-y chart of mtsim (report, sweep) is drawn here, with
//! plotters' SVG backend, so that all plots share one look.
//!
//! The look: white ground, light grey grid, sans-serif text, axis titles that say the
//! quantity and its unit ("deviation (µm)"), the legend in a strip above the plot area (so it
//! never covers a curve), vertical marker lines with their label at the top edge, and
//! numbered marks whose labels are pushed apart so that none overlap.
//!
//! Long series are reduced by [`decimate_min_max`]: per x bucket the first, smallest and
//! largest point, so that a one-sample spike survives the reduction.

use std::path::PathBuf;

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::error::{Error, Result};
use crate::Axis;

/// Text colour of axis labels and captions.
pub const INK: RGBColor = RGBColor(30, 30, 30);
/// Grid lines.
pub const GRID: RGBColor = RGBColor(225, 225, 225);
/// Counter-clockwise and clockwise runs.
pub const CCW: RGBColor = RGBColor(20, 90, 200);
pub const CW: RGBColor = RGBColor(200, 40, 40);
/// The font family of every plot.
pub const FONT: &str = "sans-serif";

/// The colour of an axis, the same in every plot.
pub fn axis_colour(axis: Axis) -> RGBColor {
    match axis {
        Axis::X => RGBColor(215, 110, 0),
        Axis::Y => RGBColor(0, 140, 60),
        Axis::Z => RGBColor(130, 40, 170),
        Axis::A => RGBColor(140, 90, 40),
        Axis::B => RGBColor(0, 130, 140),
        Axis::C => RGBColor(90, 90, 90),
        Axis::U => RGBColor(200, 60, 120),
        Axis::V => RGBColor(90, 110, 200),
        Axis::W => RGBColor(160, 150, 30),
    }
}

/// A text style of `size` px in the plots' font.
pub fn text(size: f64, colour: &RGBColor, h: HPos) -> TextStyle<'static> {
    // plotters' SVG backend writes font-size as size / 1.24.
    (FONT, size * 1.24)
        .into_font()
        .color(colour)
        .pos(Pos::new(h, VPos::Center))
}

/// A drawing error as an mtsim error.
pub fn draw_error(e: impl std::fmt::Display) -> Error {
    Error::Write {
        path: PathBuf::from("<svg>"),
        source: std::io::Error::other(format!("cannot draw the plot: {e}")),
    }
}

/// One curve (`points` joined by lines) or point cloud.
#[derive(Clone, Debug)]
pub struct Series {
    pub label: String,
    pub colour: RGBColor,
    pub points: Vec<(f64, f64)>,
    /// Dots instead of a line.
    pub dots: bool,
}

/// A vertical marker line at x, labelled at the top of the plot area.
#[derive(Clone, Debug)]
pub struct Marker {
    pub x: f64,
    pub label: String,
    pub colour: RGBColor,
}

/// A numbered mark at a point of a curve.
#[derive(Clone, Debug)]
pub struct Mark {
    pub x: f64,
    pub y: f64,
    pub label: String,
    pub colour: RGBColor,
}

/// An x-y chart.
#[derive(Clone, Debug)]
pub struct Chart {
    pub title: String,
    /// Axis titles, with the unit: "θ (deg)", "following error (µm)".
    pub x_label: String,
    pub y_label: String,
    /// The x range; the series' extent when None.
    pub x_range: Option<(f64, f64)>,
    /// The y range; the series' extent (padded) when None.
    pub y_range: Option<(f64, f64)>,
    /// Tick every this much on x (None: plotters' choice).
    pub x_tick: Option<f64>,
    /// A y range at most this wide (or within a few ULP of the values) is flat: the plot
    /// shows one labelled value instead of ticks that all read the same. Default 1e-9 of
    /// the unit.
    pub y_resolution: f64,
    pub series: Vec<Series>,
    pub markers: Vec<Marker>,
    pub marks: Vec<Mark>,
    pub width: u32,
    pub height: u32,
}

impl Chart {
    /// An empty chart of `width` x `height` px.
    pub fn new(title: &str, x_label: &str, y_label: &str, width: u32, height: u32) -> Chart {
        Chart {
            title: title.to_string(),
            x_label: x_label.to_string(),
            y_label: y_label.to_string(),
            x_range: None,
            y_range: None,
            x_tick: None,
            y_resolution: 1e-9,
            series: Vec::new(),
            markers: Vec::new(),
            marks: Vec::new(),
            width,
            height,
        }
    }

    /// The SVG text of the chart.
    pub fn to_svg(&self) -> Result<String> {
        let finite = |p: &&(f64, f64)| p.0.is_finite() && p.1.is_finite();
        let ((x0, x1), (y0, y1), flat) = self.ranges();
        let mut svg = String::new();
        {
            let root =
                SVGBackend::with_string(&mut svg, (self.width, self.height)).into_drawing_area();
            root.fill(&WHITE).map_err(draw_error)?;
            // Title and legend strip above the plot area.
            let (head, body) = root.split_vertically(44);
            head.draw(&Text::new(
                self.title.clone(),
                (8, 12),
                text(14.0, &INK, HPos::Left),
            ))
            .map_err(draw_error)?;
            let mut x = 8;
            for s in &self.series {
                if s.label.is_empty() {
                    continue;
                }
                head.draw(&PathElement::new(
                    vec![(x, 32), (x + 18, 32)],
                    s.colour.stroke_width(3),
                ))
                .map_err(draw_error)?;
                head.draw(&Text::new(
                    s.label.clone(),
                    (x + 24, 32),
                    text(12.0, &INK, HPos::Left),
                ))
                .map_err(draw_error)?;
                x += 34 + 7 * s.label.chars().count() as i32;
            }
            let mut chart = ChartBuilder::on(&body)
                .margin_right(16)
                .margin_top(16)
                .margin_left(6)
                .margin_bottom(4)
                .x_label_area_size(40)
                .y_label_area_size(74)
                .build_cartesian_2d(x0..x1, y0..y1)
                .map_err(draw_error)?;
            let mut mesh = chart.configure_mesh();
            mesh.x_desc(self.x_label.as_str())
                .y_desc(self.y_label.as_str())
                .axis_desc_style((FONT, 15))
                .label_style((FONT, 13))
                .light_line_style(GRID.mix(0.5))
                .bold_line_style(GRID)
                .y_label_formatter(&|v| format_tick(*v));
            if flat.is_some() {
                mesh.y_labels(0);
            }
            let x_ticks;
            if let Some(step) = self.x_tick {
                x_ticks = ((x1 - x0) / step).round() as usize + 1;
                mesh.x_labels(x_ticks.min(40))
                    .x_label_formatter(&|v| format_tick(*v));
            }
            mesh.draw().map_err(draw_error)?;

            for m in &self.markers {
                if m.x < x0 || m.x > x1 {
                    continue;
                }
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        vec![(m.x, y0), (m.x, y1)],
                        m.colour.mix(0.8).stroke_width(1),
                    )))
                    .map_err(draw_error)?;
            }
            for s in &self.series {
                let points: Vec<(f64, f64)> = s.points.iter().filter(finite).copied().collect();
                if s.dots {
                    chart
                        .draw_series(points.iter().map(|p| Circle::new(*p, 2, s.colour.filled())))
                        .map_err(draw_error)?;
                } else {
                    // Break the line at gaps (NaN), one path per finite run.
                    for run in s.points.split(|p| !(p.0.is_finite() && p.1.is_finite())) {
                        if run.len() > 1 {
                            chart
                                .draw_series(std::iter::once(PathElement::new(
                                    run.to_vec(),
                                    s.colour.stroke_width(1),
                                )))
                                .map_err(draw_error)?;
                        }
                    }
                }
            }
            if let Some(mid) = flat {
                let (px, py) = chart.backend_coord(&(x0, mid));
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        vec![(x0, mid), (x1, mid)],
                        GRID.stroke_width(1),
                    )))
                    .map_err(draw_error)?;
                root.draw(&Text::new(
                    format_flat(mid, self.y_resolution),
                    (px - 6, py),
                    text(13.0 / 1.24, &INK, HPos::Right),
                ))
                .map_err(draw_error)?;
                root.draw(&Text::new(
                    format!(
                        "flat: the range is below {}",
                        format_tick(self.y_resolution.max(8.0 * f64::EPSILON * mid.abs()))
                    ),
                    (px + 8, py - 12),
                    text(11.0, &INK, HPos::Left),
                ))
                .map_err(draw_error)?;
            }
            self.draw_labels(&root, chart.plotting_area(), (x0, x1), (y0, y1))?;
            root.present().map_err(draw_error)?;
        }
        Ok(svg)
    }
}

impl Chart {
    /// The plot's x and y ranges and, for a flat signal, its value ([`Chart::flat_value`]):
    /// x over the finite points (or [`Chart::x_range`]), y over those within x, padded by 8 %
    /// (or [`Chart::y_range`], or ten resolutions about a flat value).
    #[allow(clippy::type_complexity)]
    fn ranges(&self) -> ((f64, f64), (f64, f64), Option<f64>) {
        let finite = |p: &&(f64, f64)| p.0.is_finite() && p.1.is_finite();
        let all = || {
            self.series
                .iter()
                .flat_map(|s| s.points.iter())
                .filter(finite)
        };
        let (mut x0, mut x1) = self.x_range.unwrap_or_else(|| {
            all().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p.0), b.max(p.0))
            })
        });
        if !(x0.is_finite() && x1.is_finite()) {
            (x0, x1) = (0.0, 1.0);
        }
        if x1 <= x0 {
            (x0, x1) = (x0 - 0.5, x0 + 0.5);
        }
        let in_x = |p: &&(f64, f64)| p.0 >= x0 && p.0 <= x1;
        let (mut y0, mut y1) = all()
            .filter(in_x)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p.1), b.max(p.1))
            });
        if !(y0.is_finite() && y1.is_finite()) {
            (y0, y1) = (-1.0, 1.0);
        }
        let flat = self
            .y_range
            .is_none()
            .then(|| self.flat_value(y0, y1))
            .flatten();
        let pad = ((y1 - y0) * 0.08)
            .max(1e-9 * y0.abs().max(y1.abs()))
            .max(1e-12);
        let (y0, y1) = match (self.y_range, flat) {
            (Some(range), _) => range,
            (None, Some(mid)) => {
                let half = 10.0 * self.y_resolution.max(1e-9 * mid.abs()).max(1e-12);
                (mid - half, mid + half)
            }
            (None, None) => (y0 - pad, y1 + pad),
        };
        ((x0, x1), (y0, y1), flat)
    }

    /// The markers' labels at the top edge of the plot area, pushed apart, and the numbered
    /// marks: a ring on the curve, labels spread along x above the curves.
    fn draw_labels(
        &self,
        root: &DrawingArea<SVGBackend<'_>, Shift>,
        plot: &DrawingArea<SVGBackend<'_>, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
        (x0, x1): (f64, f64),
        (y0, y1): (f64, f64),
    ) -> Result<()> {
        // Marker labels at the top edge, pushed apart.
        let top = plot.get_pixel_range().1.start - 8;
        let xs: Vec<f64> = self
            .markers
            .iter()
            .filter(|m| m.x >= x0 && m.x <= x1)
            .map(|m| plot.map_coordinate(&(m.x, y1)).0 as f64)
            .collect();
        let spread = spread_labels(&xs, 16.0);
        for (m, px) in self
            .markers
            .iter()
            .filter(|m| m.x >= x0 && m.x <= x1)
            .zip(spread)
        {
            root.draw(&Text::new(
                m.label.clone(),
                (px.round() as i32, top),
                text(11.0, &m.colour, HPos::Center),
            ))
            .map_err(draw_error)?;
        }
        // Numbered marks: a ring on the curve, labels spread along x above the curves.
        let mut marks: Vec<&Mark> = self
            .marks
            .iter()
            .filter(|m| m.x >= x0 && m.x <= x1 && m.y.is_finite())
            .collect();
        marks.sort_by(|a, b| a.x.total_cmp(&b.x));
        let xs: Vec<f64> = marks
            .iter()
            .map(|m| plot.map_coordinate(&(m.x, m.y)).0 as f64)
            .collect();
        let spread = spread_labels(&xs, 18.0);
        for (m, px) in marks.iter().zip(spread) {
            let p = plot.map_coordinate(&(m.x, m.y.clamp(y0, y1)));
            plot.draw(&Circle::new(
                (m.x, m.y.clamp(y0, y1)),
                4,
                m.colour.stroke_width(2),
            ))
            .map_err(draw_error)?;
            let label_y = if p.1 > top + 60 { p.1 - 22 } else { p.1 + 22 };
            let lx = px.round() as i32;
            root.draw(&PathElement::new(
                vec![p, (lx, label_y)],
                m.colour.mix(0.6).stroke_width(1),
            ))
            .map_err(draw_error)?;
            root.draw(&Text::new(
                m.label.clone(),
                (lx, label_y - 6),
                text(12.0, &m.colour, HPos::Center),
            ))
            .map_err(draw_error)?;
        }
        Ok(())
    }
}

impl Chart {
    /// The value of a flat signal spanning `y0..y1` (its mid-point), or None when the
    /// range is wider than [`Chart::y_resolution`] and than 8 ULP of the values.
    fn flat_value(&self, y0: f64, y1: f64) -> Option<f64> {
        let ulp = 8.0 * f64::EPSILON * y0.abs().max(y1.abs());
        (y1 - y0 <= self.y_resolution.max(ulp)).then_some(0.5 * (y0 + y1))
    }
}

/// The one label of a flat signal: `v` to the decimals `resolution` resolves (at most 9).
pub fn format_flat(v: f64, resolution: f64) -> String {
    let digits = (-resolution.log10()).ceil().clamp(0.0, 9.0) as usize;
    let s = format!("{v:.digits$}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        &s
    };
    if s == "-0" {
        "0".to_string()
    } else {
        s.to_string()
    }
}

/// Positions near `xs` (sorted ascending, px) at least `gap` apart: labels that never overlap.
/// Each cluster of crowded labels is centred on its members' mean.
pub fn spread_labels(xs: &[f64], gap: f64) -> Vec<f64> {
    // Clusters of (start index, end index), merged until no two neighbours crowd.
    let mut clusters: Vec<(usize, usize, f64)> = Vec::new(); // (first, count, left edge)
    for (i, &x) in xs.iter().enumerate() {
        clusters.push((i, 1, x));
        loop {
            let n = clusters.len();
            if n < 2 {
                break;
            }
            let (pf, pc, pl) = clusters[n - 2];
            let (cf, cc, cl) = clusters[n - 1];
            if pl + pc as f64 * gap <= cl {
                break;
            }
            let count = pc + cc;
            let mean = xs[pf..cf + cc].iter().sum::<f64>() / count as f64;
            let left = mean - (count - 1) as f64 * gap / 2.0;
            let _ = pl;
            clusters.truncate(n - 2);
            clusters.push((pf, count, left));
        }
    }
    let mut out = Vec::with_capacity(xs.len());
    for (_, count, left) in clusters {
        for k in 0..count {
            out.push(left + k as f64 * gap);
        }
    }
    out
}

/// A tick label without trailing noise: 0.5, 12, 1.25e-3.
pub fn format_tick(v: f64) -> String {
    if v == 0.0 {
        return "0".to_string();
    }
    let a = v.abs();
    if !(1e-3..1e6).contains(&a) {
        return format!("{v:.2e}");
    }
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".to_string()
    } else {
        s.to_string()
    }
}

/// At most about `2 * buckets + 1` points of `points` (sorted by x): per bucket of equal x
/// width, its first, lowest and highest point in x order. NaN points are kept as gaps.
pub fn decimate_min_max(points: &[(f64, f64)], buckets: usize) -> Vec<(f64, f64)> {
    if points.len() <= 3 * buckets.max(1) {
        return points.to_vec();
    }
    let (lo, hi) = points
        .iter()
        .filter(|p| p.0.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.0), b.max(p.0))
        });
    if !(hi > lo) {
        return points.to_vec();
    }
    let width = (hi - lo) / buckets as f64;
    let bucket = |x: f64| (((x - lo) / width) as usize).min(buckets - 1);
    let mut out = Vec::new();
    let mut i = 0;
    while i < points.len() {
        let p = points[i];
        if !(p.0.is_finite() && p.1.is_finite()) {
            out.push((f64::NAN, f64::NAN));
            i += 1;
            continue;
        }
        let b = bucket(p.0);
        let mut j = i;
        let (mut min_i, mut max_i) = (i, i);
        while j < points.len()
            && points[j].0.is_finite()
            && points[j].1.is_finite()
            && bucket(points[j].0) == b
        {
            if points[j].1 < points[min_i].1 {
                min_i = j;
            }
            if points[j].1 > points[max_i].1 {
                max_i = j;
            }
            j += 1;
        }
        let mut keep = vec![i, min_i, max_i, j - 1];
        keep.sort_unstable();
        keep.dedup();
        out.extend(keep.into_iter().map(|k| points[k]));
        i = j;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crowded_labels_are_pushed_apart_and_stay_centred() {
        let xs = [100.0, 101.0, 102.0, 300.0];
        let out = spread_labels(&xs, 10.0);
        for w in out.windows(2) {
            assert!(w[1] - w[0] >= 10.0 - 1e-9, "{out:?}");
        }
        assert!(
            (out[1] - 101.0).abs() < 1e-9,
            "cluster centred on its mean: {out:?}"
        );
        assert_eq!(out[3], 300.0);
    }

    #[test]
    fn decimation_keeps_a_one_sample_spike() {
        let mut points: Vec<(f64, f64)> = (0..10_000).map(|i| (i as f64 * 0.036, 0.0)).collect();
        points[5_000].1 = 7.0;
        let out = decimate_min_max(&points, 100);
        assert!(out.len() <= 4 * 100 + 4, "{}", out.len());
        assert!(out.iter().any(|p| p.1 == 7.0));
    }

    #[test]
    fn a_flat_value_is_labelled_to_its_resolution() {
        assert_eq!(format_flat(99.9990234, 1e-5), "99.99902");
        assert_eq!(format_flat(-1e-12, 1e-9), "0");
        assert_eq!(format_flat(100.0, 1e-9), "100");
    }

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(format_tick(0.5), "0.5");
        assert_eq!(format_tick(120.0), "120");
        assert_eq!(format_tick(-2.25), "-2.25");
    }
}
