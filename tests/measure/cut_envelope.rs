//! The cut's depths and its streamed envelope (`measure::cut::geometry`, `measure::cut::envelope`)
//! against a closed form and against a brute-force envelope: a cutter moved off the nominal
//! cut cone along the surface normal by δ leaves δ at every row on its flutes, whatever the
//! number of rows (the rows go four at a time, the last chunk filled up); and the envelope
//! streamed with its pruning (the clearance bound, and the buffer's order in θ) is, bit for
//! bit, the least depth of every position at every grid point computed without pruning.

use mtsim::measure::cut::envelope::Envelope;
use mtsim::measure::cut::geometry::{CutGeometry, CutterLine, Row, NOT_CUT};
use nalgebra::Vector3;

use crate::cut::{cone_body, scenario, the_cone};

/// The 15° cone of L = 100 mm with a 20 mm cutter, 40 mm of flutes.
fn geometry() -> CutGeometry {
    let s = scenario("envelope", &cone_body(15.0, 10.0, 100.0), 20.0, 40.0);
    CutGeometry::new(&the_cone(&s), 10.0, 40.0)
}

/// Rows at heights `z`, mm, on the nominal frustum.
fn rows(g: &CutGeometry, z: &[f64]) -> Vec<Row> {
    z.iter()
        .map(|&z_mm| Row {
            z_mm,
            radius_mm: g.radius_at(z_mm),
        })
        .collect()
}

/// The nominal cutter at θ (rad), moved by `delta_mm` along the surface normal n(θ): tip
/// `L (cos α cos θ, cos α sin θ, sin α) + δ n`, axis along the generatrix,
/// `(−sin α cos θ, −sin α sin θ, cos α)`.
fn cutter(g: &CutGeometry, theta: f64, delta_mm: f64) -> CutterLine {
    let (sa, ca) = g.alpha_rad.sin_cos();
    let (st, ct) = theta.sin_cos();
    let n = Vector3::new(ca * ct, ca * st, sa);
    CutterLine {
        tip: Vector3::new(ca * ct, ca * st, sa) * g.length_mm + n * delta_mm,
        axis: Vector3::new(-sa * ct, -sa * st, ca),
    }
}

/// The cutter's axis is perpendicular to n (n·t = cos α sin α − sin α cos α = 0) and lies R
/// from the nominal surface, so moved by δ along n it meets the ray `S + d n` at d = δ on
/// every row between the tip height (L − R) sin α = 23.29 mm and the flutes' end 23.29 +
/// 40 cos α = 61.93 mm, and nowhere above; for 1 to 9 rows (whole chunks of four and tails).
#[test]
fn a_cutter_moved_along_the_normal_leaves_its_offset_on_every_row() {
    let g = geometry();
    assert!((g.tip_height_mm() - 90.0 * 15f64.to_radians().sin()).abs() < 1e-12);
    let delta_mm = 0.005;
    for theta_deg in [0.0, 37.0, 211.5] {
        let theta = f64::to_radians(theta_deg);
        let line = cutter(&g, theta, delta_mm);
        for count in 1..=9 {
            // Every other row above the flutes' end (62 to 70 mm): not cut.
            let z: Vec<f64> = (0..count)
                .map(|i| match i % 2 {
                    0 => 24.0 + 4.0 * i as f64,
                    _ => 62.5 + i as f64,
                })
                .collect();
            let rows = rows(&g, &z);
            let mut out = vec![-1.0; count];
            g.depths_um(theta.sin_cos().rev2(), &rows, &line, &mut out);
            for (i, d) in out.iter().enumerate() {
                if i % 2 == 0 {
                    assert!(
                        (d - 5.0).abs() < 1e-6,
                        "θ {theta_deg}°, {count} rows, row {i} at z {}: {d} um",
                        z[i]
                    );
                } else {
                    assert_eq!(*d, NOT_CUT, "θ {theta_deg}°, {count} rows, row {i}");
                }
            }
        }
    }
}

/// `(sin, cos)` → `(cos, sin)`.
trait Rev2 {
    fn rev2(self) -> (f64, f64);
}

impl Rev2 for (f64, f64) {
    fn rev2(self) -> (f64, f64) {
        (self.1, self.0)
    }
}

/// A deterministic jitter in [−1, 1) (a linear congruential generator's top bits).
fn jitter(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*state >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// Positions about the revolution: θ_k stepping by `step_deg` (negative: clockwise) with
/// `back` of them stepping back by a third of a step, each moved along n by
/// 3 µm sin 5θ + 1 µm of jitter.
fn positions(g: &CutGeometry, count: usize, step_deg: f64, back: usize) -> Vec<CutterLine> {
    let mut state = 7;
    let mut theta_deg: f64 = 3.0;
    (0..count)
        .map(|k| {
            theta_deg += match back > 0 && k % (count / back.max(1)) == 1 {
                true => -step_deg / 3.0,
                false => step_deg,
            };
            let theta = theta_deg.to_radians();
            let delta_mm = 3e-3 * (5.0 * theta).sin() + 1e-3 * jitter(&mut state);
            cutter(g, theta, delta_mm)
        })
        .collect()
}

/// The least depth of every position at every grid point, without pruning.
fn brute_force(g: &CutGeometry, envelope: &Envelope, lines: &[CutterLine]) -> Vec<f64> {
    let h = envelope.rows.len();
    let mut values = vec![NOT_CUT; envelope.column_count() * h];
    let mut out = vec![0.0; h];
    for j in 0..envelope.column_count() {
        let theta = (j as f64 * envelope.step_deg).to_radians();
        for line in lines {
            g.depths_um(theta.sin_cos().rev2(), &envelope.rows, line, &mut out);
            for (v, d) in values[j * h..(j + 1) * h].iter_mut().zip(&out) {
                *v = v.min(*d);
            }
        }
    }
    values
}

/// Counter-clockwise, clockwise, and with positions stepping back (the buffer out of order,
/// its unpruned scan), 1.3 revolutions at 0.5° a column and 4 positions a column: every grid
/// point the same bits as the brute force, and every point cut.
#[test]
fn the_streamed_envelope_is_the_least_depth_of_every_position() {
    let g = geometry();
    let rows = rows(&g, &[23.4, 30.0, 42.6, 55.0, 61.8]);
    for (step_deg, back) in [(0.125, 0), (-0.125, 0), (0.125, 40)] {
        let lines = positions(&g, 3744, step_deg, back);
        let mut envelope = Envelope::new(&g, 0.5, rows.clone());
        for line in &lines {
            envelope.push(&g, *line);
        }
        envelope.end_run(&g);
        let expected = brute_force(&g, &envelope, &lines);
        assert!(expected.iter().all(|d| d.is_finite() && d.abs() < 5.0));
        for (p, (got, want)) in envelope.values.iter().zip(&expected).enumerate() {
            assert_eq!(
                got.to_bits(),
                want.to_bits(),
                "step {step_deg}°, {back} back: point {p}: {got} against {want} um"
            );
        }
    }
}
