//! The planner against LinuxCNC 2.9's own (issue 44): each program runs on LinuxCNC, started
//! headless (`common::linuxcnc`) with a `sampler` recording its joints' commanded positions
//! every 1 ms servo period, and through mtsim's interpolator on a machine file with the same
//! limits. LinuxCNC is a black box here: only its commanded stream is read.
//!
//! Compared, per program: the total motion time (first to last sample that moves, within
//! 1 %), at each blended corner the commanded path's distance from the programmed corner
//! (within 5 um of LinuxCNC's) and the path speed there (within 10 %), every axis reversal
//! (within 20 ms), and no axis over its limits in mtsim's stream.

use crate::common::{linuxcnc, scratch};

use mtsim::input::machine::Machine;
use mtsim::motion::interpolation::{InterpolationOptions, Interpolator};
use mtsim::Axis;

/// One LinuxCNC sample configuration and the mtsim machine file with its limits.
struct Config {
    /// Folder of the configuration (below `linuxcnc::SAMPLES`, or absolute) and its ini.
    folder: &'static str,
    ini: &'static str,
    /// The HAL signals holding the joints' commanded positions, in joint order.
    signals: &'static [&'static str],
    /// mtsim's machine file for the same limits (path from the crate root).
    machine: &'static str,
}

const XYZAC_TRT: Config = Config {
    folder: "table-rotary-tilting",
    ini: "xyzac-trt.ini",
    signals: &[
        "J0:pos-cmd",
        "J1:pos-cmd",
        "J2:pos-cmd",
        "J3:pos-cmd",
        "J4:pos-cmd",
    ],
    machine: "machines/linuxcnc/xyzac-trt.toml",
};

const THREE_AXIS: Config = Config {
    folder: "/usr/share/doc/linuxcnc/examples/sample-configs/sim/axis/vismach/3axis-tutorial",
    ini: "3axis-tutorial.ini",
    signals: &["Xpos", "Ypos", "Zpos"],
    machine: "machines/linuxcnc/3axis-tutorial.toml",
};

/// The programs run on xyzac-trt (name, text).
/// Corners of straight blocks under G64 P on xyzac-trt: the figures the issue asks for hold.
const BLENDED_PROGRAMS: &[(&str, &str)] = &[
    (
        "hexagon_p005",
        "G21 G90 G17 G64 P0.05\nG0 X0 Y0 Z0\nG1 X20 F900\nG1 X30 Y17.3205\nG1 X20 Y34.641\nG1 X0\nG1 X-10 Y17.3205\nG1 X0 Y0\nM2\n",
    ),
    (
        "hexagon_p001",
        "G21 G90 G17 G64 P0.01\nG0 X0 Y0 Z0\nG1 X20 F900\nG1 X30 Y17.3205\nG1 X20 Y34.641\nG1 X0\nG1 X-10 Y17.3205\nG1 X0 Y0\nM2\n",
    ),
    (
        "hexagon_p02",
        "G21 G90 G17 G64 P0.2\nG0 X0 Y0 Z0\nG1 X20 F900\nG1 X30 Y17.3205\nG1 X20 Y34.641\nG1 X0\nG1 X-10 Y17.3205\nG1 X0 Y0\nM2\n",
    ),
    (
        "zigzag_p01",
        "G21 G90 G17 G64 P0.1\nG0 X0 Y0 Z0\nG1 X10 Y3 F1200\nG1 X20 Y0\nG1 X30 Y3\nG1 X40 Y0\nG1 X40 Y10\nG1 X0 Y10 Z-2\nM2\n",
    ),
];

/// Corners of straight blocks under G64 without P (and one at P5, as large) on xyzac-trt,
/// feed moves and XY rapids, 150° turns, and G61 stopping at them (and between a rapid and a feed move): the figures the issue asks for hold.
const G64_PROGRAMS: &[(&str, &str)] = &[
    (
        "square_g61",
        "G21 G90 G17 G61\nG0 X0 Y0 Z0\nG1 X20 F1000\nG1 Y20\nG1 X0\nG1 Y0\nM2\n",
    ),
    (
        "square_g64",
        "G21 G90 G17 G64\nG0 X0 Y0 Z0\nG1 X20 F1000\nG1 Y20\nG1 X0\nG1 Y0\nM2\n",
    ),
    (
        "square_g64_f300",
        "G21 G90 G17 G64\nG0 X0 Y0 Z0\nG1 X20 F300\nG1 Y20\nG1 X0\nG1 Y0\nM2\n",
    ),
    (
        "square_p5",
        "G21 G90 G17 G64 P5\nG0 X0 Y0 Z0\nG1 X20 F1000\nG1 Y20\nG1 X0\nG1 Y0\nM2\n",
    ),
    (
        "hexagon_g64",
        "G21 G90 G17 G64\nG0 X0 Y0 Z0\nG1 X20 F900\nG1 X30 Y17.3205\nG1 X20 Y34.641\nG1 X0\nG1 X-10 Y17.3205\nG1 X0 Y0\nM2\n",
    ),
    (
        "rapids_xy",
        "G21 G90 G17 G64\nG0 X0 Y0 Z0\nG0 X40\nG0 Y40\nG0 X0\nG1 Y0 F1000\nM2\n",
    ),
    (
        "sharp_g64",
        "G21 G90 G17 G64\nG0 X0 Y0 Z0\nG1 X40 F1000\nG1 X14.0192 Y15\nG1 X18.0192 Y8.0718\nM2\n",
    ),
    (
        "shallow_g64",
        "G21 G90 G17 G64\nG0 X0 Y0 Z0\nG1 X20 F1000\nG1 X40 Y3\nG1 X60 Y0\nG1 X80 Y10\nM2\n",
    ),
];

/// Arcs on xyzac-trt: the speed LinuxCNC holds on a circle and its acceleration there,
/// corners between lines and arcs curving away from the turn or the same way, blended
/// (`arc_corner`): the figures the issue asks for hold.
const ARC_PROGRAMS: &[(&str, &str)] = &[
    (
        "arcs",
        "G21 G90 G17 G64 P0.02\nG0 X0 Y0 Z0\nG1 X10 F600\nG3 X20 Y10 I0 J10\nG2 X30 Y20 I10 J0\nG1 X30 Y30\nG3 X10 Y30 I-10 J0\nG1 X0 Y0\nM2\n",
    ),
    (
        "arc_away_p005",
        "G21 G90 G17 G64 P0.05\nG0 X0 Y0 Z0\nG1 X10 F800\nG2 X20 Y10 I10 J0\nG1 X30\nM2\n",
    ),
    (
        "arc_away_g64",
        "G21 G90 G17 G64\nG0 X0 Y0 Z0\nG1 X10 F800\nG2 X15 Y5 I5 J0\nG1 X25\nM2\n",
    ),
    (
        "arc_then_line_g64",
        "G21 G90 G17 G64\nG0 X0 Y0 Z0\nG3 X10 Y10 I0 J10 F800\nG1 X20 Y10\nM2\n",
    ),
    (
        "circle_r1",
        "G21 G90 G17 G64\nG0 X0 Y0 Z0\nG3 X0 Y0 I0 J1 F1200\nM2\n",
    ),
    (
        "circle_first",
        "G21 G90 G17 G64\nG0 X0 Y0 Z0\nG3 X0 Y0 I0 J20 F1200\nG1 X10\nM2\n",
    ),
    (
        "circle_last",
        "G21 G90 G17 G64\nG0 X0 Y0 Z0\nG1 X10 F1200\nG3 X10 Y0 I0 J20\nM2\n",
    ),
    (
        "line_into_arc",
        "G21 G90 G17 G64 P0.05\nG0 X0 Y0 Z0\nG1 X10 Y5 F800\nG2 X30 Y5 I10 J-5\nG1 X30 Y-10\nG3 X10 Y-10 I-10 J0\nG1 X0 Y0\nM2\n",
    ),
    (
        "same_way_g64",
        "G21 G90 G17 G64\nG0 X0 Y0 Z0\nG1 X20 F800\nG3 X10 Y10 I-10 J0\nG1 X10 Y-5\nM2\n",
    ),
    (
        "same_way_p005",
        "G21 G90 G17 G64 P0.05\nG0 X0 Y0 Z0\nG1 X20 F800\nG3 X10 Y10 I-10 J0\nG1 X10 Y-5\nM2\n",
    ),
    (
        "same_way_short_g2",
        "G21 G90 G17 G64\nG0 X0 Y0 Z0\nG1 X20 F800\nG2 X17.071068 Y-7.071068 I-10 J0\nG1 X10 Y0\nM2\n",
    ),
];

/// Moves with rotary axes on xyzac-trt, which LinuxCNC overlaps ([`mtsim::motion::overlap`]):
/// G93 five-axis moves, rapids with A and C, XC and AC feed moves at several tolerances.
const ROTARY_PROGRAMS: &[(&str, &str)] = &[
    (
        "five_axis_g93",
        "G21 G90 G17 G64 P0.05\nG0 X0 Y0 Z0 A0 C0\nG93\nG1 X10 Y5 A-10 C30 F60\nG1 X20 Y0 Z-5 A-20 C90 F40\nG1 X10 Y-10 A-5 C120 F50\nG94\nG1 X0 Y0 Z0 A0 C120 F900\nM2\n",
    ),
    (
        "rapids",
        "G21 G90 G17 G64\nG0 X0 Y0 Z0 A0 C0\nG0 X40 Y10\nG0 Z-20 C45\nG0 X-20 Y-30 A-30\nG0 X0 Y0 Z0 A0 C0\nM2\n",
    ),
    (
        "xc_p005",
        "G21 G90 G17 G64 P0.05\nG0 X0 Y0 Z0 A0 C0\nG1 X20 C30 F600\nG1 X30 Y10 C60\nG1 X10 Y20 C20\nG1 X0 Y0 C0\nM2\n",
    ),
    (
        "xc_g64",
        "G21 G90 G17 G64\nG0 X0 Y0 Z0 A0 C0\nG1 X20 C30 F900\nG1 X30 Y10 C60\nG1 X10 Y20 C20\nG1 X0 Y0 C0\nM2\n",
    ),
    (
        "ac_p001",
        "G21 G90 G17 G64 P0.01\nG0 X0 Y0 Z0 A0 C0\nG1 Y15 A-20 F500\nG1 Y25 Z-5 A-10\nG1 Y10 Z-10 A-30\nG1 Y0 Z0 A0\nM2\n",
    ),
    (
        "ac_p02",
        "G21 G90 G17 G64 P0.2\nG0 X0 Y0 Z0 A0 C0\nG1 X10 A-15 F800\nG1 X20 Y-10 A-25\nG1 X5 Y-15 A-5 C40\nG1 X0 Y0 A0 C0\nM2\n",
    ),
];

/// Over LinuxCNC's velocity limit where it overlaps two moves at a large tolerance (see
/// `where_linuxcnc_adds_x_past_its_limit_mtsim_does_not`).
const X_PAST_LIMIT: (&str, &str) = (
    "x_past_limit",
    "G21 G90 G17 G64\nG0 X0 Y0 Z0 A0 C0\nG1 X30 C60 F1200\nG1 X60 C65\nM2\n",
);

/// A ring of 120 five-axis moves at G64 P0.01: X Y on a circle of 20 mm, C turning with it,
/// A tilting back and forth.
fn ring() -> String {
    let mut text = String::from("G21 G90 G17 G64 P0.01\nG0 X20 Y0 Z0 A0 C0\n");
    for k in 1..=120 {
        let phi = k as f64 * std::f64::consts::TAU / 120.0;
        text += &format!(
            "G1 X{:.4} Y{:.4} A{:.4} C{:.4} F1000\n",
            20.0 * phi.cos(),
            20.0 * phi.sin(),
            -10.0 * (2.0 * phi).sin(),
            k as f64 * 3.0
        );
    }
    text + "M2\n"
}

/// The programs run on the three-axis sample (override 1.2, 25 mm/s, 750 mm/s²), a pocket
/// with a plunge and a tangent arc among them: the figures the issue asks for hold.
const THREE_AXIS_PROGRAMS: &[(&str, &str)] = &[
    (
        "hexagon_p005",
        "G21 G90 G17 G64 P0.05\nG0 X0 Y0 Z0\nG1 X20 F900\nG1 X30 Y17.3205\nG1 X20 Y34.641\nG1 X0\nG1 X-10 Y17.3205\nG1 X0 Y0\nM2\n",
    ),
    (
        "square_g64",
        "G21 G90 G17 G64\nG0 X0 Y0 Z0\nG1 X20 F1000\nG1 Y20\nG1 X0\nG1 Y0\nM2\n",
    ),
    (
        "square_g64_f600",
        "G21 G90 G17 G64\nG0 X0 Y0 Z0\nG1 X20 F600\nG1 Y20\nG1 X0\nG1 Y0\nM2\n",
    ),
    (
        "pocket_p002",
        "G21 G90 G17 G64 P0.02\nG0 X0 Y0 Z0\nG1 Z-2 F300\nG1 X30 F1500\nG1 Y20\nG3 X20 Y30 I-10 J0\nG1 X0\nG1 Y0\nG0 Z0\nM2\n",
    ),
];

/// Rapids in 3D on the three-axis sample: corners in planes tilted across the axes, blended
/// from the limits of their plane.
const THREE_AXIS_RAPIDS: &[(&str, &str)] = &[
    (
        "rapids_3d",
        "G21 G90 G17 G64\nG0 X0 Y0 Z0\nG0 X50 Y20\nG0 Z-30\nG0 X-20 Y-40 Z-10\nG0 X0 Y0 Z0\nM2\n",
    ),
    (
        "tilted_3d",
        "G21 G90 G17 G64\nG0 X0 Y0 Z0\nG0 X28.2843 Y28.2843\nG0 X0 Z-28.2843\nM2\n",
    ),
];

/// LinuxCNC's commanded joint stream for each program on `config`, recorded once into
/// `<scratch>/<ini>/<program>.samples` (one row per servo period).
fn linuxcnc_streams(config: &Config, programs: &[(&str, &str)]) -> Vec<Vec<Vec<f64>>> {
    // One folder per test (its first program names it): tests on the same sample run side
    // by side, and one's clean-up must not remove another's running copy.
    let first = programs.first().map_or("none", |p| p.0);
    let dir = scratch("linuxcnc-planner", &format!("{}-{first}", config.ini));
    let cmds = linuxcnc::recording(config.signals);
    let refs: Vec<&str> = cmds.iter().map(String::as_str).collect();
    let run = linuxcnc::start_with(config.folder, config.ini, &dir.join("lcnc"), &refs);
    programs
        .iter()
        .map(|(name, text)| run.run_program(name, text))
        .collect()
}

/// The programmed corners of a program where LinuxCNC blends (XYZ, mm), compared one by one
/// (not those where it stops: G61, between a rapid and a feed move).
fn corners(name: &str) -> Vec<[f64; 3]> {
    let hexagon = vec![
        [20.0, 0.0, 0.0],
        [30.0, 17.3205, 0.0],
        [20.0, 34.641, 0.0],
        [0.0, 34.641, 0.0],
        [-10.0, 17.3205, 0.0],
    ];
    let square = |a: f64| vec![[a, 0.0, 0.0], [a, a, 0.0], [0.0, a, 0.0]];
    match name {
        "hexagon_p005" | "hexagon_p001" | "hexagon_p02" | "hexagon_g64" => hexagon,
        "square_g64" | "square_g64_f300" | "square_g64_f600" | "square_p5" => square(20.0),
        "rapids_xy" => vec![[40.0, 0.0, 0.0], [40.0, 40.0, 0.0]],
        "shallow_g64" => vec![[20.0, 0.0, 0.0], [40.0, 3.0, 0.0], [60.0, 0.0, 0.0]],
        "rapids_3d" => vec![
            [50.0, 20.0, 0.0],
            [50.0, 20.0, -30.0],
            [-20.0, -40.0, -10.0],
        ],
        // (Both stop where the plunge meets the first cut: 0.15 and 0.33 mm/s.)
        "pocket_p002" => vec![[30.0, 0.0, -2.0], [0.0, 30.0, -2.0]],
        "arcs" => vec![[30.0, 20.0, 0.0], [10.0, 30.0, 0.0]],
        // (Not the reversal at X30 Y-10: neither blends it.)
        "line_into_arc" => vec![[10.0, 5.0, 0.0], [30.0, 5.0, 0.0], [10.0, -10.0, 0.0]],
        "same_way_g64" | "same_way_p005" => vec![[20.0, 0.0, 0.0], [10.0, 10.0, 0.0]],
        // (A 45° arc, its end rounded: the second pad is a third of what the first blend
        // left of the arc.)
        "same_way_short_g2" => vec![[20.0, 0.0, 0.0], [17.071068, -7.071068, 0.0]],
        // (150° turns: the second's blend held to a quarter of its 8 mm block.)
        "sharp_g64" => vec![[40.0, 0.0, 0.0], [14.0192, 15.0, 0.0]],
        "tilted_3d" => vec![[28.2843, 28.2843, 0.0]],
        "arc_away_p005" | "arc_away_g64" => vec![[10.0, 0.0, 0.0]],
        "arc_then_line_g64" => vec![[10.0, 10.0, 0.0]],
        "zigzag_p01" => vec![
            [10.0, 3.0, 0.0],
            [20.0, 0.0, 0.0],
            [30.0, 3.0, 0.0],
            [40.0, 0.0, 0.0],
        ],
        _ => vec![],
    }
}

/// mtsim's setpoints (one row of axis positions per period, the joints of `config` in order)
/// for `program` on the config's machine file, with the jerk limits raised to 1e9 (LinuxCNC
/// 2.9's planner has none), started where LinuxCNC's run started (`start`).
fn mtsim_stream(config: &Config, program: &str, start: &[f64]) -> Vec<Vec<f64>> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join(config.machine)).unwrap();
    let text: String = text
        .lines()
        .map(|l| {
            if l.trim_start().starts_with("max_jerk") {
                "max_jerk = 1e9".to_string()
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    let machine = Machine::from_toml(&root.join(config.machine), &text, None).unwrap();
    let axes: Vec<Axis> = machine.axes().to_vec();
    let mut options = ngc::Options {
        dialect: ngc::Dialect::Linuxcnc,
        ..ngc::Options::default()
    };
    for (k, &axis) in axes.iter().enumerate() {
        options.start[axis] = start[k];
    }
    let path = std::path::PathBuf::from("p.ngc");
    let moves =
        ngc::read_str_with(&path, program, &options).map(|m| m.map_err(mtsim::error::Error::from));
    let setpoints = Interpolator::new(moves, &machine, InterpolationOptions::default()).unwrap();
    setpoints
        .map(|s| {
            let s = s.unwrap();
            axes.iter().map(|&a| s.q[a]).collect()
        })
        .collect()
}

/// The rows from the first that moves to the last that moves (rest before and after cut).
fn motion(rows: &[Vec<f64>]) -> &[Vec<f64>] {
    let moves = |k: usize| {
        rows[k]
            .iter()
            .zip(&rows[k + 1])
            .any(|(a, b)| (a - b).abs() > 1e-9)
    };
    let first = (0..rows.len() - 1).find(|&k| moves(k)).unwrap_or(0);
    let last = (0..rows.len() - 1).rev().find(|&k| moves(k)).unwrap_or(0);
    &rows[first..=last + 1]
}

/// At each corner, the least XYZ distance of the stream from it (mm) and the XYZ path speed
/// there (mm/s, central difference over ±1 period).
fn at_corners(rows: &[Vec<f64>], corners: &[[f64; 3]]) -> Vec<(f64, f64)> {
    corners
        .iter()
        .map(|c| {
            let dist = |r: &Vec<f64>| (0..3).map(|i| (r[i] - c[i]).powi(2)).sum::<f64>().sqrt();
            let k = (1..rows.len() - 1)
                .min_by(|&a, &b| dist(&rows[a]).total_cmp(&dist(&rows[b])))
                .unwrap();
            let v = (0..3)
                .map(|i| ((rows[k + 1][i] - rows[k - 1][i]) / (2.0 * PERIOD_S)).powi(2))
                .sum::<f64>()
                .sqrt();
            (dist(&rows[k]), v)
        })
        .collect()
}

/// Every axis's reversals: times (s from the stream's start) where its velocity changes
/// sign, counting only speeds above 0.01 units/s (the midpoint between the two periods).
fn reversals(rows: &[Vec<f64>]) -> Vec<Vec<f64>> {
    (0..rows[0].len())
        .map(|j| {
            let mut out = vec![];
            let mut last: Option<(f64, usize)> = None;
            for k in 0..rows.len() - 1 {
                let v = (rows[k + 1][j] - rows[k][j]) / PERIOD_S;
                if v.abs() < 0.01 {
                    continue;
                }
                if let Some((s, kk)) = last {
                    if s != v.signum() {
                        out.push(0.5 * (kk + k) as f64 * PERIOD_S);
                    }
                }
                last = Some((v.signum(), k));
            }
            out
        })
        .collect()
}

/// The largest sampled velocity and acceleration of each joint over its limit, as `check`
/// measures them (finite differences of the samples), as ratios.
fn over_limits(rows: &[Vec<f64>], machine: &Machine) -> Vec<(f64, f64)> {
    machine
        .axes()
        .iter()
        .enumerate()
        .map(|(j, &a)| {
            let c = machine.axis(a);
            let (mut v_max, mut a_max) = (0.0f64, 0.0f64);
            for k in 1..rows.len() - 1 {
                let v = (rows[k + 1][j] - rows[k][j]) / PERIOD_S;
                let acc = (rows[k + 1][j] - 2.0 * rows[k][j] + rows[k - 1][j]) / PERIOD_S.powi(2);
                v_max = v_max.max(v.abs());
                a_max = a_max.max(acc.abs());
            }
            (v_max * 60.0 / c.max_velocity, a_max / c.max_acceleration)
        })
        .collect()
}

const PERIOD_S: f64 = 1e-3;

/// Runs `programs` on LinuxCNC and mtsim and holds mtsim to the figures; prints
/// every figure, and fails listing those that do not hold.
fn compare(config: &Config, programs: &[(&str, &str)]) {
    let streams = linuxcnc_streams(config, programs);
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let machine = Machine::load(&root.join(config.machine)).unwrap();
    let mut failures = vec![];
    for ((name, program), lcnc) in programs.iter().zip(&streams) {
        let start = lcnc[0].clone();
        let ours = mtsim_stream(config, program, &start);
        let (l, m) = (motion(lcnc), motion(&ours));
        let (tl, tm) = (
            (l.len() - 1) as f64 * PERIOD_S,
            (m.len() - 1) as f64 * PERIOD_S,
        );
        let dt = (tm - tl) / tl;
        eprintln!(
            "{} {name}: motion time LinuxCNC {tl:.3} s, mtsim {tm:.3} s ({:+.2} %)",
            config.ini,
            dt * 100.0
        );
        if dt.abs() > 0.01 {
            failures.push(format!(
                "{name}: motion time {tm:.3} s vs LinuxCNC {tl:.3} s ({:+.2} %)",
                dt * 100.0
            ));
        }
        let cs = corners(name);
        for (k, ((dl, vl), (dm, vm))) in at_corners(l, &cs)
            .into_iter()
            .zip(at_corners(m, &cs))
            .enumerate()
        {
            eprintln!("  corner {k}: distance LinuxCNC {:.1} um, mtsim {:.1} um; speed {vl:.3} vs {vm:.3} mm/s", dl * 1e3, dm * 1e3);
            if (dl - dm).abs() > 5e-3 || (vm - vl).abs() > 0.1 * vl {
                failures.push(format!("{name} corner {k}: distance {:.1} um vs LinuxCNC {:.1} um, speed {vm:.3} vs {vl:.3} mm/s", dm * 1e3, dl * 1e3));
            }
        }
        for (j, (rl, rm)) in reversals(l).iter().zip(reversals(m)).enumerate() {
            let worst = rl
                .iter()
                .zip(&rm)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            eprintln!(
                "  joint {j}: {} reversals LinuxCNC, {} mtsim, worst {:.1} ms apart",
                rl.len(),
                rm.len(),
                worst * 1e3
            );
            if rl.len() != rm.len() || worst > 0.020 {
                failures.push(format!(
                    "{name} joint {j}: reversals {rm:?} vs LinuxCNC {rl:?}"
                ));
            }
        }
        for (j, (v, a)) in over_limits(m, &machine).into_iter().enumerate() {
            if v > 1.0 + 1e-9 || a > 1.0 + 1e-6 {
                failures.push(format!("{name} joint {j}: mtsim at {v:.4} of its velocity and {a:.4} of its acceleration limit"));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} against LinuxCNC:\n{}",
        config.ini,
        failures.join("\n")
    );
}

/// Blended corners of straight moves at three tolerances and a zigzag: total time within
/// 1 %, each corner's distance within 5 um and its speed within 10 % of LinuxCNC's,
/// reversals within 20 ms, no axis over its limits.
#[test]
fn g64_p_corners_blend_as_linuxcnc_blends_them() {
    if linuxcnc::require("g64_p_corners_blend_as_linuxcnc_blends_them") {
        compare(&XYZAC_TRT, BLENDED_PROGRAMS);
    }
}

/// Corners under G64 without P: LinuxCNC's arc as long as the feed at its highest override
/// needs ([`mtsim::motion::blend::arc_length_for_speed`]), feed moves and rapids; G61 stops.
#[test]
fn g64_corners_blend_as_linuxcnc_blends_them() {
    if linuxcnc::require("g64_corners_blend_as_linuxcnc_blends_them") {
        compare(&XYZAC_TRT, G64_PROGRAMS);
    }
}

/// Arcs: the speed on a circle within `√3/2` of each axis's acceleration, the path
/// acceleration what the centripetal term leaves (a quarter on a program's last move), and
/// line-arc corners blended as LinuxCNC blends them, the arc curving away from the turn or
/// the same way (inside the arc, the turn padded by part of the arc's sweep).
#[test]
fn arcs_as_linuxcnc_plans_them() {
    if linuxcnc::require("arcs_as_linuxcnc_plans_them") {
        compare(&XYZAC_TRT, ARC_PROGRAMS);
    }
}

/// Moves with rotary axes, overlapped as LinuxCNC overlaps them ([`mtsim::motion::overlap`]):
/// total time within 1 %, reversals within 20 ms, no axis over its limits; a ring of 120
/// five-axis moves among them.
#[test]
fn rotary_moves_overlap_as_linuxcnc_plans_them() {
    if linuxcnc::require("rotary_moves_overlap_as_linuxcnc_plans_them") {
        let ring = ring();
        let mut programs = ROTARY_PROGRAMS.to_vec();
        programs.push(("ring_p001", &ring));
        compare(&XYZAC_TRT, &programs);
    }
}

/// The three-axis sample, homed headless with a home sequence of its own (the harness's):
/// corners under G64 P and G64 as LinuxCNC blends them, at its override of 1.2, and a pocket
/// (a plunge at F300, then F1500: the path speed continuous at the feed change).
#[test]
fn three_axis_sample_as_linuxcnc_plans_it() {
    if linuxcnc::require("three_axis_sample_as_linuxcnc_plans_it") {
        compare(&THREE_AXIS, THREE_AXIS_PROGRAMS);
    }
}

/// Corners between rapids in 3D: the blend in the plane of the two moves, sized from that
/// plane's limits (above each axis's own where the plane is tilted across three axes) and,
/// past 99°, for the speed it passes at (`blend::SpeedSizing::radius`).
#[test]
fn three_axis_3d_rapids_as_linuxcnc_plans_them() {
    if linuxcnc::require("three_axis_3d_rapids_as_linuxcnc_plans_them") {
        compare(&THREE_AXIS, THREE_AXIS_RAPIDS);
    }
}

/// Where LinuxCNC overlaps two moves at a large tolerance (P1) it starts the second while the
/// first still cruises, and X's two speeds add past its velocity limit; mtsim delays the
/// overlap until their sum is within it ([`mtsim::motion::overlap`]), so it takes longer.
#[test]
fn where_linuxcnc_adds_x_past_its_limit_mtsim_does_not() {
    if !linuxcnc::require("where_linuxcnc_adds_x_past_its_limit_mtsim_does_not") {
        return;
    }
    let (name, program) = X_PAST_LIMIT;
    let lcnc = &linuxcnc_streams(&XYZAC_TRT, &[X_PAST_LIMIT])[0];
    let ours = mtsim_stream(&XYZAC_TRT, program, &lcnc[0]);
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let machine = Machine::load(&root.join(XYZAC_TRT.machine)).unwrap();
    let (l, m) = (motion(lcnc), motion(&ours));
    let (tl, tm) = (
        (l.len() - 1) as f64 * PERIOD_S,
        (m.len() - 1) as f64 * PERIOD_S,
    );
    let (xl, xm) = (over_limits(l, &machine)[0], over_limits(m, &machine)[0]);
    eprintln!(
        "{name}: LinuxCNC {tl:.3} s, X at {:.3} of its velocity limit; mtsim {tm:.3} s ({:+.2} %), X at {:.3}",
        xl.0,
        (tm - tl) / tl * 100.0,
        xm.0
    );
    // LinuxCNC starts `G1 X60 C65` where `G1 X30 C60` (15 mm/s) starts slowing down: X's two
    // speeds add up to 15 − 75 t + 150 t, 25 mm/s at t = 2/15 s, 1.25 of its limit; mtsim starts it 1/15 s later
    // (`tests/motion/overlap.rs`, by hand: 3.633 s against 3.700 s).
    assert!(
        (xl.0 - 1.25).abs() < 0.01,
        "LinuxCNC's X at {:.4} of its limit",
        xl.0
    );
    assert!(
        xm.0 <= 1.0 + 1e-9 && xm.0 > 0.995,
        "mtsim's X at {:.4}",
        xm.0
    );
    assert!(
        (tl - (3.7 - 1.0 / 15.0)).abs() < 2.5e-3,
        "LinuxCNC {tl:.3} s"
    );
    assert!(
        (tm - tl - 1.0 / 15.0).abs() < 2.5e-3,
        "mtsim {tm:.3} s, LinuxCNC {tl:.3} s"
    );
    for (j, (v, a)) in over_limits(m, &machine).into_iter().enumerate() {
        assert!(
            v <= 1.0 + 1e-9 && a <= 1.0 + 1e-6,
            "mtsim joint {j}: {v:.4} of its velocity, {a:.4} of its acceleration limit"
        );
    }
}
