//! The placement map: over a grid of cone positions on the table, where the test fits.
//!
//! Each cell runs the full `check` (travel, velocity, acceleration, collisions) with the cone
//! centre moved there. Its margin is the smallest of the linear axes' travel margins and the
//! smallest clearance between bodies that must not touch, mm: positive where the test fits
//! with that much to spare. A cell with any violation (a rotary limit or speed included)
//! does not fit, whatever its margin.

use rayon::prelude::*;
use serde::{Deserialize, Deserializer, Serialize};

use crate::check::{check, CheckOptions};
use crate::error::{Error, Result};
use crate::input::scenario::{check_cone, Program, Scenario};
use crate::study::sweep::SweepParam;

/// One grid cell.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlacementCell {
    pub x: f64,
    pub y: f64,
    /// Smallest margin, mm (negative: exceeded); infinite (JSON null) when nothing bounds it.
    #[serde(deserialize_with = "null_is_infinite")]
    pub margin_mm: f64,
    /// No violation of any kind.
    pub fits: bool,
    /// What sets the margin ("X travel", "clearance holder / workpiece", ...).
    pub limiting: String,
    /// Violations found.
    pub violations: usize,
}

/// JSON writes an infinite margin as null; read null back as +inf.
fn null_is_infinite<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::INFINITY))
}

#[derive(Clone, Debug, Serialize)]
pub struct PlacementMap {
    pub params: [String; 2],
    pub cells: Vec<PlacementCell>,
    /// The scenario's own values of the two parameters (its cone), marked on the map.
    pub scenario_at: [f64; 2],
    /// Radius of the rotary table, mm (its outline is drawn when both parameters are
    /// centre coordinates in the table plane).
    pub table_radius_mm: f64,
}

/// Checks the scenario's cone at every (x, y) of the grid, in parallel.
/// The value of `param` in `cone` (mm or deg).
fn value_of(param: SweepParam, cone: &crate::input::program::ConeTest) -> f64 {
    match param {
        SweepParam::CenterX => cone.center_mm.x,
        SweepParam::CenterY => cone.center_mm.y,
        SweepParam::CenterZ => cone.center_mm.z,
        SweepParam::HalfApex => cone.half_apex_deg,
        SweepParam::Inclination => cone.inclination_deg,
        SweepParam::BallbarLength => cone.ballbar_length_mm,
    }
}

pub fn placement_map(
    scenario: &Scenario,
    params: [SweepParam; 2],
    xs: &[f64],
    ys: &[f64],
    progress: &(dyn Fn() + Sync),
) -> Result<PlacementMap> {
    let n = xs.len() * ys.len();
    let cells = placement_cells(scenario, params, xs, ys, 0..n, progress)?;
    let (scenario_at, table_radius_mm) = scenario_marks(scenario, params);
    Ok(PlacementMap {
        params: [params[0].name().to_string(), params[1].name().to_string()],
        cells,
        scenario_at,
        table_radius_mm,
    })
}

/// What the map marks besides its cells: the scenario's own values of the two parameters
/// (zero without a cone) and the rotary table's radius, mm.
pub fn scenario_marks(scenario: &Scenario, params: [SweepParam; 2]) -> ([f64; 2], f64) {
    let at = match &scenario.program {
        Program::Cone { cone, .. } => [value_of(params[0], cone), value_of(params[1], cone)],
        _ => [0.0, 0.0],
    };
    (at, scenario.machine.scene.table.radius_mm)
}

/// The cells `range` of the grid (row by row in y, x fastest): one shard of the map.
pub fn placement_cells(
    scenario: &Scenario,
    params: [SweepParam; 2],
    xs: &[f64],
    ys: &[f64],
    range: std::ops::Range<usize>,
    progress: &(dyn Fn() + Sync),
) -> Result<Vec<PlacementCell>> {
    let Program::Cone { cone, .. } = &scenario.program else {
        return Err(Error::invalid(
            &scenario.path,
            "a placement map needs a [program.cone]",
        ));
    };
    let points: Vec<(f64, f64)> = ys
        .iter()
        .flat_map(|&y| xs.iter().map(move |&x| (x, y)))
        .collect();
    for &(x, y) in &points {
        let c = params[1].apply(&params[0].apply(cone, x), y);
        check_cone(&c).map_err(|(key, message)| {
            Error::usage(format!(
                "the grid reaches ({x}, {y}), where `{key}` is invalid: {message}"
            ))
        })?;
    }
    points[range]
        .par_iter()
        .map(|&(x, y)| {
            let mut s = scenario.clone();
            let c = params[1].apply(&params[0].apply(cone, x), y);
            if let Program::Cone { cone, .. } = &mut s.program {
                *cone = c;
            }
            s.workpiece.cone.center_mm = c.center_mm.into();
            s.workpiece.cone.half_apex_deg = c.half_apex_deg;
            s.workpiece.cone.inclination_deg = c.inclination_deg;
            s.workpiece.cone.ballbar_length_mm = c.ballbar_length_mm;
            let report = check(&s, &CheckOptions::default())?;
            progress();
            let mut margin = f64::INFINITY;
            let mut limiting = String::new();
            for (axis, usage) in &report.axes {
                if let (false, Some(m)) = ("ABC".contains(axis.as_str()), usage.margin) {
                    if m < margin {
                        margin = m;
                        limiting = format!("{axis} travel");
                    }
                }
            }
            if let (Some(c), Some(b)) = (report.min_clearance_mm, &report.min_clearance_bodies) {
                if c < margin {
                    margin = c;
                    limiting = format!("clearance {} / {}", b[0], b[1]);
                }
            }
            Ok(PlacementCell {
                x,
                y,
                margin_mm: margin,
                fits: report.is_clean(),
                limiting,
                violations: report.violations.len(),
            })
        })
        .collect::<Result<Vec<_>>>()
}

impl PlacementMap {
    /// The CSV table as Parquet: `<param x>`, `<param y>`, `margin_mm` (full precision),
    /// `fits`, `violations`, `limiting`.
    pub fn to_parquet(&self) -> Result<Vec<u8>> {
        use crate::report::parquet::{Column, Table};
        let c = &self.cells;
        Table::new()
            .with(
                &self.params[0],
                Column::F64(c.iter().map(|c| Some(c.x)).collect()),
            )
            .with(
                &self.params[1],
                Column::F64(c.iter().map(|c| Some(c.y)).collect()),
            )
            .with(
                "margin_mm",
                Column::F64(c.iter().map(|c| Some(c.margin_mm)).collect()),
            )
            .with(
                "fits",
                Column::Bool(c.iter().map(|c| Some(c.fits)).collect()),
            )
            .with(
                "violations",
                Column::U64(c.iter().map(|c| Some(c.violations as u64)).collect()),
            )
            .with(
                "limiting",
                Column::Str(c.iter().map(|c| Some(c.limiting.clone())).collect()),
            )
            .to_parquet()
    }

    pub fn to_csv(&self) -> Result<Vec<u8>> {
        let mut w = csv::Writer::from_writer(Vec::new());
        let err = |e: csv::Error| Error::usage(format!("cannot format the CSV: {e}"));
        w.write_record([
            self.params[0].as_str(),
            self.params[1].as_str(),
            "margin_mm",
            "fits",
            "violations",
            "limiting",
        ])
        .map_err(err)?;
        for c in &self.cells {
            w.write_record([
                c.x.to_string(),
                c.y.to_string(),
                format!("{:.3}", c.margin_mm),
                c.fits.to_string(),
                c.violations.to_string(),
                c.limiting.clone(),
            ])
            .map_err(err)?;
        }
        w.into_inner()
            .map_err(|e| Error::usage(format!("cannot format the CSV: {e}")))
    }

    /// The range of each parameter over the cells that fit: ((x min, x max), (y min, y max)).
    pub fn fitting_range(&self) -> Option<((f64, f64), (f64, f64))> {
        let fit: Vec<&PlacementCell> = self.cells.iter().filter(|c| c.fits).collect();
        if fit.is_empty() {
            return None;
        }
        let r = |f: &dyn Fn(&PlacementCell) -> f64| {
            fit.iter()
                .map(|c| f(c))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                    (a.min(v), b.max(v))
                })
        };
        Some((r(&|c| c.x), r(&|c| c.y)))
    }

    /// SVG heat map: one cell per grid point, coloured by the rank of its margin among the
    /// fit cells, with the scenario's position ringed and the table edge drawn; cells that do not fit are
    /// hatched grey with a cross.
    pub fn to_svg(&self, title: &str) -> Result<String> {
        use plotters::prelude::*;
        let draw_err =
            |e: &dyn std::fmt::Display| Error::usage(format!("cannot draw the map: {e}"));
        let uniq = |f: &dyn Fn(&PlacementCell) -> f64| {
            let mut v: Vec<f64> = self.cells.iter().map(|c| f(c)).collect();
            v.sort_by(f64::total_cmp);
            v.dedup();
            v
        };
        let (xs, ys) = (uniq(&|c| c.x), uniq(&|c| c.y));
        let half = |v: &[f64]| {
            if v.len() > 1 {
                (v[1] - v[0]) / 2.0
            } else {
                0.5
            }
        };
        let (hx, hy) = (half(&xs), half(&ys));
        let (x0, x1) = (xs[0] - hx, xs[xs.len() - 1] + hx);
        let (y0, y1) = (ys[0] - hy, ys[ys.len() - 1] + hy);
        // The colour scale: by rank among the distinct margins of the cells that fit
        // (to 1 µm), so that any two fit cells with different margins differ in colour,
        // however close the margins (a linear scale let one large clearance wash out the rest).
        let mut levels: Vec<f64> = self
            .cells
            .iter()
            .filter(|c| c.fits && c.margin_mm.is_finite())
            .map(|c| (c.margin_mm * 1e3).round() / 1e3)
            .collect();
        levels.sort_by(f64::total_cmp);
        levels.dedup();
        let rank = |m: f64| -> f64 {
            let m = (m * 1e3).round() / 1e3;
            let i = levels.partition_point(|&l| l < m);
            if levels.len() > 1 {
                i as f64 / (levels.len() - 1) as f64
            } else {
                1.0
            }
        };
        let level_at = |t: f64| -> f64 {
            if levels.is_empty() {
                0.0
            } else {
                levels[((t * (levels.len() - 1) as f64).round() as usize).min(levels.len() - 1)]
            }
        };
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (900, 700)).into_drawing_area();
            root.fill(&WHITE).map_err(|e| draw_err(&e))?;
            let (plot, legend) = root.split_horizontally(760);
            let mut chart = ChartBuilder::on(&plot)
                .caption(title, ("sans-serif", 18))
                .margin(15)
                .x_label_area_size(45)
                .y_label_area_size(60)
                .build_cartesian_2d(x0..x1, y0..y1)
                .map_err(|e| draw_err(&e))?;
            chart
                .configure_mesh()
                .disable_mesh()
                .x_desc(axis_title(&self.params[0]))
                .y_desc(axis_title(&self.params[1]))
                .draw()
                .map_err(|e| draw_err(&e))?;
            let colour_at = |t: f64| HSLColor(t.clamp(0.0, 1.0) * 0.66, 0.75, 0.5);
            let colour = |m: f64| colour_at(rank(m));
            chart
                .draw_series(self.cells.iter().map(|c| {
                    let style = if c.fits {
                        colour(c.margin_mm).filled()
                    } else {
                        RGBColor(200, 200, 200).filled()
                    };
                    Rectangle::new([(c.x - hx, c.y - hy), (c.x + hx, c.y + hy)], style)
                }))
                .map_err(|e| draw_err(&e))?;
            chart
                .draw_series(self.cells.iter().filter(|c| !c.fits).flat_map(|c| {
                    let (a, b) = (
                        (c.x - hx * 0.6, c.y - hy * 0.6),
                        (c.x + hx * 0.6, c.y + hy * 0.6),
                    );
                    [
                        PathElement::new(vec![a, b], RGBColor(120, 120, 120)),
                        PathElement::new(vec![(a.0, b.1), (b.0, a.1)], RGBColor(120, 120, 120)),
                    ]
                }))
                .map_err(|e| draw_err(&e))?;
            // The table outline (a circle about the C axis), when the map is of the centre's
            // X and Y, and the scenario's own position.
            if self.params[0] == "center_x" && self.params[1] == "center_y" {
                let r = self.table_radius_mm;
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        (0..=360)
                            .map(|k| {
                                let t = (k as f64).to_radians();
                                (r * t.cos(), r * t.sin())
                            })
                            .filter(|&(x, y)| x >= x0 && x <= x1 && y >= y0 && y <= y1)
                            .collect::<Vec<_>>(),
                        BLACK.stroke_width(2),
                    )))
                    .map_err(|e| draw_err(&e))?
                    .label("table edge");
            }
            let [sx, sy] = self.scenario_at;
            if sx >= x0 && sx <= x1 && sy >= y0 && sy <= y1 {
                chart
                    .draw_series([
                        Circle::new((sx, sy), 8, BLACK.stroke_width(3)),
                        Circle::new((sx, sy), 2, BLACK.filled()),
                    ])
                    .map_err(|e| draw_err(&e))?;
                chart
                    .draw_series(std::iter::once(Text::new(
                        "scenario",
                        (sx, sy),
                        ("sans-serif", 13).into_font().color(&BLACK),
                    )))
                    .map_err(|e| draw_err(&e))?;
            }
            // Outline of the mapped area.
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)],
                    BLACK.stroke_width(1),
                )))
                .map_err(|e| draw_err(&e))?;
            // Legend: the colour scale and the cross.
            let lg = legend.margin(60, 60, 10, 10);
            let (_, h) = lg.dim_in_pixel();
            for k in 0..100 {
                let t = 1.0 - k as f64 / 100.0;
                let y = (k as f64 / 100.0 * (h as f64 - 80.0)) as i32 + 30;
                lg.draw(&Rectangle::new(
                    [(0, y), (30, y + (h as i32 - 80) / 100 + 1)],
                    colour_at(t).filled(),
                ))
                .map_err(|e| draw_err(&e))?;
            }
            lg.draw(&Text::new("margin (mm)", (0, 5), ("sans-serif", 14)))
                .map_err(|e| draw_err(&e))?;
            for t in [1.0, 0.75, 0.5, 0.25, 0.0] {
                let y = ((1.0 - t) * (h as f64 - 80.0)) as i32 + 30;
                lg.draw(&Text::new(
                    format!("{:.3}", level_at(t)),
                    (35, y - 5),
                    ("sans-serif", 12),
                ))
                .map_err(|e| draw_err(&e))?;
            }
            lg.draw(&Text::new(
                "(rank scale)",
                (0, h as i32 - 48),
                ("sans-serif", 11),
            ))
            .map_err(|e| draw_err(&e))?;
            lg.draw(&Rectangle::new(
                [(0, h as i32 - 35), (30, h as i32 - 15)],
                RGBColor(200, 200, 200).filled(),
            ))
            .map_err(|e| draw_err(&e))?;
            lg.draw(&Text::new(
                "does not fit",
                (0, h as i32 - 10),
                ("sans-serif", 12),
            ))
            .map_err(|e| draw_err(&e))?;
            root.present().map_err(|e| draw_err(&e))?;
        }
        Ok(svg)
    }
}

/// A placement parameter in words, with its unit.
fn axis_title(param: &str) -> String {
    let unit = if matches!(param, "half_apex" | "inclination") {
        "deg"
    } else {
        "mm"
    };
    format!("{} ({unit})", crate::study::sweep::param_words(param))
}
