//! `report.html`: one self-contained page per run folder, for people to open.
//!
//! Reads what `simulate` wrote into the folder — `summary.json`, `test.json`, `trace.csv`
//! (or `trace.parquet`), `ballbar.svg`, `check.json`, and `placement.svg` / `sweep-*.svg`
//! when present — and writes one HTML file with inline SVG and CSS: no network, no
//! JavaScript. Sections:
//! test parameters (ISO 230-4, 5.2), the figures (G, F, H per direction and
//! bi-directional), the polar plot, deviation against θ, each axis's position, velocity and
//! following error against θ with its reversal angles (the paper's Figs. 5 and 11), the mark
//! table with attribution, the diagnoses, the limits and collision summary, and links to
//! the files beside it. The page depends only on the folder's files (and the `date` given),
//! so the same run gives the same bytes.
//!
//! Velocity is the central difference of the actual position over the trace's time column,
//! `v_i = (p_{i+1} - p_{i-1}) / (t_{i+1} - t_{i-1})`, in mm/min (deg/min for rotary axes).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde_json::Value;

use super::plot::{self, Chart, Mark, Marker, Series};
use super::test_info::{TestParameters, TEST_FILE};
use crate::error::{Error, Result};
use crate::Axis;

/// The file a report is written to, in the run folder.
pub const REPORT_FILE: &str = "report.html";
/// The limits and collision summary a simulation leaves beside its trace.
pub const CHECK_FILE: &str = "check.json";

/// Points per curve after decimation (per direction).
const BUCKETS: usize = 900;

/// One direction's columns of `trace.csv`.
#[derive(Clone, Debug, Default)]
pub struct TraceRun {
    pub direction: String,
    pub time_s: Vec<f64>,
    pub theta_deg: Vec<f64>,
    pub deviation_centred_um: Vec<f64>,
    /// Per axis: actual position and following error (mm or deg).
    pub actual: Vec<Vec<f64>>,
    pub following_error: Vec<Vec<f64>>,
}

/// `trace.csv`, by direction.
#[derive(Clone, Debug, Default)]
pub struct Trace {
    pub axes: Vec<Axis>,
    pub runs: Vec<TraceRun>,
}

/// The file at `path`, or None when there is none.
fn open_if_present(path: &Path) -> Result<Option<std::fs::File>> {
    match std::fs::File::open(path) {
        Ok(f) => Ok(Some(f)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(source) => Err(Error::Read {
            path: path.to_path_buf(),
            source,
        }),
    }
}

/// The run a trace row of `direction` belongs to: the last one, or a new one where the
/// direction changes (the rows of one direction come together).
fn run_of<'r>(runs: &'r mut Vec<TraceRun>, direction: &str, n_axes: usize) -> &'r mut TraceRun {
    if runs.last().is_none_or(|r| r.direction != direction) {
        runs.push(TraceRun {
            direction: direction.to_string(),
            actual: vec![Vec::new(); n_axes],
            following_error: vec![Vec::new(); n_axes],
            ..TraceRun::default()
        });
    }
    runs.last_mut().expect("pushed above")
}

/// Reads `trace.parquet` (`[simulate] trace_format = "parquet"`): the columns of
/// `trace.csv`, as f64; None when the file is missing.
pub fn read_trace_parquet(path: &Path) -> Result<Option<Trace>> {
    use arrow::array::{Array, Float64Array, RecordBatchReader, StringArray};
    use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;

    let Some(file) = open_if_present(path)? else {
        return Ok(None);
    };
    let bad = |what: String| Error::invalid(path, what);
    let reader = ParquetRecordBatchReaderBuilder::try_new(file)
        .and_then(|b| b.build())
        .map_err(|e| bad(format!("not a readable Parquet file: {e}")))?;
    let schema = reader.schema();
    let names: Vec<String> = schema.fields().iter().map(|f| f.name().clone()).collect();
    let mut axes = Vec::new();
    for axis in Axis::ALL {
        let unit = axis.unit();
        if names.contains(&format!("{axis}_act_{unit}"))
            && names.contains(&format!("{axis}_ferr_{unit}"))
        {
            axes.push(axis);
        }
    }
    let mut runs: Vec<TraceRun> = Vec::new();
    for batch in reader {
        let batch = batch.map_err(|e| bad(format!("cannot read a row group: {e}")))?;
        let floats = |name: &str| -> Result<&Float64Array> {
            batch
                .column_by_name(name)
                .and_then(|c| c.as_any().downcast_ref::<Float64Array>())
                .ok_or_else(|| bad(format!("no f64 column `{name}`")))
        };
        let direction = batch
            .column_by_name("direction")
            .and_then(|c| c.as_any().downcast_ref::<StringArray>())
            .ok_or_else(|| bad("no text column `direction`".into()))?;
        let (time, theta, dev) = (
            floats("time_s")?,
            floats("theta_deg")?,
            floats("deviation_centred_um")?,
        );
        let mut axis_columns = Vec::new();
        for axis in &axes {
            let unit = axis.unit();
            axis_columns.push((
                floats(&format!("{axis}_act_{unit}"))?,
                floats(&format!("{axis}_ferr_{unit}"))?,
            ));
        }
        let value = |a: &Float64Array, i: usize| if a.is_null(i) { f64::NAN } else { a.value(i) };
        for i in 0..batch.num_rows() {
            let dir = if direction.is_null(i) {
                ""
            } else {
                direction.value(i)
            };
            let run = run_of(&mut runs, dir, axes.len());
            run.time_s.push(value(time, i));
            run.theta_deg.push(value(theta, i));
            run.deviation_centred_um.push(value(dev, i));
            for (k, (a, f)) in axis_columns.iter().enumerate() {
                run.actual[k].push(value(a, i));
                run.following_error[k].push(value(f, i));
            }
        }
    }
    Ok(Some(Trace { axes, runs }))
}

/// Reads `trace.csv`; None when the file is missing.
pub fn read_trace(path: &Path) -> Result<Option<Trace>> {
    let Some(file) = open_if_present(path)? else {
        return Ok(None);
    };
    let bad = |what: String| Error::invalid(path, what);
    let mut reader = csv::Reader::from_reader(std::io::BufReader::new(file));
    let header = reader
        .headers()
        .map_err(|e| bad(format!("cannot read the header: {e}")))?
        .clone();
    let col = |name: &str| header.iter().position(|h| h == name);
    let need = |name: &str| col(name).ok_or_else(|| bad(format!("no column `{name}`")));
    let (c_dir, c_time, c_theta, c_dev) = (
        need("direction")?,
        need("time_s")?,
        need("theta_deg")?,
        need("deviation_centred_um")?,
    );
    let mut axes = Vec::new();
    let mut axis_cols = Vec::new();
    for axis in Axis::ALL {
        let unit = if axis.is_rotary() { "deg" } else { "mm" };
        if let (Some(a), Some(f)) = (
            col(&format!("{axis}_act_{unit}")),
            col(&format!("{axis}_ferr_{unit}")),
        ) {
            axes.push(axis);
            axis_cols.push((a, f));
        }
    }
    let mut runs: Vec<TraceRun> = Vec::new();
    for (i, record) in reader.records().enumerate() {
        let record = record.map_err(|e| bad(format!("row {}: {e}", i + 2)))?;
        let num = |c: usize| -> f64 {
            record
                .get(c)
                .and_then(|s| s.trim().parse().ok())
                .unwrap_or(f64::NAN)
        };
        let run = run_of(&mut runs, record.get(c_dir).unwrap_or(""), axes.len());
        run.time_s.push(num(c_time));
        run.theta_deg.push(num(c_theta));
        run.deviation_centred_um.push(num(c_dev));
        for (k, &(a, f)) in axis_cols.iter().enumerate() {
            run.actual[k].push(num(a));
            run.following_error[k].push(num(f));
        }
    }
    Ok(Some(Trace { axes, runs }))
}

/// Everything a report shows, read from a run folder.
#[derive(Clone, Debug)]
pub struct RunFolder {
    pub dir: PathBuf,
    pub summary: Value,
    pub test: Option<TestParameters>,
    pub check: Option<Value>,
    pub trace: Option<Trace>,
    /// Inline SVG documents found beside the trace: (file name, text).
    pub svgs: Vec<(String, String)>,
    /// Every CSV, JSON, SVG and NC file in the folder (for the links).
    pub files: Vec<String>,
}

fn read_json(path: &Path) -> Result<Option<Value>> {
    match std::fs::read_to_string(path) {
        Ok(text) => serde_json::from_str(&text)
            .map(Some)
            .map_err(|e| Error::invalid(path, format!("not valid JSON: {e}"))),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(source) => Err(Error::Read {
            path: path.to_path_buf(),
            source,
        }),
    }
}

impl RunFolder {
    /// Reads the run folder `dir` (what `mtsim simulate -o dir` wrote).
    pub fn read(dir: &Path) -> Result<RunFolder> {
        let summary_path = dir.join("summary.json");
        let summary = read_json(&summary_path)?.ok_or_else(|| {
            Error::invalid(
                &summary_path,
                "no summary.json: not a run folder".to_string(),
            )
            .with_help("give the folder `mtsim simulate SCENARIO -o FOLDER` wrote")
        })?;
        let test = match read_json(&dir.join(TEST_FILE))? {
            Some(v) => Some(serde_json::from_value(v).map_err(|e| {
                Error::invalid(&dir.join(TEST_FILE), format!("unexpected contents: {e}"))
            })?),
            None => None,
        };
        let check = read_json(&dir.join(CHECK_FILE))?;
        let trace = match read_trace(&dir.join("trace.csv"))? {
            Some(trace) => Some(trace),
            None => read_trace_parquet(&dir.join("trace.parquet"))?,
        };
        let mut files: Vec<String> = std::fs::read_dir(dir)
            .map_err(|source| Error::Read {
                path: dir.to_path_buf(),
                source,
            })?
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| {
                [".csv", ".json", ".svg", ".nc", ".parquet"]
                    .iter()
                    .any(|ext| n.ends_with(ext))
            })
            .collect();
        files.sort();
        let mut svgs = Vec::new();
        for name in &files {
            if name == "ballbar.svg" || name == "placement.svg" || name.starts_with("sweep-") {
                if let Ok(text) = std::fs::read_to_string(dir.join(name)) {
                    svgs.push((name.clone(), text));
                }
            }
        }
        Ok(RunFolder {
            dir: dir.to_path_buf(),
            summary,
            test,
            check,
            trace,
            svgs,
            files,
        })
    }
}

/// Escapes text for HTML.
pub fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// An SVG document as an inline element: without the XML prolog, with a class and a
/// `data-plot` name (for tests), scaled to the page width.
fn inline_svg(svg: &str, name: &str) -> String {
    let start = svg.find("<svg").unwrap_or(0);
    let body = &svg[start..];
    let body = body.replacen(
        "<svg",
        &format!("<svg class=\"plot\" data-plot=\"{}\"", esc(name)),
        1,
    );
    // A viewBox so that the plot scales with the page.
    let with_box = match (attr(&body, "width"), attr(&body, "height")) {
        (Some(w), Some(h)) if !body[..body.find('>').unwrap_or(0)].contains("viewBox") => body
            .replacen(
                "<svg",
                &format!("<svg viewBox=\"0 0 {w} {h}\" preserveAspectRatio=\"xMinYMin meet\""),
                1,
            ),
        _ => body,
    };
    format!("<figure>{with_box}</figure>\n")
}

fn attr(svg: &str, name: &str) -> Option<String> {
    let head = &svg[..svg.find('>')?];
    let key = format!(" {name}=\"");
    let i = head.find(&key)? + key.len();
    let j = head[i..].find('"')? + i;
    Some(head[i..j].to_string())
}

fn num(v: &Value) -> Option<f64> {
    v.as_f64()
}

fn fmt_opt(v: Option<f64>, digits: usize, unit: &str) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{x:.digits$} {unit}").trim_end().to_string(),
        _ => "–".to_string(),
    }
}

fn axis_unit(axis: Axis) -> (&'static str, &'static str, &'static str, f64) {
    // (position unit, velocity unit, following-error unit, following-error scale)
    if axis.is_rotary() {
        ("deg", "deg/min", "mdeg", 1e3)
    } else {
        ("mm", "mm/min", "µm", 1e3)
    }
}

fn direction_colour(direction: &str) -> plotters::style::RGBColor {
    if direction == "cw" {
        plot::CW
    } else {
        plot::CCW
    }
}

/// One event of `summary.json`'s ball-bar result.
struct Event {
    number: usize,
    theta_deg: f64,
    height_um: f64,
    width_deg: f64,
    kind: String,
    direction: String,
    axis: Option<String>,
    confidence: f64,
}

fn events(summary: &Value) -> Vec<Event> {
    summary["ballbar"]["spikes"]
        .as_array()
        .map(|a| {
            a.iter()
                .enumerate()
                .map(|(i, e)| Event {
                    number: i + 1,
                    theta_deg: num(&e["theta_deg"]).unwrap_or(f64::NAN),
                    height_um: num(&e["height_um"]).unwrap_or(f64::NAN),
                    width_deg: num(&e["width_deg"]).unwrap_or(f64::NAN),
                    kind: e["kind"].as_str().unwrap_or("?").to_string(),
                    direction: e["direction"].as_str().unwrap_or("?").to_string(),
                    axis: e["axis"].as_str().map(str::to_string),
                    confidence: num(&e["confidence"]).unwrap_or(0.0),
                })
                .collect()
        })
        .unwrap_or_default()
}

fn reversals(summary: &Value) -> BTreeMap<String, Vec<f64>> {
    summary["reversals_deg"]
        .as_object()
        .map(|o| {
            o.iter()
                .map(|(k, v)| {
                    (
                        k.clone(),
                        v.as_array()
                            .map(|a| a.iter().filter_map(Value::as_f64).collect())
                            .unwrap_or_default(),
                    )
                })
                .collect()
        })
        .unwrap_or_default()
}

fn angle_distance(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(360.0);
    d.min(360.0 - d)
}

/// Peak-to-peak of `dev` with the ±`half_window_deg` around its extreme left out: how much of
/// G one spot makes. Returns (G, G without the spot, θ of the spot).
pub fn g_without_peak(theta: &[f64], dev: &[f64], half_window_deg: f64) -> Option<(f64, f64, f64)> {
    let finite: Vec<(f64, f64)> = theta
        .iter()
        .zip(dev)
        .filter(|(t, d)| t.is_finite() && d.is_finite())
        .map(|(t, d)| (*t, *d))
        .collect();
    if finite.len() < 3 {
        return None;
    }
    let (lo, hi) = finite
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.1), b.max(p.1))
        });
    let mean = finite.iter().map(|p| p.1).sum::<f64>() / finite.len() as f64;
    // The spot: the extreme farther from the mean.
    let spot = finite
        .iter()
        .max_by(|a, b| (a.1 - mean).abs().total_cmp(&(b.1 - mean).abs()))
        .map(|p| p.0)?;
    let rest: Vec<f64> = finite
        .iter()
        .filter(|p| angle_distance(p.0, spot) > half_window_deg)
        .map(|p| p.1)
        .collect();
    let (rlo, rhi) = rest
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), d| {
            (a.min(*d), b.max(*d))
        });
    Some((hi - lo, if rest.is_empty() { 0.0 } else { rhi - rlo }, spot))
}

/// Least-squares amplitude (µm) and orientation (deg, 0..180) of the 2θ (elliptical) part of
/// `dev`: `d ≈ c cos 2θ + s sin 2θ`, amplitude `√(c² + s²)`, long axis at `atan2(s, c) / 2`.
pub fn ellipse_um(theta: &[f64], dev: &[f64]) -> Option<(f64, f64)> {
    let (mut cc, mut ss, mut cs, mut dc, mut ds, mut n) = (0.0, 0.0, 0.0, 0.0, 0.0, 0);
    for (t, d) in theta.iter().zip(dev) {
        if !(t.is_finite() && d.is_finite()) {
            continue;
        }
        let (s2, c2) = (2.0 * t.to_radians()).sin_cos();
        cc += c2 * c2;
        ss += s2 * s2;
        cs += c2 * s2;
        dc += d * c2;
        ds += d * s2;
        n += 1;
    }
    let det = cc * ss - cs * cs;
    if n < 8 || det.abs() < 1e-12 {
        return None;
    }
    let c = (dc * ss - ds * cs) / det;
    let s = (ds * cc - dc * cs) / det;
    Some((
        (c * c + s * s).sqrt(),
        (s.atan2(c).to_degrees() / 2.0).rem_euclid(180.0),
    ))
}

/// The diagnoses: what the figures and marks point to, in words.
pub fn diagnoses(folder: &RunFolder) -> Vec<String> {
    let s = &folder.summary;
    let b = &s["ballbar"];
    let mut out = Vec::new();
    if b.is_null() {
        return vec!["No measured circle: the run has no ball-bar figures.".to_string()];
    }
    let g = num(&b["circular_deviation_um"]).unwrap_or(f64::NAN);
    if let Some(trace) = &folder.trace {
        for run in &trace.runs {
            if let Some((g_run, g_rest, spot)) =
                g_without_peak(&run.theta_deg, &run.deviation_centred_um, 5.0)
            {
                if g_run > 0.0 && g_rest < 0.5 * g_run {
                    out.push(format!(
                        "One spot dominates G ({} run): the deviation at θ = {spot:.1}° makes G = {g_run:.2} µm; \
                         without ±5° around it G would be {g_rest:.2} µm. Look at that spot (a transient, \
                         a reversal spike or a program artefact) before reading G as the machine's contouring error.",
                        run.direction.to_uppercase()
                    ));
                }
            }
            if let Some((amp, dir)) = ellipse_um(&run.theta_deg, &run.deviation_centred_um) {
                if g.is_finite() && amp > 0.15 * g && amp > 0.5 {
                    out.push(format!(
                        "Elliptical shape ({} run): 2θ component {amp:.2} µm, long axis at {dir:.0}°. \
                         In a planar test a long axis near 45° or 135° points to a servo gain mismatch \
                         between the two axes, near 0° or 90° to a scale mismatch; on a cone it also \
                         holds the rotary axes' share.",
                        run.direction.to_uppercase()
                    ));
                }
            }
        }
    }
    let revs = reversals(s);
    for e in events(s) {
        let where_ = format!("#{} at θ = {:.1}° ({})", e.number, e.theta_deg, e.direction);
        let text = match (&e.axis, e.kind.as_str()) {
            (Some(axis), "spike") => format!(
                "Reversal spike {where_}, {:+.2} µm: axis {axis} reverses there; a spike at a reversal is \
                 lost motion from friction (stick-slip, the quadrant glitch) and servo lag. \
                 Friction compensation or more velocity feedforward on {axis} reduces it.",
                e.height_um
            ),
            (Some(axis), "step") => format!(
                "Step {where_}, {:+.2} µm: axis {axis} reverses there; a step that stays is backlash or \
                 lost motion of {axis} (drive, guide or nut clearance). Backlash compensation on {axis} \
                 removes it.",
                e.height_um
            ),
            _ => {
                let nearest = revs
                    .iter()
                    .flat_map(|(a, v)| v.iter().map(move |t| (angle_distance(*t, e.theta_deg), a)))
                    .min_by(|a, b| a.0.total_cmp(&b.0));
                format!(
                    "Unattributed {} {where_}, {:+.2} µm: no axis reverses within 3°{}. Look for a block \
                     boundary, a feed change or the start and end of the measured revolution.",
                    e.kind,
                    e.height_um,
                    nearest.map_or(String::new(), |(d, a)| format!(
                        " (nearest: {a} at {d:.1}° away)"
                    ))
                )
            }
        };
        out.push(text);
    }
    if let Some(h) = num(&b["hysteresis_um"]) {
        if g.is_finite() && h > 0.3 * g {
            out.push(format!(
                "Hysteresis H = {h:.2} µm between the CW and CCW runs: lost motion that changes sign with \
                 the direction (backlash, servo lag, friction)."
            ));
        }
    }
    if let Some(runs) = b["runs"].as_array() {
        for r in runs {
            let dir = r["direction"].as_str().unwrap_or("?").to_uppercase();
            let c = &r["centring"];
            if let Some(r0) = num(&c["r0_um"]) {
                if r0.abs() > 1.0 {
                    out.push(format!(
                        "Mean radius {r0:+.2} µm off the bar length ({dir} run): servo lag shortens the \
                         radius of a contoured circle (radial error ≈ −v²/(2 Kv² R) without feedforward); \
                         a scale error changes it too."
                    ));
                }
            }
        }
    }
    if let Some(test) = &folder.test {
        if test.test.starts_with("cone") && !test.tcp {
            out.push(
                "The fine sawtooth with a period of one program block (strongest where the rotary axes \
                 turn fastest, on the 15/10 cone between about 150° and 210°) is real, not an artefact of \
                 the plot: without tool-centre-point control the axes move linearly in joint space between \
                 block end points, and the tool tip sags off the cone between them. Its height falls with \
                 the square of the block length (4× the segments: 1/16 of the sag); the same sag is the \
                 cutter engagement depth `check` reports."
                    .to_string(),
            );
        }
    }
    if out.is_empty() {
        out.push("Nothing stands out: no marks above noise.".to_string());
    }
    out
}

fn row(out: &mut String, key: &str, value: &str) {
    let _ = writeln!(out, "<tr><th>{}</th><td>{}</td></tr>", esc(key), esc(value));
}

fn test_table(folder: &RunFolder, date: Option<&str>) -> String {
    let mut out = String::from("<table class=\"params\">\n");
    match &folder.test {
        Some(t) => {
            row(
                &mut out,
                "Machine",
                &format!("{} ({})", t.machine, t.kinematics),
            );
            row(&mut out, "Machine file", &t.machine_file);
            row(&mut out, "Test", &t.test);
            row(&mut out, "Scenario", &t.scenario);
            if let Some(p) = &t.program_file {
                row(&mut out, "Program file", p);
            }
            row(&mut out, "Geometry", &t.geometry);
            row(&mut out, "Radius", &fmt_opt(t.radius_mm, 3, "mm"));
            row(&mut out, "Feed", &fmt_opt(t.feed_mm_min, 0, "mm/min"));
            row(
                &mut out,
                "Direction",
                &t.directions.join(", ").to_uppercase(),
            );
            row(&mut out, "Plane", &t.plane);
            row(
                &mut out,
                "Position (centre)",
                &t.position_mm.map_or("as programmed".to_string(), |p| {
                    format!("X {} Y {} Z {} mm", p[0], p[1], p[2])
                }),
            );
            row(
                &mut out,
                "Start arc / overshoot arc",
                &match (t.start_arc_deg, t.overshoot_arc_deg) {
                    (Some(s), Some(o)) => format!("{s}° / {o}°"),
                    _ => match t.measure_lines {
                        Some([a, b]) => format!("as programmed; measured lines {a}..{b}"),
                        None => "as programmed".to_string(),
                    },
                },
            );
            for c in &t.compensation {
                row(&mut out, "Compensation", c);
            }
            row(
                &mut out,
                "Interpolation",
                if t.tcp {
                    "tool-centre-point control"
                } else {
                    "joint space between blocks"
                },
            );
            row(
                &mut out,
                "Sample period",
                &format!(
                    "{} ms (trace: every {} sample{})",
                    t.sample_period_ms,
                    t.trace_every,
                    if t.trace_every == 1 { "" } else { "s" }
                ),
            );
            let date = date
                .map(str::to_string)
                .or_else(|| t.date.clone())
                .unwrap_or_else(|| {
                    "not recorded (simulate --no-timing; report --date)".to_string()
                });
            row(&mut out, "Date", &date);
            row(&mut out, "mtsim version", &t.mtsim_version);
            row(&mut out, "Scenario hash (XXH64)", &t.scenario_hash);
        }
        None => {
            row(
                &mut out,
                "Test parameters",
                "not recorded: this folder has no test.json (made before mtsim wrote it)",
            );
            if let Some(d) = date {
                row(&mut out, "Date", d);
            }
        }
    }
    let s = &folder.summary;
    row(
        &mut out,
        "Machine time",
        &format!(
            "{} ({} interpolation periods)",
            fmt_opt(num(&s["sim_time_s"]), 2, "s"),
            s["setpoints"]
        ),
    );
    out.push_str("</table>\n");
    out
}

fn figures_table(summary: &Value) -> String {
    let b = &summary["ballbar"];
    if b.is_null() {
        return "<p>No measured circle: no ball-bar figures.</p>\n".to_string();
    }
    let mut out = String::from(
        "<table class=\"figures\">\n<tr><th>run</th><th>G circular deviation (µm)</th>\
         <th>F max (µm)</th><th>F min (µm)</th><th>H hysteresis (µm)</th><th>centre offset a, b (µm)</th>\
         <th>mean radius error (µm)</th><th>noise (µm)</th><th>samples</th></tr>\n",
    );
    let f = |v: &Value, d: usize| fmt_opt(num(v), d, "");
    if let Some(runs) = b["runs"].as_array() {
        for r in runs {
            let _ = writeln!(
                out,
                "<tr><td>{}</td><td class=\"figure\" data-figure=\"G-{0}\">{}</td><td>{}</td><td>{}</td><td>–</td>\
                 <td>{}, {}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
                esc(&r["direction"].as_str().unwrap_or("?").to_uppercase()),
                f(&r["circular_deviation_um"], 2),
                f(&r["radial_max_um"], 2),
                f(&r["radial_min_um"], 2),
                f(&r["centring"]["a_um"], 2),
                f(&r["centring"]["b_um"], 2),
                f(&r["centring"]["r0_um"], 2),
                f(&r["noise_um"], 3),
                r["samples"],
            );
        }
    }
    let _ = writeln!(
        out,
        "<tr class=\"total\"><td>bi-directional</td><td class=\"figure\" data-figure=\"G\">{}</td>\
         <td class=\"figure\" data-figure=\"F-max\">{}</td><td class=\"figure\" data-figure=\"F-min\">{}</td>\
         <td class=\"figure\" data-figure=\"H\">{}</td><td></td><td></td><td></td><td></td></tr>",
        f(&b["circular_deviation_um"], 2),
        f(&b["radial_max_um"], 2),
        f(&b["radial_min_um"], 2),
        if b["hysteresis_um"].is_null() {
            "– (one direction)".to_string()
        } else {
            f(&b["hysteresis_um"], 2)
        },
    );
    out.push_str("</table>\n");
    out
}

fn marks_table(summary: &Value) -> String {
    let evs = events(summary);
    if evs.is_empty() {
        return "<p>No spikes or steps above noise.</p>\n".to_string();
    }
    let revs = reversals(summary);
    let mut out = String::from(
        "<table class=\"marks\">\n<tr><th>#</th><th>kind</th><th>run</th><th>θ (deg)</th><th>height (µm)</th>\
         <th>width (deg)</th><th>axis</th><th>confidence</th><th>attribution</th></tr>\n",
    );
    for e in &evs {
        let attribution = match &e.axis {
            Some(a) => revs
                .get(a)
                .and_then(|v| {
                    v.iter()
                        .map(|t| (angle_distance(*t, e.theta_deg), *t))
                        .min_by(|x, y| x.0.total_cmp(&y.0))
                })
                .map_or(format!("axis {a}"), |(d, t)| {
                    format!("{a} reverses at {t:.2}° ({d:.2}° away)")
                }),
            None => "none: no axis reverses within 3°".to_string(),
        };
        let _ = writeln!(
            out,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{:.2}</td><td>{:+.2}</td><td>{:.2}</td><td>{}</td>\
             <td>{:.2}</td><td>{}</td></tr>",
            e.number,
            esc(&e.kind),
            esc(&e.direction.to_uppercase()),
            e.theta_deg,
            e.height_um,
            e.width_deg,
            esc(e.axis.as_deref().unwrap_or("?")),
            e.confidence,
            esc(&attribution)
        );
    }
    out.push_str("</table>\n");
    out
}

fn check_section(check: &Value) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "<p>{} samples, {} positions.</p>",
        check["samples"],
        if check["dynamics"].as_bool() == Some(true) {
            "actual (servo)"
        } else {
            "commanded"
        }
    );
    out.push_str(
        "<table class=\"limits\">\n<tr><th>axis</th><th>used</th><th>travel</th><th>margin</th>\
         <th>peak velocity / limit</th><th>peak acceleration / limit</th></tr>\n",
    );
    if let Some(axes) = check["axes"].as_object() {
        for (name, u) in axes {
            let rotary = "ABC".contains(name.as_str());
            let (unit, vunit, aunit) = if rotary {
                ("deg", "deg/min", "deg/s²")
            } else {
                ("mm", "mm/min", "mm/s²")
            };
            let f = |k: &str, d: usize| fmt_opt(num(&u[k]), d, "");
            let _ = writeln!(
                out,
                "<tr><td>{}</td><td>{} … {} {unit}</td><td>{} … {} {unit}</td><td>{}</td><td>{} / {} {vunit}</td>\
                 <td>{} / {} {aunit}</td></tr>",
                esc(name),
                f("min", 3),
                f("max", 3),
                f("limit_min", 3),
                f("limit_max", 3),
                if u["margin"].is_null() {
                    "continuous".to_string()
                } else {
                    fmt_opt(num(&u["margin"]), 3, unit)
                },
                f("peak_velocity_per_min", 0),
                f("velocity_limit_per_min", 0),
                f("peak_acceleration_per_s2", 0),
                f("acceleration_limit_per_s2", 0),
            );
        }
    }
    out.push_str("</table>\n<ul>\n");
    if let (Some(c), Some(b)) = (
        num(&check["min_clearance_mm"]),
        check["min_clearance_bodies"].as_array(),
    ) {
        let _ = writeln!(
            out,
            "<li>Smallest clearance: {c:.3} mm ({} / {}).</li>",
            esc(b.first().and_then(Value::as_str).unwrap_or("?")),
            esc(b.get(1).and_then(Value::as_str).unwrap_or("?"))
        );
    }
    if let Some(eng) = check["engagement"].as_array() {
        for e in eng {
            let bodies = e["bodies"].as_array();
            let _ = writeln!(
                out,
                "<li>Cutting: {} in {}, deepest {:.4} mm. Expected, not a collision: the cone-frustum test \
                 cuts the cone; between block end points the joint-space interpolation lets the tip sag \
                 into the nominal surface, by an amount that falls with the square of the block length.</li>",
                esc(bodies.and_then(|b| b.first()).and_then(Value::as_str).unwrap_or("?")),
                esc(bodies.and_then(|b| b.get(1)).and_then(Value::as_str).unwrap_or("?")),
                num(&e["max_depth_mm"]).unwrap_or(f64::NAN)
            );
        }
    }
    match check["violations"].as_array() {
        Some(v) if !v.is_empty() => {
            for x in v {
                let what = x["axis"]
                    .as_str()
                    .map(str::to_string)
                    .or_else(|| {
                        x["bodies"].as_array().map(|b| {
                            b.iter()
                                .filter_map(Value::as_str)
                                .collect::<Vec<_>>()
                                .join(" / ")
                        })
                    })
                    .unwrap_or_default();
                let _ = writeln!(
                    out,
                    "<li class=\"violation\">{} {}: line {}, t {:.3}…{:.3} s, worst {:.3}{}</li>",
                    esc(x["kind"].as_str().unwrap_or("?")),
                    esc(&what),
                    x["line"],
                    num(&x["time_start_s"]).unwrap_or(f64::NAN),
                    num(&x["time_end_s"]).unwrap_or(f64::NAN),
                    num(&x["worst"]).unwrap_or(f64::NAN),
                    num(&x["limit"]).map_or(String::new(), |l| format!(", limit {l:.3}")),
                );
            }
        }
        _ => out.push_str("<li>Clean: no violations and no near misses.</li>\n"),
    }
    out.push_str("</ul>\n");
    out
}

/// Deviation against θ, both directions, with the numbered marks.
fn deviation_chart(folder: &RunFolder, trace: &Trace) -> Result<String> {
    let mut chart = Chart::new(
        "Deviation from the nominal circle, centred (least squares), against θ",
        "θ (deg)",
        "deviation (µm)",
        1100,
        360,
    );
    chart.x_range = Some((0.0, 360.0));
    chart.x_tick = Some(30.0);
    for run in &trace.runs {
        let points = sorted_by_theta(&run.theta_deg, &run.deviation_centred_um, 1.0);
        chart.series.push(Series {
            label: format!("{} run", run.direction.to_uppercase()),
            colour: direction_colour(&run.direction),
            points: plot::decimate_min_max(&points, BUCKETS),
            dots: false,
        });
    }
    for e in events(&folder.summary) {
        let y = trace
            .runs
            .iter()
            .find(|r| r.direction == e.direction)
            .and_then(|r| value_at(&r.theta_deg, &r.deviation_centred_um, e.theta_deg));
        chart.marks.push(Mark {
            x: e.theta_deg,
            y: y.unwrap_or(0.0),
            label: e.number.to_string(),
            colour: e
                .axis
                .as_deref()
                .and_then(|a| Axis::ALL.into_iter().find(|x| x.to_string() == a))
                .map_or(plot::INK, plot::axis_colour),
        });
    }
    chart.to_svg()
}

/// (θ, y) pairs, θ wrapped into [0, 360), sorted by θ, with a gap (NaN) where θ jumps.
fn sorted_by_theta(theta: &[f64], y: &[f64], scale: f64) -> Vec<(f64, f64)> {
    let mut p: Vec<(f64, f64)> = theta
        .iter()
        .zip(y)
        .filter(|(t, v)| t.is_finite() && v.is_finite())
        .map(|(t, v)| (t.rem_euclid(360.0), v * scale))
        .collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out = Vec::with_capacity(p.len());
    for (i, q) in p.iter().enumerate() {
        if i > 0 && q.0 - p[i - 1].0 > 5.0 {
            out.push((f64::NAN, f64::NAN));
        }
        out.push(*q);
    }
    out
}

fn value_at(theta: &[f64], y: &[f64], at: f64) -> Option<f64> {
    theta
        .iter()
        .zip(y)
        .filter(|(t, v)| t.is_finite() && v.is_finite())
        .min_by(|a, b| angle_distance(*a.0, at).total_cmp(&angle_distance(*b.0, at)))
        .map(|(_, v)| *v)
}

/// The central-difference velocity of `p` over `t`, per minute.
pub fn velocity_per_min(t: &[f64], p: &[f64]) -> Vec<f64> {
    let n = p.len();
    (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(1), (i + 1).min(n.saturating_sub(1)));
            let dt = t[b] - t[a];
            if b > a && dt > 0.0 {
                60.0 * (p[b] - p[a]) / dt
            } else {
                f64::NAN
            }
        })
        .collect()
}

/// Position, velocity and following error of each axis against θ (the paper's Figs. 5, 11).
fn axis_charts(folder: &RunFolder, trace: &Trace) -> Result<Vec<(String, String)>> {
    let revs = reversals(&folder.summary);
    let mut out = Vec::new();
    for (k, &axis) in trace.axes.iter().enumerate() {
        let (pu, vu, fu, fscale) = axis_unit(axis);
        let quantities: [(&str, String, String); 3] = [
            (
                "position",
                format!("{axis} position ({pu})"),
                format!("{axis} actual position"),
            ),
            (
                "velocity",
                format!("{axis} velocity ({vu})"),
                format!("{axis} velocity"),
            ),
            (
                "following-error",
                format!("{axis} following error ({fu})"),
                format!("{axis} following error (commanded − actual)"),
            ),
        ];
        for (q, (name, y_label, title)) in quantities.iter().enumerate() {
            let mut chart = Chart::new(title, "θ (deg)", y_label, 540, 300);
            chart.x_range = Some((0.0, 360.0));
            chart.x_tick = Some(60.0);
            for run in &trace.runs {
                let y: Vec<f64> = match q {
                    0 => run.actual[k].clone(),
                    1 => velocity_per_min(&run.time_s, &run.actual[k]),
                    _ => run.following_error[k].iter().map(|v| v * fscale).collect(),
                };
                let points = sorted_by_theta(&run.theta_deg, &y, 1.0);
                chart.series.push(Series {
                    label: run.direction.to_uppercase(),
                    colour: direction_colour(&run.direction),
                    points: plot::decimate_min_max(&points, BUCKETS / 2),
                    dots: false,
                });
            }
            for t in revs.get(&axis.to_string()).into_iter().flatten() {
                chart.markers.push(Marker {
                    x: t.rem_euclid(360.0),
                    label: format!("{axis} rev. {:.1}°", t.rem_euclid(360.0)),
                    colour: plot::axis_colour(axis),
                });
            }
            out.push((format!("{axis}-{name}"), chart.to_svg()?));
        }
    }
    Ok(out)
}

const CSS: &str = "body{font-family:sans-serif;color:#1e1e1e;max-width:1180px;margin:1.5em auto;padding:0 1em;line-height:1.4}\
h1{font-size:1.5em}h2{font-size:1.2em;border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:2em}\
table{border-collapse:collapse;margin:.5em 0}th,td{border:1px solid #ddd;padding:.25em .6em;text-align:left;vertical-align:top}\
table.params th{background:#f5f5f5;width:16em}table.figures td,table.marks td,table.limits td{text-align:right}\
tr.total{font-weight:bold}figure{margin:.5em 0}svg.plot{width:100%;height:auto;display:block}\
.axes{display:grid;grid-template-columns:repeat(3,1fr);gap:.5em}.axes figure{margin:0}\
li.violation{color:#b00}.note{color:#555;font-size:.95em}";

/// A page with the limits and collision summary of `mtsim check` alone.
pub fn render_check_page(name: &str, check: &Value) -> String {
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <title>mtsim check: {0}</title>\n<style>{CSS}</style>\n</head>\n<body>\n\
         <h1>mtsim check: {0}</h1>\n<h2 id=\"check\">Limits and collisions</h2>\n{1}\
         <p class=\"note\">Made by mtsim {2}.</p>\n</body>\n</html>\n",
        esc(name),
        check_section(check),
        env!("CARGO_PKG_VERSION")
    )
}

/// The HTML text of the report of `folder`; `date` (YYYY-MM-DD) overrides the recorded one.
pub fn render(folder: &RunFolder, date: Option<&str>) -> Result<String> {
    let name = folder
        .test
        .as_ref()
        .map(|t| t.scenario.clone())
        .unwrap_or_else(|| folder.dir.display().to_string());
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <title>mtsim report: {}</title>\n<style>{CSS}</style>\n</head>\n<body>\n\
         <h1>mtsim report: {0}</h1>\n",
        esc(&name)
    );
    h.push_str("<h2 id=\"test\">Test parameters (ISO 230-4)</h2>\n");
    h.push_str(&test_table(folder, date));
    h.push_str("<h2 id=\"figures\">Figures (ISO 230-4)</h2>\n");
    h.push_str(&figures_table(&folder.summary));
    h.push_str(
        "<p class=\"note\">G: circular deviation, the radial band of the centred trace. F: radial deviation, \
         the largest and smallest radius against the nominal. H: circular hysteresis between the CW and \
         CCW runs, about the common centre. Centring: least-squares centre offset a (cos θ), b (sin θ) \
         and mean radius error r0, removed before the figures.</p>\n",
    );
    if let Some((_, svg)) = folder.svgs.iter().find(|(n, _)| n == "ballbar.svg") {
        h.push_str("<h2 id=\"polar\">Polar plot</h2>\n");
        h.push_str(&inline_svg(svg, "polar"));
    }
    if let Some(trace) = folder.trace.as_ref().filter(|t| !t.runs.is_empty()) {
        h.push_str("<h2 id=\"linear\">Deviation against θ</h2>\n");
        h.push_str(&inline_svg(&deviation_chart(folder, trace)?, "deviation"));
        h.push_str(
            "<h2 id=\"axes\">Axis position, velocity and following error against θ</h2>\n\
             <p class=\"note\">One row per axis, as in the paper's Figs. 5 and 11; the vertical lines are \
             the axis's reversal angles from the program. Velocity: central difference of the actual \
             position over the trace's time.</p>\n",
        );
        for (i, (name, svg)) in axis_charts(folder, trace)?.iter().enumerate() {
            if i % 3 == 0 {
                h.push_str("<div class=\"axes\">\n");
            }
            h.push_str(&inline_svg(svg, name));
            if i % 3 == 2 {
                h.push_str("</div>\n");
            }
        }
    }
    h.push_str("<h2 id=\"marks\">Marks</h2>\n");
    h.push_str(&marks_table(&folder.summary));
    h.push_str("<h2 id=\"diagnoses\">Diagnoses</h2>\n<ul class=\"diagnoses\">\n");
    for d in diagnoses(folder) {
        let _ = writeln!(h, "<li>{}</li>", esc(&d));
    }
    h.push_str("</ul>\n");
    h.push_str("<h2 id=\"check\">Limits and collisions</h2>\n");
    match &folder.check {
        Some(c) => h.push_str(&check_section(c)),
        None => h.push_str("<p>Not checked: the folder has no check.json.</p>\n"),
    }
    for (file, svg) in folder.svgs.iter().filter(|(n, _)| n != "ballbar.svg") {
        let _ = writeln!(h, "<h2>{}</h2>", esc(file));
        h.push_str(&inline_svg(svg, file.trim_end_matches(".svg")));
    }
    h.push_str("<h2 id=\"files\">Files</h2>\n<ul class=\"files\">\n");
    for f in &folder.files {
        let _ = writeln!(h, "<li><a href=\"{0}\">{0}</a></li>", esc(f));
    }
    h.push_str("</ul>\n<p class=\"note\">Made by mtsim ");
    h.push_str(env!("CARGO_PKG_VERSION"));
    h.push_str(".</p>\n</body>\n</html>\n");
    Ok(h)
}

/// The plots a `sweep` folder holds: (file name, SVG text) of `placement.svg` and
/// `sweep-*.svg`, and every CSV, JSON and SVG file for the links.
fn study_files(dir: &Path) -> (Vec<(String, String)>, Vec<String>) {
    let mut files: Vec<String> = std::fs::read_dir(dir)
        .map(|r| {
            r.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| [".csv", ".json", ".svg"].iter().any(|x| n.ends_with(x)))
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    let svgs = files
        .iter()
        .filter(|n| *n == "placement.svg" || (n.starts_with("sweep-") && n.ends_with(".svg")))
        .filter_map(|n| Some((n.clone(), std::fs::read_to_string(dir.join(n)).ok()?)))
        .collect();
    (svgs, files)
}

/// The page of a `sweep` output folder: its plots and links.
pub fn render_study(dir: &Path, svgs: &[(String, String)], files: &[String]) -> String {
    let mut h = format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <title>mtsim study: {0}</title>\n<style>{CSS}</style>\n</head>\n<body>\n\
         <h1>mtsim study: {0}</h1>\n",
        esc(&dir.display().to_string())
    );
    for (name, svg) in svgs {
        let title = if name == "placement.svg" {
            "Placement map: where the test fits".to_string()
        } else {
            format!("Reversal angles: {}", name.trim_end_matches(".svg"))
        };
        let _ = writeln!(h, "<h2>{}</h2>", esc(&title));
        h.push_str(&inline_svg(svg, name.trim_end_matches(".svg")));
    }
    h.push_str("<h2 id=\"files\">Files</h2>\n<ul class=\"files\">\n");
    for f in files {
        let _ = writeln!(h, "<li><a href=\"{0}\">{0}</a></li>", esc(f));
    }
    let _ = write!(
        h,
        "</ul>\n<p class=\"note\">Made by mtsim {}.</p>\n</body>\n</html>\n",
        env!("CARGO_PKG_VERSION")
    );
    h
}

/// Reads `dir`, writes `dir/report.html` atomically and returns its path. A folder `sweep`
/// wrote (no summary.json, but sweep or placement plots) gets the study page.
pub fn write_report(dir: &Path, date: Option<&str>) -> Result<PathBuf> {
    if !dir.join("summary.json").exists() {
        let (svgs, files) = study_files(dir);
        if !svgs.is_empty() {
            let path = dir.join(REPORT_FILE);
            super::write_atomic(&path, render_study(dir, &svgs, &files).as_bytes())?;
            return Ok(path);
        }
    }
    let folder = RunFolder::read(dir)?;
    let html = render(&folder, date)?;
    let path = dir.join(REPORT_FILE);
    super::write_atomic(&path, html.as_bytes())?;
    Ok(path)
}
