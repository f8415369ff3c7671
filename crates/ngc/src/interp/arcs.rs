//! Arcs G2/G3: the centre from I J K or R, the radius check, several turns (LinuxCNC P),
//! and arcs in a tilted (G68.2, G254) frame.

use super::Interp;
use crate::axis::{Axis, AxisVec, Plane};
use crate::canon::{Motion, FULL_CIRCLE_TOLERANCE_MM};
use crate::code::FeedRead;
use crate::dialect::ArcRadiusRule;
use crate::frame;
use crate::lex::{LineError, LineResult, Word};
use crate::units::{ARC_RADIUS_TOLERANCE_MM, MM_PER_INCH, OBLIQUE_ARC_CHORD_TOLERANCE_MM};

/// Most chords an oblique arc is cut into.
const MAX_CHORDS: usize = 100_000;

/// An arc in a tilted frame, as it reaches the machine.
pub(super) enum TiltedArc {
    /// In a machine plane: one canonical arc.
    Canonical(Motion),
    /// In an oblique plane: straight moves through these points (then the arc's end).
    Chords(Vec<AxisVec>),
}

impl Interp {
    /// An arc in the plane of a G68.2 or G254 frame: the centre is found in program
    /// coordinates, then mapped to the machine plane its normal turns into (clockwise flips
    /// when the normal turns to the machine axis's negative direction). When the normal is
    /// along no machine axis (the table tilted off 90°), the arc runs as chords within
    /// [`OBLIQUE_ARC_CHORD_TOLERANCE_MM`], as the control interpolates it in the tilted
    /// plane.
    pub(super) fn tilted_arc<'l>(
        &self,
        line: &str,
        get: &dyn Fn(char) -> Option<Word<'l>>,
        words: &[Word],
        clockwise: bool,
        target: AxisVec,
        at: std::ops::Range<usize>,
    ) -> LineResult<TiltedArc> {
        let f = self.frame().expect("called with a frame");
        if Axis::XYZABC[3..].iter().any(|&a| target[a] != self.pos[a]) {
            return Err(LineError::new(at, "arc that turns a rotary axis with G68.2 or G254 active: expected the rotary axes still during G02/G03", "rotary arc in a tilted frame"));
        }
        let mut tip_end = [target[Axis::X], target[Axis::Y], target[Axis::Z]];
        tip_end[2] -= self.tool_length_mm;
        let ps = f.to_program(self.tip(), &self.offset, &self.pos);
        let pe = f.to_program(tip_end, &self.offset, &target);
        let (mut s, mut e) = (AxisVec::ZERO, AxisVec::ZERO);
        for k in 0..3 {
            s.0[k] = ps[k];
            e.0[k] = pe[k];
        }
        let c = self.arc_center(line, get, words, clockwise, s, e)?;
        let (_, _, n) = self.plane.axes();
        let mut normal = [0.0; 3];
        normal[n.index()] = 1.0;
        let mn = frame::apply(&f.direction_rotation(&target), normal);
        let Some(k) = (0..3).find(|&k| mn[k].abs() > 1.0 - 1e-9) else {
            let points = oblique_chords(self.plane, ps, pe, c, clockwise).ok_or_else(|| {
                LineError::new(at, format!("arc in a tilted plane whose normal is ({:.4}, {:.4}, {:.4}) in machine axes needs more than {MAX_CHORDS} chords of {OBLIQUE_ARC_CHORD_TOLERANCE_MM} mm sagitta", mn[0], mn[1], mn[2]), "oblique arc too long")
            })?;
            let chords = points
                .into_iter()
                .map(|p| {
                    let m = f.to_machine(p, &self.offset, &target);
                    let mut q = target;
                    q[Axis::X] = m[0];
                    q[Axis::Y] = m[1];
                    q[Axis::Z] = m[2] + self.tool_length_mm;
                    q
                })
                .collect();
            return Ok(TiltedArc::Chords(chords));
        };
        let plane = [Plane::YZ, Plane::ZX, Plane::XY][k];
        let mut center_mm = f.to_machine(c, &self.offset, &target);
        center_mm[2] += self.tool_length_mm;
        Ok(TiltedArc::Canonical(Motion::Arc {
            clockwise: clockwise != (mn[k] < 0.0),
            plane,
            center_mm,
        }))
    }

    /// The absolute arc centre `[X, Y, Z]`, machine mm, from I J K or R.
    ///
    /// For R, with chord length d from s to e and midpoint m, the centre lies at distance
    /// `h = sqrt(R² - (d/2)²)` from m along the chord's normal; it is on the left of the
    /// direction of travel for a counter-clockwise short arc and for a clockwise long arc.
    pub(super) fn arc_center<'l>(
        &self,
        line: &str,
        get: &dyn Fn(char) -> Option<Word<'l>>,
        words: &[Word],
        clockwise: bool,
        start: AxisVec,
        end: AxisVec,
    ) -> LineResult<[f64; 3]> {
        let scale = self.scale();
        let (u, v, n) = self.plane.axes();
        let letter = |axis: Axis| match axis {
            Axis::X => 'I',
            Axis::Y => 'J',
            _ => 'K',
        };
        let block_span = words
            .iter()
            .fold(None, |acc: Option<(usize, usize)>, w| {
                Some(acc.map_or(w.span, |(a, b)| (a.min(w.span.0), b.max(w.span.1))))
            })
            .map_or(0..line.len(), |(a, b)| a..b);
        if let Some(w) = get(letter(n)) {
            if !self.dialect.table().zero_off_plane_offset || w.value != 0.0 {
                return Err(LineError::new(
                    w.span(),
                    format!(
                        "`{}` is not in the arc plane {}: expected {} and {}",
                        &line[w.span()],
                        self.plane.g_code(),
                        letter(u),
                        letter(v)
                    ),
                    "off-plane centre offset",
                )
                .help("select the plane of the arc with G17, G18 or G19"));
            }
        }
        let (su, sv) = (start[u], start[v]);
        let (eu, ev) = (end[u], end[v]);
        let mut center = [start[Axis::X], start[Axis::Y], start[Axis::Z]];
        let mut offsets = (get(letter(u)), get(letter(v)));
        if self.dialect.table().arc_r_over_offsets && get('R').is_some() {
            // Fanuc and Haas: "the arc specified by address R takes precedence".
            offsets = (None, None);
        }
        match (get('R'), offsets) {
            (Some(r), (Some(w), _) | (_, Some(w))) => {
                let first = if r.span.0 < w.span.0 { w } else { r };
                Err(LineError::new(first.span(), "arc with both R and I J K: expected either the radius R or the centre offsets I J K", "second arc definition"))
            }
            (None, (None, None)) => Err(LineError::new(block_span, format!("arc without a centre: expected {} {} (centre offsets from the start) or R (radius)", letter(u), letter(v)), "no centre")),
            (None, (i, j)) => {
                let (cu, cv) = if self.rotation.is_some() && self.frame().is_none() {
                    // A rotated work system: only G17 arcs (checked by the caller).
                    let c = if self.arc_absolute {
                        let p = self.xy_to_program([su, sv]);
                        self.xy_to_machine([i.map_or(p[0], |w| w.value * scale), j.map_or(p[1], |w| w.value * scale)])
                    } else {
                        let d = self.xy_increment([i.map_or(0.0, |w| w.value * scale), j.map_or(0.0, |w| w.value * scale)]);
                        [su + d[0], sv + d[1]]
                    };
                    (c[0], c[1])
                } else if self.arc_absolute {
                    // In a tilted frame, start and end are program coordinates already.
                    let tilted = self.frame().is_some();
                    let base = |a: Axis| if tilted { 0.0 } else { self.offset[a] + if a == Axis::Z { self.tool_length_mm } else { 0.0 } };
                    (i.map_or(su, |w| w.value * scale + base(u)), j.map_or(sv, |w| w.value * scale + base(v)))
                } else {
                    (su + i.map_or(0.0, |w| w.value * scale), sv + j.map_or(0.0, |w| w.value * scale))
                };
                let r_start = (su - cu).hypot(sv - cv);
                let r_end = (eu - cu).hypot(ev - cv);
                if r_start == 0.0 {
                    return Err(LineError::new(block_span, "arc of radius zero: expected centre offsets that are not all zero", "zero radius"));
                }
                let diff = (r_start - r_end).abs();
                let (ok, rule) = match self.dialect.table().arc_radius {
                    ArcRadiusRule::Linuxcnc => {
                        // Measured with rs274 2.9 (docs/gcode.md): an error only when the
                        // difference exceeds both 0.02·√2 mm (0.002·√2 in under G20) and
                        // 0.1 % of the start radius.
                        let abs_tol = std::f64::consts::SQRT_2 * if self.inch { 0.002 * MM_PER_INCH } else { 0.02 };
                        (diff <= abs_tol || diff / r_start <= 0.001, format!("{abs_tol:.4} mm or 0.1 % of the radius"))
                    }
                    ArcRadiusRule::Absolute(tolerance_mm) => (diff <= tolerance_mm, format!("{tolerance_mm} mm")),
                };
                if !ok {
                    return Err(LineError::new(block_span, format!("arc radius at the start is {r_start:.6} mm but at the end {r_end:.6} mm: expected them to agree within {rule}"), "inconsistent arc")
                        .help("I J K are incremental from the start point (G91.1); check them and the end point"));
                }
                center[u.index()] = cu;
                center[v.index()] = cv;
                Ok(center)
            }
            (Some(r), (None, None)) => {
                let radius = r.value * scale;
                let (du, dv) = (eu - su, ev - sv);
                let chord = du.hypot(dv);
                if chord < FULL_CIRCLE_TOLERANCE_MM {
                    return Err(LineError::new(r.span(), "R arc whose end is its start: expected an end point away from the start (R cannot describe a full circle)", "R arc with no chord").help("program a full circle with I J K"));
                }
                if radius == 0.0 {
                    return Err(LineError::new(r.span(), "arc of radius zero: expected R other than zero", "zero radius"));
                }
                let half = chord / 2.0;
                let h2 = radius * radius - half * half;
                if h2 < 0.0 && half - radius.abs() > ARC_RADIUS_TOLERANCE_MM {
                    return Err(LineError::new(r.span(), format!("radius {:.6} mm is shorter than half the chord, {half:.6} mm: expected |R| of at least half the distance from start to end", radius.abs()), "radius too small"));
                }
                let h = h2.max(0.0).sqrt();
                let long = radius < 0.0;
                let left = !clockwise != long;
                let side = if left { h } else { -h };
                center[u.index()] = su + du / 2.0 - side * dv / chord;
                center[v.index()] = sv + dv / 2.0 + side * du / chord;
                Ok(center)
            }
        }
    }
}

/// The number of turns of a LinuxCNC `G2`/`G3 ... P<n>` arc: a whole number from 1.
pub(super) fn turns(line: &str, p: &Word, feed_mode: FeedRead) -> LineResult<u32> {
    if p.value.fract() != 0.0 || !(1.0..=10_000.0).contains(&p.value) {
        return Err(LineError::new(
            p.span(),
            format!(
                "`{}`: expected a whole number of turns from 1",
                &line[p.span()]
            ),
            "turns",
        ));
    }
    if p.value > 1.0 && matches!(feed_mode, FeedRead::InverseTime) {
        return Err(LineError::new(
            p.span(),
            "an arc of several turns under G93 inverse-time feed: not supported",
            "turns under G93",
        ));
    }
    Ok(p.value as u32)
}

/// The inner points of the chords of the arc from `s` to `e` about centre `c` in `plane`
/// (program mm), in the direction given: the angle φ and the radius go linearly from
/// start to end (a spiral when the radii differ, a helix along the normal), n chords with
/// sagitta `r (1 − cos(Δφ/2n)) ≤` [`OBLIQUE_ARC_CHORD_TOLERANCE_MM`]; `None` beyond
/// [`MAX_CHORDS`].
fn oblique_chords(
    plane: Plane,
    s: [f64; 3],
    e: [f64; 3],
    c: [f64; 3],
    clockwise: bool,
) -> Option<Vec<[f64; 3]>> {
    use std::f64::consts::TAU;
    let (u, v, n) = plane.axes();
    let (u, v, n) = (u.index(), v.index(), n.index());
    let (r0, r1) = (
        (s[u] - c[u]).hypot(s[v] - c[v]),
        (e[u] - c[u]).hypot(e[v] - c[v]),
    );
    let a0 = (s[v] - c[v]).atan2(s[u] - c[u]);
    let a1 = (e[v] - c[v]).atan2(e[u] - c[u]);
    // Counter-clockwise sweep in (0, 2π]; a closed arc is a full turn.
    let mut sweep = (a1 - a0).rem_euclid(TAU);
    if clockwise {
        sweep -= TAU;
    }
    if sweep.abs() < 1e-12 {
        sweep = if clockwise { -TAU } else { TAU };
    }
    let r = r0.max(r1);
    let step = if r > OBLIQUE_ARC_CHORD_TOLERANCE_MM {
        2.0 * (1.0 - OBLIQUE_ARC_CHORD_TOLERANCE_MM / r).acos()
    } else {
        TAU
    };
    let count = (sweep.abs() / step).ceil().max(1.0);
    if count > MAX_CHORDS as f64 {
        return None;
    }
    let count = count as usize;
    Some(
        (1..count)
            .map(|k| {
                let t = k as f64 / count as f64;
                let (a, radius) = (a0 + sweep * t, r0 + (r1 - r0) * t);
                let mut p = [0.0; 3];
                p[u] = c[u] + radius * a.cos();
                p[v] = c[v] + radius * a.sin();
                p[n] = s[n] + (e[n] - s[n]) * t;
                p
            })
            .collect(),
    )
}
