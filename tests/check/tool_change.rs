//! The tool in the spindle follows the program (T + M6, M61 Q): the collision scene takes
//! each tool-table tool's length and diameter when the samples reach the block that changed
//! it, and the clearances that `check` reports are the ones worked out by hand below.
//!
//! The machine is the bundled vmc-3axis (pivot at the origin, no rotary axes): the table top
//! is the plane z = 0 (radius 200 mm) and the default trunnion's right wall has its inner
//! face at x = 250 mm (up to z = 60 mm). The scenario's `[tool]` is the machine's (tip at
//! the Z point, gauge length 140 mm, holder 50 x 60 mm). A tool-table length L puts the
//! tip L below the Z point (docs/scene.md), so that G43 H lands it on the programmed Z.

use crate::common;

use std::path::Path;

use common::{machine, scratch};
use mtsim::check::limits::{Violation, ViolationKind};
use mtsim::check::{check, CheckOptions, CheckReport};
use mtsim::input::scenario::Scenario;

const TOOL_TABLE: &str = "\
T1 P1 Z+0.0 D10.0 ; short 10 mm end mill, tip at the Z point
T2 P2 Z+25.0 D10.0 ; the same, 25 mm longer
T3 P3 Z+10.0 D40.0 ; a 40 mm cutter, 10 mm longer
";

fn run(name: &str, program: &str, reader: &str) -> CheckReport {
    let dir = scratch("tool-change", name);
    std::fs::write(dir.join("tools.tbl"), TOOL_TABLE).unwrap();
    std::fs::write(dir.join("p.ngc"), program).unwrap();
    let text = format!(
        "machine = {:?}\n[program]\nfile = \"p.ngc\"\n[reader]\ndialect = \"linuxcnc\"\n{reader}",
        machine("vmc-3axis")
    );
    let path = dir.join("s.toml");
    std::fs::write(&path, text).unwrap();
    let scenario = Scenario::load(Path::new(&path)).unwrap();
    check(&scenario, &CheckOptions::default()).unwrap()
}

fn bodies(v: &Violation) -> Vec<String> {
    let mut b = v.bodies.clone().unwrap().to_vec();
    b.sort();
    b
}

#[test]
fn a_longer_tool_without_its_offset_plunges_into_the_table_where_the_short_one_cleared_it() {
    // With T1 the tip is 20 mm above the table top. T2 hangs 25 mm further down: without
    // G43 its tip is 5 mm into the table. With G43 H2 the Z axis goes 25 mm higher for the
    // same programmed Z, and the tip is back 20 mm above the table.
    let program = "G21 G90 G17\n\
                   T1 M6\n\
                   G0 X0 Y0 Z20\n\
                   G4 P0.5\n\
                   T2 M6\n\
                   G4 P0.5\n\
                   G0 Z60\n\
                   G43 H2\n\
                   G0 Z20\n\
                   G4 P0.5\n\
                   M2\n";
    let r = run("long", program, "tool_table = \"tools.tbl\"\n");
    let collisions: Vec<_> = r
        .violations
        .iter()
        .filter(|v| v.kind == ViolationKind::Collision)
        .collect();
    assert_eq!(collisions.len(), 1, "{:#?}", r.violations);
    let c = collisions[0];
    assert_eq!(bodies(c), ["cutter", "table"]);
    assert!((c.worst - 5.0).abs() < 1e-6, "depth {}", c.worst);
    assert_eq!(c.line, 6, "the dwell after T2 M6");
    // The short tool and the compensated long tool both clear the table by 20 mm; the
    // smallest clearance of the run is the 5 mm penetration.
    assert!((r.min_clearance_mm.unwrap() + 5.0).abs() < 1e-6);
}

#[test]
fn the_same_program_with_the_short_tool_only_is_clean() {
    let program = "G21 G90 G17\nT1 M6\nG0 X0 Y0 Z20\nG4 P0.5\nG4 P0.5\nM2\n";
    let r = run("short", program, "tool_table = \"tools.tbl\"\n");
    assert!(r.violations.is_empty(), "{:#?}", r.violations);
    // The cutter's tip 20 mm above the table top is the nearest approach of any pair.
    assert!(
        (r.min_clearance_mm.unwrap() - 20.0).abs() < 1e-6,
        "{:?} {:?}",
        r.min_clearance_mm,
        r.min_clearance_bodies
    );
}

#[test]
fn a_wider_cutter_comes_within_the_near_miss_of_the_trunnion_wall() {
    // The tool axis at X = 229 mm: T1's 5 mm radius clears the wall (x = 250) by 16 mm,
    // T3's 20 mm radius by 1 mm (its tip 10 mm above the table top, the wall up to z = 60).
    // M61 Q3 changes the tool without a tool-change move.
    let program = "G21 G90 G17\n\
                   T1 M6\n\
                   G0 X229 Y0 Z30\n\
                   G4 P0.5\n\
                   M61 Q3\n\
                   G4 P0.5\n\
                   M2\n";
    let r = run("wide", program, "tool_table = \"tools.tbl\"\n");
    // A table tool's shank has the cutter's diameter, so cutter and shank both pass 1 mm
    // from the wall (the cutter from z = 10 to 50, the shank above it).
    let mut near: Vec<_> = r.violations.iter().map(|v| (bodies(v), v)).collect();
    near.sort_by(|a, b| a.0.cmp(&b.0));
    assert_eq!(near.len(), 2, "{:#?}", r.violations);
    assert_eq!(near[0].0, ["cradle wall +X", "cutter"]);
    assert_eq!(near[1].0, ["cradle wall +X", "shank"]);
    for (_, v) in near {
        assert_eq!(v.kind, ViolationKind::NearMiss);
        assert_eq!(v.line, 6, "the dwell after M61 Q3");
        assert!((v.worst - 1.0).abs() < 1e-6, "clearance {}", v.worst);
    }
    // With T1 the nearest pair was 16 mm apart; nothing came nearer than T3's 1 mm.
    assert!((r.min_clearance_mm.unwrap() - 1.0).abs() < 1e-6);
}

#[test]
fn an_inline_tool_brings_its_own_holder() {
    // Inline tool 4: 30 mm longer than the [tool] (gauge length 170 mm) with a 100 mm wide,
    // 120 mm long holder: its bottom face is 170 - 120 = 50 mm above the tip. The tool is
    // compensated (G43 H4), tip at Z = 5 over the table: the holder's face is 55 mm above
    // the table top, and at X = 215 the holder (radius 50, out to x = 265) overhangs the
    // trunnion wall (x >= 250, top at z = 60): 5 mm into it, the least way out being up.
    let reader = "tools = [{ number = 4, length_mm = 30.0, diameter_mm = 10.0, \
                  holder_diameter_mm = 100.0, holder_length_mm = 120.0 }]\n";
    let program = "G21 G90 G17\nT4 M6 G43 H4\nG0 X215 Y0 Z5\nG4 P0.5\nM2\n";
    let r = run("holder", program, reader);
    let holder: Vec<_> = r
        .violations
        .iter()
        .filter(|v| bodies(v).contains(&"holder".to_string()))
        .collect();
    assert_eq!(holder.len(), 1, "{:#?}", r.violations);
    assert_eq!(holder[0].kind, ViolationKind::Collision);
    assert!((holder[0].worst - 5.0).abs() < 1e-6, "{}", holder[0].worst);
}

#[test]
fn the_servo_run_changes_the_tool_at_the_same_block() {
    // `check --dynamics` samples the interpolator and servo instead of the programmed
    // timing; the tool still changes at the dwell after T2 M6, where the axes stand still.
    let program = "G21 G90 G17\nT1 M6\nG0 X0 Y0 Z20\nG4 P1\nT2 M6\nG4 P1\nM2\n";
    let dir = scratch("tool-change", "dynamics");
    std::fs::write(dir.join("tools.tbl"), TOOL_TABLE).unwrap();
    std::fs::write(dir.join("p.ngc"), program).unwrap();
    let text = format!(
        "machine = {:?}\n[program]\nfile = \"p.ngc\"\n[reader]\ndialect = \"linuxcnc\"\ntool_table = \"tools.tbl\"\n",
        machine("vmc-3axis")
    );
    std::fs::write(dir.join("s.toml"), text).unwrap();
    let scenario = Scenario::load(&dir.join("s.toml")).unwrap();
    let options = CheckOptions {
        dynamics: true,
        ..CheckOptions::default()
    };
    let r = check(&scenario, &options).unwrap();
    let c: Vec<_> = r
        .violations
        .iter()
        .filter(|v| v.kind == ViolationKind::Collision)
        .collect();
    assert_eq!(c.len(), 1, "{:#?}", r.violations);
    assert_eq!(c[0].line, 6);
    assert!((c[0].worst - 5.0).abs() < 1e-3, "depth {}", c[0].worst);
}

#[test]
fn a_tool_whose_tip_would_sit_inside_the_holder_is_refused_with_what_to_do() {
    // T5 is 100 mm shorter than the [tool]: gauge length 40 mm, less than the 60 mm holder.
    let dir = scratch("tool-change", "refused");
    std::fs::write(dir.join("p.ngc"), "G21\nT5 M6\nG0 X0 Y0 Z50\nM2\n").unwrap();
    let text = format!(
        "machine = {:?}\n[program]\nfile = \"p.ngc\"\n[reader]\ndialect = \"linuxcnc\"\ntools = [{{ number = 5, length_mm = -100.0, diameter_mm = 6.0 }}]\n",
        machine("vmc-3axis")
    );
    std::fs::write(dir.join("s.toml"), text).unwrap();
    let scenario = Scenario::load(&dir.join("s.toml")).unwrap();
    let e = check(&scenario, &CheckOptions::default()).unwrap_err();
    assert_eq!(e.exit_code(), 2);
    let message = e.to_string();
    assert!(
        message.contains("T5") && message.contains("gauge_length_mm"),
        "{message}"
    );
}

#[test]
fn under_tcp_the_tool_length_lies_along_the_tool_axis_not_the_tables_z() {
    // trt-ac, pivot at the origin. T1 is 30 mm long; G43.4 H1 puts its tip on table
    // (0, 0, 20). At A = 90 deg Rx(90) takes table +Z to machine -Y, so the tip is at
    // machine (0, -20, 0) and the Z point 30 mm above it along the spindle: (0, -20, 30).
    // Over the move Y = -20 sin A and Z = 20 cos A + 30.
    let dir = scratch("tool-change", "tcp-length");
    std::fs::write(
        dir.join("p.nc"),
        "G21 G90\nT1 M6\nG43.4 H1\nG1 F500 X0 Y0 Z20 A0 C0\nG1 A90\nG49\nM30\n",
    )
    .unwrap();
    let text = format!(
        "machine = {:?}\n[program]\nfile = \"p.nc\"\n[reader]\ntools = [{{ number = 1, length_mm = 30.0, diameter_mm = 10.0 }}]\n[check]\ncollisions = false\n",
        machine("trt-ac")
    );
    std::fs::write(dir.join("s.toml"), text).unwrap();
    let scenario = Scenario::load(&dir.join("s.toml")).unwrap();
    let r = check(&scenario, &CheckOptions::default()).unwrap();
    let (y, z) = (&r.axes["Y"], &r.axes["Z"]);
    assert!((y.min + 20.0).abs() < 1e-6 && y.max.abs() < 1e-6, "{y:?}");
    assert!(
        (z.min - 30.0).abs() < 1e-6 && (z.max - 50.0).abs() < 1e-6,
        "{z:?}"
    );
    // The interpolator and servos (check --dynamics) reach the same end, settled.
    let options = CheckOptions {
        dynamics: true,
        ..CheckOptions::default()
    };
    let r = check(&scenario, &options).unwrap();
    let (y, z) = (&r.axes["Y"], &r.axes["Z"]);
    assert!((y.min + 20.0).abs() < 0.01, "{y:?}");
    assert!((z.min - 30.0).abs() < 0.01, "{z:?}");
}
