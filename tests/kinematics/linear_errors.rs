//! ISO 230-1 errors of the linear axes (geometric-errors.md, "Errors of the linear axes"):
//! `simulate`'s ball-bar trace against a forward kinematics written here from the spec's
//! equations alone (its own Rodrigues, its own interpolation of the tables, its own chain;
//! nothing of mtsim's kinematics), and the squareness ellipse of ISO 230-4.

use crate::common;
use crate::common::CsvTable as Trace;

use std::path::Path;

use super::geometric_errors::{add, cross, norm, rodrigues, scale, sub, V};

// ---------- the independent reference ----------

/// A component-error table as the test writes it: rows of (position mm, δ um, ε urad).
struct Table {
    rows: Vec<(f64, [f64; 6])>,
    reference_mm: V,
}

impl Table {
    /// Linear between rows, ends held.
    fn at(&self, u: f64) -> [f64; 6] {
        let r = &self.rows;
        if u <= r[0].0 {
            return r[0].1;
        }
        if u >= r[r.len() - 1].0 {
            return r[r.len() - 1].1;
        }
        let k = r.iter().position(|row| row.0 > u).unwrap();
        let (a, b) = (r[k - 1], r[k]);
        let f = (u - a.0) / (b.0 - a.0);
        let mut out = [0.0; 6];
        for i in 0..6 {
            out[i] = a.1[i] + f * (b.1[i] - a.1[i]);
        }
        out
    }

    /// E_J(u) x = Rot(ε)(x − r) + r + δ, Rot by Rodrigues about ε/|ε|.
    fn apply(&self, u: f64, x: V) -> V {
        let e = self.at(u);
        let delta = [e[0] * 1e-3, e[1] * 1e-3, e[2] * 1e-3];
        let eps = [e[3] * 1e-6, e[4] * 1e-6, e[5] * 1e-6];
        let angle = norm(eps);
        let r = self.reference_mm;
        let turned = if angle == 0.0 {
            sub(x, r)
        } else {
            rodrigues(scale(eps, 1.0 / angle), angle, sub(x, r))
        };
        add(add(turned, r), delta)
    }

    fn csv(&self, letter: char) -> String {
        let mut s = format!(
            "position_mm,EX{l}_um,EY{l}_um,EZ{l}_um,EA{l}_urad,EB{l}_urad,EC{l}_urad\n",
            l = letter
        );
        for (p, e) in &self.rows {
            let cells: Vec<String> = e.iter().map(|v| format!("{v}")).collect();
            s.push_str(&format!("{p},{}\n", cells.join(",")));
        }
        s
    }
}

/// Squareness in urad, and the three tables.
struct LinearErrors {
    ec0y: f64,
    eb0z: f64,
    ea0z: f64,
    tables: [Table; 3],
}

impl LinearErrors {
    /// Actual unit directions of X, Y, Z: u = unit(d + (EA, EB, EC) × d).
    fn directions(&self) -> [V; 3] {
        let squared = |d: V, eps: V| {
            let u = add(d, cross(scale(eps, 1e-6), d));
            scale(u, 1.0 / norm(u))
        };
        [
            [1.0, 0.0, 0.0],
            squared([0.0, 1.0, 0.0], [0.0, 0.0, self.ec0y]),
            squared([0.0, 0.0, 1.0], [self.ea0z, self.eb0z, 0.0]),
        ]
    }

    /// The tool's gauge point (the origin at home) at X Y Z: M_X E_X M_Y E_Y M_Z E_Z (0).
    fn tool(&self, x: f64, y: f64, z: f64) -> V {
        let [ux, uy, uz] = self.directions();
        let mut p = [0.0; 3];
        p = add(self.tables[2].apply(z, p), scale(uz, z));
        p = add(self.tables[1].apply(y, p), scale(uy, y));
        add(self.tables[0].apply(x, p), scale(ux, x))
    }
}

/// The errors of both checks: squareness, straightness and yaw (and a pitch) of each axis,
/// measured about reference points off the origin.
fn errors() -> LinearErrors {
    // (EXJ, EYJ, EZJ um; EAJ, EBJ, ECJ urad)
    let x = Table {
        rows: vec![
            (-100.0, [0.0, -3.0, 1.0, 0.0, 0.0, -12.0]),
            (0.0, [0.0, 2.0, -1.5, 0.0, 4.0, 5.0]),
            (120.0, [0.0, -1.0, 2.0, 0.0, -6.0, 20.0]),
        ],
        reference_mm: [0.0, 50.0, 120.0],
    };
    let y = Table {
        rows: vec![
            (-120.0, [2.5, 0.0, 0.0, 0.0, 0.0, 15.0]),
            (30.0, [-4.0, 0.0, 0.0, 0.0, 0.0, -8.0]),
            (110.0, [1.0, 0.0, 0.0, 0.0, 0.0, 10.0]),
        ],
        reference_mm: [-20.0, 0.0, 100.0],
    };
    let z = Table {
        rows: vec![
            (0.0, [3.0, -2.0, 0.0, 0.0, 0.0, 0.0]),
            (300.0, [-3.0, 2.0, 0.0, 5.0, 10.0, 0.0]),
        ],
        reference_mm: [0.0, 0.0, 0.0],
    };
    LinearErrors {
        ec0y: 40.0,
        eb0z: -25.0,
        ea0z: 30.0,
        tables: [x, y, z],
    }
}

// ---------- the runs ----------

/// `machine` with the errors of `e`, written into `dir` (tables beside it).
fn machine_with(dir: &Path, machine: &str, e: &LinearErrors) -> String {
    let mut text = std::fs::read_to_string(common::machine(machine)).unwrap();
    text.push_str(&format!(
        "\n[location_errors]\nEC0Y_urad = {}\nEB0Z_urad = {}\nEA0Z_urad = {}\n",
        e.ec0y, e.eb0z, e.ea0z
    ));
    text.push_str("\n[component_errors]\n");
    for (t, l) in e.tables.iter().zip(['X', 'Y', 'Z']) {
        std::fs::create_dir_all(dir.join("errors")).unwrap();
        std::fs::write(dir.join(format!("errors/{l}.csv")), t.csv(l)).unwrap();
        text.push_str(&format!("{l} = \"errors/{l}.csv\"\n"));
    }
    for (t, l) in e.tables.iter().zip(['X', 'Y', 'Z']) {
        text = text.replacen(
            &format!("[axes.{l}]\n"),
            &format!("[axes.{l}]\nreference_mm = {:?}\n", t.reference_mm),
            1,
        );
    }
    let path = dir.join("m.toml");
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}

/// Runs `simulate` on `body` with `machine`; its trace and summary.
fn simulate(dir: &Path, machine: &str, body: &str) -> (Trace, serde_json::Value) {
    let scenario = common::write_scenario(dir, machine, body);
    let out = dir.join("out");
    let run = common::mtsim(&[
        "simulate",
        scenario.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--no-timing",
    ]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    (
        Trace::read(&out.join("trace.csv")),
        serde_json::from_str(&summary).unwrap(),
    )
}

/// trt-ac's nominal table (pivot at the origin): m = Rx(A) Rz(C) p.
fn table_ball(a_deg: f64, c_deg: f64, p: V) -> V {
    let on_c = rodrigues([0.0, 0.0, 1.0], c_deg.to_radians(), p);
    rodrigues([1.0, 0.0, 0.0], a_deg.to_radians(), on_c)
}

/// The largest |trace − reference| and the peak-to-peak of the linear errors' part, um.
fn against_reference(t: &Trace, e: &LinearErrors, ball: V, length: f64, cone: bool) -> (f64, f64) {
    let ideal = LinearErrors {
        ec0y: 0.0,
        eb0z: 0.0,
        ea0z: 0.0,
        tables: std::array::from_fn(|_| Table {
            rows: vec![(0.0, [0.0; 6])],
            reference_mm: [0.0; 3],
        }),
    };
    let c = |n: &str| t.col(n);
    let (cx, cy, cz, cd) = (
        c("X_act_mm"),
        c("Y_act_mm"),
        c("Z_act_mm"),
        c("deviation_um"),
    );
    let rotaries = cone.then(|| (c("A_act_deg"), c("C_act_deg")));
    let (mut worst, mut lo, mut hi) = (0.0_f64, f64::MAX, f64::MIN);
    assert!(t.rows.len() > 500, "{} rows", t.rows.len());
    for r in &t.rows {
        let table = match rotaries {
            Some((ca, cc)) => table_ball(r[ca], r[cc], ball),
            None => ball,
        };
        let dl = |m: &LinearErrors| (norm(sub(m.tool(r[cx], r[cy], r[cz]), table)) - length) * 1e3;
        let (with, without) = (dl(e), dl(&ideal));
        worst = worst.max((with - r[cd]).abs());
        lo = lo.min(with - without);
        hi = hi.max(with - without);
    }
    (worst, hi - lo)
}

/// Done when: squareness, straightness and yaw tables give a ball-bar trace equal to an
/// independent forward kinematics within 0.01 um, on a circle.
#[test]
fn circle_with_squareness_and_tables_equals_the_reference() {
    let dir = common::scratch("linear", "circle");
    let e = errors();
    let machine = machine_with(&dir, "vmc-3axis", &e);
    let centre = [10.0, -20.0, 150.0];
    let body = format!(
        "[program.circle]\nplane = \"XY\"\nradius_mm = 150.0\nfeed_mm_min = 3000.0\n\
         directions = [\"ccw\"]\ncenter_mm = {centre:?}\n"
    );
    let (trace, _) = simulate(&dir, &machine, &body);
    let (worst, p2p) = against_reference(&trace, &e, centre, 150.0, false);
    println!("circle: worst {worst:.5} um, linear errors' part {p2p:.2} um p-p");
    assert!(
        worst < 0.01,
        "the trace differs from the reference by {worst} um"
    );
    assert!(p2p > 5.0, "the errors barely show ({p2p} um p-p): vacuous");
}

/// The same on a 15/10 cone of trt-ac (the rotaries turn, the head's errors act).
#[test]
fn cone_with_squareness_and_tables_equals_the_reference() {
    let dir = common::scratch("linear", "cone");
    let e = errors();
    let machine = machine_with(&dir, "trt-ac", &e);
    let o = [15.0, -10.0, 180.0];
    let body = format!(
        "[program.cone]\nhalf_apex_deg = 15.0\ninclination_deg = 10.0\ncenter_mm = {o:?}\n\
         ballbar_length_mm = 100.0\nfeed_mm_min = 3000.0\n[check]\ncollisions = false\n"
    );
    let (trace, _) = simulate(&dir, &machine, &body);
    let (worst, p2p) = against_reference(&trace, &e, o, 100.0, true);
    println!("cone: worst {worst:.5} um, linear errors' part {p2p:.2} um p-p");
    assert!(
        worst < 0.01,
        "the trace differs from the reference by {worst} um"
    );
    assert!(p2p > 3.0, "the errors barely show ({p2p} um p-p): vacuous");
}

/// The spec's check: EC0Y = 50 urad on an XY circle of radius 150 mm is a 7.5 um
/// peak-to-valley sin 2θ term (least squares on the trace here), and the circle diagnosis
/// reads α = −EC0Y within 3 %.
#[test]
fn squareness_alone_is_the_iso_230_4_ellipse_and_is_diagnosed() {
    let dir = common::scratch("linear", "squareness");
    let mut text = std::fs::read_to_string(common::machine("vmc-3axis")).unwrap();
    text.push_str("\n[location_errors]\nEC0Y_urad = 50.0\n");
    let machine = dir.join("m.toml");
    std::fs::write(&machine, text).unwrap();
    let body = "[program.circle]\nplane = \"XY\"\nradius_mm = 150.0\nfeed_mm_min = 500.0\n\
                directions = [\"ccw\", \"cw\"]\ncenter_mm = [0.0, 0.0, 100.0]\n";
    let (trace, summary) = simulate(&dir, &machine.display().to_string(), body);
    // Least squares of the deviation dL on (1, sin 2θ, cos 2θ, sin θ, cos θ), each row: the
    // first harmonic is the set-up offset the centring removes.
    let (ct, cd) = (trace.col("theta_deg"), trace.col("deviation_um"));
    let mut ata = nalgebra::SMatrix::<f64, 5, 5>::zeros();
    let mut aty = nalgebra::SVector::<f64, 5>::zeros();
    for r in &trace.rows {
        let t = r[ct].to_radians();
        let a = nalgebra::SVector::<f64, 5>::from([
            1.0,
            (2.0 * t).sin(),
            (2.0 * t).cos(),
            t.sin(),
            t.cos(),
        ]);
        ata += a * a.transpose();
        aty += a * r[cd];
    }
    let b = ata.try_inverse().unwrap() * aty;
    let p2p = 2.0 * b[1].abs();
    println!("sin 2θ coefficient {:.4} um, p-v {p2p:.4} um", b[1]);
    // −(r EC0Y / 2) sin 2θ: −3.75 um.
    assert!((b[1] + 3.75).abs() < 0.03 * 3.75, "sin 2θ term {} um", b[1]);
    let alpha = summary["diagnostics"]["circle"]["squareness_urad"]
        .as_f64()
        .unwrap();
    println!("diagnosed squareness α = {alpha:.3} urad");
    assert!(
        (alpha + 50.0).abs() < 0.03 * 50.0,
        "α = {alpha} urad, expected −50"
    );
}

/// Bad tables are refused with their file, line and column, exit 2.
#[test]
fn bad_component_tables_name_the_place() {
    let dir = common::scratch("linear", "bad");
    let cases = [
        (
            "position_mm,EXX_um,EQX_um\n0,1,2\n",
            "unknown column `EQX_um`",
            ":1:20",
        ),
        (
            "position_mm,EYX_um\n0,1\n10,zz\n",
            "expected a finite number",
            ":3:4",
        ),
        (
            "position_mm,EYX_um\n10,1\n0,2\n",
            "positions must ascend",
            ":3:1",
        ),
        ("position_mm,EYX_um\n0,1,3\n", "a row has 2 values", ":2:1"),
        ("EYX_um\n1\n", "no `position_mm`", ":1:1"),
    ];
    for (csv, message, place) in cases {
        std::fs::write(dir.join("x.csv"), csv).unwrap();
        let mut text = std::fs::read_to_string(common::machine("vmc-3axis")).unwrap();
        text.push_str("\n[component_errors]\nX = \"x.csv\"\n");
        std::fs::write(dir.join("m.toml"), text).unwrap();
        let scenario = common::write_scenario(
            &dir,
            &dir.join("m.toml").display().to_string(),
            "[program.circle]\nplane = \"XY\"\nradius_mm = 10.0\nfeed_mm_min = 500.0\ncenter_mm = [0.0, 0.0, 100.0]\n",
        );
        let run = common::mtsim(&["simulate", scenario.to_str().unwrap(), "-o", "/dev/null/x"]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{csv}: {stderr}");
        assert!(stderr.contains(message), "{csv}: {stderr}");
        assert!(
            stderr.contains(&format!("x.csv{place}")),
            "{csv}: no {place} in {stderr}"
        );
    }
}
