//! Jerk-limited speed profiles along a path: one speed change with zero acceleration at
//! both ends ([`SpeedChange`]), a block's change-cruise-change profile ([`Profile`]), and
//! the root finders the look-ahead uses on them ([`largest_feasible`], [`reach`]). Speeds and
//! distances in path units (mm, or deg counted as mm), times in s.

use libm::cbrt;

/// One jerk-limited speed change from `v0` to `v1` with zero acceleration at both ends.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct SpeedChange {
    pub(super) v0: f64,
    pub(super) v1: f64,
    /// Signed jerk of the first phase, path units/s³.
    pub(super) jerk: f64,
    /// Duration of each jerk phase and of the constant-acceleration phase, s.
    pub(super) t1: f64,
    pub(super) t2: f64,
    pub(super) duration: f64,
    pub(super) distance: f64,
}

/// Duration of a speed change of `dv >= 0` under acceleration `a` and jerk `j`.
pub(super) fn change_time(dv: f64, a: f64, j: f64) -> f64 {
    if dv * j <= a * a {
        2.0 * (dv / j).sqrt()
    } else {
        dv / a + a / j
    }
}

/// Exact distance of the speed change `v0 → v1`.
pub(super) fn change_distance(v0: f64, v1: f64, a: f64, j: f64) -> f64 {
    0.5 * (v0 + v1) * change_time((v1 - v0).abs(), a, j)
}

/// Monotone upper bound on [`change_distance`]: `max(v0, v1) T`.
pub(super) fn change_distance_bound(v0: f64, v1: f64, a: f64, j: f64) -> f64 {
    v0.max(v1) * change_time((v1 - v0).abs(), a, j)
}

impl SpeedChange {
    pub(super) fn new(v0: f64, v1: f64, a: f64, j: f64) -> SpeedChange {
        let dv = (v1 - v0).abs();
        if dv == 0.0 {
            return SpeedChange {
                v0,
                v1,
                ..SpeedChange::default()
            };
        }
        let (t1, t2) = if dv * j <= a * a {
            ((dv / j).sqrt(), 0.0)
        } else {
            (a / j, dv / a - a / j)
        };
        let duration = 2.0 * t1 + t2;
        SpeedChange {
            v0,
            v1,
            jerk: j.copysign(v1 - v0),
            t1,
            t2,
            duration,
            distance: 0.5 * (v0 + v1) * duration,
        }
    }

    /// Distance travelled `tau` s into the change.
    pub(super) fn position(&self, tau: f64) -> f64 {
        let j = self.jerk;
        if tau < self.t1 {
            self.v0 * tau + j * tau * tau * tau / 6.0
        } else if tau < self.t1 + self.t2 {
            let t1 = self.t1;
            let u = tau - t1;
            let a = j * t1;
            self.v0 * t1
                + j * t1 * t1 * t1 / 6.0
                + (self.v0 + 0.5 * j * t1 * t1) * u
                + 0.5 * a * u * u
        } else {
            let r = (self.duration - tau).max(0.0);
            self.distance - (self.v1 * r - j * r * r * r / 6.0)
        }
    }
}

impl SpeedChange {
    /// Speed `tau` s into the change (the derivative of [`SpeedChange::position`]):
    /// `v0 + j τ²/2`, then `v0 + j t1²/2 + j t1 (τ − t1)`, then `v1 − j r²/2` with `r` the
    /// time left.
    pub(super) fn speed(&self, tau: f64) -> f64 {
        let j = self.jerk;
        if self.duration == 0.0 {
            return self.v0;
        }
        if tau < self.t1 {
            self.v0 + 0.5 * j * tau * tau
        } else if tau < self.t1 + self.t2 {
            self.v0 + 0.5 * j * self.t1 * self.t1 + j * self.t1 * (tau - self.t1)
        } else {
            let r = (self.duration - tau).clamp(0.0, self.t1);
            self.v1 - 0.5 * j * r * r
        }
    }
}

/// Speed profile of one block: change to `vp`, cruise, change to the exit speed.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Profile {
    pub(super) up: SpeedChange,
    pub(super) cruise_speed: f64,
    pub(super) cruise_time: f64,
    pub(super) down: SpeedChange,
    pub(super) duration: f64,
}

impl Profile {
    /// Profile over `length` from `vs` to `ve` with cruise cap `cap` (all path units).
    pub(super) fn new(vs: f64, ve: f64, cap: f64, length: f64, a: f64, j: f64) -> Profile {
        let total = |vp: f64| change_distance(vs, vp, a, j) + change_distance(vp, ve, a, j);
        let floor = vs.max(ve);
        let vp = if cap <= floor {
            floor
        } else {
            let excess = total(cap) - length;
            if excess <= 0.0 {
                cap
            } else {
                largest_feasible(floor, cap, excess, |vp| total(vp) - length)
            }
        };
        let up = SpeedChange::new(vs, vp, a, j);
        let down = SpeedChange::new(vp, ve, a, j);
        let rest = length - up.distance - down.distance;
        let cruise_time = if rest > 0.0 && vp > 0.0 {
            rest / vp
        } else {
            0.0
        };
        Profile {
            up,
            cruise_speed: vp,
            cruise_time,
            down,
            duration: up.duration + cruise_time + down.duration,
        }
    }

    /// Distance travelled `tau` s into the block.
    pub(super) fn position(&self, tau: f64) -> f64 {
        if tau < self.up.duration {
            return self.up.position(tau);
        }
        let tau = tau - self.up.duration;
        if tau < self.cruise_time {
            return self.up.distance + self.cruise_speed * tau;
        }
        let cruise = self.cruise_speed * self.cruise_time;
        self.up.distance
            + cruise
            + self
                .down
                .position((tau - self.cruise_time).min(self.down.duration))
    }
}

impl Profile {
    /// Path speed `tau` s into the block (0 outside it).
    pub(super) fn speed(&self, tau: f64) -> f64 {
        if !(0.0..=self.duration).contains(&tau) {
            return 0.0;
        }
        if tau < self.up.duration {
            return self.up.speed(tau);
        }
        let tau = tau - self.up.duration;
        if tau < self.cruise_time {
            return self.cruise_speed;
        }
        self.down
            .speed((tau - self.cruise_time).min(self.down.duration))
    }

    /// When the last speed change starts (s into the block): the end of the cruise.
    pub(super) fn down_start(&self) -> f64 {
        self.up.duration + self.cruise_time
    }

    /// When the block has travelled `distance` (s into it; its duration when it never does):
    /// bisection of the increasing [`Profile::position`].
    pub(super) fn time_at(&self, distance: f64) -> f64 {
        if !(self.position(self.duration) > distance) {
            return self.duration;
        }
        let before = bisect(0.0, self.duration, |t| self.position(t) <= distance);
        before.min(self.duration)
    }
}

/// Largest float `x` in `[lo, hi]` with `f(x) ≤ 0`, given `f(lo) ≤ 0 < f(hi) = f_hi` and `f`
/// increasing: the float that bisection of the bracket finds (it ends with `lo` feasible and
/// `hi` the next float up), in about a quarter of the evaluations.
///
/// False position with the Illinois modification (when one end stays twice running, its `f`
/// is halved) closes in superlinearly on the root, `x = lo - f(lo) (hi - lo) / (f(hi) - f(lo))`,
/// to a few ulps on one side. Then steps of 2, 4, 8, ... ulps from that side cross the root
/// and bisection between two floats a few ulps apart ends it. Bisection alone takes about 40
/// evaluations when `vp` lies just above the entry and exit speeds (a fine-segment program's
/// blocks too short to reach their feed): the look-ahead's largest cost per block.
pub(super) fn largest_feasible(mut lo: f64, mut hi: f64, f_hi: f64, f: impl Fn(f64) -> f64) -> f64 {
    let mut f_lo = f(lo);
    let mut f_hi = f_hi;
    // Which end moved last: +1 hi, -1 lo.
    let mut moved = 0;
    for _ in 0..12 {
        let x = lo - f_lo * ((hi - lo) / (f_hi - f_lo));
        if !(x > lo && x < hi) {
            break;
        }
        let fx = f(x);
        if fx <= 0.0 {
            (lo, f_lo) = (x, fx);
            if moved == -1 {
                f_hi *= 0.5;
            }
            moved = -1;
        } else {
            (hi, f_hi) = (x, fx);
            if moved == 1 {
                f_lo *= 0.5;
            }
            moved = 1;
        }
        if hi - lo <= 8.0 * f64::EPSILON * hi.abs() {
            break;
        }
    }
    // Cross the root from the end that moved last, in steps that double.
    let mut step = 2.0 * f64::EPSILON * lo.abs().max(hi.abs()).max(f64::MIN_POSITIVE);
    while hi - lo > 2.0 * step {
        if moved == 1 {
            let x = hi - step;
            if f(x) <= 0.0 {
                lo = x;
                break;
            }
            hi = x;
        } else {
            let x = lo + step;
            if f(x) > 0.0 {
                hi = x;
                break;
            }
            lo = x;
        }
        step *= 2.0;
    }
    bisect(lo, hi, |x| f(x) <= 0.0)
}

/// Largest `x` in `[lo, hi]` with `feasible(x)`, given `feasible(lo)` and monotonicity.
pub(super) fn bisect(mut lo: f64, mut hi: f64, feasible: impl Fn(f64) -> bool) -> f64 {
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if feasible(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// Highest speed `≤ cap` reachable from (or able to reach) `v` within `length`,
/// by the monotone bound [`change_distance_bound`], in closed form.
///
/// For `x > v` the bound is `x T(x - v)`, increasing in `x`; `x` solves `x T(x - v) = L`:
///
/// ```text
/// x - v > a²/j:  x (x - v)/a + x a/j = L   →  x = (-(a²/j - v) + sqrt((a²/j - v)² + 4 a L)) / 2
/// x - v ≤ a²/j:  2 x sqrt((x - v)/j) = L   →  x³ - v x² - j L²/4 = 0
/// ```
///
/// The cubic has one real root above `v` (Cardano with `x = y + v/3`, `y³ + p y + q = 0`,
/// `p = -v²/3`, `q = -2v³/27 - jL²/4`, discriminant `(q/2)² + (p/3)³ ≥ 0`; the root is
/// `y = w + v²/(9w)` with `w = cbrt(-q/2 + sqrt(disc))`, written so that nothing cancels),
/// polished by one Newton step.
pub(super) fn reach(v: f64, length: f64, cap: f64, a: f64, j: f64) -> f64 {
    if cap <= v || change_distance_bound(v, cap, a, j) <= length {
        return cap;
    }
    let knee = a * a / j;
    let b = knee - v;
    let x = 0.5 * (-b + (b * b + 4.0 * a * length).sqrt());
    let x = if x - v > knee {
        x
    } else {
        let c = 0.25 * j * length * length;
        let half_q = v * v * v / 27.0 + 0.5 * c;
        let disc = (half_q * half_q - (v * v / 9.0).powi(3)).max(0.0);
        let w = cbrt(half_q + disc.sqrt());
        let mut x = if w > 0.0 { w + v * v / (9.0 * w) } else { 0.0 } + v / 3.0;
        let f = x * x * (x - v) - c;
        let df = x * (3.0 * x - 2.0 * v);
        if df > 0.0 {
            x -= f / df;
        }
        x
    };
    // Rounding may leave the root a hair outside [v, cap] or its bound a hair above length.
    let mut x = x.clamp(v, cap);
    while x > v && change_distance_bound(v, x, a, j) > length {
        x = (x - x.abs() * 4.0 * f64::EPSILON).max(v);
    }
    x
}

/// `v` is above `reach(0, length, cap, a, j)` for certain, whatever the cap: the monotone
/// bound of the speed change from rest to `v` exceeds `length` by more than a relative 1e-9.
/// [`reach`] from rest returns its cap when that cap's bound is within `length` (or the cap is
/// not above 0), else a speed `x` whose computed bound is at most `length` (or 0); the bound
/// `x T(x)` is increasing and computed to a few ulps, so `bound(v) > length (1 + 1e-9)`
/// puts `v` above any of them. Then `reach(v, ..) ≥ min(v, cap) ≥ reach(0, ..)`: the limit
/// from rest cannot raise a block's limit from `v` (the backward pass skips it).
pub(super) fn rest_reach_below(v: f64, length: f64, a: f64, j: f64) -> bool {
    change_distance_bound(0.0, v, a, j) > length * (1.0 + 1e-9)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed-form `reach` against bisection of its defining inequality, on both sides of
    /// the knee `a²/j` and from rest.
    #[test]
    fn closed_form_reach_matches_bisection() {
        let cases = [
            (0.0, 0.001, 1e9, 3000.0, 50000.0),
            (0.0, 5.0, 1e9, 3000.0, 50000.0),
            (10.0, 0.01, 1e9, 3000.0, 50000.0),
            (16.7, 0.0044, 40.0, 1200.0, 20000.0),
            (0.3, 200.0, 1e9, 100.0, 1000.0),
            (50.0, 1e-6, 1e9, 2.0, 5.0),
            (2.0, 3.0, 2.5, 100.0, 1000.0),
        ];
        for (v, length, cap, a, j) in cases {
            let got = reach(v, length, cap, a, j);
            let want = bisect(v, cap, |x| change_distance_bound(v, x, a, j) <= length);
            assert!(
                (got - want).abs() <= 1e-12 * want.max(1.0),
                "reach({v}, {length}, {cap}, {a}, {j}) = {got}, bisection {want}"
            );
            assert!(change_distance_bound(v, got, a, j) <= length || got == v);
        }
    }

    #[test]
    fn speed_change_covers_its_closed_form_distance_and_time() {
        // 0 → 50 with a = 200, j = 2000: 50 > a²/j, so T = v/a + a/j = 0.35 s, D = 25 · 0.35.
        let c = SpeedChange::new(0.0, 50.0, 200.0, 2000.0);
        assert!((c.duration - 0.35).abs() < 1e-12);
        assert!((c.position(c.duration) - 8.75).abs() < 1e-12);
        // Triangular acceleration: 0 → 10 (< a²/j = 20): T = 2 sqrt(10/2000).
        let c = SpeedChange::new(10.0, 0.0, 200.0, 2000.0);
        assert!((c.duration - 2.0 * (10.0f64 / 2000.0).sqrt()).abs() < 1e-12);
        assert!((c.position(c.duration) - 5.0 * c.duration).abs() < 1e-12);
        // 5 → 45 with a = 100, j = 1000: t1 = a/j = 0.1 s, t2 = 40/100 - 0.1 = 0.3 s.
        // At T/2 = 0.25 s: s(t1) = 5·0.1 + 1000·0.1³/6, then 0.15 s at a = 100 from
        // v = 5 + 1000·0.1²/2 = 10: s = 0.6667 + 10·0.15 + 100·0.15²/2 = 3.29167.
        let c = SpeedChange::new(5.0, 45.0, 100.0, 1000.0);
        assert!((c.t1 - 0.1).abs() < 1e-12 && (c.t2 - 0.3).abs() < 1e-12);
        for tau in [c.t1, c.t1 + c.t2] {
            let (before, after) = (c.position(tau - 1e-9), c.position(tau + 1e-9));
            assert!(
                (after - before).abs() < 1e-7,
                "jump at {tau}: {before} → {after}"
            );
        }
        let mid = c.position(0.25);
        let expected = 0.5 + 1000.0 * 0.001 / 6.0 + 10.0 * 0.15 + 50.0 * 0.15 * 0.15;
        assert!((mid - expected).abs() < 1e-12, "{mid} vs {expected}");
    }

    proptest::proptest! {
        /// The block's peak speed by false position and doubling steps is the very float
        /// bisection finds, for peaks from a hair to ten times above the entry and exit
        /// speeds, on both sides of the knee `a²/j`.
        #[test]
        fn peak_speed_is_the_float_bisection_finds(
            vs in 0.0..60.0f64,
            ve in 0.0..60.0f64,
            rise_exp in -12.0..1.0f64,
            share in 0.0..1.0f64,
            a in 10.0..5000.0f64,
            j in 100.0..1e6f64,
        ) {
            let floor = vs.max(ve);
            let cap = floor * (1.0 + 10f64.powf(rise_exp)) + 1e-6;
            let total = |vp: f64| change_distance(vs, vp, a, j) + change_distance(vp, ve, a, j);
            let length = total(floor) + share * (total(cap) - total(floor));
            proptest::prop_assume!(total(floor) <= length && total(cap) > length);
            let want = bisect(floor, cap, |x| total(x) <= length);
            let got = largest_feasible(floor, cap, total(cap) - length, |x| total(x) - length);
            proptest::prop_assert_eq!(got.to_bits(), want.to_bits(), "got {} want {}", got, want);
        }

        /// Where [`rest_reach_below`] says so, the limit from rest is below `v` and below the
        /// limit from `v`, so the larger of the two is the latter bit for bit; `v` is drawn
        /// around the limit from rest (a relative 1e-15 to 1e-3 either side), where the
        /// margin is tested, and far from it.
        #[test]
        fn a_speed_above_the_limit_from_rest_by_the_bound_is_above_it(
            length_exp in -6.0..2.0f64,
            cap_exp in -3.0..3.0f64,
            a in 10.0..5000.0f64,
            j in 100.0..1e6f64,
            offset_exp in -15.0..-3.0f64,
            side in -1.0..1.0f64,
            far in proptest::bool::ANY,
        ) {
            let (length, cap) = (10f64.powf(length_exp), 10f64.powf(cap_exp));
            let rest = reach(0.0, length, cap, a, j);
            let rest_uncapped = reach(0.0, length, 1e9, a, j);
            let scale = if far { 1.0 + 10.0 * side.abs() } else { 1.0 + side * 10f64.powf(offset_exp) };
            let v = rest_uncapped * scale;
            if rest_reach_below(v, length, a, j) {
                proptest::prop_assert!(rest < v, "rest {} v {}", rest, v);
                let from_v = reach(v, length, cap, a, j);
                proptest::prop_assert!(from_v >= rest, "from v {} rest {}", from_v, rest);
                proptest::prop_assert_eq!(from_v.max(rest).to_bits(), from_v.to_bits());
            }
            // It is not vacuous: a speed a tenth above the limit from rest qualifies.
            proptest::prop_assert!(rest_reach_below(rest_uncapped * 1.1, length, a, j));
        }

        /// `reach` is the largest speed its bound allows, to 1e-12 of bisection, and
        /// within the bound, from rest and from speed, short blocks and long.
        #[test]
        fn reach_is_the_bound_s_largest_speed(
            v in 0.0..60.0f64,
            length_exp in -6.0..2.0f64,
            a in 10.0..5000.0f64,
            j in 100.0..1e6f64,
            from_rest in proptest::bool::ANY,
        ) {
            let v = if from_rest { 0.0 } else { v };
            let (length, cap) = (10f64.powf(length_exp), 1e6);
            let got = reach(v, length, cap, a, j);
            let want = bisect(v, cap, |x| change_distance_bound(v, x, a, j) <= length);
            proptest::prop_assert!((got - want).abs() <= 1e-12 * want.max(1.0), "{} {}", got, want);
            proptest::prop_assert!(change_distance_bound(v, got, a, j) <= length || got == v);
        }
    }
}
