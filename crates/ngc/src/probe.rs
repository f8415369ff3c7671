//! Straight probing G38.2-G38.5 (LinuxCNC) in a simulator, which has no probe input.
//!
//! mtsim does what LinuxCNC's standalone interpreter `rs274` does with its model of the
//! world (its canonical `STRAIGHT_PROBE` call): the probe **never trips**. So
//!
//! 1. the probe move is a feed move (G01 at the F in effect) from the current point `s` to
//!    the programmed point `t`, for all four codes alike (G38.2/.4 would raise an error on
//!    a real machine when the probe does not trip; rs274 does not, and neither does mtsim);
//! 2. the probe then backs off by `b` = 0.254 mm (0.010 in under G20, the same length)
//!    towards the start, along X Y Z:
//!    ```text
//!    p = t + b (s - t) / |s - t|        (no back-off when |s - t| = 0 in X Y Z)
//!    ```
//!    and the program goes on from `p`, as rs274's current position does (it is a second
//!    feed move in mtsim; rs274 prints no call for it);
//! 3. the probe parameters hold the programmed point in the work system and units active
//!    at the probe: `#5061`-`#5069` = X Y Z A B C U V W of `t`, and
//!    `#5070` = 0 (not tripped). A loop that waits for `#5070` to become 0 therefore ends
//!    after its first probe; any other loop is bounded by the interpreter's iteration limit.
//!
//! Refused as rs274 refuses: G38.2 or G38.4 to the start point ("Start point too close
//! to probe point"; G38.3 and G38.5 there move nothing and set the parameters), G93, cutter radius compensation on, no feed, a
//! probe block without axis words.

use crate::axis::{Axis, AxisVec};

/// The back-off after a probe move, mm (LinuxCNC: 0.254 mm, or 0.01 in under G20).
pub const BACKOFF_MM: f64 = 0.254;

/// The first of LinuxCNC's probe parameters (`#5061` X ... `#5070` tripped).
pub const FIRST_PARAMETER: usize = 5061;

/// Where the probe stands after backing off from `target` towards `start` (machine
/// coordinates, mm and deg; X Y Z move, A B C U V W stay at the target).
pub fn backoff(start: AxisVec, target: AxisVec) -> AxisVec {
    let d: [f64; 3] = std::array::from_fn(|k| start[Axis::LINEAR[k]] - target[Axis::LINEAR[k]]);
    let distance = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let mut p = target;
    if distance > 0.0 {
        for (k, a) in Axis::LINEAR.into_iter().enumerate() {
            p[a] = target[a] + BACKOFF_MM * d[k] / distance;
        }
    }
    p
}

/// The values of `#5061`-`#5070` after a probe to `target_program` (program coordinates,
/// program units and deg): X Y Z A B C U V W, tripped = 0.
pub fn parameters(target_program: AxisVec) -> [f64; 10] {
    let mut v = [0.0; 10];
    for a in Axis::ALL {
        v[a.index()] = target_program[a];
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_probe_backs_off_a_quarter_millimetre_towards_the_start() {
        let mut s = AxisVec::ZERO;
        s[Axis::Z] = 10.0;
        let mut t = AxisVec::ZERO;
        t[Axis::Z] = -5.0;
        t[Axis::A] = 30.0;
        let p = backoff(s, t);
        assert!((p[Axis::Z] - (-5.0 + 0.254)).abs() < 1e-12);
        assert_eq!(p[Axis::X], 0.0);
        assert_eq!(p[Axis::A], 30.0);
        // A 3-4-5 diagonal: back along (-3, -4) / 5.
        let mut t2 = AxisVec::ZERO;
        t2[Axis::X] = 3.0;
        t2[Axis::Y] = 4.0;
        let q = backoff(AxisVec::ZERO, t2);
        assert!((q[Axis::X] - (3.0 - 0.254 * 0.6)).abs() < 1e-12);
        assert!((q[Axis::Y] - (4.0 - 0.254 * 0.8)).abs() < 1e-12);
        // A rotary-only probe does not back off.
        assert_eq!(backoff(t, t), t);
    }

    #[test]
    fn probe_parameters_hold_the_programmed_point_and_not_tripped() {
        let mut t = AxisVec::ZERO;
        t[Axis::X] = 1.5;
        t[Axis::C] = 90.0;
        let v = parameters(t);
        assert_eq!(v[0], 1.5);
        assert_eq!(v[5], 90.0);
        assert_eq!(v[9], 0.0);
    }
}
