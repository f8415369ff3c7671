//! The geometric errors in the error budget, one row per cause: the rotaries' location
//! errors, the squareness of the linear axes and each linear axis's ISO 230-1 table, each
//! against a closed form (a circle) or the commanded path read through a forward kinematics
//! written out here (a cone).

use std::path::PathBuf;

use mtsim::report::run::BudgetMechanism;

use super::budget::{
    assert_consistent, budget, centred_peak_to_valley, circle, clean, commanded_rows, cone,
    g_direction, rows, run, trt_ac_reading, CONE_AXES,
};
use crate::common::scratch;

/// An X table whose only error is a straightness in Y growing linearly with X:
/// `EYX(x) = k x`, k in µm per mm, over ±500 mm; its absolute path.
fn x_straightness_table(name: &str, k_um_per_mm: f64) -> PathBuf {
    let dir = scratch("budget-tables", name);
    let path = dir.join("x.csv");
    let mut text = String::from("position_mm,EXX_um,EYX_um,EZX_um,EAX_urad,EBX_urad,ECX_urad\n");
    for x in [-500.0, 0.0, 500.0] {
        text += &format!("{x},0,{},0,0,0,0\n", k_um_per_mm * x);
    }
    std::fs::write(&path, text).unwrap();
    path
}

/// Overrides giving the machine squareness `EC0Y` (µrad) and the X table at `table`.
fn squareness_and_table(ec0y_urad: f64, table: &PathBuf) -> String {
    format!(
        "[machine_overrides.location_errors]\nEC0Y_urad = {ec0y_urad}\n\
         [machine_overrides.component_errors]\nX = {:?}\n",
        table.display().to_string()
    )
}

/// On an XY circle of radius r, squareness ε alone reads `−(r ε / 2) sin 2θ` (ISO 230-4's
/// ellipse), and a Y straightness of X growing as k x shears the circle, `±(r k / 2) sin 2θ`:
/// peak-to-valley r ε and r k. Each is a row of its own; the rotaries have no errors, so no
/// geometric row, and Y and Z have no table, so no rows for them.
#[test]
fn squareness_and_a_straightness_table_are_rows_of_their_own_on_a_circle() {
    let (eps_urad, k) = (60.0, 0.1);
    let table = x_straightness_table("circle", k);
    let text = circle(&clean(
        &["X", "Y", "Z"],
        &[],
        &[],
        &squareness_and_table(eps_urad, &table),
    ));
    let (s, _) = run("squareness-circle", &text);
    assert_consistent(&s, &[]);
    let b = budget(&s);
    assert!(rows(b, BudgetMechanism::Geometric).is_empty(), "{b:?}");
    let square = rows(b, BudgetMechanism::Squareness);
    assert_eq!(square.len(), 1, "{b:?}");
    assert_eq!(square[0].axis, None);
    let r_mm = 50.0;
    let want = r_mm * eps_urad * 1e-3;
    assert!(
        (square[0].pv_um - want).abs() <= 0.01 * want,
        "squareness row {} µm, closed form r ε = {want} µm",
        square[0].pv_um
    );
    let tables = rows(b, BudgetMechanism::ComponentErrors);
    assert_eq!(tables.len(), 1, "{b:?}");
    assert_eq!(tables[0].axis.as_deref(), Some("X"));
    let want = r_mm * k;
    assert!(
        (tables[0].pv_um - want).abs() <= 0.01 * want,
        "X table row {} µm, closed form r k = {want} µm",
        tables[0].pv_um
    );
    // The two make almost all of G (the servos are alike and the chords short).
    let geometric: f64 = square[0].share + tables[0].share;
    assert!(geometric > 0.9, "{b:?}");
    eprintln!(
        "circle: squareness row {:.4} µm share {:.3}, X table row {:.4} µm share {:.3}, G {:.3} µm",
        square[0].pv_um, square[0].share, tables[0].pv_um, tables[0].share, b.g_um
    );
}

/// On the cone (trt-ac, whose X, Y and Z carry the tool), each row against the commanded
/// positions read through a forward kinematics written out here: squareness ε turns Y's
/// line to `(−ε, 1, 0)/√(1+ε²)`, so the tool is at `(x − ε y/n, y/n, z)`; the X table
/// moves the tool by `(0, k x, 0)`. A row is the centred difference from the nominal
/// reading.
#[test]
fn squareness_and_a_straightness_table_are_rows_of_their_own_on_a_cone() {
    let (eps_urad, k) = (200.0, 0.1);
    let table = x_straightness_table("cone", k);
    let (linear, rotary) = CONE_AXES;
    let text = cone(&clean(
        linear,
        rotary,
        &[],
        &squareness_and_table(eps_urad, &table),
    ));
    let (s, out) = run("squareness-cone", &text);
    assert_consistent(&s, &[]);
    let b = budget(&s);
    assert!(rows(b, BudgetMechanism::Geometric).is_empty(), "{b:?}");
    let (_, direction) = g_direction(&s);
    let commanded = commanded_rows(&out, direction);
    assert!(commanded.len() > 10_000, "{}", commanded.len());
    let row_of = |moved: &dyn Fn([f64; 5]) -> [f64; 5]| {
        let samples: Vec<(f64, f64)> = commanded
            .iter()
            .map(|(t, q)| {
                (
                    *t,
                    trt_ac_reading(moved(*q), 100.0) - trt_ac_reading(*q, 100.0),
                )
            })
            .collect();
        centred_peak_to_valley(&samples)
    };
    let eps = eps_urad * 1e-6;
    let n = (1.0 + eps * eps).sqrt();
    let want_square = row_of(&|[x, y, z, a, c]| [x - eps * y / n, y / n, z, a, c]);
    let want_table = row_of(&|[x, y, z, a, c]| [x, y + k * x * 1e-3, z, a, c]);
    let square = rows(b, BudgetMechanism::Squareness);
    let tables = rows(b, BudgetMechanism::ComponentErrors);
    assert_eq!((square.len(), tables.len()), (1, 1), "{b:?}");
    eprintln!(
        "cone: squareness row {:.4} µm (written out {want_square:.4}), X table row {:.4} µm \
         (written out {want_table:.4})",
        square[0].pv_um, tables[0].pv_um
    );
    // The trace's positions are written to 6 decimals and binned as the run's are.
    assert!(
        want_square > 1.0 && want_table > 1.0,
        "{want_square} {want_table}"
    );
    assert!(
        (square[0].pv_um - want_square).abs() <= 0.05,
        "squareness row {} µm, written out {want_square} µm",
        square[0].pv_um
    );
    assert!(
        (tables[0].pv_um - want_table).abs() <= 0.05,
        "X table row {} µm, written out {want_table} µm",
        tables[0].pv_um
    );
}
