//! The placement map: over a grid of cone positions on the table, where the test fits.
//!
//! Each cell runs the full `check` (travel, velocity, acceleration, collisions) with the cone
//! centre moved there. Its margin is the smallest of the linear axes' travel margins and the
//! smallest clearance between bodies that must not touch, and, on a rotary table, the
//! distance from the cone's base circle to the table top's edge, mm: positive where the test
//! fits with that much to spare. A cell with any violation (a rotary limit or speed
//! included), or whose cone base reaches past the table's edge, does not fit, whatever its
//! margin; its `limiting` says why.

use rayon::prelude::*;
use serde::{Deserialize, Deserializer, Serialize};

use crate::check::{check, CheckOptions};
use crate::error::{Error, Result};
use crate::input::scenario::{check_cone, Scenario};
use crate::program::test_of;
use crate::program::tests::generated_cone_mut;
use crate::study::sweep::SweepParam;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;

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
    let at = match test_of(scenario).generated_cone() {
        Some((cone, _)) => [value_of(params[0], cone), value_of(params[1], cone)],
        None => [0.0, 0.0],
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
    let test = test_of(scenario);
    let Some((cone, _)) = test.generated_cone() else {
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
            if let Some(cone) = generated_cone_mut(&mut s.program) {
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
            let mut fits = report.is_clean();
            if let Some(over) = base_overhang_mm(&s) {
                let edge = if over > 0.0 {
                    format!("cone base {over:.1} mm {OVER_THE_EDGE}")
                } else {
                    "cone base / table edge".to_string()
                };
                // A limit or collision the check found is named first; the edge beside it.
                if over > 0.0 && !fits {
                    limiting = format!("{limiting}; {edge}");
                } else if -over < margin {
                    limiting = edge;
                }
                margin = margin.min(-over);
                fits &= over <= 0.0;
            }
            Ok(PlacementCell {
                x,
                y,
                margin_mm: margin,
                fits,
                limiting,
                violations: report.violations.len(),
            })
        })
        .collect::<Result<Vec<_>>>()
}

/// The words of a cell whose cone base leaves the table (in its `limiting`).
pub const OVER_THE_EDGE: &str = "over the table edge";
/// The crosses of cells that do not fit: a limit or collision, the cone base off the table.
const LIMIT_CROSS: plotters::style::RGBColor = plotters::style::RGBColor(110, 110, 110);
const EDGE_CROSS: plotters::style::RGBColor = plotters::style::RGBColor(190, 40, 30);

/// How far the cone's base circle reaches past the edge of the rotary table's top, mm
/// (negative: inside by that much); None for a table that is not a top face about Z.
///
/// The base circle (radius ρ about O, in the plane normal to the cone axis `(−sin β, 0,
/// cos β)`) projects on the table top as `(O_x + ρ cos β cos φ, O_y + ρ sin φ)`; ρ is the
/// frustum's base `(L − R) / cos α` (R the cutter radius) for the cone frustum, else the
/// path cone's `L / cos α`. Its farthest point from the C axis, less the table radius.
pub fn base_overhang_mm(scenario: &Scenario) -> Option<f64> {
    use crate::input::scene::{TableAxis, WorkpieceKind};
    let table = &scenario.machine.scene.table;
    if table.axis != TableAxis::Z {
        return None;
    }
    let cone = &scenario.workpiece.cone;
    let (alpha, beta) = (
        cone.half_apex_deg.to_radians(),
        cone.inclination_deg.to_radians(),
    );
    let cutter = match scenario.workpiece.kind {
        WorkpieceKind::ConeFrustum => 0.5 * scenario.tool.cutter_diameter_mm,
        _ => 0.0,
    };
    let rho = (cone.ballbar_length_mm - cutter) / alpha.cos();
    let [ox, oy, _] = cone.center_mm;
    let farthest = (0..1440)
        .map(|k| {
            let phi = (k as f64 * 0.25).to_radians();
            (ox + rho * beta.cos() * phi.cos()).hypot(oy + rho * phi.sin())
        })
        .fold(0.0, f64::max);
    Some(farthest - table.radius_mm)
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

    /// SVG heat map: one cell per grid point, coloured linearly by its margin (mm) between
    /// the smallest and largest margin of the fit cells, with the scenario's position ringed and the table edge drawn; cells that do not fit are
    /// hatched grey with a cross.
    pub fn to_svg(&self, title: &str) -> Result<String> {
        use plotters::prelude::*;
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
        // The colour scale: linear in the margin, mm, from the smallest to the largest
        // margin of the cells that fit.
        let (lo, hi) = self
            .cells
            .iter()
            .filter(|c| c.fits && c.margin_mm.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), c| {
                (a.min(c.margin_mm), b.max(c.margin_mm))
            });
        let span = if hi > lo { hi - lo } else { 1.0 };
        let scale = |m: f64| -> f64 {
            if lo.is_finite() {
                ((m - lo) / span).clamp(0.0, 1.0)
            } else {
                1.0
            }
        };
        let level_at = |t: f64| -> f64 {
            if lo.is_finite() {
                lo + t * (hi - lo)
            } else {
                0.0
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
            let colour = |m: f64| margin_colour(scale(m));
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
                    let colour = if c.limiting.contains(OVER_THE_EDGE) {
                        EDGE_CROSS
                    } else {
                        LIMIT_CROSS
                    };
                    [
                        PathElement::new(vec![a, b], colour.stroke_width(2)),
                        PathElement::new(vec![(a.0, b.1), (b.0, a.1)], colour.stroke_width(2)),
                    ]
                }))
                .map_err(|e| draw_err(&e))?;
            self.draw_landmarks(&mut chart, (x0, x1), (y0, y1))?;
            // Outline of the mapped area.
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)],
                    BLACK.stroke_width(1),
                )))
                .map_err(|e| draw_err(&e))?;
            draw_legend(&legend, level_at)?;
            root.present().map_err(|e| draw_err(&e))?;
        }
        Ok(svg)
    }

    /// The map's landmarks: the table outline (a circle about the C axis) with its label,
    /// when the map is of the centre's X and Y, and the scenario's own position, ringed;
    /// each where it lies within `x0..x1`, `y0..y1`.
    fn draw_landmarks(
        &self,
        chart: &mut plotters::prelude::ChartContext<
            '_,
            plotters::prelude::SVGBackend<'_>,
            plotters::prelude::Cartesian2d<RangedCoordf64, RangedCoordf64>,
        >,
        (x0, x1): (f64, f64),
        (y0, y1): (f64, f64),
    ) -> Result<()> {
        use plotters::prelude::*;
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
                .map_err(|e| draw_err(&e))?;
            // Its label at the top of the circle, or where it enters the map.
            let (lx, ly) = if r <= y1 && r >= y0 && 0.0 >= x0 && 0.0 <= x1 {
                (0.0, r)
            } else {
                (x0 + 0.02 * (x1 - x0), y1 - 0.04 * (y1 - y0))
            };
            chart
                .draw_series(std::iter::once(Text::new(
                    format!("table edge (radius {r} mm)"),
                    (lx, ly),
                    ("sans-serif", 13).into_font().color(&BLACK),
                )))
                .map_err(|e| draw_err(&e))?;
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
        Ok(())
    }
}

/// The map's legend in `legend`: the colour scale from the smallest to the largest margin
/// (`level_at(t)` for `t` from 0 to 1, mm) and what the cell crosses mean.
fn draw_legend(
    legend: &plotters::prelude::DrawingArea<plotters::prelude::SVGBackend<'_>, Shift>,
    level_at: impl Fn(f64) -> f64,
) -> Result<()> {
    use plotters::prelude::*;
    let lg = legend.margin(60, 60, 10, 10);
    let (_, h) = lg.dim_in_pixel();
    for k in 0..100 {
        let t = 1.0 - k as f64 / 100.0;
        let y = (k as f64 / 100.0 * (h as f64 - 130.0)) as i32 + 30;
        lg.draw(&Rectangle::new(
            [(0, y), (30, y + (h as i32 - 130) / 100 + 1)],
            margin_colour(t).filled(),
        ))
        .map_err(|e| draw_err(&e))?;
    }
    lg.draw(&Text::new("margin (mm)", (0, 5), ("sans-serif", 14)))
        .map_err(|e| draw_err(&e))?;
    for t in [1.0, 0.75, 0.5, 0.25, 0.0] {
        let y = ((1.0 - t) * (h as f64 - 130.0)) as i32 + 30;
        lg.draw(&Text::new(
            format!("{:.2}", level_at(t)),
            (35, y - 5),
            ("sans-serif", 12),
        ))
        .map_err(|e| draw_err(&e))?;
    }
    lg.draw(&Text::new(
        "(linear scale)",
        (0, h as i32 - 92),
        ("sans-serif", 11),
    ))
    .map_err(|e| draw_err(&e))?;
    lg.draw(&Rectangle::new(
        [(0, h as i32 - 76), (30, h as i32 - 58)],
        RGBColor(200, 200, 200).filled(),
    ))
    .map_err(|e| draw_err(&e))?;
    for (k, (line, colour)) in [
        ("does not fit:", BLACK),
        ("× a limit or collision", LIMIT_CROSS),
        ("× cone base over", EDGE_CROSS),
        ("   the table edge", EDGE_CROSS),
    ]
    .into_iter()
    .enumerate()
    {
        lg.draw(&Text::new(
            line,
            (0, h as i32 - 44 + 13 * k as i32),
            ("sans-serif", 11).into_font().color(&colour),
        ))
        .map_err(|e| draw_err(&e))?;
    }
    Ok(())
}

/// The colour of scale position `t` (0 the smallest margin, 1 the largest): hue from red
/// to blue.
fn margin_colour(t: f64) -> plotters::prelude::HSLColor {
    plotters::prelude::HSLColor(t.clamp(0.0, 1.0) * 0.66, 0.75, 0.5)
}

/// A drawing error of the map, as a usage error.
fn draw_err(e: &dyn std::fmt::Display) -> Error {
    Error::usage(format!("cannot draw the map: {e}"))
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
