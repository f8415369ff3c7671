//! `mtsim blocks`: the interpreter's canonical output, one row per move (line, kind, end
//! point in machine coordinates, feed, tool), as a table, CSV or JSON.
//!
//! Table and CSV stream one row per move, so memory does not grow with the program; JSON
//! is one array, built in memory. A program the reader cannot read ends the output with
//! exit code 2 and the reader's message (file:line:column) on stderr. On a machine with
//! any of U V W their end points follow as three more columns (keys), after `tool`.

use std::io::Write;
use std::path::Path;

use serde::Serialize;

use crate::error::Result;
use crate::input::machine::Machine;
use crate::input::program::Direction;
use crate::input::scenario::Scenario;
use crate::motion::sampling::position_in_block;
use crate::program::{self, Feed, Motion, Move};
use crate::Axis;

/// How to print the rows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Table,
    Csv,
    Json,
}

/// One canonical move as `mtsim blocks` prints it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BlockRow {
    /// 1-based source line of the block.
    pub line: usize,
    /// `rapid`, `feed`, `arc` or `dwell`.
    pub kind: &'static str,
    /// End point, machine coordinates: X Y Z in mm, A B C in deg.
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub a: f64,
    pub b: f64,
    pub c: f64,
    /// Path feed, mm/min (G93 converted with the block's length); null for rapids and
    /// dwells, and for a feed move with no F in effect.
    pub feed_mm_min: Option<f64>,
    /// Dwell time, s; null for other moves.
    pub dwell_s: Option<f64>,
    /// Active tool number (the T of the last tool change), 0 for no tool.
    pub tool: u32,
    /// End point of U V W, mm, on a machine that has any of them; absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub u: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub v: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub w: Option<f64>,
}

impl BlockRow {
    /// The row of `m` on `machine`. Under tool-centre-point control (G43.4) the move's
    /// X Y Z are the tool tip in the table frame; the row gives the machine axes that put
    /// the tip there, as the pipeline samples them.
    pub fn of(m: &Move, machine: &Machine) -> BlockRow {
        let e = if m.tcp {
            position_in_block(m, machine, 1.0)
        } else {
            m.end
        };
        let dwell_s = match m.motion {
            Motion::Dwell { seconds } => Some(seconds),
            _ => None,
        };
        let uvw = machine.axes().iter().any(|a| a.is_secondary());
        let secondary = |a: Axis| uvw.then_some(e[a]);
        BlockRow {
            line: m.line,
            kind: m.kind().name(),
            x: e[Axis::X],
            y: e[Axis::Y],
            z: e[Axis::Z],
            a: e[Axis::A],
            b: e[Axis::B],
            c: e[Axis::C],
            feed_mm_min: feed_mm_min(m),
            dwell_s,
            tool: m.tool,
            u: secondary(Axis::U),
            v: secondary(Axis::V),
            w: secondary(Axis::W),
        }
    }
}

/// The path feed of a feed move, mm/min. Under G93 (inverse time, F in 1/min) it is F times
/// the block's length, as LinuxCNC's interpreter converts it: the XYZ length (for an arc,
/// `hypot(r·|sweep|, axial travel)`), or when X Y Z do not move the U V W length, or
/// when those do not move either the A B C length in deg.
pub fn feed_mm_min(m: &Move) -> Option<f64> {
    if matches!(m.motion, Motion::Rapid | Motion::Dwell { .. }) {
        return None;
    }
    match m.feed {
        Feed::None => None,
        Feed::PerMinute(f) => Some(f),
        Feed::InverseTime(f) => Some(f * block_length(m)),
    }
}

/// Length of a feed move as LinuxCNC counts it for inverse time: mm of X Y Z, or mm of
/// U V W when X Y Z stay, or deg of A B C when those stay too.
fn block_length(m: &Move) -> f64 {
    let d = m.end - m.start;
    let rotary = (d[Axis::A].powi(2) + d[Axis::B].powi(2) + d[Axis::C].powi(2)).sqrt();
    let secondary = (d[Axis::U].powi(2) + d[Axis::V].powi(2) + d[Axis::W].powi(2)).sqrt();
    let linear = match (m.motion, m.arc_sweep_rad()) {
        (
            Motion::Arc {
                plane, center_mm, ..
            },
            Some(sweep),
        ) => {
            let (u, v, n) = plane.axes();
            let r = (m.start[u] - center_mm[u.index()]).hypot(m.start[v] - center_mm[v.index()]);
            (r * sweep.abs()).hypot(d[n])
        }
        _ => (d[Axis::X].powi(2) + d[Axis::Y].powi(2) + d[Axis::Z].powi(2)).sqrt(),
    };
    if linear > 0.0 {
        linear
    } else if secondary > 0.0 {
        secondary
    } else {
        rotary
    }
}

/// CSV header, in the order of [`BlockRow`] (followed by [`CSV_HEADER_UVW`] on a machine
/// with U V W).
pub const CSV_HEADER: &str = "line,kind,x_mm,y_mm,z_mm,a_deg,b_deg,c_deg,feed_mm_min,dwell_s,tool";
/// The CSV columns of U V W, after [`CSV_HEADER`]'s.
pub const CSV_HEADER_UVW: &str = ",u_mm,v_mm,w_mm";

/// `,u,v,w` of a row that has them, for the CSV.
fn uvw_csv(r: &BlockRow) -> String {
    match (r.u, r.v, r.w) {
        (Some(u), Some(v), Some(w)) => format!(",{u},{v},{w}"),
        _ => String::new(),
    }
}

fn opt<T: ToString>(v: Option<T>) -> String {
    v.map_or(String::new(), |v| v.to_string())
}

fn csv_row(r: &BlockRow) -> String {
    // f64 Display is the shortest text that reads back to the same number: exact, and
    // byte-identical between runs.
    format!(
        "{},{},{},{},{},{},{},{},{},{},{}{}\n",
        r.line,
        r.kind,
        r.x,
        r.y,
        r.z,
        r.a,
        r.b,
        r.c,
        opt(r.feed_mm_min),
        opt(r.dwell_s),
        r.tool,
        uvw_csv(r)
    )
}

fn table_header(uvw: bool) -> String {
    let mut h = format!(
        "{:>6} {:<5} {:>12} {:>12} {:>12} {:>10} {:>10} {:>10} {:>11} {:>4}",
        "line", "kind", "X mm", "Y mm", "Z mm", "A deg", "B deg", "C deg", "feed mm/min", "tool"
    );
    if uvw {
        h += &format!(" {:>12} {:>12} {:>12}", "U mm", "V mm", "W mm");
    }
    h + "\n"
}

fn table_row(r: &BlockRow) -> String {
    let feed = match (r.feed_mm_min, r.dwell_s) {
        (Some(f), _) => format!("{f:.4}"),
        (None, Some(s)) => format!("{s:.4} s"),
        (None, None) => "-".to_string(),
    };
    let uvw = match (r.u, r.v, r.w) {
        (Some(u), Some(v), Some(w)) => format!(" {u:>12.4} {v:>12.4} {w:>12.4}"),
        _ => String::new(),
    };
    format!(
        "{:>6} {:<5} {:>12.4} {:>12.4} {:>12.4} {:>10.4} {:>10.4} {:>10.4} {:>11} {:>4}{uvw}\n",
        r.line, r.kind, r.x, r.y, r.z, r.a, r.b, r.c, feed, r.tool
    )
}

/// The canonical moves of the scenario's program as rows, in memory (`--json`): one
/// counter-clockwise revolution of a generated cone or circle, with no lead.
pub fn block_rows(scenario: &Scenario) -> Result<Vec<BlockRow>> {
    program::scenario_run_unchecked(scenario, Direction::Ccw)?
        .moves
        .map(|m| m.map(|m| BlockRow::of(&m, &scenario.machine)))
        .collect()
}

/// Prints the canonical moves of the scenario's program. A generated cone or circle is
/// printed as the generator emits it: one revolution, counter-clockwise, with no lead.
pub fn run(path: &Path, format: Format) -> Result<i32> {
    let scenario = Scenario::load(path)?;
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    // A closed pipe (`| head`) ends the output quietly.
    let mut write = |text: &str| out.write_all(text.as_bytes()).is_ok();
    match format {
        Format::Json => {
            let rows = block_rows(&scenario)?;
            let json = serde_json::to_string_pretty(&rows).expect("plain data serializes");
            write(&format!("{json}\n"));
        }
        Format::Csv | Format::Table => {
            let run = program::scenario_run_unchecked(&scenario, Direction::Ccw)?;
            let uvw = scenario.machine.axes().iter().any(|a| a.is_secondary());
            let (header, row): (String, fn(&BlockRow) -> String) = match format {
                Format::Csv if uvw => (format!("{CSV_HEADER}{CSV_HEADER_UVW}\n"), csv_row),
                Format::Csv => (format!("{CSV_HEADER}\n"), csv_row),
                _ => (table_header(uvw), table_row),
            };
            let mut open = write(&header);
            for m in run.moves {
                // On an error the rows before it stay printed (the writer flushes on drop).
                let m = m?;
                if open {
                    open = write(&row(&BlockRow::of(&m, &scenario.machine)));
                }
            }
        }
    }
    Ok(0)
}
