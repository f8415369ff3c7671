//! Reversal angles against one placement or geometry parameter, and the coincidences where
//! the X, Y and Z reversal angles meet (the paper's Figs. 16 and 17).
//!
//! The spread of the linear axes at a parameter value is the smallest arc of the circle
//! that holds one reversal angle of each of X, Y and Z, minimised over the choice of
//! reversals. A coincidence is a local minimum of the spread below
//! [`COINCIDENCE_SPREAD_DEG`], refined by golden-section search to [`REFINE_TOLERANCE`].

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::input::machine::Machine;
use crate::input::program::ConeTest;
use crate::input::scenario::check_cone;
use crate::program::cone::ConePath;
use crate::study::reversals::{analyse_cone, Analysis};
use crate::Axis;

/// A local minimum of the spread counts as a coincidence below this, deg.
pub const COINCIDENCE_SPREAD_DEG: f64 = 0.5;
/// Refinement tolerance of a coincidence, in the parameter's unit (mm or deg).
pub const REFINE_TOLERANCE: f64 = 0.1;

/// The parameter a sweep varies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
#[value(rename_all = "snake_case")]
pub enum SweepParam {
    CenterX,
    CenterY,
    CenterZ,
    HalfApex,
    Inclination,
    BallbarLength,
}

impl SweepParam {
    pub fn name(self) -> &'static str {
        match self {
            SweepParam::CenterX => "center_x",
            SweepParam::CenterY => "center_y",
            SweepParam::CenterZ => "center_z",
            SweepParam::HalfApex => "half_apex",
            SweepParam::Inclination => "inclination",
            SweepParam::BallbarLength => "ballbar_length",
        }
    }

    pub fn unit(self) -> &'static str {
        match self {
            SweepParam::HalfApex | SweepParam::Inclination => "deg",
            _ => "mm",
        }
    }

    /// `cone` with this parameter set to `value`.
    pub fn apply(self, cone: &ConeTest, value: f64) -> ConeTest {
        let mut c = *cone;
        match self {
            SweepParam::CenterX => c.center_mm.x = value,
            SweepParam::CenterY => c.center_mm.y = value,
            SweepParam::CenterZ => c.center_mm.z = value,
            SweepParam::HalfApex => c.half_apex_deg = value,
            SweepParam::Inclination => c.inclination_deg = value,
            SweepParam::BallbarLength => c.ballbar_length_mm = value,
        }
        c
    }
}

/// One row of a sweep.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SweepRow {
    pub value: f64,
    /// Reversal angles per axis, deg.
    pub reversals_deg: std::collections::BTreeMap<String, Vec<f64>>,
    /// Spread of the closest X/Y/Z reversal triple, deg (None if an axis does not reverse).
    pub spread_deg: Option<f64>,
}

/// A parameter value at which the X, Y and Z reversal angles meet.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Coincidence {
    pub value: f64,
    /// The mean angle of the closest triple, deg.
    pub theta_deg: f64,
    pub spread_deg: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct SweepResult {
    pub param: String,
    pub rows: Vec<SweepRow>,
    pub coincidences: Vec<Coincidence>,
}

/// The values `from, from + step, ...` up to `to` (inclusive within step/1e6).
pub fn grid(from: f64, to: f64, step: f64) -> Result<Vec<f64>> {
    if !(from.is_finite() && to.is_finite() && step.is_finite()) || step <= 0.0 || to < from {
        return Err(Error::usage(format!(
            "--from {from} --to {to} --step {step}: expected finite numbers with from <= to and step > 0"
        )));
    }
    let n = ((to - from) / step + 1e-6).floor() as usize;
    if n > 1_000_000 {
        return Err(Error::usage(format!(
            "{} steps is too many: use a larger --step (at most 1000000 steps)",
            n + 1
        )));
    }
    Ok((0..=n).map(|k| from + step * k as f64).collect())
}

/// One shard's part of a sweep: its rows, and the coincidences found at its rows before
/// neighbouring ones are merged ([`SweepResult::join`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SweepPart {
    pub rows: Vec<SweepRow>,
    pub candidates: Vec<Coincidence>,
}

impl crate::study::shard::ShardPart for SweepPart {
    fn rows(&self) -> usize {
        self.rows.len()
    }
}

/// Reversal analysis of `cone` with `param` at each value of `values`, in parallel.
/// `progress` is called once per finished value (from any thread).
pub fn sweep(
    machine: &Machine,
    cone: &ConeTest,
    param: SweepParam,
    values: &[f64],
    progress: &(dyn Fn() + Sync),
) -> Result<SweepResult> {
    let part = sweep_part(machine, cone, param, values, 0..values.len(), progress)?;
    Ok(SweepResult::join(param.name(), vec![part]))
}

/// The rows `range` of a sweep over `values` (one shard of it), in parallel. A coincidence
/// is a local minimum over neighbouring rows, so the rows just outside `range` are analysed
/// too (not returned): each shard finds exactly the coincidences of its rows.
pub fn sweep_part(
    machine: &Machine,
    cone: &ConeTest,
    param: SweepParam,
    values: &[f64],
    range: std::ops::Range<usize>,
    progress: &(dyn Fn() + Sync),
) -> Result<SweepPart> {
    for &v in values {
        check_cone(&param.apply(cone, v)).map_err(|(key, message)| {
            Error::usage(format!(
                "--vary {} reaches {v}, which makes `{key}` invalid: {message}",
                param.name()
            ))
        })?;
    }
    let halo = range.start.saturating_sub(1)..(range.end + 1).min(values.len());
    let halo = if range.is_empty() {
        range.clone()
    } else {
        halo
    };
    let rows: Vec<SweepRow> = values[halo.clone()]
        .par_iter()
        .enumerate()
        .map(|(k, &value)| {
            let analysis = analyse_at(machine, cone, param, value);
            if range.contains(&(halo.start + k)) {
                progress();
            }
            SweepRow {
                value,
                reversals_deg: analysis
                    .axes
                    .iter()
                    .map(|a| (a.axis.to_string(), a.reversals_deg.clone()))
                    .collect(),
                spread_deg: linear_spread(&analysis).map(|(s, _)| s),
            }
        })
        .collect();
    let own = range.start - halo.start..range.end - halo.start;
    let candidates = find_coincidences(machine, cone, param, &rows, own.clone());
    Ok(SweepPart {
        rows: rows[own].to_vec(),
        candidates,
    })
}

impl SweepResult {
    /// The sweep from its parts in order: rows concatenated; of neighbouring coincidences
    /// (plateaus of equal spread give several minima) the first is kept.
    pub fn join(param: &str, parts: Vec<SweepPart>) -> SweepResult {
        let mut rows = Vec::new();
        let mut coincidences: Vec<Coincidence> = Vec::new();
        for part in parts {
            rows.extend(part.rows);
            for c in part.candidates {
                if coincidences
                    .last()
                    .is_none_or(|l| (l.value - c.value).abs() > 2.0 * REFINE_TOLERANCE)
                {
                    coincidences.push(c);
                }
            }
        }
        SweepResult {
            param: param.to_string(),
            rows,
            coincidences,
        }
    }
}

fn analyse_at(machine: &Machine, cone: &ConeTest, param: SweepParam, value: f64) -> Analysis {
    let c = param.apply(cone, value);
    analyse_cone(&ConePath::new(c, machine), 1000.0)
}

/// The smallest arc (deg) holding one reversal of each of X, Y, Z, and its mid angle.
pub fn linear_spread(analysis: &Analysis) -> Option<(f64, f64)> {
    let revs = |a: Axis| {
        analysis
            .axis(a)
            .map(|m| m.reversals_deg.clone())
            .unwrap_or_default()
    };
    let (xs, ys, zs) = (revs(Axis::X), revs(Axis::Y), revs(Axis::Z));
    let mut best: Option<(f64, f64)> = None;
    for &x in &xs {
        for &y in &ys {
            for &z in &zs {
                let (spread, mid) = arc_spread([x, y, z]);
                if best.is_none_or(|(b, _)| spread < b) {
                    best = Some((spread, mid));
                }
            }
        }
    }
    best
}

/// Smallest arc containing the angles (deg) and its midpoint: 360 minus the largest gap
/// between neighbours on the circle.
fn arc_spread(mut angles: [f64; 3]) -> (f64, f64) {
    angles.sort_by(f64::total_cmp);
    let gaps = [
        angles[1] - angles[0],
        angles[2] - angles[1],
        angles[0] + 360.0 - angles[2],
    ];
    let (i, largest) =
        gaps.iter().enumerate().fold(
            (0, f64::NEG_INFINITY),
            |b, (i, &g)| if g > b.1 { (i, g) } else { b },
        );
    let start = angles[(i + 1) % 3];
    let spread = 360.0 - largest;
    (spread, (start + spread / 2.0).rem_euclid(360.0))
}

/// Coincidence candidates at the rows `own` of `rows` (in order, not yet de-duplicated),
/// refined in parallel.
fn find_coincidences(
    machine: &Machine,
    cone: &ConeTest,
    param: SweepParam,
    rows: &[SweepRow],
    own: std::ops::Range<usize>,
) -> Vec<Coincidence> {
    let spread_at = |v: f64| linear_spread(&analyse_at(machine, cone, param, v));
    let found: Vec<Option<Coincidence>> = own
        .into_par_iter()
        .map(|i| {
            let s = rows[i].spread_deg?;
            let left = i.checked_sub(1).and_then(|j| rows[j].spread_deg);
            let right = rows.get(i + 1).and_then(|r| r.spread_deg);
            if left.is_some_and(|l| l < s) || right.is_some_and(|r| r < s) {
                return None;
            }
            // Bracket the minimum by the neighbours, then golden-section search in it.
            let lo = rows[i.saturating_sub(1)].value;
            let hi = rows[(i + 1).min(rows.len() - 1)].value;
            let (mut a, mut b) = (lo, hi);
            let g = 0.5 * (5f64.sqrt() - 1.0);
            let f = |v: f64| spread_at(v).map_or(f64::INFINITY, |(s, _)| s);
            let (mut c, mut d) = (b - g * (b - a), a + g * (b - a));
            let (mut fc, mut fd) = (f(c), f(d));
            while b - a > REFINE_TOLERANCE / 10.0 {
                if fc < fd {
                    b = d;
                    d = c;
                    fd = fc;
                    c = b - g * (b - a);
                    fc = f(c);
                } else {
                    a = c;
                    c = d;
                    fc = fd;
                    d = a + g * (b - a);
                    fd = f(d);
                }
            }
            let v = 0.5 * (a + b);
            let (spread, theta) = spread_at(v)?;
            (spread < COINCIDENCE_SPREAD_DEG).then(|| Coincidence {
                value: (v / REFINE_TOLERANCE).round() / REFINE_TOLERANCE.recip(),
                theta_deg: theta,
                spread_deg: spread,
            })
        })
        .collect();
    found.into_iter().flatten().collect()
}

impl SweepResult {
    /// The CSV table as Parquet: columns `<param>`, `axis`, `reversal_deg`, `spread_deg`
    /// (null where the CSV cell is empty), full precision.
    pub fn to_parquet(&self) -> Result<Vec<u8>> {
        use crate::report::parquet::{Column, Table};
        let (mut value, mut axis, mut reversal, mut spread) = (vec![], vec![], vec![], vec![]);
        for row in &self.rows {
            for (a, angles) in &row.reversals_deg {
                for r in angles {
                    value.push(Some(row.value));
                    axis.push(Some(a.clone()));
                    reversal.push(Some(*r));
                    spread.push(row.spread_deg);
                }
            }
        }
        for c in &self.coincidences {
            value.push(Some(c.value));
            axis.push(Some("XYZ".to_string()));
            reversal.push(Some(c.theta_deg));
            spread.push(Some(c.spread_deg));
        }
        Table::new()
            .with(&self.param, Column::F64(value))
            .with("axis", Column::Str(axis))
            .with("reversal_deg", Column::F64(reversal))
            .with("spread_deg", Column::F64(spread))
            .to_parquet()
    }

    /// CSV: one row per (value, axis, reversal), then the coincidences.
    pub fn to_csv(&self) -> Result<Vec<u8>> {
        let mut w = csv::Writer::from_writer(Vec::new());
        let err = |e: csv::Error| Error::usage(format!("cannot format the CSV: {e}"));
        w.write_record([self.param.as_str(), "axis", "reversal_deg", "spread_deg"])
            .map_err(err)?;
        for row in &self.rows {
            let spread = row
                .spread_deg
                .map(|s| format!("{s:.4}"))
                .unwrap_or_default();
            for (axis, angles) in &row.reversals_deg {
                for a in angles {
                    w.write_record([
                        format!("{}", row.value),
                        axis.clone(),
                        format!("{a:.4}"),
                        spread.clone(),
                    ])
                    .map_err(err)?;
                }
            }
        }
        for c in &self.coincidences {
            w.write_record([
                format!("{}", c.value),
                "XYZ".into(),
                format!("{:.4}", c.theta_deg),
                format!("{:.4}", c.spread_deg),
            ])
            .map_err(err)?;
        }
        w.into_inner()
            .map_err(|e| Error::usage(format!("cannot format the CSV: {e}")))
    }

    /// SVG like the paper's Figs. 16/17: reversal angle of X, Y and Z against the parameter,
    /// with the coincidences ringed and numbered; drawn by the one plotting layer
    /// ([`crate::report::plot`]), the legend above the plot so that it covers no point.
    pub fn to_svg(&self, unit: &str, title: &str) -> Result<String> {
        use crate::report::plot::{axis_colour, Chart, Mark, Series};
        let mut chart = Chart::new(
            title,
            &format!("{} ({unit})", param_words(&self.param)),
            "reversal angle θ (deg)",
            900,
            620,
        );
        chart.y_range = Some((0.0, 360.0));
        if let (Some(a), Some(b)) = (self.rows.first(), self.rows.last()) {
            chart.x_range = Some(if b.value > a.value {
                (a.value, b.value)
            } else {
                (a.value - 1.0, a.value + 1.0)
            });
        }
        for axis in [Axis::X, Axis::Y, Axis::Z] {
            let name = axis.to_string();
            chart.series.push(Series {
                label: format!("{name} reversal"),
                colour: axis_colour(axis),
                points: self
                    .rows
                    .iter()
                    .flat_map(|r| {
                        r.reversals_deg
                            .get(&name)
                            .into_iter()
                            .flatten()
                            .map(move |a| (r.value, *a))
                    })
                    .collect(),
                dots: true,
            });
        }
        for (i, c) in self.coincidences.iter().enumerate() {
            chart.marks.push(Mark {
                x: c.value,
                y: c.theta_deg,
                label: format!("{}", i + 1),
                colour: plotters::style::RGBColor(0, 0, 0),
            });
            chart.series.push(Series {
                label: format!(
                    "{}: X, Y, Z coincide at {:.1} {unit}, θ {:.0}°",
                    i + 1,
                    c.value,
                    c.theta_deg
                ),
                colour: plotters::style::RGBColor(0, 0, 0),
                points: Vec::new(),
                dots: true,
            });
        }
        chart.to_svg()
    }
}

/// A sweep parameter in words, for axis titles.
pub fn param_words(name: &str) -> &str {
    match name {
        "center_x" => "cone centre X, table frame",
        "center_y" => "cone centre Y, table frame",
        "center_z" => "cone centre Z, table frame",
        "half_apex" => "cone half apex angle",
        "inclination" => "cone inclination",
        "ballbar_length" => "ball-bar length",
        other => other,
    }
}
