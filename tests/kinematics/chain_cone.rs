//! The cone-frustum test on every shipped chain, checked with the spec's forward kinematics
//! written out here (Rodrigues, the kinematic-chains spec) and the cone of
//! the cone-frustum spec: `mtsim cone` puts the tool ball on the test circle within
//! 2 µm at every block end, pointing at the apex within 0.01°; `simulate`'s ball-bar
//! deviation is the spec's forward kinematics of the trace's actual axis positions within
//! 0.01 µm.

use crate::common;

use std::path::Path;

use common::{mtsim_plain, scratch};
use mtsim::input::machine::Machine;
use mtsim::kinematics::{Chain, Side};
use mtsim::{Axis, AxisVec};

// The vector helpers and Rodrigues of the independent reference in geometric_errors.rs.
use super::geometric_errors::{add, dot, norm, rodrigues, scale, sub, V};

/// Rodrigues: v turned by `deg` about the unit `d`.
fn turn(d: V, deg: f64, v: V) -> V {
    rodrigues(d, deg.to_radians(), v)
}

/// One axis of the chain as plain numbers: (rotary, direction, point).
pub(super) type Joint = (Axis, bool, V, V);

/// The spec's M_k(q) x applied for the links `links` from the outermost inward
/// (`M_1 ⋯ M_n x`); `vector`: turn only (a direction).
pub(super) fn apply(links: &[Joint], q: &AxisVec, x: V, vector: bool) -> V {
    links.iter().rev().fold(x, |x, (axis, rotary, d, p)| {
        if *rotary {
            if vector {
                turn(*d, q[*axis], x)
            } else {
                add(turn(*d, q[*axis], sub(x, *p)), *p)
            }
        } else if vector {
            x
        } else {
            add(x, scale(*d, q[*axis]))
        }
    })
}

/// The inverse of [`apply`]: `M_n⁻¹ ⋯ M_1⁻¹ x`.
fn unapply(links: &[Joint], q: &AxisVec, x: V, vector: bool) -> V {
    links.iter().fold(x, |x, (axis, rotary, d, p)| {
        if *rotary {
            if vector {
                turn(*d, -q[*axis], x)
            } else {
                add(turn(*d, -q[*axis], sub(x, *p)), *p)
            }
        } else if vector {
            x
        } else {
            sub(x, scale(*d, q[*axis]))
        }
    })
}

pub(crate) struct Spec {
    pub(crate) table: Vec<Joint>,
    pub(crate) head: Vec<Joint>,
    gauge: V,
    tool: V,
}

impl Spec {
    /// The machine file's chain as numbers (its data, not its code).
    pub(super) fn of(chain: &Chain) -> Spec {
        let joints = |side: Side| {
            chain
                .links()
                .filter(|(s, _)| *s == side)
                .map(|(_, l)| {
                    let v = |x: nalgebra::Vector3<f64>| [x.x, x.y, x.z];
                    (l.axis, l.axis.is_rotary(), v(l.direction), v(l.point_mm))
                })
                .collect()
        };
        let v = |x: nalgebra::Vector3<f64>| [x.x, x.y, x.z];
        Spec {
            table: joints(Side::Table),
            head: joints(Side::Head),
            gauge: v(chain.gauge_point_mm),
            tool: v(chain.tool_direction),
        }
    }

    /// Tool tip (tool length 0) and tool direction in the machine frame.
    pub(super) fn tool_in_machine(&self, q: &AxisVec) -> (V, V) {
        (
            apply(&self.head, q, self.gauge, false),
            apply(&self.head, q, self.tool, true),
        )
    }

    /// Tool tip and tool direction in the workpiece frame.
    pub(crate) fn tool_in_workpiece(&self, q: &AxisVec) -> (V, V) {
        let (tip, t) = self.tool_in_machine(q);
        (
            unapply(&self.table, q, tip, false),
            unapply(&self.table, q, t, true),
        )
    }
}

use super::chains::SHIPPED;

/// The 15/10 cone at O = 0, L = 100 (the cone-frustum spec), in plain numbers.
const ALPHA: f64 = 15.0;
const BETA: f64 = 10.0;
const L: f64 = 100.0;

fn scenario(dir: &Path, machine: &str) {
    write_scenario(dir, "s.toml", machine, "", "");
}

/// A scenario `name` in `dir` with the 15/10 cone on `machine`; `program` goes before the
/// cone table (a `file`), `extra` after it.
fn write_scenario(dir: &Path, name: &str, machine: &str, program: &str, extra: &str) {
    let m = Path::new(env!("CARGO_MANIFEST_DIR")).join(machine);
    std::fs::write(
        dir.join(name),
        format!(
            "machine = {:?}\n[program]\n{program}[program.cone]\nhalf_apex_deg = {ALPHA}\ninclination_deg = {BETA}\ncenter_mm = [0.0, 0.0, 0.0]\nballbar_length_mm = {L}\n{extra}[check]\ncollisions = false\n",
            m.display().to_string()
        ),
    )
    .unwrap();
}

/// The TCP cone (`[program.cone] tcp`, G43.4: X Y Z the tool tip) as `s.toml`, and the
/// program `mtsim cone` writes from it read back as a file, `f.toml`.
fn tcp_scenarios(dir: &Path, machine: &str) {
    write_scenario(
        dir,
        "s.toml",
        machine,
        "",
        "tcp = true\n[simulate]\ntcp = true\n",
    );
    let out = mtsim_plain(dir, &["cone", "s.toml", "-o", "cone.nc"]);
    assert!(
        out.status.success(),
        "{machine}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    write_scenario(
        dir,
        "f.toml",
        machine,
        "file = \"cone.nc\"\n",
        // The generated program is Fanuc-style (its O1001 line is no LinuxCNC o-word).
        "[simulate]\ntcp = true\n[reader]\ndialect = \"fanuc\"\n",
    );
}

pub(crate) fn load(machine: &str) -> (Machine, Spec) {
    let m = Machine::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join(machine)).unwrap();
    let spec = Spec::of(&m.kinematics.chain().unwrap());
    (m, spec)
}

/// A workpiece point in the cone frame: Ry(β) (p − O) with O = 0.
fn in_cone_frame(p: V) -> V {
    let (s, c) = BETA.to_radians().sin_cos();
    // Ry(β) (x, y, z) = (c x + s z, y, −s x + c z).
    [c * p[0] + s * p[2], p[1], -s * p[0] + c * p[2]]
}

/// How far the tool ball of the spec's forward kinematics at `q` lies from the test circle
/// (mm: the larger of the radial and the height error) and the tool direction from the
/// apex (deg).
fn off_the_cone(spec: &Spec, q: &AxisVec) -> (f64, f64) {
    let (sa, ca) = ALPHA.to_radians().sin_cos();
    let (r, h) = (L * ca, L * sa);
    let apex_cone = [0.0, 0.0, L / sa];
    let (tip, t) = spec.tool_in_workpiece(q);
    let p = in_cone_frame(tip);
    let radial = (p[0].hypot(p[1]) - r).abs();
    let height = (p[2] - h).abs();
    let toward_apex = sub(apex_cone, p);
    let t_cone = in_cone_frame(t);
    let angle = (dot(toward_apex, t_cone) / norm(toward_apex) / norm(t_cone))
        .clamp(-1.0, 1.0)
        .acos();
    (radial.max(height), angle.to_degrees())
}

#[test]
fn the_cone_program_puts_the_tool_ball_on_the_circle_pointing_at_the_apex_on_every_chain() {
    for machine in SHIPPED {
        let dir = scratch(
            "chain-cone",
            Path::new(machine).file_stem().unwrap().to_str().unwrap(),
        );
        scenario(&dir, machine);
        let out = mtsim_plain(&dir, &["cone", "s.toml", "-o", "cone.nc"]);
        assert!(
            out.status.success(),
            "{machine}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let (m, spec) = load(machine);
        let text = std::fs::read_to_string(dir.join("cone.nc")).unwrap();
        let (mut blocks, mut worst_mm, mut worst_deg) = (0, 0.0f64, 0.0f64);
        for line in text.lines().filter(|l| l.starts_with("G0")) {
            let mut q = AxisVec::ZERO;
            for word in line.split_whitespace().skip(1) {
                let letter = word.chars().next().unwrap();
                if let Some(axis) = Axis::from_letter(letter).filter(|a| m.has_axis(*a)) {
                    q[axis] = word[1..].parse().unwrap();
                }
            }
            let (off_mm, off_deg) = off_the_cone(&spec, &q);
            assert!(
                off_mm < 2e-3 && off_deg < 0.01,
                "{machine}: {line}: off the circle by {off_mm} mm, {off_deg} deg off the apex"
            );
            worst_mm = worst_mm.max(off_mm);
            worst_deg = worst_deg.max(off_deg);
            blocks += 1;
        }
        // analyze's ranges of the machine's own axes are those of the program's blocks
        // (1° apart: their extremes within 0.01 mm or deg of the exact path's).
        let analysis = common::stdout_json(&mtsim_plain(&dir, &["analyze", "s.toml", "--json"]));
        for axis in m.axes() {
            let values: Vec<f64> = text
                .lines()
                .filter(|l| l.starts_with("G0"))
                .filter_map(|l| l.split_whitespace().find(|w| w.starts_with(axis.letter())))
                .map(|w| w[1..].parse().unwrap())
                .collect();
            let lo = values.iter().cloned().fold(f64::INFINITY, f64::min);
            let hi = values.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            let a = &analysis["axes"][axis.to_string()];
            let (min, max) = (a["min"].as_f64().unwrap(), a["max"].as_f64().unwrap());
            assert!(
                (min - lo).abs() < 0.01 && (max - hi).abs() < 0.01,
                "{machine} {axis}: analyze {min}..{max}, program {lo}..{hi}"
            );
        }
        eprintln!("{machine}: {blocks} blocks, worst {worst_mm:.2e} mm off the circle, {worst_deg:.2e} deg off the apex");
        assert!(blocks > 360, "{machine}: {blocks} blocks");
    }
}

#[test]
fn the_ball_bar_reads_the_spec_forward_kinematics_of_the_actual_axes_on_every_chain() {
    for machine in SHIPPED {
        let dir = scratch(
            "chain-bar",
            Path::new(machine).file_stem().unwrap().to_str().unwrap(),
        );
        scenario(&dir, machine);
        let out = mtsim_plain(&dir, &["simulate", "s.toml", "-o", "run", "--no-timing"]);
        assert!(
            out.status.code() == Some(0) || out.status.code() == Some(1),
            "{machine}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let (rows, worst) = ball_bar_against_the_spec(machine, &dir.join("run/trace.csv"));
        eprintln!("{machine}: {rows} samples, worst difference {worst:.2e} um");
        assert!(rows > 1000, "{machine}: {rows} rows");
        // The trace gives positions to 1e-6 mm and deg and the deviation to 1e-4 um.
        assert!(worst < 0.01, "{machine}: worst difference {worst} um");
        // The report knows the machine: its test parameters name the chain, and the trace
        // the axis plots are drawn from has the machine's own axes, no others.
        let (m, spec) = load(machine);
        let names = |links: &[Joint]| match links {
            [] => "-".to_string(),
            l => l
                .iter()
                .map(|j| j.0.to_string())
                .collect::<Vec<_>>()
                .join(" "),
        };
        let info: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("run/test.json")).unwrap())
                .unwrap();
        assert_eq!(
            info["kinematics"],
            format!(
                "chain: table {}; head {}",
                names(&spec.table),
                names(&spec.head)
            ),
            "{machine}"
        );
        let trace = std::fs::read_to_string(dir.join("run/trace.csv")).unwrap();
        let plotted: Vec<String> = trace
            .lines()
            .next()
            .unwrap()
            .split(',')
            .filter_map(|h| h.split_once("_act_").map(|(a, _)| a.to_string()))
            .collect();
        let own: Vec<String> = m.axes().iter().map(|a| a.to_string()).collect();
        assert_eq!(plotted, own, "{machine}");
    }
}

/// The trace's rows and the largest difference (µm) between its ball-bar deviation and
/// the spec's forward kinematics of its actual axes: the table ball at O = 0 (workpiece
/// frame), the tool ball at the gauge point, the bar L long.
fn ball_bar_against_the_spec(machine: &str, trace: &Path) -> (usize, f64) {
    ball_bar_against(machine, trace, [0.0; 3], L)
}

/// [`ball_bar_against_the_spec`] with the table ball at `ball` (workpiece frame) and a bar
/// `length` mm long.
fn ball_bar_against(machine: &str, trace: &Path, ball: V, length: f64) -> (usize, f64) {
    {
        let (m, spec) = load(machine);
        let trace = std::fs::read_to_string(trace).unwrap();
        let mut lines = trace.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let col = |name: &str| {
            header
                .iter()
                .position(|h| *h == name)
                .unwrap_or_else(|| panic!("{name}"))
        };
        let actual: Vec<(Axis, usize)> = m
            .axes()
            .iter()
            .map(|a| (*a, col(&format!("{a}_act_{}", a.unit()))))
            .collect();
        let deviation = col("deviation_um");
        let (mut rows, mut worst) = (0, 0.0f64);
        for row in lines {
            let f: Vec<&str> = row.split(',').collect();
            let mut q = AxisVec::ZERO;
            for (a, i) in &actual {
                q[*a] = f[*i].parse().unwrap();
            }
            // The table ball at O = 0 (workpiece frame) and the tool ball at the gauge point.
            let (tool, _) = spec.tool_in_machine(&q);
            let ball = apply(&spec.table, &q, ball, false);
            let expected_um = (norm(sub(tool, ball)) - length) * 1e3;
            let got: f64 = f[deviation].parse().unwrap();
            worst = worst.max((got - expected_um).abs());
            rows += 1;
        }
        (rows, worst)
    }
}

#[test]
fn the_tcp_cone_puts_the_tool_ball_on_the_circle_pointing_at_the_apex_on_every_chain() {
    for machine in SHIPPED {
        let dir = scratch(
            "chain-tcp-cone",
            Path::new(machine).file_stem().unwrap().to_str().unwrap(),
        );
        tcp_scenarios(&dir, machine);
        // The written G43.4 program read back: its block ends as the machine's own axes.
        let rows = common::stdout_json(&mtsim_plain(&dir, &["blocks", "f.toml", "--json"]));
        let (m, spec) = load(machine);
        let (mut blocks, mut worst_mm, mut worst_deg) = (0, 0.0f64, 0.0f64);
        for row in rows.as_array().unwrap() {
            let mut q = AxisVec::ZERO;
            for axis in m.axes() {
                q[*axis] = row[axis.letter().to_ascii_lowercase().to_string()]
                    .as_f64()
                    .unwrap_or_else(|| panic!("{machine}: no {axis} in {row}"));
            }
            let (off_mm, off_deg) = off_the_cone(&spec, &q);
            assert!(
                off_mm < 2e-3 && off_deg < 0.01,
                "{machine}: line {}: off the circle by {off_mm} mm, {off_deg} deg off the apex",
                row["line"]
            );
            worst_mm = worst_mm.max(off_mm);
            worst_deg = worst_deg.max(off_deg);
            blocks += 1;
        }
        eprintln!("{machine} (TCP): {blocks} blocks, worst {worst_mm:.2e} mm off the circle, {worst_deg:.2e} deg off the apex");
        assert!(blocks > 360, "{machine}: {blocks} blocks");
    }
}

#[test]
fn the_tcp_cone_ball_bar_reads_the_spec_forward_kinematics_of_the_actual_axes_on_every_chain() {
    for machine in SHIPPED {
        let dir = scratch(
            "chain-tcp-bar",
            Path::new(machine).file_stem().unwrap().to_str().unwrap(),
        );
        tcp_scenarios(&dir, machine);
        for scenario in ["s.toml", "f.toml"] {
            let out = mtsim_plain(&dir, &["simulate", scenario, "-o", "run", "--no-timing"]);
            assert!(
                out.status.code() == Some(0) || out.status.code() == Some(1),
                "{machine} {scenario}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            let (rows, worst) = ball_bar_against_the_spec(machine, &dir.join("run/trace.csv"));
            eprintln!(
                "{machine} {scenario} (TCP): {rows} samples, worst difference {worst:.2e} um"
            );
            assert!(rows > 1000, "{machine}: {rows} rows");
            assert!(
                worst < 0.01,
                "{machine} {scenario}: worst difference {worst} um"
            );
        }
    }
}

#[test]
fn the_circular_test_runs_on_every_chain_with_the_rotaries_held() {
    // ISO 230-4 in XY, radius 80 mm about (10, 20, 30): the table ball where those axis
    // values put the tool ball with every rotary at 0, by the spec's forward kinematics.
    let (center, radius) = ([10.0, 20.0, 30.0], 80.0);
    for machine in SHIPPED {
        let dir = scratch(
            "chain-circle",
            Path::new(machine).file_stem().unwrap().to_str().unwrap(),
        );
        let m = Path::new(env!("CARGO_MANIFEST_DIR")).join(machine);
        std::fs::write(
            dir.join("c.toml"),
            format!(
                "machine = {:?}\n[program.circle]\nplane = \"XY\"\nradius_mm = {radius}\nfeed_mm_min = 2000.0\ncenter_mm = {center:?}\n[check]\ncollisions = false\n",
                m.display().to_string()
            ),
        )
        .unwrap();
        let out = mtsim_plain(&dir, &["simulate", "c.toml", "-o", "run", "--no-timing"]);
        assert!(
            out.status.code() == Some(0) || out.status.code() == Some(1),
            "{machine}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let (_, spec) = load(machine);
        let mut q = AxisVec::ZERO;
        (q[Axis::X], q[Axis::Y], q[Axis::Z]) = (center[0], center[1], center[2]);
        let (ball, _) = spec.tool_in_workpiece(&q);
        let (rows, worst) = ball_bar_against(machine, &dir.join("run/trace.csv"), ball, radius);
        eprintln!("{machine} circle: {rows} samples, worst difference {worst:.2e} um");
        assert!(rows > 1000, "{machine}: {rows} rows");
        assert!(worst < 0.01, "{machine}: worst difference {worst} um");
        // The rotaries stand still through the whole test.
        let trace = std::fs::read_to_string(dir.join("run/trace.csv")).unwrap();
        let header: Vec<&str> = trace.lines().next().unwrap().split(',').collect();
        for (i, h) in header.iter().enumerate() {
            if h.ends_with("_cmd_deg") {
                assert!(
                    trace
                        .lines()
                        .skip(1)
                        .all(|r| r.split(',').nth(i) == Some("0.000000")
                            || r.split(',').nth(i).and_then(|v| v.parse::<f64>().ok())
                                == Some(0.0)),
                    "{machine}: {h} moves"
                );
            }
        }
    }
}
