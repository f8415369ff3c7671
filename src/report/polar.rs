//! The ball-bar polar plot (SVG).
//!
//! The nominal circle is drawn at a fixed radius `R_PX`; a deviation d (um) at angle theta
//! is drawn at radius `R_PX + d * DIV_PX / scale`, where `scale` (µm per division) is the
//! smallest of 1, 2, 5 x 10^k that keeps the largest |d| within `DIVS` divisions. Theta runs
//! counter-clockwise from the right, as seen from the circle frame's +Z.
//!
//! Every run is drawn about the *common* centre (the mean of the runs' least-squares
//! centrings), so the gap between CW and CCW traces is the hysteresis. Each axis's analytic
//! reversal angles are radial ticks outside the grid, labelled with the axis letter; each
//! detected event is a ring on its trace, numbered on a circle outside the grid (the numbers
//! spread apart in angle so that they never overlap) and listed in the table on the right.
//! Each grid circle carries the deviation it stands for, in µm.
//!
//! The file is rendered in memory, written to `<path>.tmp` and renamed, so a reader never
//! sees a partial plot. The output depends only on the input (no time stamps).

use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::plot::{self, axis_colour};
use crate::error::{Error, Result};
use crate::input::program::Direction;
use crate::measure::ballbar::{BallbarResult, BallbarRun, Centring, EventKind, BIN_DEG};
use crate::Axis;

const WIDTH: u32 = 1240;
const HEIGHT: u32 = 980;
const CX: f64 = 480.0;
const CY: f64 = 540.0;
/// Radius of the nominal circle, px.
const R_PX: f64 = 250.0;
/// One division, px.
const DIV_PX: f64 = 30.0;
/// Divisions on each side of the nominal circle.
const DIVS: f64 = 4.0;
/// Left edge of the table on the right, px.
const TABLE_X: i32 = 945;
/// Most events listed in the table.
const TABLE_ROWS: usize = 30;

const GRID: RGBColor = RGBColor(205, 205, 205);
const NOMINAL: RGBColor = RGBColor(60, 60, 60);

fn direction_colour(direction: Direction) -> RGBColor {
    match direction {
        Direction::Ccw => plot::CCW,
        Direction::Cw => plot::CW,
    }
}

fn direction_name(direction: Direction) -> &'static str {
    match direction {
        Direction::Ccw => "CCW",
        Direction::Cw => "CW",
    }
}

/// The smallest of 1, 2, 5 x 10^k µm per division (at least 0.1) that keeps
/// `max_abs_um` within `DIVS` divisions.
pub fn scale_um_per_div(max_abs_um: f64) -> f64 {
    let need = if max_abs_um.is_finite() {
        max_abs_um / DIVS
    } else {
        0.0
    };
    let mut decade = 0.1;
    loop {
        for m in [1.0, 2.0, 5.0] {
            if m * decade >= need || decade > 1e9 {
                return m * decade;
            }
        }
        decade *= 10.0;
    }
}

/// Screen point at `radius_px` and `theta_deg` (counter-clockwise from the right).
fn at(radius_px: f64, theta_deg: f64) -> (i32, i32) {
    let t = theta_deg * PI / 180.0;
    let (sin, cos) = t.sin_cos();
    (
        (CX + radius_px * cos).round() as i32,
        (CY - radius_px * sin).round() as i32,
    )
}

/// A text style of `size` px. (plotters' SVG backend writes font-size as size / 1.24.)
fn font(size: f64, colour: &RGBColor, h: HPos) -> TextStyle<'static> {
    styled("sans-serif", size, colour, h)
}

fn styled(family: &'static str, size: f64, colour: &RGBColor, h: HPos) -> TextStyle<'static> {
    (family, size * 1.24)
        .into_font()
        .color(colour)
        .pos(Pos::new(h, VPos::Center))
}

/// Writes the polar plot of `runs` to `path` (SVG), atomically.
pub fn write_polar_svg(
    path: &Path,
    runs: &[BallbarRun],
    reversals: &[(Axis, Vec<f64>)],
    result: &BallbarResult,
    title: &str,
) -> Result<()> {
    let svg = render_polar_svg(runs, reversals, result, title)?;
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    let write_error = |source| Error::Write {
        path: path.to_path_buf(),
        source,
    };
    std::fs::write(&tmp, svg).map_err(write_error)?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        write_error(e)
    })
}

/// The SVG text of the polar plot.
pub fn render_polar_svg(
    runs: &[BallbarRun],
    reversals: &[(Axis, Vec<f64>)],
    result: &BallbarResult,
    title: &str,
) -> Result<String> {
    // Traces about the common centre.
    let count = runs.len().max(1) as f64;
    let centre = runs
        .iter()
        .map(BallbarRun::centring)
        .fold(Centring::default(), |acc, c| Centring {
            r0_um: acc.r0_um + c.r0_um / count,
            a_um: acc.a_um + c.a_um / count,
            b_um: acc.b_um + c.b_um / count,
        });
    let mut traces = Vec::with_capacity(runs.len());
    for run in runs {
        let raw = run.trace_um(false)?;
        let trace: Vec<f64> = raw
            .iter()
            .enumerate()
            .map(|(i, d)| {
                let theta = (i as f64 + 0.5) * BIN_DEG;
                d - centre.r0_um - centre.offset_um(theta)
            })
            .collect();
        traces.push((run.direction(), trace));
    }
    let max_abs = traces
        .iter()
        .flat_map(|(_, t)| t.iter())
        .fold(0.0f64, |m, d| m.max(d.abs()));
    let scale = scale_um_per_div(max_abs);

    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE).map_err(svg_err)?;
        draw_grid(&root)?;
        draw_reversal_ticks(&root, reversals)?;
        draw_traces(&root, &traces, scale)?;
        draw_ring_values(&root, scale)?;
        draw_event_marks(&root, &traces, result, scale)?;
        draw_header(&root, title, result, scale)?;
        draw_legend_and_table(&root, &traces, result)?;
        root.present().map_err(svg_err)?;
    }
    Ok(svg)
}

/// The drawing area of the polar plot.
type Area<'a> = DrawingArea<SVGBackend<'a>, plotters::coord::Shift>;

/// One run's direction and its centred trace, µm per θ bin.
type Trace = (Direction, Vec<f64>);

/// A drawing error of the plot, as a write error of the SVG text.
fn svg_err<E: std::error::Error + Send + Sync>(e: DrawingAreaErrorKind<E>) -> Error {
    Error::Write {
        path: PathBuf::from("<svg>"),
        source: std::io::Error::other(e.to_string()),
    }
}

/// The plot radius of a deviation `d_um` at `scale` µm per division, px, kept inside the
/// grid's inner circle and 1.5 times its outer reach.
fn radius_px(d_um: f64, scale: f64) -> f64 {
    R_PX + (d_um * DIV_PX / scale).clamp(-R_PX, 1.5 * DIVS * DIV_PX)
}

/// Circles every division, spokes every 30°, the θ labels.
fn draw_grid(root: &Area) -> Result<()> {
    // Grid: circles every division, spokes every 30 deg, theta labels.
    for k in -(DIVS as i32)..=(DIVS as i32) {
        let r = R_PX + k as f64 * DIV_PX;
        let style = if k == 0 {
            NOMINAL.stroke_width(2)
        } else {
            GRID.stroke_width(1)
        };
        root.draw(&Circle::new(
            (CX as i32, CY as i32),
            r.round() as i32,
            style,
        ))
        .map_err(svg_err)?;
    }
    for k in 0..12 {
        let theta = 30.0 * k as f64;
        let inner = R_PX - DIVS * DIV_PX;
        let outer = R_PX + DIVS * DIV_PX;
        root.draw(&PathElement::new(
            vec![at(inner, theta), at(outer, theta)],
            GRID.stroke_width(1),
        ))
        .map_err(svg_err)?;
        root.draw(&Text::new(
            format!("{theta:.0}°"),
            at(inner - 16.0, theta),
            font(12.0, &RGBColor(120, 120, 120), HPos::Center),
        ))
        .map_err(svg_err)?;
    }

    Ok(())
}

/// Each axis's reversal angles as ticks, labels staggered outward where angles crowd.
fn draw_reversal_ticks(root: &Area, reversals: &[(Axis, Vec<f64>)]) -> Result<()> {
    // Reversal ticks, labels staggered outward where angles crowd.
    let mut ticks: Vec<(f64, Axis)> = reversals
        .iter()
        .flat_map(|(axis, angles)| {
            angles
                .iter()
                .filter(|a| a.is_finite())
                .map(move |&a| (a.rem_euclid(360.0), *axis))
        })
        .collect();
    ticks.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut placed: Vec<f64> = Vec::new();
    for &(theta, axis) in &ticks {
        let crowd = placed
            .iter()
            .filter(|&&p| crate::measure::ballbar::angle_distance_deg(p, theta) < 4.0)
            .count();
        placed.push(theta);
        let colour = axis_colour(axis);
        let r0 = R_PX + DIVS * DIV_PX;
        root.draw(&PathElement::new(
            vec![at(r0 - 6.0, theta), at(r0 + 14.0, theta)],
            colour.stroke_width(2),
        ))
        .map_err(svg_err)?;
        root.draw(&Text::new(
            axis.letter().to_string(),
            at(r0 + 26.0 + 15.0 * crowd as f64, theta),
            font(14.0, &colour, HPos::Center),
        ))
        .map_err(svg_err)?;
    }

    Ok(())
}

/// Each run's trace, closed on itself.
fn draw_traces(root: &Area, traces: &[Trace], scale: f64) -> Result<()> {
    let radius = |d_um: f64| radius_px(d_um, scale);
    // Traces.
    for (direction, trace) in traces {
        let mut points: Vec<(i32, i32)> = Vec::with_capacity(trace.len() + 1);
        for (i, &d) in trace.iter().chain(trace.first()).enumerate() {
            let p = at(radius(d), (i as f64 + 0.5) * BIN_DEG);
            if points.last() != Some(&p) {
                points.push(p);
            }
        }
        root.draw(&PathElement::new(
            points,
            direction_colour(*direction).stroke_width(1),
        ))
        .map_err(svg_err)?;
    }

    Ok(())
}

/// The deviation each grid circle stands for.
fn draw_ring_values(root: &Area, scale: f64) -> Result<()> {
    // Ring values: the deviation each grid circle stands for, µm, along the 75° ray
    // (between two spokes, clear of the θ labels).
    for k in -(DIVS as i32)..=(DIVS as i32) {
        let value = k as f64 * scale;
        let label = if k == 0 {
            "0 µm".to_string()
        } else {
            format!(
                "{}{} µm",
                if k > 0 { "+" } else { "−" },
                fmt_scale(value.abs())
            )
        };
        root.draw(&Text::new(
            label,
            at(R_PX + k as f64 * DIV_PX + 4.0, 75.0),
            font(11.0, &RGBColor(110, 110, 110), HPos::Left),
        ))
        .map_err(svg_err)?;
    }

    Ok(())
}

/// The events ringed on their traces and numbered outside the grid.
fn draw_event_marks(
    root: &Area,
    traces: &[Trace],
    result: &BallbarResult,
    scale: f64,
) -> Result<()> {
    let radius = |d_um: f64| radius_px(d_um, scale);
    // Events: a ring on the trace, and its number on a circle outside the grid and the
    // reversal ticks (where no trace runs), the
    // numbers pushed apart in angle (plot::spread_labels) so that none overlap, each
    // joined to its ring by a leader line.
    let label_r = R_PX + DIVS * DIV_PX + 62.0;
    let mut marks: Vec<(usize, f64, f64, RGBColor)> = Vec::new(); // (number, θ, r, colour)
    for (number, event) in result.events.iter().enumerate() {
        let Some((_, trace)) = traces.iter().find(|(d, _)| *d == event.direction) else {
            continue;
        };
        let theta = event.peak_deg.rem_euclid(360.0);
        let bin = ((theta / BIN_DEG) as usize).min(trace.len() - 1);
        let colour = event.axis.map_or(BLACK, axis_colour);
        marks.push((number + 1, theta, radius(trace[bin]), colour));
    }
    marks.sort_by(|a, b| a.1.total_cmp(&b.1));
    // Cut the circle at its widest empty arc, so that the spreading needs no wrap.
    let cut = if marks.len() > 1 {
        let mut best = (marks[0].1 + 360.0 - marks[marks.len() - 1].1, 0);
        for i in 1..marks.len() {
            let gap = marks[i].1 - marks[i - 1].1;
            if gap > best.0 {
                best = (gap, i);
            }
        }
        best.1
    } else {
        0
    };
    marks.rotate_left(cut);
    let base = marks.first().map_or(0.0, |m| m.1);
    let unwrapped: Vec<f64> = marks
        .iter()
        .map(|m| base + (m.1 - base).rem_euclid(360.0))
        .collect();
    let gap_deg = (18.0 / label_r).to_degrees();
    let spread = super::plot::spread_labels(&unwrapped, gap_deg);
    for ((number, theta, r, colour), label_theta) in marks.iter().zip(spread) {
        root.draw(&Circle::new(at(*r, *theta), 4, colour.stroke_width(2)))
            .map_err(svg_err)?;
        root.draw(&PathElement::new(
            vec![at(*r, *theta), at(label_r - 9.0, label_theta)],
            colour.mix(0.5).stroke_width(1),
        ))
        .map_err(svg_err)?;
        root.draw(&Text::new(
            number.to_string(),
            at(label_r, label_theta),
            font(13.0, colour, HPos::Center),
        ))
        .map_err(svg_err)?;
    }

    Ok(())
}

/// The title, the figures and the scale, top left.
fn draw_header(root: &Area, title: &str, result: &BallbarResult, scale: f64) -> Result<()> {
    // Header.
    let black = RGBColor(0, 0, 0);
    let mut y = 24;
    let mut line = |text: String, size: f64, root: &DrawingArea<SVGBackend, _>| {
        let r = root.draw(&Text::new(text, (20, y), font(size, &black, HPos::Left)));
        y += (size * 1.5) as i32;
        r
    };
    line(title.to_string(), 20.0, root).map_err(svg_err)?;
    let mut figures = format!(
        "G = {:.2} µm,  F max = {:.2} µm,  F min = {:.2} µm",
        result.circular_deviation_um, result.radial_max_um, result.radial_min_um
    );
    if let Some(h) = result.hysteresis_um {
        let _ = write!(figures, ",  H = {h:.2} µm");
    }
    line(figures, 15.0, root).map_err(svg_err)?;
    line(
        format!(
            "scale: {} µm per division (nominal circle in black)",
            fmt_scale(scale)
        ),
        15.0,
        root,
    )
    .map_err(svg_err)?;
    line(
        "centred on the mean least-squares centre of the runs".to_string(),
        13.0,
        root,
    )
    .map_err(svg_err)?;

    Ok(())
}

/// The legend of the runs and ticks, and the table of events, top right.
fn draw_legend_and_table(root: &Area, traces: &[Trace], result: &BallbarResult) -> Result<()> {
    let black = RGBColor(0, 0, 0);
    // Legend and event table.
    let mut y = 40;
    let mut text = |t: String, colour: &RGBColor, size: f64, root: &DrawingArea<SVGBackend, _>| {
        let style = styled("monospace", size, colour, HPos::Left);
        let r = root.draw(&Text::new(t, (TABLE_X, y), style));
        y += (size * 1.5) as i32;
        r
    };
    let mut directions: Vec<Direction> = traces.iter().map(|(d, _)| *d).collect();
    directions.dedup();
    for d in directions {
        text(
            format!("—— {} run", direction_name(d)),
            &direction_colour(d),
            14.0,
            root,
        )
        .map_err(svg_err)?;
    }
    text(
        "| reversal angle of an axis".to_string(),
        &RGBColor(60, 60, 60),
        13.0,
        root,
    )
    .map_err(svg_err)?;
    text(String::new(), &black, 8.0, root).map_err(svg_err)?;
    text(
        format!("events ({})", result.events.len()),
        &black,
        15.0,
        root,
    )
    .map_err(svg_err)?;
    let row =
        |cells: [String; 7], colour: &RGBColor, y: i32| -> Vec<Text<'static, (i32, i32), String>> {
            const COLUMNS: [i32; 7] = [0, 20, 56, 100, 158, 204, 240];
            cells
                .into_iter()
                .zip(COLUMNS)
                .map(|(cell, dx)| {
                    Text::new(
                        cell,
                        (TABLE_X + dx, y),
                        styled("monospace", 12.0, colour, HPos::Left),
                    )
                })
                .collect()
        };
    let header = ["#", "axis", "kind", "peak θ", "µm", "run", "conf."].map(String::from);
    for cell in row(header, &black, y) {
        root.draw(&cell).map_err(svg_err)?;
    }
    y += 18;
    for (number, event) in result.events.iter().enumerate().take(TABLE_ROWS) {
        let kind = match event.kind {
            EventKind::Spike => "spike",
            EventKind::Step => "step",
        };
        let cells = [
            format!("{}", number + 1),
            event
                .axis
                .map_or("?".to_string(), |a| a.letter().to_string()),
            kind.to_string(),
            format!("{:.1}°", event.peak_deg),
            format!("{:+.1}", event.height_um),
            direction_name(event.direction).to_string(),
            format!("{:.2}", event.confidence),
        ];
        for cell in row(cells, &event.axis.map_or(black, axis_colour), y) {
            root.draw(&cell).map_err(svg_err)?;
        }
        y += 18;
    }
    if result.events.len() > TABLE_ROWS {
        let more = format!("... {} more", result.events.len() - TABLE_ROWS);
        let style = styled("monospace", 12.0, &black, HPos::Left);
        root.draw(&Text::new(more, (TABLE_X, y), style))
            .map_err(svg_err)?;
    }
    Ok(())
}

/// "5", "0.2", "20": the scale without trailing zeros.
fn fmt_scale(scale: f64) -> String {
    let s = format!("{scale:.1}");
    s.trim_end_matches(".0").to_string()
}
