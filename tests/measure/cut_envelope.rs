//! The cut's depths and its streamed envelope (`measure::cut::geometry`, `measure::cut::envelope`)
//! against a closed form and against a brute-force envelope: a cutter moved off the nominal
//! cut cone along the surface normal by δ leaves δ at every row on its flutes, whatever the
//! number of rows (the rows go four at a time, the last chunk ending at the last row), and
//! bit for bit the row-by-row formula at any width; and the envelope
//! streamed with its pruning (the clearance bound, and the buffer's order in θ) is, bit for
//! bit, the least depth of every position at every grid point computed without pruning.

use mtsim::measure::cut::envelope::Envelope;
use mtsim::measure::cut::geometry::{CutGeometry, CutterLine, Row, NOT_CUT};
use mtsim::measure::cut::least_bound::{least_depth_bounds_um, Chord};
use nalgebra::{Rotation3, Vector3};

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
/// The envelope of `lines` streamed over `rows`, and [`brute_force`]'s least depths of the
/// same positions.
fn streamed_and_brute_force(
    g: &CutGeometry,
    rows: &[Row],
    lines: &[CutterLine],
) -> (Envelope, Vec<f64>) {
    let mut envelope = Envelope::new(g, 0.5, rows.to_vec());
    for line in lines {
        envelope.push(g, *line);
    }
    envelope.end_run(g);
    let expected = brute_force(g, &envelope, lines);
    (envelope, expected)
}

/// Every point of `got` has the bits of `want`'s.
fn assert_same_bits(got: &[f64], want: &[f64], case: &str) {
    assert_eq!(got.len(), want.len(), "{case}: point counts");
    for (p, (got, want)) in got.iter().zip(want).enumerate() {
        assert_eq!(
            got.to_bits(),
            want.to_bits(),
            "{case}: point {p}: {got} against {want} um"
        );
    }
}

#[test]
fn the_streamed_envelope_is_the_least_depth_of_every_position() {
    let g = geometry();
    let rows = rows(&g, &[23.4, 30.0, 42.6, 55.0, 61.8]);
    for (step_deg, back) in [(0.125, 0), (-0.125, 0), (0.125, 40)] {
        let lines = positions(&g, 3744, step_deg, back);
        let (envelope, expected) = streamed_and_brute_force(&g, &rows, &lines);
        assert!(expected.iter().all(|d| d.is_finite() && d.abs() < 5.0));
        assert_same_bits(
            &envelope.values,
            &expected,
            &format!("step {step_deg}°, {back} back"),
        );
    }
}

/// The depth of `line` at one row by the module's formula (`measure::cut::geometry`), row
/// by row: `A = 1 − (n·t)²`, `B = w·n − (w·t)(n·t)`, `C = |w|² − (w·t)² − R²`,
/// `d = (−B − √(B² − A C)) / A` (as a product with 1/A), cut where the discriminant is not
/// negative, `B < 0` and the entry lies on the flutes; [`NOT_CUT`] otherwise.
fn depth_of_row(g: &CutGeometry, (c, s): (f64, f64), row: Row, line: &CutterLine) -> f64 {
    let (sa, ca) = g.alpha_rad.sin_cos();
    let n = Vector3::new(ca * c, ca * s, sa);
    let t = line.axis;
    let nt = n.dot(&t);
    let a = 1.0 - nt * nt;
    if a < 1e-12 {
        return NOT_CUT;
    }
    let w = Vector3::new(row.radius_mm * c, row.radius_mm * s, row.z_mm) - line.tip;
    let wt = w.dot(&t);
    let b = w.dot(&n) - wt * nt;
    let cc = w.norm_squared() - wt * wt - g.cutter_radius_mm * g.cutter_radius_mm;
    let disc = b * b - a * cc;
    let d = (-b - disc.sqrt()) * (1.0 / a);
    let along = wt + d * nt;
    if disc >= 0.0 && b < 0.0 && along >= 0.0 && along <= g.flute_length_mm {
        d * 1e3
    } else {
        NOT_CUT
    }
}

/// Every row's depth is the row-by-row formula's, bit for bit, whatever the number of rows
/// (1 to 30: below a chunk, whole chunks, and a last chunk overlapping the one before) and
/// however many rows go side by side (1, 2, 3, 4 as `depths_um` takes them, 8): cutters
/// tilted and moved off the nominal by a few µm, with rows above the flutes' end (not cut).
#[test]
fn the_depths_are_each_rows_formula_whatever_the_rows_side_by_side() {
    let g = geometry();
    let mut state = 11;
    let mut cut = 0;
    for case in 0..40 {
        let theta = f64::to_radians(9.0 * case as f64 + 0.3);
        let mut line = cutter(&g, theta, 5e-3 * jitter(&mut state));
        line.axis = (line.axis + Vector3::new(jitter(&mut state), jitter(&mut state), 0.0) * 2e-4)
            .normalize();
        let column = (theta + 1e-3 * jitter(&mut state)).sin_cos().rev2();
        for count in 1..=30 {
            let z: Vec<f64> = (0..count)
                .map(|i| 23.4 + 44.0 * i as f64 / count as f64)
                .collect();
            let rows = rows(&g, &z);
            let want: Vec<f64> = rows
                .iter()
                .map(|&r| depth_of_row(&g, column, r, &line))
                .collect();
            cut += want.iter().filter(|d| d.is_finite()).count();
            let mut got = vec![-1.0; count];
            let check = |width: &str, got: &[f64]| {
                for (i, (d, w)) in got.iter().zip(&want).enumerate() {
                    assert_eq!(
                        d.to_bits(),
                        w.to_bits(),
                        "case {case}, {count} rows, {width}: row {i}: {d} against {w} um"
                    );
                }
            };
            g.depths_um(column, &rows, &line, &mut got);
            check("depths_um", &got);
            g.depths_um_by::<1>(column, &rows, &line, &mut got);
            check("1 a time", &got);
            g.depths_um_by::<2>(column, &rows, &line, &mut got);
            check("2 a time", &got);
            g.depths_um_by::<3>(column, &rows, &line, &mut got);
            check("3 a time", &got);
            g.depths_um_by::<8>(column, &rows, &line, &mut got);
            check("8 a time", &got);
        }
    }
    // Rows cut and rows not cut (above the flutes' end, 61.93 mm) both.
    let all = 40 * (1..=30).sum::<usize>();
    assert!(cut > all / 2 && cut < all, "{cut} of {all} rows cut");
}

/// `wrap_euclid(x, n)` is `x.rem_euclid(n)` bit for bit: inside (−n, 2n), at its edges,
/// signed zeros, far outside, infinities and NaN.
#[test]
fn the_contacts_wrap_is_rem_euclid() {
    use mtsim::measure::cut::envelope::wrap_euclid;
    let n = 3600.0;
    let mut xs = vec![
        0.0,
        -0.0,
        n,
        -n,
        2.0 * n,
        -2.0 * n,
        n / 2.0,
        1e-300,
        -1e-300,
        n - 1e-12,
        2.0 * n - 1e-12,
        -n + 1e-12,
        -n - 1e-12,
        1e9,
        -1e9,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NAN,
    ];
    let mut state = 5;
    xs.extend((0..10_000).map(|_| 3.0 * n * jitter(&mut state)));
    for x in xs {
        let (got, want) = (wrap_euclid(x, n), x.rem_euclid(n));
        assert_eq!(
            got.to_bits(),
            want.to_bits(),
            "x = {x:e}: {got:e} against {want:e}"
        );
    }
}

/// Positions that come back to columns already computed (every 97th returns twice the
/// reach behind, 6 µm deeper than its neighbours: the envelope applies it to those columns
/// directly), both senses: every grid point the brute force's bits, and the returns did
/// lower the surface.
#[test]
fn positions_coming_back_to_computed_columns_are_applied_to_them() {
    let g = geometry();
    let rows = rows(&g, &[23.4, 30.0, 42.6, 55.0, 61.8]);
    // The reach, in columns of 0.5° (`Envelope::new`): twice it behind is computed.
    let per_column2 = Envelope::new(&g, 0.5, rows.clone()).clearance_per_column2_um();
    let reach = (200.0 / per_column2).sqrt().ceil().clamp(2.0, 400.0);
    let back_steps = 2.0 * reach * 4.0;
    assert!(back_steps * 0.125 < 180.0, "reach {reach} columns");
    for step_deg in [0.125, -0.125] {
        let mut state = 3;
        let mut theta_deg: f64 = 3.0;
        let lines: Vec<CutterLine> = (0..3744)
            .map(|k| {
                theta_deg += step_deg;
                let jitter_mm = 1e-3 * jitter(&mut state);
                match k % 97 == 96 {
                    true => cutter(&g, (theta_deg - back_steps * step_deg).to_radians(), -6e-3),
                    false => cutter(&g, theta_deg.to_radians(), jitter_mm),
                }
            })
            .collect();
        let (envelope, expected) = streamed_and_brute_force(&g, &rows, &lines);
        assert!(expected.iter().filter(|d| **d < -3.0).count() > 100);
        assert_same_bits(&envelope.values, &expected, &format!("step {step_deg}°"));
    }
}

/// The cutter at θ moved by δ along n(θ), then turned about a point 20 mm up its axis by
/// `tangential` rad about n (its axis then skew to the generatrix: the depth along the
/// height is least inside, a convex curve) and by `radial` rad about the tangent
/// `n × axis` (the depth rising or falling along the height).
fn tilted(g: &CutGeometry, theta: f64, delta_mm: f64, tangential: f64, radial: f64) -> CutterLine {
    let line = cutter(g, theta, delta_mm);
    let (sa, ca) = g.alpha_rad.sin_cos();
    let (st, ct) = theta.sin_cos();
    let n = Vector3::new(ca * ct, ca * st, sa);
    let side = n.cross(&line.axis);
    let turn = Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(n), tangential)
        * Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(side), radial);
    let pivot = line.tip + line.axis * 20.0;
    let axis = turn * line.axis;
    CutterLine {
        tip: pivot - axis * 20.0,
        axis,
    }
}

/// The grid's rows of the bundled cone's cut: every 2 mm from 0.1 mm above the tip height
/// to 0.1 mm below the flutes' end, with three more heights between.
fn grid(g: &CutGeometry) -> Vec<Row> {
    let (bottom, top) = (g.tip_height_mm() + 0.1, g.flute_end_height_mm() - 0.1);
    let mut z: Vec<f64> = (0..)
        .map(|k| bottom + 2.0 * k as f64)
        .take_while(|z| *z <= top)
        .collect();
    z.extend([
        bottom + 0.25 * (top - bottom),
        bottom + 0.5 * (top - bottom),
        41.3,
    ]);
    z.sort_by(f64::total_cmp);
    rows(g, &z)
}

/// The bounds of a position's least depth at its own θ (`least_bound`) hold it: for
/// cutters tilted about n and about the tangent by up to 2 mrad and moved along n by up to
/// ±50 µm, lower ≤ the least of every row's depth (`depths_um`, then the plain minimum) ≤
/// upper. They are tight (within 10⁻⁴ µm where the least row is an end row, within 1 µm
/// elsewhere), they say something for nearly every position, and some least rows lie
/// inside (the tangents' crossing, which a bound from the end rows alone would miss).
#[test]
fn the_least_depths_bounds_hold_it() {
    let g = geometry();
    let rows = grid(&g);
    let chord = Chord::of(&rows).expect("rows on a chord");
    assert!(chord.offset_mm < 1e-9, "offset {}", chord.offset_mm);
    let mut state = 5;
    let (mut said, mut inside, mut all) = (0, 0, 0);
    let mut out = vec![0.0; rows.len()];
    for case in 0..4000 {
        let theta = f64::to_radians(0.09 * case as f64 + 0.01);
        let delta_mm = 0.05 * jitter(&mut state);
        let tangential = 2e-3 * jitter(&mut state);
        let radial = match case % 3 {
            0 => 0.0,
            _ => 2e-3 * jitter(&mut state),
        };
        let line = tilted(&g, theta, delta_mm, tangential, radial);
        let contact = line.tip.y.atan2(line.tip.x);
        let at = contact.sin_cos().rev2();
        g.depths_um(at, &rows, &line, &mut out);
        let least = out.iter().fold(NOT_CUT, |m, &d| m.min(d));
        let row = out.iter().position(|&d| d == least).expect("a least row");
        all += 1;
        let Some((lower, upper)) = least_depth_bounds_um(&g, at, &rows, &chord, &line) else {
            continue;
        };
        said += 1;
        assert!(
            lower <= least && least <= upper,
            "case {case}: {lower} <= {least} <= {upper} um (row {row})"
        );
        let interior =
            row > 0 && row + 1 < rows.len() && out[0] > least && out[rows.len() - 1] > least;
        inside += interior as usize;
        let slack = if interior { 1.0 } else { 1e-4 };
        assert!(
            upper - lower < slack,
            "case {case}: {lower}..{upper} um (row {row})"
        );
    }
    assert!(said * 100 >= all * 99, "{said} of {all} said");
    assert!(inside > 100, "{inside} least rows inside");
}

/// Tilted cutters (their least depth at their own θ inside the rows or at either end, so
/// that the bounds decide most takes and e_min itself the rest) with the bundled cone's
/// rows: the streamed envelope is the brute force's, bit for bit, both senses.
#[test]
fn the_streamed_envelope_of_tilted_cutters_is_the_least_depth_of_every_position() {
    let g = geometry();
    let rows = grid(&g);
    for step_deg in [0.125, -0.125] {
        let mut state = 9;
        let lines: Vec<CutterLine> = (0..3744)
            .map(|k| {
                let theta = (3.0 + step_deg * k as f64).to_radians();
                let delta_mm = 3e-3 * (5.0 * theta).sin() + 1e-3 * jitter(&mut state);
                tilted(
                    &g,
                    theta,
                    delta_mm,
                    1e-3 * (3.0 * theta).cos(),
                    5e-4 * jitter(&mut state),
                )
            })
            .collect();
        let (envelope, expected) = streamed_and_brute_force(&g, &rows, &lines);
        assert!(expected.iter().all(|d| d.is_finite()));
        assert_same_bits(&envelope.values, &expected, &format!("step {step_deg}°"));
    }
}

/// A position's own θ direction, its tip's `(x, y)` scaled to 1, is `(cos θ, sin θ)` of the
/// tip's `atan2` within 2 ulp over every quadrant and radii from 10⁻¹⁰ mm to 10 m; on the
/// cone axis, where `atan2` gives 0, it is `(1, 0)`.
#[test]
fn a_positions_own_direction_is_the_cosine_and_sine_of_its_contact_angle() {
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    for k in 0..20_000 {
        let theta = -std::f64::consts::PI + 2.0 * std::f64::consts::PI * jitter(&mut state);
        let r = 10f64.powf(-3.0 + 7.0 * jitter(&mut state));
        let line = CutterLine {
            tip: Vector3::new(r * theta.cos(), r * theta.sin(), 5.0),
            axis: Vector3::z(),
        };
        let (c, s) = line.contact_direction();
        let (want_s, want_c) = line.contact_rad().sin_cos();
        let ulp = f64::EPSILON;
        assert!(
            (c - want_c).abs() <= 2.0 * ulp,
            "{k}: cos {c} against {want_c}"
        );
        assert!(
            (s - want_s).abs() <= 2.0 * ulp,
            "{k}: sin {s} against {want_s}"
        );
    }
    let on_axis = CutterLine {
        tip: Vector3::new(0.0, 0.0, 5.0),
        axis: Vector3::z(),
    };
    assert_eq!(on_axis.contact_direction(), (1.0, 0.0));
    assert_eq!(on_axis.contact_rad(), 0.0);
}
