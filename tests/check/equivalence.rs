//! The bounded `check` (θ only where reported, flat limits, conservative advancement with
//! lever-arm and relative-motion bounds) against the unoptimised reference
//! ([`check_reference`]: every pair queried at every sample) on the bundled scenarios.
//!
//! Tolerances, from what the monitor guarantees:
//! - limit violations: identical (kind, axis, times, lines, worst, θ to 1e-9 deg);
//! - collisions and near misses: the same events, same sample times; a near miss's smallest
//!   clearance within GJK's relative tolerance (a pair in an event is measured wherever its
//!   bounds could end the event or bring a new smallest clearance; GJK is warm-started from
//!   different samples); a collision's depth `W` at most the reference's, and the
//!   reference's at most `W + tolerance.at(W)` (the report's `collision_depth_tolerance`),
//!   both to GJK's tolerance;
//! - smallest clearance: equal to GJK's tolerance when below the near-miss threshold and not
//!   a collision's (a collision's: within the depth tolerance); above it the reference's
//!   (true, at samples) minimum lies between the threshold and the bounded one;
//! - engagement depth: within the engagement resolution, never above the reference.

use mtsim::check::limits::ViolationKind;
use mtsim::check::{check_reference, check_with, CheckOptions, SceneQueries};
use mtsim::input::scenario::Scenario;

fn scenario(name: &str, extra: &str) -> Scenario {
    let root = env!("CARGO_MANIFEST_DIR");
    let text = std::fs::read_to_string(format!("{root}/scenarios/{name}.toml"))
        .unwrap()
        .replace("../machines/", &format!("{root}/machines/"))
        .replace("programs/", &format!("{root}/scenarios/programs/"));
    let dir = std::env::temp_dir().join(format!("mtsim-equiv-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}-{}.toml", extra.len()));
    std::fs::write(&path, format!("{text}\n{extra}")).unwrap();
    Scenario::load(&path).unwrap()
}

fn agree(name: &str, extra: &str, options: CheckOptions) -> (usize, f64) {
    let s = scenario(name, extra);
    let slow = check_reference(&s, &options).unwrap();
    let mut result = (0, 0.0);
    for mode in [SceneQueries::Bounded, SceneQueries::BoundedRelative] {
        result = agree_with(
            name,
            extra,
            &s,
            &slow,
            check_with(&s, &options, mode).unwrap(),
        );
    }
    result
}

fn agree_with(
    name: &str,
    extra: &str,
    s: &Scenario,
    slow: &mtsim::check::CheckReport,
    fast: mtsim::check::CheckReport,
) -> (usize, f64) {
    let what = format!("{name} {extra:?}");
    assert_eq!(fast.samples, slow.samples, "{what}");
    assert_eq!(
        fast.violations.len(),
        slow.violations.len(),
        "{what}: {:#?}\n{:#?}",
        fast.violations,
        slow.violations
    );
    for (a, b) in fast.violations.iter().zip(slow.violations.iter()) {
        assert_eq!(
            (a.kind, a.axis, &a.bodies, a.line),
            (b.kind, b.axis, &b.bodies, b.line),
            "{what}"
        );
        assert_eq!(
            (a.time_start_s, a.time_end_s),
            (b.time_start_s, b.time_end_s),
            "{what}"
        );
        // GJK stops within a relative tolerance (1.1e-6 of the distance seen), and the two
        // paths warm-start it from different samples.
        let gjk = 1e-9 + 2e-6 * b.worst.abs();
        match a.kind {
            ViolationKind::Collision => {
                let tolerance = fast.collision_depth_tolerance.unwrap().at(a.worst);
                assert!(
                    a.worst <= b.worst + gjk && b.worst <= a.worst + tolerance + gjk,
                    "{what}: {a:?} {b:?}"
                );
            }
            _ => assert!((a.worst - b.worst).abs() <= gjk, "{what}: {a:?} {b:?}"),
        }
        for (x, y) in [
            (a.theta_start_deg, b.theta_start_deg),
            (a.theta_end_deg, b.theta_end_deg),
        ] {
            assert!(
                x.zip(y).is_none_or(|(x, y)| (x - y).abs() <= 1e-9) && x.is_some() == y.is_some(),
                "{what}"
            );
        }
    }
    assert_eq!(fast.axes.len(), slow.axes.len());
    for (axis, u) in &fast.axes {
        let v = &slow.axes[axis];
        assert_eq!(
            (
                u.min,
                u.max,
                u.peak_velocity_per_min,
                u.peak_acceleration_per_s2
            ),
            (
                v.min,
                v.max,
                v.peak_velocity_per_min,
                v.peak_acceleration_per_s2
            ),
            "{what} {axis}"
        );
    }
    let near_miss = s.check.near_miss_mm;
    // GJK is warm-started from the pair's previous query, and the two paths query different
    // samples, so the same pose can come back a few tenths of a µm apart (seen: 0.28 µm at
    // 18 mm on cone-15-10-yt25 once the scene used the actual kinematic chain).
    const GJK_MM: f64 = 1e-3;
    match (fast.min_clearance_mm, slow.min_clearance_mm) {
        (Some(f), Some(r)) if r < near_miss => {
            // A collision's depth may be short of the deepest sample's by its tolerance.
            let depth = fast.collision_depth_tolerance.unwrap().at(-f.min(0.0));
            assert!(
                r <= f + GJK_MM && f <= r + depth + GJK_MM,
                "{what}: {f} vs {r}"
            )
        }
        (Some(f), Some(r)) => assert!(
            r >= near_miss - GJK_MM && f >= r - GJK_MM,
            "{what}: {f} vs {r}"
        ),
        (f, r) => assert_eq!(f.is_some(), r.is_some(), "{what}"),
    }
    for (a, b) in fast.engagement.iter().zip(slow.engagement.iter()) {
        assert!(a.max_depth_mm <= b.max_depth_mm + 1e-9, "{what}");
        assert!(
            b.max_depth_mm - a.max_depth_mm <= a.resolution_mm,
            "{what}: {} vs {}",
            a.max_depth_mm,
            b.max_depth_mm
        );
    }
    let (fq, rq) = (
        fast.scene_queries.unwrap_or(0),
        slow.scene_queries.unwrap_or(0),
    );
    assert!(fq <= rq, "{what}");
    (fast.violations.len(), fq as f64 / rq.max(1) as f64)
}

#[test]
fn the_bounded_check_agrees_with_the_reference_on_the_bundled_cones() {
    for name in [
        "cone-15-10",
        "cone-15-10-offset",
        "cone-15-10-yt25",
        "cone-45-30",
        "file-cone-15-10-yt25",
    ] {
        let (_, ratio) = agree(name, "", CheckOptions::default());
        assert!(
            ratio < 0.2,
            "{name}: the bounds skip too few queries ({ratio})"
        );
    }
}

#[test]
fn the_bounded_check_agrees_where_there_are_near_misses_and_collisions() {
    // A 40 mm near-miss threshold puts parts of the tool stack within it of the workpiece.
    let (n, _) = agree(
        "cone-15-10",
        "[check]\nnear_miss_mm = 40.0\n",
        CheckOptions::default(),
    );
    assert!(n > 0, "the threshold should give near misses");
}

/// A small deterministic generator (no seed files, same poses every run).
pub(crate) struct Lcg(pub(crate) u64);

impl Lcg {
    pub(crate) fn unit(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    pub(crate) fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    pub(crate) fn direction(&mut self) -> parry3d_f64::math::Vector {
        loop {
            let v = parry3d_f64::math::Vector::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            if v.length() > 0.1 && v.length() <= 1.0 {
                return v.normalize();
            }
        }
    }
}

#[test]
fn the_closed_form_cylinder_to_frustum_distance_agrees_with_gjk_on_random_poses() {
    use mtsim::check::scene::frustum::{self, Cylinder, Frustum};
    use mtsim::check::scene::{signed_distance, Circle, CircleHull};
    use parry3d_f64::math::{Pose, Rotation, Vector};
    use parry3d_f64::shape::SharedShape;

    let mut rng = Lcg(7);
    let (mut certified, mut total, mut worst) = (0, 0, 0.0f64);
    for case in 0..3000 {
        // A frustum leaning like the cone tests', with the cutter on its flank (most cases)
        // or anywhere around it.
        let alpha = rng.range(5.0, 50.0f64).to_radians();
        let beta = rng.range(0.0, 35.0f64).to_radians();
        let axis = Vector::new(-beta.sin(), 0.0, beta.cos());
        let o = Vector::new(
            rng.range(-50.0, 50.0),
            rng.range(-80.0, 0.0),
            rng.range(150.0, 250.0),
        );
        let r0 = rng.range(60.0, 130.0);
        let height = rng.range(10.0, 0.8 * r0 / alpha.tan());
        let r1 = r0 - height * alpha.tan();
        let hull = CircleHull {
            circles: [
                Circle {
                    centre: o,
                    normal: axis,
                    radius: r0,
                },
                Circle {
                    centre: o + axis * height,
                    normal: axis,
                    radius: r1,
                },
            ],
        };
        let f = Frustum::from_circles(o, r0, o + axis * height, r1, axis).unwrap();
        let (radius, half) = (rng.range(2.0, 30.0), rng.range(5.0, 60.0));
        let (centre, t) = if case % 3 != 0 {
            // On the flank: a generatrix point, the cutter axis along the generatrix (tilted
            // a little), set off along the outward normal by a gap in [-0.5, 5] mm.
            let phi = rng.range(0.0, std::f64::consts::TAU);
            let u = axis.any_orthonormal_vector();
            let e = u * phi.cos() + axis.cross(u) * phi.sin();
            let z = rng.range(0.1, 0.9) * height;
            let surface = o + axis * z + e * (r0 - z * alpha.tan());
            let generatrix = (axis - e * alpha.tan()).normalize();
            let outward = (e + axis * alpha.tan()).normalize();
            let tilt = if case % 3 == 1 {
                0.0
            } else {
                rng.range(-0.05, 0.05)
            };
            let t = (generatrix + outward.cross(generatrix) * tilt).normalize();
            let gap = rng.range(-0.5, 5.0);
            (
                surface + outward * (radius + gap) + t * rng.range(-0.5, 0.5) * half,
                t,
            )
        } else {
            let d = rng.direction();
            (
                o + axis * (0.5 * height) + d * rng.range(r1, 2.5 * r0),
                rng.direction(),
            )
        };
        let cylinder = Cylinder {
            c: centre,
            t,
            half_height: half,
            radius,
        };
        let pose = Pose::from_parts(centre, Rotation::from_rotation_arc(Vector::Y, t));
        let reference = signed_distance(
            &pose,
            SharedShape::cylinder(half, radius).as_ref(),
            &Pose::IDENTITY,
            &hull,
            &mut None,
        );
        total += 1;
        if let Some((d, _)) = frustum::signed_distance(&f, &cylinder, None) {
            certified += 1;
            // GJK stops within its own tolerance, which is relative (2.7e-5 mm seen at
            // 25 mm, 1.1e-6 of the distance); the closed form is certified to 1e-6 mm.
            let diff = (d - reference).abs();
            // Overlapping, parry's depth comes from EPA (or, where EPA fails its check, a
            // separating translation along a chosen normal): never below the true depth,
            // and above it by EPA's tolerance (2e-5 mm seen).
            let allowed = if reference < 0.0 && d > reference {
                1e-4
            } else {
                1e-6 + 2e-6 * reference.abs()
            };
            // Independently: no point of the cylinder (a dense grid over its surface) is
            // nearer the frustum than the closed form says the cylinder is.
            if case % 3 == 0 {
                let u = t.any_orthonormal_vector();
                let w = t.cross(u);
                let mut nearest = f64::INFINITY;
                for i in 0..=40 {
                    let s = -half + 2.0 * half * i as f64 / 40.0;
                    for j in 0..72 {
                        let phi = std::f64::consts::TAU * j as f64 / 72.0;
                        let x = centre + t * s + (u * phi.cos() + w * phi.sin()) * radius;
                        nearest = nearest.min(f.point_sd(x).0);
                    }
                }
                assert!(
                    nearest >= d - 1e-9,
                    "case {case}: a point at {nearest} mm, closed form {d} mm"
                );
            }
            worst = worst.max(diff / allowed);
            if diff > allowed {
                println!("DBG o {:?} axis {:?} r0 {r0} r1 {r1} height {height} c {:?} t {:?} half {half} radius {radius}", o.to_array(), axis.to_array(), centre.to_array(), t.to_array());
            }
            assert!(
                diff <= allowed,
                "case {case}: closed form {d} mm, GJK {reference} mm"
            );
        }
    }
    println!(
        "certified {certified} of {total}; largest difference from GJK {worst:.3} of the allowance"
    );
    // Every flank pose (two thirds of the cases) has a line or point contact on the
    // lateral face, which the closed form certifies.
    assert!(certified * 3 >= total * 2, "{certified} of {total}");
}

/// A program that runs the tool into the table and keeps it there while it moves: plunged
/// (the depth growing), dragged along the table top at one depth, the table turning under
/// it, tilted, then skimming the top within the near-miss threshold, out, and back in. The
/// bounded check measures a pair in an event only where its bound could end the event or
/// bring a new worst value (the lever-arm bound, then the plane bound of the last query's
/// separating direction); the reference measures every pair at every sample. They must
/// find the same events at the same samples with the same worst values (to GJK's warm-start
/// noise, as the two query different samples), for a small share of the queries.
#[test]
fn the_bounded_check_agrees_with_the_reference_through_long_collisions_and_near_misses() {
    through_events(
        "trt-bc",
        "G21 G90 G17 G94\nG0 X0 Y0 Z60 B0 C0\nG1 Z-12 F3000\nG1 X120 F4000\nG1 Y100 C90\n\
         G1 X-80 Z-6 C200\nG1 Z-15\nG1 X0 Y-60 B-20\nG1 Z0.5 B0\nG1 X100 Z1.5 C250\nG1 Z40\n\
         G1 X-100 Z-5\nM2\n",
    );
}

/// The same on the three-axis machine, where every pair is two parallel prisms (the closed
/// form): a slow plunge through the table's whole thickness and out below (the depth
/// growing, then shrinking as the shank and holder pass through), a drag at one depth, a
/// ramp along the trunnion wall, a skim within the near-miss threshold.
#[test]
fn the_bounded_check_agrees_with_the_reference_through_a_plunge_on_three_axes() {
    through_events(
        "vmc-3axis",
        "G21 G90 G17 G94\nG0 X50 Y0 Z60\nG1 Z-150 F600\nG1 Z-20 F3000\nG1 X150 F4000\n\
         G1 X215 Y40 Z-70\nG1 X150 Z-5\nG1 Z1.2\nG1 X-100 Y-50\nG1 Z-30\nG1 Z40\nM2\n",
    );
}

/// The tool stack pushed deeper into a tilted table sample by sample (B at -25° on the B-C
/// trunnion, so the pairs are not parallel prisms and GJK/EPA answers), the table turning
/// under it, as in the corpus's UMC-750 post: every sample brings a new deepest value. With
/// exact depths the bounded check measures each of them; with the default depth tolerance
/// (0.01 mm + 1 % of the depth) it measures about once per 1 % of growth, and each
/// collision's depth `W` is still at most the reference's deepest sample's and within
/// `tolerance.at(W)` of it.
#[test]
fn a_tilted_tool_pushed_deeper_is_measured_within_the_depth_tolerance() {
    let program = "G21 G90 G17 G94\nG0 X0 Y0 Z80 B0 C0\nG0 B-25\nG1 Z5 F3000\n\
         G1 Z-30 C90 F100\nG1 X40 Z-45 C180 F300\nG1 Z-10 F3000\nG1 Z1 X60\nG1 Z-20 F200\n\
         G1 Z80 F3000\nM2\n";
    let (slow, exact) = both_ways("trt-bc", program, EXACT_DEPTHS);
    agree_through_events(&slow, &exact, "trt-bc", 0.1);
    let (_, fast) = both_ways("trt-bc", program, "");
    agree_through_events(&slow, &fast, "trt-bc", 0.05);
    let deepest = slow
        .violations
        .iter()
        .filter(|v| v.kind == ViolationKind::Collision)
        .map(|v| v.worst)
        .fold(0.0, f64::max);
    assert!(deepest > 20.0, "{deepest}");
    let (e, f) = (exact.scene_queries.unwrap(), fast.scene_queries.unwrap());
    assert!(
        2 * f < e,
        "{f} queries with the tolerance against {e} without"
    );
}

/// The scenario text that makes a collision's reported depth exact (no depth tolerance).
const EXACT_DEPTHS: &str =
    "[machine_overrides.scene]\ndepth_tolerance_mm = 0.0\ndepth_tolerance_relative = 0.0\n";

/// Checks `program` on `machine` (a bundled machine file) both ways and compares them, with
/// exact depths and with the default depth tolerance.
fn through_events(machine: &str, program: &str) {
    for extra in [EXACT_DEPTHS, ""] {
        let (slow, fast) = both_ways(machine, program, extra);
        agree_through_events(&slow, &fast, machine, 0.05);
    }
}

/// `program` on `machine` checked by the reference and by the bounded monitor, with
/// `extra` appended to the scenario.
fn both_ways(
    machine: &str,
    program: &str,
    extra: &str,
) -> (mtsim::check::CheckReport, mtsim::check::CheckReport) {
    let root = env!("CARGO_MANIFEST_DIR");
    let dir = std::env::temp_dir().join(format!(
        "mtsim-equiv-events-{machine}-{}-{}",
        extra.len(),
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("p.ngc"), program).unwrap();
    std::fs::write(
        dir.join("s.toml"),
        format!(
            "machine = \"{root}/machines/{machine}.toml\"\n[program]\nfile = \"p.ngc\"\n[reader]\ndialect = \"linuxcnc\"\n[workpiece]\nkind = \"none\"\n{extra}"
        ),
    )
    .unwrap();
    let s = Scenario::load(&dir.join("s.toml")).unwrap();
    let options = CheckOptions::default();
    let slow = check_reference(&s, &options).unwrap();
    let fast = check_with(&s, &options, SceneQueries::Bounded).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    (slow, fast)
}

/// The same events at the same samples; near misses' smallest clearances to 1e-6 mm, and
/// collisions' depths `W` at most the reference's and the reference's at most
/// `W + tolerance.at(W)` (1e-6 mm more for GJK); at least two collisions and two near
/// misses, one over 10 s long; under `max_share` of the reference's queries.
fn agree_through_events(
    slow: &mtsim::check::CheckReport,
    fast: &mtsim::check::CheckReport,
    machine: &str,
    max_share: f64,
) {
    assert_eq!(fast.samples, slow.samples);
    assert_eq!(
        fast.violations.len(),
        slow.violations.len(),
        "{:#?}\n{:#?}",
        fast.violations,
        slow.violations
    );
    let kinds = |k: ViolationKind| slow.violations.iter().filter(|v| v.kind == k).count();
    assert!(kinds(ViolationKind::Collision) >= 2 && kinds(ViolationKind::NearMiss) >= 2);
    let tolerance = fast.collision_depth_tolerance.unwrap();
    for (a, b) in fast.violations.iter().zip(&slow.violations) {
        assert_eq!(
            (a.kind, &a.bodies, a.line, a.time_start_s, a.time_end_s),
            (b.kind, &b.bodies, b.line, b.time_start_s, b.time_end_s),
        );
        match a.kind {
            ViolationKind::Collision => assert!(
                a.worst <= b.worst + 1e-6 && b.worst <= a.worst + tolerance.at(a.worst) + 1e-6,
                "{tolerance:?}: {a:?} {b:?}"
            ),
            _ => assert!((a.worst - b.worst).abs() < 1e-6, "{a:?} {b:?}"),
        }
        assert_eq!(a.theta_end_deg.is_some(), b.theta_end_deg.is_some());
    }
    // The longest event lasts over 10 s (10,000 samples).
    let longest = slow
        .violations
        .iter()
        .map(|v| v.time_end_s - v.time_start_s)
        .fold(0.0, f64::max);
    assert!(longest > 10.0, "{longest}");
    let (f, r) = (fast.scene_queries.unwrap(), slow.scene_queries.unwrap());
    eprintln!("long events on {machine} ({tolerance:?}): {f} of the reference's {r} queries");
    assert!((f as f64) < max_share * r as f64, "{f} of {r}");
    let (fc, rc) = (
        fast.min_clearance_mm.unwrap(),
        slow.min_clearance_mm.unwrap(),
    );
    assert!(
        rc <= fc + 1e-6 && fc <= rc + tolerance.at(-fc.min(0.0)) + 1e-6,
        "{fc} {rc}"
    );
}
