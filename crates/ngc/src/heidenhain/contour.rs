//! Path contours: `L`, `LP`, `CC`, `C`, `CR`, `CT`, `CP`, `RND`, `CHF`, with `R0/RL/RR`,
//! `F/FMAX/FAUTO` and M functions, as G0-G3 words (working plane XY, tool axis Z; circles
//! also in the planes Z X and Y Z that `CC` or `CR`'s coordinates name).
//!
//! HEIDENHAIN TNC 640 Klartext programming manual, "Programming contours": "Path contours -
//! Cartesian coordinates" (L, CHF, CC, C, CR, CT, RND) and "Path contours - Polar
//! coordinates" (LP, CP, helix). Geometry (plane, mm or inch):
//!
//! ```text
//! C  about the pole c from p to q:      G2/G3 q, I J = c - p      (DR- CW, DR+ CCW)
//!    (CC X Z / CC Y Z: the plane Z X / Y Z, angle 0 on Z / Y, as G18 I K / G19 J K)
//! CT from p tangent to t, to q:          c = p + n s, n ⟂ t (left), s = |q-p|² / (2 (q-p)·n)
//! CHF s at corner k (lines u in, v out): k - u s → k + v s
//! RND r at corner k:                     tangent points k ∓ u, v · r tan(φ/2), φ = ∠(u, v)
//! LP / CP about the pole c:              c + r (cos a, sin a)
//! ```
//!
//! A straight line is held until the next block, which may be a `RND` or `CHF` that cuts its
//! end (the corner needs the line after it too); anything else releases it unchanged.

use std::ops::Range;

use crate::lex::{LineError, LineResult};

use super::state::{self, Block, Corner, Extras, Held, Reader};
use super::text::{split_word, value};
use super::{cycles, frames};

const X: usize = 0;
const Y: usize = 1;
const Z: usize = 2;
const LETTERS: [char; 6] = ['X', 'Y', 'Z', 'A', 'B', 'C'];

/// A contour block.
pub(super) fn block(r: &mut Reader, b: &Block, key: &str) -> LineResult<()> {
    match key {
        "L" | "LP" => line(r, b, key == "LP"),
        "CC" => pole(r, b),
        "RND" | "CHF" => corner(r, b, key == "RND"),
        _ => {
            release(r, b)?;
            arc(r, b, key)
        }
    }
}

/// Parses token `k` as a word besides coordinates (R0/RL/RR, F, M); false if it is none.
pub(super) fn extra(r: &mut Reader, b: &Block, k: usize, e: &mut Extras) -> LineResult<bool> {
    let t = b.tok(k);
    let (name, rest) = split_word(t);
    let span = b.span(k);
    let mut upper = [0u8; 8];
    let n = name.len().min(8);
    for (u, c) in upper.iter_mut().zip(&name.as_bytes()[..n]) {
        *u = c.to_ascii_uppercase();
    }
    match std::str::from_utf8(&upper[..n]).unwrap_or("") {
        "R" if rest == "0" => e.comp = Some(0),
        "RL" if rest.is_empty() => e.comp = Some(1),
        "RR" if rest.is_empty() => e.comp = Some(2),
        "FMAX" if rest.is_empty() => e.rapid = true,
        "MAX" if rest.is_empty() && b.is(k.wrapping_sub(1), "F") => e.rapid = true,
        "F" if rest.is_empty() && (b.is(k + 1, "MAX") || b.is(k + 1, "AUTO")) => {}
        // `FAUTO`, or `F AUTO` as some posts space it: the TOOL CALL's feed.
        "FAUTO" if rest.is_empty() => e.feed = Some(tool_feed(r, span)?),
        "AUTO" if rest.is_empty() && b.is(k.wrapping_sub(1), "F") => {
            e.feed = Some(tool_feed(r, span)?)
        }
        "FU" | "FZ" => {
            return Err(LineError::new(
                span,
                format!(
                "`{t}` (feed per revolution or per tooth) is not supported: expected F in mm/min"
            ),
                "feed per revolution",
            ))
        }
        // `FQ53`: the feed in a Q parameter (as `F+Q53`).
        "F" | "FQ" | "FQL" | "FQR" => {
            let v = b.value(k, 1, &r.q)?;
            if v <= 0.0 {
                return Err(LineError::new(
                    span,
                    format!("`{t}`: expected a positive feed"),
                    "bad feed",
                ));
            }
            e.feed = Some(v);
        }
        _ => return m_word(r, b, k, e),
    }
    Ok(true)
}

/// The `TOOL CALL`'s feed, for `FAUTO`.
fn tool_feed(r: &Reader, span: std::ops::Range<usize>) -> LineResult<f64> {
    r.path.tool_feed.ok_or_else(|| {
        LineError::new(
            span,
            "FAUTO with no feed in the TOOL CALL: expected `TOOL CALL … F`",
            "no tool feed",
        )
    })
}

/// Parses token `k` as an M function (and `MB` after M140); false if it is none.
pub(super) fn m_word(r: &mut Reader, b: &Block, k: usize, e: &mut Extras) -> LineResult<bool> {
    let t = b.tok(k);
    let (name, rest) = split_word(t);
    let span = b.span(k);
    let upper = name.to_ascii_uppercase();
    if upper == "MB" {
        if !matches!(e.m140, Some(_)) {
            return Err(LineError::new(
                span,
                "MB without M140: expected `M140 MB …`",
                "MB alone",
            ));
        }
        // `MB MAX`, `MBMAX`; `MB 20`, `MB+20`, `MB20`: the distance.
        let next = b.tok(k + 1);
        let distance = if rest.eq_ignore_ascii_case("MAX") {
            None
        } else if !rest.is_empty() {
            Some(value(rest, &r.q, span)?)
        } else if b.is(k + 1, "MAX") {
            None
        } else if next
            .starts_with(|c: char| c.is_ascii_digit() || matches!(c, '+' | '-' | '.' | 'Q' | 'q'))
        {
            Some(value(next, &r.q, b.span(k + 1))?)
        } else {
            return Err(LineError::new(
                span,
                "`M140 MB` without a distance: expected `MB MAX` or `MB` and the retraction distance",
                "MB without a distance",
            ));
        };
        e.m140 = Some(distance);
        return Ok(true);
    }
    if b.is(k.wrapping_sub(1), "MB")
        && (upper == "MAX" || name.is_empty() || upper.starts_with('Q'))
    {
        // The `MAX` or distance after `MB`, read with it.
        return Ok(true);
    }
    if upper != "M" || rest.is_empty() || !rest.bytes().all(|c| c.is_ascii_digit()) {
        return Ok(false);
    }
    let n: u32 = rest.parse().unwrap_or(u32::MAX);
    e.span = span.clone();
    match n {
        0 | 1 | 2 | 3 | 4 | 5 | 8 | 9 | 30 => e.m.push((n as f64, span)),
        13 | 14 => {
            e.m.push(((n - 10) as f64, span.clone()));
            e.m.push((8.0, span));
        }
        6 => {}
        91 => e.m91 = true,
        99 => e.m99 = true,
        89 => r.modal_cycle = true,
        126 => r.shortest = true,
        127 => r.shortest = false,
        128 => e.tcp = Some(true),
        129 => e.tcp = Some(false),
        140 => e.m140 = Some(None),
        7
        | 10
        | 11
        | 94
        | 97
        | 101..=110
        | 116
        | 117
        | 118
        | 120
        | 134..=138
        | 141..=150
        | 197
        | 198 => {
            r.note(
                b,
                &format!("M{n} (Heidenhain) is accepted and not simulated"),
            );
        }
        92 => {
            return Err(LineError::new(
                span,
                "`M92`: the block's coordinates are relative to the machine datum M92, a position the machine tool builder sets in the control's machine parameters, which mtsim's machine file does not carry (KP \"Miscellaneous functions for coordinate data: M91/M92\")",
                "Heidenhain M92 not supported",
            )
            .help("post the move with M91 (machine coordinates) or in the workpiece frame"))
        }
        _ => {
            return Err(LineError::new(
                span,
                format!("`M{n}` is not a Heidenhain M function mtsim reads"),
                "M function not supported",
            )
            .help("docs/gcode.md lists the Heidenhain M functions mtsim reads"))
        }
    }
    Ok(true)
}

/// Coordinates (`X+10`, `IX-5`, …) into `target` (mask of axes given); other words into
/// `e`. `polar` also reads PR/PA/IPR/IPA into `pr_pa`.
fn words(
    r: &mut Reader,
    b: &Block,
    target: &mut [f64; 6],
    e: &mut Extras,
    mut pr_pa: Option<&mut [Option<(f64, bool)>; 2]>,
    arc_dir: &mut Option<bool>,
    radius: &mut Option<f64>,
) -> LineResult<u8> {
    let mut mask = 0u8;
    for k in 1..b.toks.len() {
        let t = b.tok(k);
        let (name, rest) = split_word(t);
        let nb = name.as_bytes();
        // The common case first: one axis letter (or I and one) and a value.
        let (inc, axis_name) = match nb {
            [b'I' | b'i', _] | [b'I' | b'i', _, _] => (true, &name[1..]),
            _ => (false, name),
        };
        if let [l] = axis_name.as_bytes() {
            let axis = LETTERS
                .iter()
                .position(|&c| c as u8 == l.to_ascii_uppercase());
            if let (Some(axis), false) = (axis, rest.is_empty()) {
                let v = b.value(k, name.len(), &r.q)?;
                target[axis] = if inc { target[axis] + v } else { v };
                mask |= 1 << axis;
                continue;
            }
        }
        if let Some(p) = pr_pa.as_deref_mut() {
            let slot = [("PR", 0), ("PA", 1)]
                .iter()
                .find(|(n, _)| axis_name.eq_ignore_ascii_case(n));
            if let Some(&(_, i)) = slot {
                p[i] = Some((value(rest, &r.q, b.span(k))?, inc));
                continue;
            }
        }
        if name.eq_ignore_ascii_case("DR") && (rest == "+" || rest == "-") {
            *arc_dir = Some(rest == "+");
            continue;
        }
        if name.eq_ignore_ascii_case("R") && rest != "0" && radius.is_some() {
            *radius = Some(value(rest, &r.q, b.span(k))?);
            continue;
        }
        if !extra(r, b, k, e)? {
            if let Some(err) = not_a_number(b, k) {
                return Err(err);
            }
            let what = match axis_name.to_ascii_uppercase().as_str() {
                "U" | "V" | "W" => "the axes X Y Z A B C (U V W are not read)",
                _ => "coordinates X Y Z A B C (I for incremental), R0/RL/RR, F, FMAX, FAUTO or M functions",
            };
            return Err(state::unexpected(b, k, &format!("`{}`", b.tok(0)), what));
        }
    }
    Ok(mask)
}

/// A coordinate written `Xnan`, `Y-inf`: a fault of the post that wrote the program (a
/// value it could not compute), named as such.
fn not_a_number(b: &Block, k: usize) -> Option<LineError> {
    let t = b.tok(k);
    let letter = t.chars().next()?;
    if !LETTERS.contains(&letter.to_ascii_uppercase()) {
        return None;
    }
    let v = t[1..].trim_start_matches(['+', '-']).to_ascii_lowercase();
    matches!(v.as_str(), "nan" | "inf" | "infinity").then(|| {
        LineError::new(
            b.span(k),
            format!("`{t}`: the coordinate {letter} has no value (`{}`, not a number): a fault of the post that wrote the program, which could not compute this point", &t[1..]),
            "coordinate without a value",
        )
        .help("post the program again; check the CAM operation that makes this block")
    })
}

/// `L` and `LP`: a straight line.
fn line(r: &mut Reader, b: &Block, polar: bool) -> LineResult<()> {
    let mut target = r.path.pos;
    let mut e = Extras::default();
    let mut pp = [None, None];
    let (mut dir, mut radius) = (None, None);
    let mut mask = words(
        r,
        b,
        &mut target,
        &mut e,
        polar.then_some(&mut pp),
        &mut dir,
        &mut radius,
    )?;
    if polar {
        let c = pole_of(r, b)?;
        let [u, v] = r.path.pole_plane;
        let p = r.path.pos;
        let (r0, a0) = polar_of(c, [p[u], p[v]]);
        let pr = pp[0].map_or(r0, |(v, inc)| if inc { r0 + v } else { v });
        let pa = pp[1].map_or(a0, |(v, inc)| if inc { a0 + v } else { v });
        target[u] = c[0] + pr * pa.to_radians().cos();
        target[v] = c[1] + pr * pa.to_radians().sin();
        mask |= (1 << u) | (1 << v);
    }
    if r.shortest && !e.m91 {
        for a in 3..6 {
            if mask & (1 << a) != 0 {
                let d = target[a] - r.path.pos[a];
                target[a] = r.path.pos[a] + (d + 180.0).rem_euclid(360.0) - 180.0;
            }
        }
    }
    if let Some(f) = e.feed {
        r.path.feed = Some(f);
    }
    if r.path.appr.is_some() {
        let d = [target[X] - r.path.pos[X], target[Y] - r.path.pos[Y]];
        let n = d[0].hypot(d[1]);
        if n < 1e-12 {
            return Err(LineError::new(b.span(0), "the first contour element after APPR does not move in the plane X Y: expected its end point", "no tangent"));
        }
        r.approach(b, Some([d[0] / n, d[1] / n]))?;
    }
    r.path.rapid = e.rapid;
    let in_plane =
        mask & !3 == 0 || (mask & 4 != 0 && target[Z] == r.path.pos[Z] && mask & !7 == 0);
    if let Some(c) = r.path.corner.take() {
        if !(in_plane && e.plain()) {
            return Err(LineError::new(c.span, "RND or CHF must be followed by a straight line in the working plane with no M function or compensation change", "corner not closed"));
        }
        return close_corner(r, c, [target[X], target[Y]], target);
    }
    release(r, b)?;
    let start = r.path.xy();
    if in_plane && e.plain() && mask != 0 {
        r.path.held = Some(Held {
            start,
            end: target,
            feed: r.path.feed,
            line: b.line,
        });
    } else {
        motion(
            r,
            b,
            if e.rapid { "0" } else { "1" },
            &target,
            mask,
            None,
            &e,
        )?;
    }
    if mask & 3 != 0 {
        let d = [target[X] - start[0], target[Y] - start[1]];
        let n = (d[0] * d[0] + d[1] * d[1]).sqrt();
        if n > 1e-12 {
            r.path.dir = Some([d[0] / n, d[1] / n]);
        }
    }
    r.path.pos = target;
    // A rotary turned under a tilted plane moves the program point in that plane.
    let turned_in_frame = mask & !7 != 0 && r.interp.framed();
    if e.m91 || e.m140.is_some() || e.tcp.is_some() || turned_in_frame {
        r.sync_position(b)?;
    }
    Ok(())
}

/// Emits one move block: the motion words, compensation, feed and M functions (TCP on
/// before the move, off after it; M140 and a cycle call after it).
pub(super) fn motion(
    r: &mut Reader,
    b: &Block,
    g: &'static str,
    target: &[f64; 6],
    mask: u8,
    centre: Option<Centre>,
    e: &Extras,
) -> LineResult<()> {
    let key = b.span(0);
    if e.tcp == Some(true) {
        frames::tcp(r, b, true);
    }
    let other_plane = centre.map(|c| c.plane()).filter(|p| *p != [X, Y]);
    if mask != 0 || centre.is_some() {
        if e.m91 {
            r.gword("53", key.clone());
        }
        // An arc outside X Y: its plane for this block (G18 Z X, G19 Y Z), X Y again after.
        match other_plane {
            Some([Z, X]) => r.gword("18", key.clone()),
            Some(_) => r.gword("19", key.clone()),
            None => {}
        }
        r.gword(g, key.clone());
        for (a, l) in LETTERS.iter().enumerate() {
            if mask & (1 << a) != 0 {
                r.word(*l, target[a], key.clone());
            }
        }
        const CENTRE_WORDS: [char; 3] = ['I', 'J', 'K'];
        match centre {
            Some(Centre::Offset(d, [u, v])) => {
                r.word(CENTRE_WORDS[u.min(v)], d[usize::from(v < u)], key.clone());
                r.word(CENTRE_WORDS[u.max(v)], d[usize::from(u < v)], key.clone());
            }
            Some(Centre::Radius(rad, _)) => r.word('R', rad, key.clone()),
            None => {}
        }
        if g != "0" {
            if let Some(f) = r.path.feed {
                r.word('F', f, key.clone());
            }
        }
    }
    if let Some(c) = e.comp {
        if c != r.path.comp {
            r.path.comp = c;
            match c {
                0 => r.gword("40", key.clone()),
                _ => {
                    r.gword(if c == 1 { "41.1" } else { "42.1" }, key.clone());
                    let d = r.comp_diameter();
                    r.word('D', d, key.clone());
                }
            }
        }
    }
    for (m, span) in &e.m {
        r.word('M', *m, span.clone());
    }
    r.end_block(b.line);
    if other_plane.is_some() {
        r.gword("17", key.clone());
        r.end_block(b.line);
    }
    run_extras(r, b, e, Some(()))
}

/// What follows a block's move: M140, TCP off, a cycle call; or, for a block of M functions
/// alone (`moved` None), its M words.
pub(super) fn run_extras(
    r: &mut Reader,
    b: &Block,
    e: &Extras,
    moved: Option<()>,
) -> LineResult<()> {
    if moved.is_none() {
        if e.tcp == Some(true) {
            frames::tcp(r, b, true);
        }
        for (m, span) in &e.m {
            r.word('M', *m, span.clone());
        }
        r.end_block(b.line);
    }
    if let Some(mb) = e.m140 {
        retract(r, b, mb)?;
    }
    if e.tcp == Some(false) {
        frames::tcp(r, b, false);
    }
    if e.m99 || (r.modal_cycle && moved.is_some()) {
        if e.m99 {
            r.modal_cycle = false;
        }
        cycles::call(r, b)?;
    }
    if moved.is_none() && e.m140.is_some() {
        r.sync_position(b)?;
    }
    Ok(())
}

/// `M140 MB d` (retract d along the tool axis) or `MB MAX` (to the reference position, as
/// G91 G28 Z0).
fn retract(r: &mut Reader, b: &Block, mb: Option<f64>) -> LineResult<()> {
    let key = b.span(0);
    match mb {
        Some(d) => {
            r.gword("0", key.clone());
            r.word('Z', r.path.pos[Z] + d, key);
            r.end_block(b.line);
        }
        None => {
            r.gword("91", key.clone());
            r.gword("28", key.clone());
            r.word('Z', 0.0, key.clone());
            r.end_block(b.line);
            r.gword("90", key);
            r.end_block(b.line);
        }
    }
    Ok(())
}

/// An arc's centre as the interpreter reads it.
#[derive(Clone, Copy)]
pub(super) enum Centre {
    /// From the start to the centre along the plane's first and second axes.
    Offset([f64; 2], [usize; 2]),
    Radius(f64, [usize; 2]),
}

impl Centre {
    fn plane(&self) -> [usize; 2] {
        match self {
            Centre::Offset(_, p) | Centre::Radius(_, p) => *p,
        }
    }
}

/// `CC`: the pole, absolute, incremental from the position, or the position itself.
fn pole(r: &mut Reader, b: &Block) -> LineResult<()> {
    let mut t = r.path.pos;
    let mut e = Extras::default();
    let (mut d, mut rad) = (None, None);
    let mask = words(r, b, &mut t, &mut e, None, &mut d, &mut rad)?;
    // TNC 640 manual, "Circle center CC" and "Circular paths in other planes": the two
    // coordinates given name the circle's plane.
    let plane = match mask {
        0..=3 => [X, Y],
        5 => [Z, X],
        6 => [Y, Z],
        _ => return Err(LineError::new(b.span(1), format!("`{}`: expected the centre's two coordinates in one plane (X Y, X Z or Y Z; A B C are not read)", b.text[b.spans(0, b.toks.len() - 1)].trim()), "not a plane")),
    };
    if !e.plain() || e.feed.is_some() {
        return Err(LineError::new(
            b.span(1),
            "CC takes only the centre's coordinates X Y (or IX IY)",
            "unexpected word",
        ));
    }
    r.path.pole = Some([t[plane[0]], t[plane[1]]]);
    r.path.pole_plane = plane;
    Ok(())
}

/// The plane of a `CR` or `CT` from the coordinates it names: X Z or Y Z alone name
/// another plane than X Y.
fn plane_of(mask: u8) -> [usize; 2] {
    match mask & 7 {
        5 => [Z, X],
        6 => [Y, Z],
        _ => [X, Y],
    }
}

fn pole_of(r: &Reader, b: &Block) -> LineResult<[f64; 2]> {
    r.path.pole.ok_or_else(|| {
        LineError::new(
            b.span(0),
            format!("`{}` with no pole: expected a CC block before it", b.tok(0)),
            "no CC",
        )
    })
}

/// Radius and angle (deg) of `p` about `c`.
fn polar_of(c: [f64; 2], p: [f64; 2]) -> (f64, f64) {
    let d = [p[0] - c[0], p[1] - c[1]];
    (d[0].hypot(d[1]), d[1].atan2(d[0]).to_degrees())
}

/// `C`, `CR`, `CT`, `CP`: in the pole's plane (`C`, `CP`) or the plane of the coordinates
/// given (`CR`, `CT`), with the third axis of that plane as a helix's linear axis.
fn arc(r: &mut Reader, b: &Block, key: &str) -> LineResult<()> {
    let mut target = r.path.pos;
    let mut e = Extras::default();
    let mut pp = [None, None];
    let mut ccw = None;
    let mut radius = (key == "CR").then_some(0.0);
    let mask = words(
        r,
        b,
        &mut target,
        &mut e,
        (key == "CP").then_some(&mut pp),
        &mut ccw,
        &mut radius,
    )?;
    if let Some(f) = e.feed {
        r.path.feed = Some(f);
    }
    let [u, v] = match key {
        "C" | "CP" => r.path.pole_plane,
        _ => plane_of(mask),
    };
    if [u, v] != [X, Y] && (key == "CT" || r.path.comp != 0 || e.comp.is_some_and(|c| c != 0)) {
        return Err(LineError::new(b.span(0), format!("`{key}` outside the plane X Y with {}: mtsim reads circles in the planes X Z and Y Z only as C, CP and CR without radius compensation", if key == "CT" { "a tangent" } else { "radius compensation" }), "not the XY plane"));
    }
    let p = [r.path.pos[u], r.path.pos[v]];
    let need_dir = || {
        LineError::new(
            b.span(0),
            format!("`{key}` without DR+ or DR-: expected the direction of rotation"),
            "no direction",
        )
    };
    let (centre, ccw, turns) = match key {
        "C" => {
            let c = pole_of(r, b)?;
            if (p[0] - c[0]).hypot(p[1] - c[1]) < 1e-9 {
                // TNC 640 manual, "Circular path C around circle center CC": the radius
                // is the distance from CC to the start point.
                return Err(LineError::new(
                    b.span(0),
                    format!(
                        "`C` (circular path around the pole CC): the start point {}{:+} {}{:+} is on CC, so the circle has radius zero; the program expects the tool placed away from CC before it (by hand, or a position mtsim does not know)",
                        LETTERS[u], p[0], LETTERS[v], p[1]
                    ),
                    "start on CC",
                ));
            }
            (c, ccw.ok_or_else(need_dir)?, 0)
        }
        "CR" => {
            let rad = radius.filter(|v| *v != 0.0).ok_or_else(|| {
                LineError::new(
                    b.span(0),
                    "CR without R: expected the radius R+… (R-… for more than 180°)",
                    "no radius",
                )
            })?;
            let ccw = ccw.ok_or_else(need_dir)?;
            (
                radius_centre(p, [target[u], target[v]], rad, ccw).ok_or_else(|| {
                    LineError::new(
                        b.span(0),
                        format!(
                            "CR: the end point is more than 2 R = {} away",
                            2.0 * rad.abs()
                        ),
                        "radius too small",
                    )
                })?,
                ccw,
                0,
            )
        }
        "CT" => {
            let t = r.path.dir.ok_or_else(|| {
                LineError::new(
                    b.span(0),
                    "CT with no contour element before it: expected a line or arc to be tangent to",
                    "nothing to be tangent to",
                )
            })?;
            let d = [target[X] - p[0], target[Y] - p[1]];
            let n = [-t[1], t[0]];
            let dn = d[0] * n[0] + d[1] * n[1];
            if dn.abs() < 1e-12 {
                return Err(LineError::new(
                    b.span(0),
                    "CT: the end point lies on the tangent: expected a line L",
                    "straight",
                ));
            }
            let s = (d[0] * d[0] + d[1] * d[1]) / (2.0 * dn);
            ([p[0] + n[0] * s, p[1] + n[1] * s], s > 0.0, 0)
        }
        _ => {
            let c = pole_of(r, b)?;
            let ccw = ccw.ok_or_else(need_dir)?;
            let (r0, a0) = polar_of(c, p);
            let (end, turns) = match pp[1] {
                Some((v, true)) => (a0 + v, (v.abs() / 360.0 - 1e-9).floor().max(0.0) as u32),
                Some((v, false)) => (v, 0),
                None => (a0, 0),
            };
            target[u] = c[0] + r0 * end.to_radians().cos();
            target[v] = c[1] + r0 * end.to_radians().sin();
            (c, ccw, turns)
        }
    };
    if r.path.appr.is_some() {
        r.approach(b, ([u, v] == [X, Y]).then(|| tangent_at(centre, p, ccw)))?;
    }
    r.path.rapid = false;
    let g = if ccw { "3" } else { "2" };
    let plane_bits = (1u8 << u) | (1 << v);
    if turns > 0 {
        let total = pp[1].map_or(360.0, |(v, _)| v.abs());
        let helix = Helix {
            g,
            plane: [u, v],
            centre,
            turns,
            total,
            mask,
        };
        full_turns(r, b, &helix, &target)?;
    }
    let start = [r.path.pos[u], r.path.pos[v]];
    let c = match (key, radius) {
        ("CR", Some(rad)) => Centre::Radius(rad, [u, v]),
        _ => Centre::Offset([centre[0] - start[0], centre[1] - start[1]], [u, v]),
    };
    motion(r, b, g, &target, mask | plane_bits, Some(c), &e)?;
    // The tangent CT and RND/CHF follow lies in the plane X Y.
    r.path.dir = ([u, v] == [X, Y]).then(|| tangent_at(centre, [target[u], target[v]], ccw));
    r.path.pos = target;
    Ok(())
}

/// The unit tangent at `p` of a circle about `c` run counter-clockwise (`ccw`) or not.
fn tangent_at(c: [f64; 2], p: [f64; 2], ccw: bool) -> [f64; 2] {
    let rv = [p[0] - c[0], p[1] - c[1]];
    let n = rv[0].hypot(rv[1]).max(1e-300);
    if ccw {
        [-rv[1] / n, rv[0] / n]
    } else {
        [rv[1] / n, -rv[0] / n]
    }
}

/// A helix of more than one turn about `centre` in `plane`, `total` degrees in all.
struct Helix {
    g: &'static str,
    plane: [usize; 2],
    centre: [f64; 2],
    turns: u32,
    total: f64,
    mask: u8,
}

/// A helix's full turns before its last part: one block per turn, the linear axis (the
/// plane's third) in proportion to the angle turned.
fn full_turns(r: &mut Reader, b: &Block, h: &Helix, target: &[f64; 6]) -> LineResult<()> {
    let [u, v] = h.plane;
    let w = 3 - u - v;
    let w0 = r.path.pos[w];
    let mut at = [r.path.pos[u], r.path.pos[v]];
    for k in 0..h.turns {
        let mut t = r.path.pos;
        t[u] = at[0];
        t[v] = at[1];
        t[w] = w0 + (target[w] - w0) * 360.0 * f64::from(k + 1) / h.total;
        let off = Centre::Offset([h.centre[0] - at[0], h.centre[1] - at[1]], h.plane);
        let helix = if target[w] != w0 { 1 << w } else { 0 };
        let bits = (1u8 << u) | (1 << v) | (h.mask & (1 << w)) | helix;
        motion(r, b, h.g, &t, bits, Some(off), &Extras::default())?;
        r.path.pos = t;
        at = [t[u], t[v]];
    }
    Ok(())
}

/// The centre of the arc from `p` to `q` of radius `rad` (negative: more than 180°).
fn radius_centre(p: [f64; 2], q: [f64; 2], rad: f64, ccw: bool) -> Option<[f64; 2]> {
    let d = [q[0] - p[0], q[1] - p[1]];
    let chord = d[0].hypot(d[1]);
    let h2 = rad * rad - chord * chord / 4.0;
    if chord < 1e-12 || h2 < -1e-9 {
        return None;
    }
    let h = h2.max(0.0).sqrt();
    // The centre is left of the chord for a short CCW arc.
    let side = if ccw == (rad > 0.0) { 1.0 } else { -1.0 };
    let n = [-d[1] / chord, d[0] / chord];
    Some([
        p[0] + d[0] / 2.0 + side * h * n[0],
        p[1] + d[1] / 2.0 + side * h * n[1],
    ])
}

/// `RND R…` / `CHF …` after a held line.
fn corner(r: &mut Reader, b: &Block, round: bool) -> LineResult<()> {
    let Some(held) = r.path.held.take() else {
        return Err(LineError::new(b.span(0), format!("`{}` must come between two straight lines in the working plane (mtsim does not round or chamfer arcs)", b.tok(0)), "no line before"));
    };
    let mut size = None;
    let mut feed = None;
    for k in 1..b.toks.len() {
        let (name, rest) = split_word(b.tok(k));
        match name.to_ascii_uppercase().as_str() {
            "R" if round => size = Some(value(rest, &r.q, b.span(k))?),
            "" if !round => size = Some(value(rest, &r.q, b.span(k))?),
            "F" => feed = Some(value(rest, &r.q, b.span(k))?),
            _ => {
                return Err(state::unexpected(
                    b,
                    k,
                    b.tok(0),
                    if round {
                        "R and F"
                    } else {
                        "the chamfer length and F"
                    },
                ))
            }
        }
    }
    let size = size.filter(|s| *s > 0.0).ok_or_else(|| {
        LineError::new(
            b.span(0),
            format!("`{}` without a positive size", b.tok(0)),
            "no size",
        )
    })?;
    r.path.corner = Some(Corner {
        held,
        round,
        size,
        feed,
        span: b.span(0),
    });
    Ok(())
}

/// The corner between the held line and the line to `p2`: the cut line, the chamfer or
/// rounding arc, and the next line held from its start.
fn close_corner(r: &mut Reader, c: Corner, p2: [f64; 2], target: [f64; 6]) -> LineResult<()> {
    let h = c.held;
    let k = [h.end[X], h.end[Y]];
    let unit = |a: [f64; 2], b: [f64; 2]| {
        let d = [b[0] - a[0], b[1] - a[1]];
        let n = d[0].hypot(d[1]);
        ([d[0] / n, d[1] / n], n)
    };
    let (u, l1) = unit(h.start, k);
    let (v, l2) = unit(k, p2);
    let cos = (u[0] * v[0] + u[1] * v[1]).clamp(-1.0, 1.0);
    let cut = if c.round {
        c.size * (cos.acos() / 2.0).tan()
    } else {
        c.size
    };
    if !(cut < l1.min(l2) + 1e-9) || cos > 1.0 - 1e-12 || !cut.is_finite() {
        return Err(LineError::new(
            c.span,
            "RND/CHF larger than the lines beside it (or the lines are in line)",
            "corner too large",
        ));
    }
    let a = [k[0] - u[0] * cut, k[1] - u[1] * cut];
    let e = [k[0] + v[0] * cut, k[1] + v[1] * cut];
    let span = c.span.start..c.span.start;
    let mut first = h.end;
    first[X] = a[0];
    first[Y] = a[1];
    emit_line(r, &first, h.feed, h.line, &span);
    let feed = c.feed.or(r.path.feed);
    r.gword(
        if !c.round {
            "1"
        } else if u[0] * v[1] - u[1] * v[0] > 0.0 {
            "3"
        } else {
            "2"
        },
        span.clone(),
    );
    r.word('X', e[0], span.clone());
    r.word('Y', e[1], span.clone());
    if c.round {
        let left = u[0] * v[1] - u[1] * v[0] > 0.0;
        let n = if left { [-u[1], u[0]] } else { [u[1], -u[0]] };
        r.word('I', n[0] * c.size, span.clone());
        r.word('J', n[1] * c.size, span.clone());
    }
    if let Some(f) = feed {
        r.word('F', f, span.clone());
    }
    r.end_block(h.line + 1);
    r.path.held = Some(Held {
        start: e,
        end: target,
        feed: r.path.feed,
        line: h.line + 2,
    });
    r.path.dir = Some(v);
    r.path.pos = target;
    Ok(())
}

fn emit_line(r: &mut Reader, t: &[f64; 6], feed: Option<f64>, line: usize, span: &Range<usize>) {
    r.gword("1", span.clone());
    r.word('X', t[X], span.clone());
    r.word('Y', t[Y], span.clone());
    if let Some(f) = feed {
        r.word('F', f, span.clone());
    }
    r.end_block(line);
}

/// Runs the held line (before any block but a corner).
pub(super) fn release(r: &mut Reader, b: &Block) -> LineResult<()> {
    if let Some(c) = &r.path.corner {
        let _ = b;
        return Err(LineError::new(
            c.span.clone(),
            "RND or CHF must be followed by a straight line L",
            "corner not closed",
        ));
    }
    if let Some(h) = r.path.held.take() {
        emit_line(r, &h.end, h.feed, h.line, &(0..0));
    }
    Ok(())
}
