//! Contour words that give a block's end point or centre another way (Fundamentals,
//! "Circular interpolation with opening angle and center point (G2/G3, AR)", "Contour
//! definitions: straight line with angle (ANG)"), turned into absolute coordinates in the
//! programmed (frame) plane before the frame maps them, as polar coordinates are.
//!
//! In the working plane, first axis `u` (X in G17, Z in G18, Y in G19) and second `v`,
//! angles counter-clockwise from `u` about the plane's normal, start S, end E, centre C:
//!
//! * `G1 X.. ANG=α` (one plane coordinate and the line's angle): E lies on the line through
//!   S at α: `E_v = S_v + (E_u - S_u) tan α`, or `E_u = S_u + (E_v - S_v) / tan α`.
//!   `ANG=` with both plane coordinates or with none (the second or first block of a
//!   two-line contour definition, whose corner is the lines' intersection) is refused.
//! * `G2/G3 X.. Y.. AR=α` (end point and opening angle, 0 < α < 360): the chord `c = |E - S|`,
//!   its midpoint M and unit direction `d`; `C = M + n (c/2) / tan(α/2)`, n the chord's left
//!   normal `(-d_v, d_u)` for G3 (counter-clockwise) and its right normal for G2; beyond
//!   180° the centre falls on the other side by the sign of the tangent.
//! * `G2/G3 I.. J.. AR=α` (centre and opening angle): E is S turned about C by +α (G3) or
//!   −α (G2).

use super::expr::Scan;
use super::words::{Coordinate, Mode, Words};
use super::Reader;
use crate::axis::Axis;
use crate::lex::{LineError, LineResult};

impl Reader {
    /// `AR=` or `ANG=` (`name`) at `at`, the cursor after the name.
    pub(super) fn angle_word(
        &mut self,
        name: &str,
        at: usize,
        sc: &mut Scan,
        w: &mut Words,
    ) -> LineResult<()> {
        let c = self.assigned(sc, at, &format!("expected `{name}=angle`"), "contour angle")?;
        let slot = if name == "AR" { &mut w.ar } else { &mut w.ang };
        if slot.replace(c).is_some() {
            return Err(sc.err(at, format!("`{name}=` twice in one block"), "contour angle"));
        }
        Ok(())
    }

    /// Resolves `ANG=` and `AR=` of the block into absolute plane coordinates (end point,
    /// centre); nothing when the block has neither.
    pub(super) fn contour_words(&mut self, w: &mut Words) -> LineResult<()> {
        if w.ang.is_none() && w.ar.is_none() {
            return Ok(());
        }
        let (u, v) = ((self.normal + 1) % 3, (self.normal + 2) % 3);
        let p = self.interp.program_position();
        let s = self.frame.frame_point([p[Axis::X], p[Axis::Y], p[Axis::Z]]);
        let end = |k: usize| {
            w.axes[k]
                .is_some()
                .then(|| Coordinate::resolve(&w.axes[k], s[k], self.absolute))
        };
        let (eu, ev) = (end(u), end(v));
        let motion = w.motion.unwrap_or(self.motion);
        if let Some(ang) = w.ang.clone() {
            let span = ang.span.clone();
            let refuse = |m: String| Err(LineError::new(span.clone(), m, "ANG="));
            if w.ar.is_some() || !matches!(motion, 0 | 1) {
                return refuse(
                    "ANG= in an arc block: expected it with G0 or G1 (a straight line's angle)"
                        .into(),
                );
            }
            let (tan, angle) = (ang.value.to_radians().tan(), ang.value);
            let (k, value) = match (eu, ev) {
                (Some(x), None) if tan.abs() < 1e15 => (v, s[v] + (x - s[u]) * tan),
                (None, Some(y)) if tan.abs() > 1e-15 => (u, s[u] + (y - s[v]) / tan),
                (Some(_), Some(_)) | (None, None) => {
                    return refuse(format!("ANG={angle} with {} of the plane's coordinates: the first or second block of a contour definition by two or more lines (their corner the lines' intersection), which mtsim does not read; expected one plane coordinate with ANG=, or the corner's coordinates", if eu.is_some() { "both" } else { "neither" }));
                }
                _ => {
                    return refuse(format!("ANG={angle}: the line at this angle never reaches the given coordinate (it runs parallel to it); expected the other plane coordinate"));
                }
            };
            w.axes[k] = Some(absolute(value, span));
            w.ang = None;
        }
        let Some(ar) = w.ar.take() else {
            return Ok(());
        };
        self.opening_angle(w, &ar, (u, v), s, (eu, ev), motion)
    }

    /// `AR=` (module doc): the centre from the end point, or the end point from the centre.
    fn opening_angle(
        &mut self,
        w: &mut Words,
        ar: &Coordinate,
        (u, v): (usize, usize),
        s: [f64; 3],
        (eu, ev): (Option<f64>, Option<f64>),
        motion: u8,
    ) -> LineResult<()> {
        let span = ar.span.clone();
        let refuse = |m: String| Err(LineError::new(span.clone(), m, "AR="));
        let alpha = ar.value;
        if !matches!(motion, 2 | 3) {
            return refuse(format!(
                "AR={alpha} outside an arc: expected it with G2 or G3 (the arc's opening angle)"
            ));
        }
        if !(alpha > 0.0 && alpha < 360.0) {
            return refuse(format!(
                "AR={alpha}: expected an opening angle over 0 and under 360 deg"
            ));
        }
        let ccw = if motion == 3 { 1.0 } else { -1.0 };
        let has_centre = w.centres[u].is_some() || w.centres[v].is_some();
        let has_end = eu.is_some() || ev.is_some();
        if w.cr.is_some() || has_centre == has_end {
            return refuse(format!("AR={alpha} with {}: expected the end point or the centre (I J K), not both, and no CR=", if has_centre { "both end point and centre" } else if w.cr.is_some() { "CR=" } else { "neither end point nor centre" }));
        }
        if has_end {
            let e = [eu.unwrap_or(s[u]), ev.unwrap_or(s[v])];
            let (du, dv) = (e[0] - s[u], e[1] - s[v]);
            let chord = du.hypot(dv);
            if chord < 1e-9 {
                return refuse(format!("AR={alpha} with the end point at the start: expected a chord to span (a full circle is not given by AR)"));
            }
            let off = ccw * (chord / 2.0) / (alpha.to_radians() / 2.0).tan();
            let n = [-dv / chord, du / chord];
            w.centres[u] = Some(absolute((s[u] + e[0]) / 2.0 + n[0] * off, span.clone()));
            w.centres[v] = Some(absolute((s[v] + e[1]) / 2.0 + n[1] * off, span.clone()));
        } else {
            // Centres are incremental from the start unless AC().
            let c = [
                Coordinate::resolve(&w.centres[u], s[u], false),
                Coordinate::resolve(&w.centres[v], s[v], false),
            ];
            let (sn, cs) = (ccw * alpha).to_radians().sin_cos();
            let (ru, rv) = (s[u] - c[0], s[v] - c[1]);
            w.axes[u] = Some(absolute(c[0] + ru * cs - rv * sn, span.clone()));
            w.axes[v] = Some(absolute(c[1] + ru * sn + rv * cs, span.clone()));
            w.centres[u] = Some(absolute(c[0], span.clone()));
            w.centres[v] = Some(absolute(c[1], span));
        }
        Ok(())
    }
}

fn absolute(value: f64, span: std::ops::Range<usize>) -> Coordinate {
    Coordinate {
        value,
        mode: Mode::Absolute,
        raw: None,
        span,
    }
}
