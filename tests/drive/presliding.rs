//! Pre-sliding friction through the servo: the reversal value an axis reports is the one it
//! shows in an ISO 230-2 bidirectional approach, `B = b + 2 Fc / k`, and the Dahl bristle
//! takes the friction over gradually, `F = Fc (1 - 2 exp(-s / δ))` after a reversal.

use mtsim::drive::AxisServo;
use mtsim::input::drive::{AxisDrive, DriveConfig, FrictionConfig, ServoConfig};
use mtsim::Axis;

/// b 10 um, Fc 150 N, k 200 N/um, δ 2 um, semi-closed cascade loop.
fn servo(presliding_um: Option<f64>) -> AxisServo {
    let servo = ServoConfig {
        model: "cascade".into(),
        ..Default::default()
    };
    let drive = DriveConfig {
        backlash_mm: Some(0.010),
        stiffness_n_per_um: Some(200.0),
        ..Default::default()
    };
    let friction = FrictionConfig {
        coulomb_n: Some(150.0),
        static_ratio: Some(1.0),
        presliding_um,
        ..Default::default()
    };
    AxisServo::new(
        &AxisDrive::resolve(Axis::X, &servo, &drive, &friction).unwrap(),
        1e-3,
        0.0,
    )
    .unwrap()
}

/// Moves from `from` to `to` mm at 10 mm/s with 1 ms setpoints, then dwells 1.5 s; returns
/// the table position at the end, mm.
fn approach(s: &mut AxisServo, from: f64, to: f64, t: &mut f64) -> f64 {
    let steps = ((to - from).abs() / 0.01).round() as usize;
    let mut actual = 0.0;
    for k in 1..=steps + 1500 {
        *t += 1e-3;
        let x = from + (to - from) * (k.min(steps) as f64 / steps as f64);
        actual = s.step(x, *t).unwrap().actual;
    }
    actual
}

#[test]
fn the_bidirectional_approach_shows_the_reported_reversal_value() {
    for presliding in [None, Some(2.0)] {
        let mut s = servo(presliding);
        let r = s.reversal_value();
        // b + 2 Fc / k = 0.010 + 2 * 150 / 200e3 mm = 0.0115 mm.
        assert!((r.b - 0.0115).abs() < 1e-12, "{r:?}");
        assert!((r.backlash - 0.010).abs() < 1e-12 && (r.elastic - 0.0015).abs() < 1e-12);
        let mut t = 0.0;
        approach(&mut s, 0.0, 5.0, &mut t);
        let up = approach(&mut s, 5.0, 10.0, &mut t);
        approach(&mut s, 10.0, 15.0, &mut t);
        let down = approach(&mut s, 15.0, 10.0, &mut t);
        let b = down - up;
        assert!(
            (b - r.b).abs() < 0.03 * r.b,
            "presliding {presliding:?}: B {b} mm vs {} mm",
            r.b
        );
    }
}

#[test]
fn presliding_turns_the_friction_over_gradually_after_a_reversal() {
    // With the motor driven slowly back through the gap, the table's friction force (the
    // spring force at quasi-static balance) follows Fc (1 - 2 exp(-s/δ)) of table travel s.
    // Checked through the servo: the table travel from the reversal at which the drive
    // force has fallen to zero is δ ln 2 = 1.386 um, where Coulomb friction gives ~0.
    let travel_at_zero_force = |presliding: Option<f64>| -> f64 {
        let mut s = servo(presliding);
        let mut t = 0.0;
        approach(&mut s, 0.0, 1.0, &mut t);
        // Back at 0.1 mm/s, watching the table.
        let start = s.step(1.0, t).unwrap().actual;
        let mut extreme = start;
        let mut out = f64::NAN;
        for k in 1..20_000 {
            t += 1e-3;
            let st = s.step(1.0 - k as f64 * 1e-4, t).unwrap();
            extreme = extreme.max(st.actual);
            // The drive force changes sign once the motor has crossed the gap and the table
            // friction has turned over: the travel since the table's extreme then.
            if st.force < 0.0 && out.is_nan() && extreme - st.actual > 0.0 {
                out = extreme - st.actual;
            }
        }
        out * 1e3
    };
    let dahl = travel_at_zero_force(Some(2.0));
    let want = 2.0 * 2f64.ln();
    println!("table travel at zero drive force: Dahl {dahl:.3} um (closed form {want:.3} um)");
    assert!(
        (dahl - want).abs() < 0.25 * want,
        "Dahl: {dahl} um vs {want} um"
    );
    // Coulomb friction with stiction: the table holds until the force has reversed fully.
    let coulomb = travel_at_zero_force(None);
    println!("... Coulomb {coulomb:.4} um");
    assert!(
        coulomb.is_nan() || coulomb < 0.1 * want,
        "Coulomb: {coulomb} um"
    );
}
