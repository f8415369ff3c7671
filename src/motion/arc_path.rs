//! The geometry of a G2/G3 block: its centre, radii and sweep in its plane, from the
//! block's end points and centre (checked: finite, a radius, the end on the circle).

use std::f64::consts::TAU;

use crate::program::Move;
use crate::Plane;

/// Arc geometry in the plane axes `(i0, i1)`; angle measured from i0 toward i1.
#[derive(Clone, Copy, Debug)]
pub(super) struct ArcGeometry {
    pub(super) i0: usize,
    pub(super) i1: usize,
    /// Centre, mm.
    pub(super) c0: f64,
    pub(super) c1: f64,
    /// Start radius and its change over the block, mm.
    pub(super) r0: f64,
    pub(super) dr: f64,
    /// Start angle and signed sweep, rad.
    pub(super) theta0: f64,
    pub(super) sweep: f64,
}

/// The arc of block `b` about the centre `c` (mm) in `plane`, or why it is refused.
pub(super) fn arc_geometry(
    b: &Move,
    clockwise: bool,
    plane: Plane,
    c: [f64; 3],
) -> Result<ArcGeometry, String> {
    if !c.iter().all(|v| v.is_finite()) {
        return Err(String::from("the arc centre is not a finite number"));
    }
    let (i0, i1) = match plane {
        Plane::XY => (0, 1),
        Plane::ZX => (2, 0),
        Plane::YZ => (1, 2),
    };
    let (s0, s1) = (b.start.0[i0] - c[i0], b.start.0[i1] - c[i1]);
    let (e0, e1) = (b.end.0[i0] - c[i0], b.end.0[i1] - c[i1]);
    let (r0, r1) = (s0.hypot(s1), e0.hypot(e1));
    if r0 <= 1e-9 || r1 <= 1e-9 {
        return Err(String::from(
            "the arc has zero radius: the centre is on its start or end point",
        ));
    }
    // The reader already held the radii to its dialect's rule (LinuxCNC under G20: up to
    // 0.002·√2 in or 0.1 % of the radius, docs/gcode.md); this only refuses what no
    // dialect accepts, so `analyze` and `check` agree on what they read.
    if (r0 - r1).abs() > (std::f64::consts::SQRT_2 * 0.002 * 25.4).max(1e-3 * r0) {
        return Err(format!(
            "the arc end is not on the circle: start radius {r0:.6} mm, end radius {r1:.6} mm; check I J K or R"
        ));
    }
    // Sweep in (0, 2π] in the arc's own direction; start = end is a full circle.
    let theta0 = s1.atan2(s0);
    let ccw = e1.atan2(e0) - theta0;
    let mut sweep = if clockwise { -ccw } else { ccw }.rem_euclid(TAU);
    if sweep <= 1e-12 * TAU {
        sweep = TAU;
    }
    if clockwise {
        sweep = -sweep;
    }
    Ok(ArcGeometry {
        i0,
        i1,
        c0: c[i0],
        c1: c[i1],
        r0,
        dr: r1 - r0,
        theta0,
        sweep,
    })
}
