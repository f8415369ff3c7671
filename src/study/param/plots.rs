//! The plots of a study (SVG): the response of one key, the G map of two keys, and for a
//! random study the distribution of G against its limit and G's rank correlation with
//! each key.

use plotters::prelude::*;

use crate::error::Result;
use crate::report::plot::{axis_colour, draw_error, Chart, Marker, Series, CCW, CW, INK};
use crate::study::param::evaluate::Row;
use crate::study::param::stats::Share;
use crate::Axis;

/// G and each axis's B against the one varied key.
pub fn response(rows: &[Row], key: &str, axes: &[String]) -> Result<String> {
    let mut chart = Chart::new(&format!("Response to {key}"), key, "G, B (µm)", 900, 520);
    // In order of the key's value, whatever order the grid gave them in.
    let curve = |y: &dyn Fn(&Row) -> Option<f64>| -> Vec<(f64, f64)> {
        let mut points: Vec<(f64, f64)> = rows
            .iter()
            .filter_map(|r| Some((*r.values.first()?, y(r)?)))
            .collect();
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        points
    };
    chart.series.push(Series {
        label: "G".into(),
        colour: INK,
        points: curve(&|r| r.g_um),
        dots: false,
    });
    for (k, a) in axes.iter().enumerate() {
        let points = curve(&|r| r.b_um.get(k).copied().flatten());
        if points.is_empty() {
            continue;
        }
        let colour = a
            .chars()
            .next()
            .and_then(Axis::from_letter)
            .map_or(CCW, axis_colour);
        chart.series.push(Series {
            label: format!("B {a}"),
            colour,
            points,
            dots: false,
        });
    }
    chart.to_svg()
}

/// The distribution of G over the points that ran (sorted G against the share of points at
/// or below it), with the limit and the share below it with its 95 % interval.
pub fn share(rows: &[Row], limit_um: f64, share: &Share) -> Result<String> {
    let mut g: Vec<f64> = rows.iter().filter_map(|r| r.g_um).collect();
    g.sort_by(f64::total_cmp);
    let n = g.len() as f64;
    let title = format!(
        "G < {limit_um} µm in {:.1} % of points (95 % CI {:.1}–{:.1} %)",
        100.0 * share.share,
        100.0 * share.low,
        100.0 * share.high
    );
    let mut chart = Chart::new(
        &title,
        "G (µm)",
        "share of points with G at or below (%)",
        900,
        520,
    );
    chart.series.push(Series {
        label: "points".into(),
        colour: CCW,
        points: g
            .iter()
            .enumerate()
            .map(|(i, &x)| (x, 100.0 * (i + 1) as f64 / n))
            .collect(),
        dots: false,
    });
    chart.y_range = Some((0.0, 100.0));
    chart.markers.push(Marker {
        x: limit_um,
        label: format!("limit {limit_um} µm"),
        colour: CW,
    });
    chart.to_svg()
}

/// Horizontal bars: Spearman's ρ of G with each key, largest |ρ| first.
pub fn sensitivity(ranking: &[(String, f64)]) -> Result<String> {
    let mut svg = String::new();
    let height = 120 + 40 * ranking.len() as u32;
    {
        let root = SVGBackend::with_string(&mut svg, (900, height)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_error)?;
        let n = ranking.len().max(1) as f64;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "Rank correlation of G with each key (Spearman ρ)",
                ("sans-serif", 18),
            )
            .margin(15)
            .x_label_area_size(40)
            .y_label_area_size(10)
            .build_cartesian_2d(-1.0..1.0, 0.0..n)
            .map_err(draw_error)?;
        chart
            .configure_mesh()
            .disable_y_mesh()
            .disable_y_axis()
            .x_desc("ρ")
            .draw()
            .map_err(draw_error)?;
        for (i, (key, rho)) in ranking.iter().enumerate() {
            let y = n - i as f64 - 0.5;
            let colour = if *rho >= 0.0 { CW } else { CCW };
            chart
                .draw_series([Rectangle::new(
                    [(0.0, y - 0.3), (*rho, y + 0.3)],
                    colour.filled(),
                )])
                .map_err(draw_error)?;
            let x = if *rho >= 0.0 { -0.98 } else { 0.02 };
            chart
                .draw_series([Text::new(
                    format!("{key}: {rho:+.3}"),
                    (x, y + 0.15),
                    ("sans-serif", 13).into_font().color(&INK),
                )])
                .map_err(draw_error)?;
        }
        root.present().map_err(draw_error)?;
    }
    Ok(svg)
}

/// The cells of one grid key's values along an axis of the heat map, whatever order the
/// values were given in: in order of value, each cell reaches halfway to its neighbours, an
/// end cell as far out as in; a lone value's cell is 1 wide.
struct Cells {
    /// The distinct values, ascending.
    sorted: Vec<f64>,
}

impl Cells {
    fn new(values: &[f64]) -> Cells {
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        sorted.dedup();
        Cells { sorted }
    }

    /// The cell of `value`, one of the grid's: (low, high) edge.
    fn of(&self, value: f64) -> Option<(f64, f64)> {
        let s = &self.sorted;
        let i = s.binary_search_by(|v| v.total_cmp(&value)).ok()?;
        let n = s.len();
        if n == 1 {
            return Some((value - 0.5, value + 0.5));
        }
        let low = match i {
            0 => s[0] - (s[1] - s[0]) / 2.0,
            _ => (s[i - 1] + s[i]) / 2.0,
        };
        let high = match i {
            _ if i == n - 1 => s[i] + (s[i] - s[i - 1]) / 2.0,
            _ => (s[i] + s[i + 1]) / 2.0,
        };
        Some((low, high))
    }

    /// From the first cell's low edge to the last one's high edge.
    fn span(&self) -> std::ops::Range<f64> {
        let edge = |v: Option<&f64>| v.and_then(|&v| self.of(v));
        let (low, high) = (edge(self.sorted.first()), edge(self.sorted.last()));
        low.map_or(0.0, |c| c.0)..high.map_or(1.0, |c| c.1)
    }
}

/// G over a grid of two keys, a colour per cell (linear from the smallest to the largest G);
/// grey where the point failed. `xs` and `ys` are each key's values, in any order.
pub fn heat_map(rows: &[Row], keys: [&str; 2], xs: &[f64], ys: &[f64]) -> Result<String> {
    let (xs, ys) = (Cells::new(xs), Cells::new(ys));
    let g: Vec<f64> = rows.iter().filter_map(|r| r.g_um).collect();
    let (lo, hi) = g
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    let t = |x: f64| if hi > lo { (x - lo) / (hi - lo) } else { 0.5 };
    // Blue (small G) to red (large G).
    let colour_at = |t: f64| HSLColor((1.0 - t.clamp(0.0, 1.0)) * 0.66, 0.75, 0.5);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 700)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_error)?;
        let (plot, legend) = root.split_horizontally(760);
        let mut chart = ChartBuilder::on(&plot)
            .caption("G (µm) over two keys", ("sans-serif", 18))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(xs.span(), ys.span())
            .map_err(draw_error)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc(keys[0])
            .y_desc(keys[1])
            .draw()
            .map_err(draw_error)?;
        chart
            .draw_series(rows.iter().filter_map(|r| {
                let (x, y) = (xs.of(*r.values.first()?)?, ys.of(*r.values.get(1)?)?);
                let style = match r.g_um {
                    Some(g) => colour_at(t(g)).filled(),
                    None => RGBColor(200, 200, 200).filled(),
                };
                Some(Rectangle::new([(x.0, y.0), (x.1, y.1)], style))
            }))
            .map_err(draw_error)?;
        let lg = legend.margin(60, 60, 10, 10);
        let (_, h) = lg.dim_in_pixel();
        let bar = h as f64 - 80.0;
        for k in 0..100 {
            let y = (k as f64 / 100.0 * bar) as i32 + 30;
            lg.draw(&Rectangle::new(
                [(0, y), (30, y + (bar / 100.0) as i32 + 1)],
                colour_at(1.0 - k as f64 / 100.0).filled(),
            ))
            .map_err(draw_error)?;
        }
        lg.draw(&Text::new("G (µm)", (0, 5), ("sans-serif", 14)))
            .map_err(draw_error)?;
        for s in [1.0, 0.5, 0.0] {
            let y = ((1.0 - s) * bar) as i32 + 30;
            let v = if hi > lo { lo + s * (hi - lo) } else { lo };
            lg.draw(&Text::new(
                format!("{v:.2}"),
                (35, y - 5),
                ("sans-serif", 12),
            ))
            .map_err(draw_error)?;
        }
        root.present().map_err(draw_error)?;
    }
    Ok(svg)
}
