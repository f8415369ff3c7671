//! Contour approach and departure: `APPR LT|LN|CT|LCT` and `DEP LT|LN|CT|LCT`, as lines
//! and arcs in the working plane X Y (the TNC 640 Klartext user's manual, "Contour approach
//! and departure"; the same section of the TNC 620 and iTNC 530 manuals).
//!
//! P_S is the position before `APPR`, P_A the first contour point (the `APPR` block's
//! X Y Z), P_H the auxiliary point, P_E the last contour point, P_N the end point. t is the
//! unit tangent of the first (last) contour element at P_A (P_E), s the unit normal on the
//! tool's side: left of t under `RL`, right under `RR`; ρ the tool radius (with `DR`).
//!
//! ```text
//! APPR LT   P_H = P_A − LEN t                                 P_S ─line→ P_H ─line→ P_A
//! APPR LN   P_H = P_A + (LEN + ρ) s                           P_S ─line→ P_H ─line→ P_A
//! APPR CT   c = P_A + R s, P_H = c + rot(∓CCA)(P_A − c)       P_S ─line→ P_H ─arc→ P_A
//! APPR LCT  c = P_A + R s, P_H the point where the line from P_S touches the circle:
//!           θ = atan2(P_S − c) ± acos(R / |P_S − c|)          P_S ─line→ P_H ─arc→ P_A
//! DEP LT    P_N = P_E + LEN t;  DEP LN  P_N = P_E + (LEN + ρ) s
//! DEP CT    c = P_E + R s, P_N = c + rot(±CCA)(P_E − c)
//! DEP LCT   c = P_E + R s, P_H where the circle's tangent runs to P_N (X Y given)
//! ```
//!
//! The arc turns counter-clockwise when its centre lies left of t (RL with R > 0, RR with
//! R < 0), as the manual's table of compensation, sign of R and direction has it. The
//! first contour element (the block after `APPR`) gives t, so the approach is held until
//! that block. Radius compensation: the `APPR` block's `RL`/`RR` starts with the move
//! P_S → P_H (G41.1/G42.1, the interpreter's entry move), `DEP` ends it after its last
//! move (G40 alone: the tool stays at the compensated point). P_S → P_H runs at the feed
//! in effect (rapid when the block before was `FMAX`), `APPR LCT`'s at its own F; a Z in
//! the block moves with the last element, as the TNC 640 does. `R0` with `LN`, `CT` or
//! `LCT` (which need the side) is refused, as the TNC 640 refuses it.

use crate::lex::{LineError, LineResult};

use super::contour::{self, Centre};
use super::state::{self, Approach, Block, Extras, Kind, Reader};
use super::text::split_word;

const X: usize = 0;
const Y: usize = 1;

/// What an `APPR`/`DEP` block gives.
#[derive(Default)]
struct Words {
    target: [f64; 6],
    mask: u8,
    len: Option<f64>,
    radius: Option<f64>,
    cca: Option<f64>,
    e: Extras,
}

fn kind_of(b: &Block) -> LineResult<Kind> {
    Ok(match b.tok(1).to_ascii_uppercase().as_str() {
        "LT" => Kind::Lt,
        "LN" => Kind::Ln,
        "CT" => Kind::Ct,
        "LCT" => Kind::Lct,
        _ => {
            return Err(LineError::new(
                b.spans(0, 1),
                format!(
                    "`{} {}` is not supported: mtsim reads {0} LT, LN, CT and LCT (the polar forms P… are refused; KP \"Contour approach and departure\")",
                    b.tok(0).to_ascii_uppercase(),
                    b.tok(1)
                ),
                "Heidenhain construct not supported",
            ))
        }
    })
}

/// The block's words after the kind: coordinates, LEN, CCA, R, R0/RL/RR, F, M.
fn read_words(r: &mut Reader, b: &Block, from: [f64; 6]) -> LineResult<Words> {
    let mut w = Words {
        target: from,
        ..Words::default()
    };
    for k in 2..b.toks.len() {
        if let Some(a) = xyz_word(r, b, k, &mut w.target)? {
            w.mask |= 1 << a;
            continue;
        }
        let (name, rest) = split_word(b.tok(k));
        let upper = name.to_ascii_uppercase();
        let slot = match upper.as_str() {
            "LEN" => Some(&mut w.len),
            "CCA" => Some(&mut w.cca),
            "R" if rest != "0" => Some(&mut w.radius),
            _ => None,
        };
        if let Some(slot) = slot {
            *slot = Some(b.value(k, name.len(), &r.q)?);
            continue;
        }
        if !contour::extra(r, b, k, &mut w.e)? {
            return Err(state::unexpected(
                b,
                k,
                &format!("`{} {}`", b.tok(0), b.tok(1)),
                "X Y Z (I for incremental), LEN, CCA, R, R0/RL/RR, F or M functions",
            ));
        }
    }
    Ok(w)
}

/// Token `k` as a coordinate `X Y Z` (`IX IY IZ` from `target`) into `target`: its axis,
/// or `None` when it is no coordinate.
pub(super) fn xyz_word(
    r: &Reader,
    b: &Block,
    k: usize,
    target: &mut [f64; 6],
) -> LineResult<Option<usize>> {
    let (name, rest) = split_word(b.tok(k));
    let upper = name.to_ascii_uppercase();
    let (inc, axis) = match upper.strip_prefix('I') {
        Some(a) if a.len() == 1 => (true, a),
        _ => (false, upper.as_str()),
    };
    let Some(a) = ["X", "Y", "Z"].iter().position(|l| *l == axis) else {
        return Ok(None);
    };
    if rest.is_empty() {
        return Ok(None);
    }
    let v = b.value(k, name.len(), &r.q)?;
    target[a] = if inc { target[a] + v } else { v };
    Ok(Some(a))
}

/// An error at the block's construct, named before `what` (`APPR CT` …).
fn named(b: &Block, what: &str, label: &'static str) -> LineError {
    let (key, kind) = (b.tok(0).to_ascii_uppercase(), b.tok(1).to_ascii_uppercase());
    LineError::new(b.spans(0, 1), format!("`{key} {kind}` {what}"), label)
}

/// A positive value the path needs, or an error naming it.
fn need(b: &Block, v: Option<f64>, what: &str, rule: &str) -> LineResult<f64> {
    match v {
        Some(v) if v > 0.0 => Ok(v),
        _ => Err(named(b, &format!("needs {what}: {rule}"), "missing value")),
    }
}

/// A signed radius (CT: the sign picks the side) or an error.
fn need_nonzero(b: &Block, v: Option<f64>) -> LineResult<f64> {
    v.filter(|v| *v != 0.0).ok_or_else(|| {
        LineError::new(
            b.spans(0, 1),
            "needs the arc's radius R (R+ on the side of the radius compensation, R- opposite)",
            "missing value",
        )
    })
}

/// The values each kind needs (LEN; CCA and R; R), checked as the manual states them.
fn check(b: &Block, kind: Kind, w: &Words, comp: u8) -> LineResult<(f64, f64, f64)> {
    if kind != Kind::Lt && comp == 0 {
        return Err(named(b, "with R0: the path's side comes from the radius compensation; expected RL or RR (the TNC 640 stops with an error here too)", "no compensation side"));
    }
    Ok(match kind {
        Kind::Lt | Kind::Ln => (need(b, w.len, "LEN", "a positive distance")?, 0.0, 0.0),
        Kind::Ct => {
            let cca = need(b, w.cca, "CCA", "a centre angle above 0, at most 360°")?;
            if cca > 360.0 {
                return Err(LineError::new(
                    b.spans(0, 1),
                    format!("CCA{cca}: the centre angle is at most 360°"),
                    "CCA too large",
                ));
            }
            (0.0, need_nonzero(b, w.radius)?, cca)
        }
        Kind::Lct => (0.0, need(b, w.radius, "R", "a positive radius")?, 0.0),
    })
}

/// `APPR …`: held until the first contour element.
pub(super) fn appr(r: &mut Reader, b: &Block) -> LineResult<()> {
    let kind = kind_of(b)?;
    let start = r.path.pos;
    let mut w = read_words(r, b, start)?;
    let comp = w.e.comp.unwrap_or(r.path.comp);
    let (len, radius, cca) = check(b, kind, &w, comp)?;
    if w.mask & 3 != 3 && w.mask & 3 != 0 || w.mask == 0 {
        return Err(LineError::new(
            b.spans(0, 1),
            "APPR needs the first contour point: expected X and Y",
            "no contour point",
        ));
    }
    r.path.appr = Some(Approach {
        kind,
        start,
        end: w.target,
        z_given: w.mask & 4 != 0,
        len,
        radius,
        cca_deg: cca,
        comp,
        feed: w.e.feed,
        rapid: r.path.rapid,
        m: std::mem::take(&mut w.e.m),
        line: b.line,
    });
    r.path.pos = w.target;
    Ok(())
}

/// Refuses a block other than a contour element after `APPR`.
pub(super) fn pending_refused(r: &Reader, b: &Block, key: &str) -> LineResult<()> {
    match &r.path.appr {
        Some(a) if !matches!(key, "L" | "LP" | "C" | "CR" | "CP" | "CC") => Err(LineError::new(
            b.span(0),
            format!(
                "`{}` after APPR (line {}): expected the first contour element (L, LP, C, CR or CP, a CC before it; CT has nothing to be tangent to)",
                b.tok(0),
                a.line
            ),
            "APPR not followed by a contour element",
        )),
        _ => Ok(()),
    }
}

/// The program ends with an `APPR` still waiting: refused, never dropped.
pub(super) fn unfinished(r: &Reader) -> LineResult<()> {
    match &r.path.appr {
        Some(a) => Err(LineError::new(
            0..0,
            format!(
                "the program ends after the APPR of line {}: expected the first contour element after it",
                a.line
            ),
            "APPR not followed by a contour element",
        )),
        None => Ok(()),
    }
}

fn left(t: [f64; 2]) -> [f64; 2] {
    [-t[1], t[0]]
}

/// The unit normal on the tool's side of t: left under RL (1), right under RR (2).
fn side(t: [f64; 2], comp: u8) -> [f64; 2] {
    if comp == 1 {
        left(t)
    } else {
        [t[1], -t[0]]
    }
}

fn add(p: [f64; 2], d: [f64; 2], k: f64) -> [f64; 2] {
    [p[0] + d[0] * k, p[1] + d[1] * k]
}

/// `v` turned by `deg` counter-clockwise.
fn rot(v: [f64; 2], deg: f64) -> [f64; 2] {
    let (s, c) = deg.to_radians().sin_cos();
    [v[0] * c - v[1] * s, v[0] * s + v[1] * c]
}

/// The circle's tangent point seen from `p` outside it: where a line from `p` runs onto
/// the circle (`onto`) or where the circle runs off to `p`, turning `ccw`.
fn touch(c: [f64; 2], radius: f64, p: [f64; 2], ccw: bool, onto: bool) -> Option<[f64; 2]> {
    let d = [p[0] - c[0], p[1] - c[1]];
    let dist = d[0].hypot(d[1]);
    if dist <= radius + 1e-9 {
        return None;
    }
    let phi = d[1].atan2(d[0]);
    let alpha = (radius / dist).acos();
    let theta = if ccw == onto {
        phi + alpha
    } else {
        phi - alpha
    };
    Some([c[0] + radius * theta.cos(), c[1] + radius * theta.sin()])
}

/// An arc's centre and direction from a point `p` with tangent t, `radius` signed toward
/// the tool's side: counter-clockwise when the centre is left of t.
fn tangent_arc(p: [f64; 2], t: [f64; 2], radius: f64, comp: u8) -> ([f64; 2], bool) {
    let c = add(p, side(t, comp), radius);
    let n = left(t);
    (c, (c[0] - p[0]) * n[0] + (c[1] - p[1]) * n[1] > 0.0)
}

/// The auxiliary point P_H of `a` and its arc (centre, ccw) if it has one, for the
/// first element's tangent `t` at P_A and the tool radius `rho`.
fn approach_points(
    a: &Approach,
    t: [f64; 2],
    rho: f64,
) -> Option<([f64; 2], Option<([f64; 2], bool)>)> {
    let (ps, pa) = ([a.start[X], a.start[Y]], [a.end[X], a.end[Y]]);
    Some(match a.kind {
        Kind::Lt => (add(pa, t, -a.len), None),
        Kind::Ln => (add(pa, side(t, a.comp), a.len + rho), None),
        Kind::Ct => {
            let (c, ccw) = tangent_arc(pa, t, a.radius, a.comp);
            let back = if ccw { -a.cca_deg } else { a.cca_deg };
            let v = rot([pa[0] - c[0], pa[1] - c[1]], back);
            ([c[0] + v[0], c[1] + v[1]], Some((c, ccw)))
        }
        Kind::Lct => {
            let (c, ccw) = tangent_arc(pa, t, a.radius, a.comp);
            (touch(c, a.radius, ps, ccw, true)?, Some((c, ccw)))
        }
    })
}

/// The first contour element, with tangent `t` at P_A, is being read: the approach's
/// moves now.
pub(super) fn run(r: &mut Reader, b: &Block, t: Option<[f64; 2]>) -> LineResult<()> {
    let Some(t) = t else {
        return Err(LineError::new(b.span(0), "the first contour element after APPR is an arc outside the plane X Y: mtsim approaches in X Y only", "not the XY plane"));
    };
    let Some(a) = r.path.appr.take() else {
        return Ok(());
    };
    let rho = r.comp_diameter() / 2.0;
    let (kind, radius, comp) = (a.kind, a.radius, a.comp);
    let Some((ph, arc)) = approach_points(&a, t, rho) else {
        return Err(LineError::new(
            b.span(0),
            format!(
                "the APPR LCT of line {}: the start point lies inside the arc of radius {radius}, so no line from it touches the arc",
                a.line
            ),
            "start inside the arc",
        ));
    };
    if kind == Kind::Lct {
        r.path.feed = a.feed.or(r.path.feed);
    }
    let mut to_h = a.start;
    to_h[X] = ph[0];
    to_h[Y] = ph[1];
    let first = Extras {
        comp: Some(comp),
        m: a.m,
        ..Extras::default()
    };
    let g = if a.rapid && kind != Kind::Lct {
        "0"
    } else {
        "1"
    };
    contour::motion(r, b, g, &to_h, 3, None, &first)?;
    r.path.feed = a.feed.or(r.path.feed);
    let mask = 3 | if a.z_given { 4 } else { 0 };
    r.path.pos = to_h;
    element(r, b, &a.end, mask, arc)?;
    r.path.pos = a.end;
    r.path.dir = Some(t);
    Ok(())
}

/// A line (no arc) or an arc about `arc`'s centre from the current position to `end`.
fn element(
    r: &mut Reader,
    b: &Block,
    end: &[f64; 6],
    mask: u8,
    arc: Option<([f64; 2], bool)>,
) -> LineResult<()> {
    let p = r.path.pos;
    match arc {
        None => contour::motion(r, b, "1", end, mask, None, &Extras::default()),
        Some((c, ccw)) => {
            let off = Centre::Offset([c[0] - p[X], c[1] - p[Y]], [X, Y]);
            let g = if ccw { "3" } else { "2" };
            contour::motion(r, b, g, end, mask, Some(off), &Extras::default())
        }
    }
}

/// `DEP …`: from the last contour point, now.
pub(super) fn dep(r: &mut Reader, b: &Block) -> LineResult<()> {
    let kind = kind_of(b)?;
    let Some(t) = r.path.dir else {
        return Err(LineError::new(
            b.spans(0, 1),
            "DEP with no contour element before it: expected a line or arc to depart from",
            "nothing to depart from",
        ));
    };
    let pe = r.path.xy();
    let w = read_words(r, b, r.path.pos)?;
    let comp = r.path.comp;
    let (len, radius, cca) = check(b, kind, &w, comp)?;
    if w.mask & 3 != 0 && kind != Kind::Lct || kind == Kind::Lct && w.mask & 3 != 3 {
        return Err(LineError::new(
            b.spans(0, 1),
            "DEP LCT takes the end point X Y; DEP LT, LN and CT take only Z",
            "coordinates",
        ));
    }
    if let Some(f) = w.e.feed {
        r.path.feed = Some(f);
    }
    let rho = r.comp_diameter() / 2.0;
    let zmask = w.mask & 4;
    let mut end = w.target;
    let (pn, arc) = match kind {
        Kind::Lt => (add(pe, t, len), None),
        Kind::Ln => (add(pe, side(t, comp), len + rho), None),
        Kind::Ct => {
            let (c, ccw) = tangent_arc(pe, t, radius, comp);
            let v = rot([pe[0] - c[0], pe[1] - c[1]], if ccw { cca } else { -cca });
            ([c[0] + v[0], c[1] + v[1]], Some((c, ccw)))
        }
        Kind::Lct => {
            let (c, ccw) = tangent_arc(pe, t, radius, comp);
            let pn = [w.target[X], w.target[Y]];
            let ph = touch(c, radius, pn, ccw, false).ok_or_else(|| {
                LineError::new(
                    b.spans(0, 1),
                    format!("DEP LCT: the end point lies inside the arc of radius {radius}"),
                    "end inside the arc",
                )
            })?;
            let mut at_h = r.path.pos;
            at_h[X] = ph[0];
            at_h[Y] = ph[1];
            element(r, b, &at_h, 3, Some((c, ccw)))?;
            r.path.pos = at_h;
            (pn, None)
        }
    };
    end[X] = pn[0];
    end[Y] = pn[1];
    element(r, b, &end, 3 | zmask, arc)?;
    let d = [pn[0] - r.path.pos[X], pn[1] - r.path.pos[Y]];
    let n = d[0].hypot(d[1]).max(1e-300);
    r.path.dir = Some([d[0] / n, d[1] / n]);
    r.path.pos = end;
    // DEP ends the compensation; the block's M functions after the moves.
    let off = Extras {
        comp: Some(0),
        m: w.e.m,
        ..Extras::default()
    };
    contour::motion(r, b, "1", &end, 0, None, &off)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn near(a: [f64; 2], b: [f64; 2]) -> bool {
        (a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9
    }

    // The first contour element runs +X from P_A (10, 20).
    const T: [f64; 2] = [1.0, 0.0];

    fn appr(kind: Kind, ps: [f64; 2], len: f64, radius: f64, cca_deg: f64, comp: u8) -> Approach {
        Approach {
            kind,
            start: [ps[0], ps[1], 0.0, 0.0, 0.0, 0.0],
            end: [10.0, 20.0, 0.0, 0.0, 0.0, 0.0],
            z_given: false,
            len,
            radius,
            cca_deg,
            comp,
            feed: None,
            rapid: false,
            m: Vec::new(),
            line: 1,
        }
    }

    #[test]
    fn ln_puts_the_auxiliary_point_len_plus_the_tool_radius_off_the_contour() {
        // RR: the tool's side of +X is −Y; 15 + 5 below P_A.
        let a = appr(Kind::Ln, [0.0; 2], 15.0, 0.0, 0.0, 2);
        let (ph, arc) = approach_points(&a, T, 5.0).expect("a point");
        assert!(near(ph, [10.0, 0.0]) && arc.is_none(), "{ph:?}");
    }

    #[test]
    fn ct_quarter_arc_ends_tangent_at_the_contour_point() {
        // RL, R+10: centre (10, 30) left of +X, counter-clockwise; 90° back from P_A is
        // (0, 30).
        let a = appr(Kind::Ct, [0.0; 2], 0.0, 10.0, 90.0, 1);
        let (ph, arc) = approach_points(&a, T, 0.0).expect("a point");
        let (c, ccw) = arc.expect("an arc");
        assert!(
            near(c, [10.0, 30.0]) && ccw && near(ph, [0.0, 30.0]),
            "{ph:?} {c:?}"
        );
        // R-10 under RL: centre (10, 10), clockwise; 90° back is (0, 10).
        let a = appr(Kind::Ct, [0.0; 2], 0.0, -10.0, 90.0, 1);
        let (ph, arc) = approach_points(&a, T, 0.0).expect("a point");
        let (c, ccw) = arc.expect("an arc");
        assert!(
            near(c, [10.0, 10.0]) && !ccw && near(ph, [0.0, 10.0]),
            "{ph:?} {c:?}"
        );
    }

    #[test]
    fn lct_line_touches_the_arc() {
        // RR, R10: centre (10, 10), clockwise. From P_S (10, −10), 20 below the centre:
        // α = acos(10/20) = 60° from the direction −90°; clockwise onto the circle turns
        // to −150°: P_H = (10 − 5√3, 5).
        let a = appr(Kind::Lct, [10.0, -10.0], 0.0, 10.0, 0.0, 2);
        let (ph, _) = approach_points(&a, T, 0.0).expect("a point");
        assert!(near(ph, [10.0 - 5.0 * 3f64.sqrt(), 5.0]), "{ph:?}");
        // The line P_S → P_H is perpendicular to the radius at P_H (a tangent).
        let (d, rad) = ([ph[0] - 10.0, ph[1] + 10.0], [ph[0] - 10.0, ph[1] - 10.0]);
        assert!((d[0] * rad[0] + d[1] * rad[1]).abs() < 1e-9);
    }
}
