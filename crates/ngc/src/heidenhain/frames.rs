//! The datum shift (cycle 7), rotation (cycle 10), tilted working plane (cycle 19 and
//! `PLANE`) and TCP (`M128`, `FUNCTION TCPM`) as the interpreter's G52, G68.2/G53.1/G69 and
//! G43.4/G49.
//!
//! HEIDENHAIN TNC 640 Klartext programming manual, "Multiple-axis machining: the PLANE
//! function" (SPATIAL, PROJECTED, EULER, VECTOR, POINTS, RELATIV, RESET; MOVE, TURN, STAY;
//! SEQ) and "M128 / FUNCTION TCPM"; cycle programming manual, "Coordinate
//! transformations" (7 DATUM SHIFT, 10 ROTATION, 19 WORKING PLANE). The working plane is the
//! rotation R whose columns are the tilted X Y Z in the work frame:
//!
//! ```text
//! SPATIAL  R = Rz(SPC) Ry(SPB) Rx(SPA)       (about the fixed axes A, then B, then C)
//! EULER    R = Rz(EULPR) Rx(EULNU) Rz(EULROT)
//! VECTOR   Z = N/|N|, X = (B - (B·Z) Z)/|…|, Y = Z × X
//! POINTS   X = (P2 - P1)/|…|, Z = X × (P3 - P1)/|…|, Y = Z × X
//! PROJECTED  the plane holds Ry(PROPR)·x̂ and Rx(PROMIN)·ŷ; X the first; then Rz(ROT)
//! RELATIV  R ← R · Rx|Ry|Rz(angle)
//! ```
//!
//! A program point p is at `d + R Rz(rot) p` in work coordinates (d the datum shift): the
//! interpreter's G68.2 with origin d and the ZXZ Euler angles of `R Rz(rot)`. Without a
//! tilt or rotation the shift is G52 (with `DL` of the tool call on Z); with one, `DL`
//! moves the origin along the plane's tool axis, d + DL R ẑ (KP "Tool length compensation":
//! the length acts in the tool axis, in the tilted plane the tilted one).

use crate::frame::{mul, rot_x, rot_y, rot_z, Mat3, IDENTITY};
use crate::lex::{LineError, LineResult};

use super::state::{self, Block, Reader};
use super::text::{split_word, value};

/// Emits the words that make the interpreter's frame the front end's.
pub(super) fn apply(r: &mut Reader, b: &Block) -> LineResult<()> {
    let span = b.span(0);
    let f = &r.frames_state;
    let rotated = f.plane.is_some() || f.rot_deg != 0.0;
    let (d, dl, tilted, shifted) = (f.datum, f.dl, f.tilted, f.shifted);
    let flip = f.map.flips_xy();
    if tilted {
        r.gword("69", span.clone());
        r.end_block(b.line);
    }
    if rotated {
        if shifted {
            g52(r, b, [0.0; 3]);
        }
        // Under a mirror of one of X Y the rotation turns the other way (`transform`).
        let sign = if flip { -1.0 } else { 1.0 };
        let m = mul(
            &r.frames_state.plane.unwrap_or(IDENTITY),
            &rot_z(sign * r.frames_state.rot_deg),
        );
        // DL along the tilted tool axis (the plane's Z, m's third column): the TNC
        // compensates the length in the tool axis of the working plane.
        let d = [
            d[0] + m[0][2] * dl,
            d[1] + m[1][2] * dl,
            d[2] + m[2][2] * dl,
        ];
        let (i, j, k) = euler_zxz(&m);
        r.gword("68.2", span.clone());
        for (l, v) in [
            ('X', d[0]),
            ('Y', d[1]),
            ('Z', d[2]),
            ('I', i),
            ('J', j),
            ('K', k),
        ] {
            r.word(l, v, span.clone());
        }
        r.end_block(b.line);
        r.frames_state.shifted = false;
    } else {
        g52(r, b, [d[0], d[1], d[2] + dl]);
        r.frames_state.shifted = d != [0.0; 3] || dl != 0.0;
    }
    r.frames_state.tilted = rotated;
    r.sync_position(b)
}

fn g52(r: &mut Reader, b: &Block, d: [f64; 3]) {
    let span = b.span(0);
    r.gword("52", span.clone());
    for (l, v) in ['X', 'Y', 'Z'].into_iter().zip(d) {
        r.word(l, v, span.clone());
    }
    r.end_block(b.line);
}

/// ZXZ Euler angles (deg) of `m = Rz(i) Rx(j) Rz(k)`.
fn euler_zxz(m: &Mat3) -> (f64, f64, f64) {
    let j = m[2][2].clamp(-1.0, 1.0).acos();
    if j.sin().abs() < 1e-12 {
        // About Z alone (j = 0) or flipped (j = 180°): i carries the turn.
        return (m[1][0].atan2(m[0][0]).to_degrees(), j.to_degrees(), 0.0);
    }
    (
        m[0][2].atan2(-m[1][2]).to_degrees(),
        j.to_degrees(),
        m[2][0].atan2(m[2][1]).to_degrees(),
    )
}

/// `CYCL DEF 7.1 X+…` (7.2 Y, 7.3 Z; `IX` incremental).
pub(super) fn datum_shift(r: &mut Reader, b: &Block) -> LineResult<()> {
    for (name, v, span) in axis_words(r, b)? {
        let (inc, axis) = match name.strip_prefix('I') {
            Some(a) => (true, a.to_string()),
            None => (false, name.clone()),
        };
        let k = ["X", "Y", "Z"]
            .iter()
            .position(|a| *a == axis)
            .ok_or_else(|| {
                LineError::new(
                    span,
                    format!("`{name}` in a datum shift: expected X, Y or Z (IX, IY, IZ)"),
                    "not X Y Z",
                )
            })?;
        let d = &mut r.frames_state.datum[k];
        *d = if inc { *d + v } else { v };
    }
    apply(r, b)
}

/// `CYCL DEF 10.1 ROT+30` (`IROT` incremental).
pub(super) fn rotation(r: &mut Reader, b: &Block) -> LineResult<()> {
    for (name, v, span) in axis_words(r, b)? {
        match name.as_str() {
            "ROT" => r.frames_state.rot_deg = v,
            "IROT" => r.frames_state.rot_deg += v,
            _ => {
                return Err(LineError::new(
                    span,
                    format!("`{name}` in a rotation: expected ROT or IROT"),
                    "not ROT",
                ))
            }
        }
    }
    apply(r, b)
}

/// `CYCL DEF 19.1 A+… B+… C+…`: the working plane by spatial angles (no positioning).
pub(super) fn working_plane(r: &mut Reader, b: &Block, minor: u32) -> LineResult<()> {
    if minor != 1 {
        return Ok(());
    }
    let mut abc = [0.0; 3];
    for (name, v, span) in axis_words(r, b)? {
        match name.as_str() {
            "A" => abc[0] = v,
            "B" => abc[1] = v,
            "C" => abc[2] = v,
            "F" | "DIST" | "ABST" => {}
            _ => {
                return Err(LineError::new(
                    span,
                    format!("`{name}` in cycle 19: expected A, B, C (spatial angles)"),
                    "not A B C",
                ))
            }
        }
    }
    r.frames_state.plane = (abc != [0.0; 3]).then(|| spatial(abc));
    apply(r, b)
}

fn spatial(abc: [f64; 3]) -> Mat3 {
    mul(&rot_z(abc[2]), &mul(&rot_y(abc[1]), &rot_x(abc[0])))
}

/// A 3-vector's unit.
fn unit(v: [f64; 3]) -> Option<[f64; 3]> {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    (n > 1e-12).then(|| [v[0] / n, v[1] / n, v[2] / n])
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The rotation whose columns are `x` and `z` (unit, orthogonal) and `z × x`.
fn from_axes(x: [f64; 3], z: [f64; 3]) -> Mat3 {
    let y = cross(z, x);
    [[x[0], y[0], z[0]], [x[1], y[1], z[1]], [x[2], y[2], z[2]]]
}

/// `PLANE …`: the working plane, then its positioning (MOVE, TURN, STAY).
pub(super) fn plane(r: &mut Reader, b: &Block) -> LineResult<()> {
    let kind = b.tok(1).to_ascii_uppercase();
    let mut v = std::collections::HashMap::new();
    let mut how = None;
    let mut seq_minus = false;
    for k in 2..b.toks.len() {
        let t = b.tok(k);
        let (name, rest) = split_word(t);
        let name = name.to_ascii_uppercase();
        match name.as_str() {
            "MOVE" | "TURN" | "STAY" => how = Some(name.clone()),
            // SYM± (the TNC 640's choice of solution by the master axis's symmetry point)
            // as SEQ±: the negative one is refused when the plane is tilted.
            "SEQ" | "SYM" => seq_minus = rest.starts_with('-'),
            "TABLE" | "COORD" | "ROT" if rest.is_empty() => {}
            "DIST" | "ABST" | "F" | "FMAX" | "MB" | "MAX" => {}
            _ if !rest.is_empty() => {
                v.insert(name.clone(), value(rest, &r.q, b.span(k))?);
            }
            _ => {
                return Err(state::unexpected(
                    b,
                    k,
                    "PLANE",
                    "the plane's angles or coordinates, then MOVE, TURN or STAY",
                ))
            }
        }
    }
    let g = |n: &str| v.get(n).copied().unwrap_or(0.0);
    let f = &mut r.frames_state;
    let bad = |what: &str| LineError::new(b.span(1), format!("PLANE {kind}: {what}"), "bad plane");
    match kind.as_str() {
        "RESET" => f.plane = None,
        "SPATIAL" => f.plane = Some(spatial([g("SPA"), g("SPB"), g("SPC")])),
        "EULER" => f.plane = Some(crate::frame::euler_zxz(g("EULPR"), g("EULNU"), g("EULROT"))),
        "VECTOR" => {
            let z = unit([g("NX"), g("NY"), g("NZ")])
                .ok_or_else(|| bad("the normal vector N is zero"))?;
            let bv = [g("BX"), g("BY"), g("BZ")];
            let dot = bv[0] * z[0] + bv[1] * z[1] + bv[2] * z[2];
            let x = unit([bv[0] - dot * z[0], bv[1] - dot * z[1], bv[2] - dot * z[2]])
                .ok_or_else(|| bad("the base vector B is parallel to N"))?;
            f.plane = Some(from_axes(x, z));
        }
        "POINTS" => {
            let p = |n: u8| {
                [
                    g(&format!("P{n}X")),
                    g(&format!("P{n}Y")),
                    g(&format!("P{n}Z")),
                ]
            };
            let (p1, p2, p3) = (p(1), p(2), p(3));
            let x = unit([p2[0] - p1[0], p2[1] - p1[1], p2[2] - p1[2]])
                .ok_or_else(|| bad("P1 and P2 are the same point"))?;
            let z = unit(cross(x, [p3[0] - p1[0], p3[1] - p1[1], p3[2] - p1[2]]))
                .ok_or_else(|| bad("the three points are in line"))?;
            f.plane = Some(from_axes(x, z));
        }
        "PROJECTED" => {
            let u = [
                g("PROPR").to_radians().cos(),
                0.0,
                -g("PROPR").to_radians().sin(),
            ];
            let w = [
                0.0,
                g("PROMIN").to_radians().cos(),
                g("PROMIN").to_radians().sin(),
            ];
            let z = unit(cross(u, w)).ok_or_else(|| bad("the projection angles give no plane"))?;
            f.plane = Some(mul(&from_axes(u, z), &rot_z(g("ROT"))));
        }
        "RELATIV" => {
            let turn = if v.contains_key("SPA") {
                rot_x(g("SPA"))
            } else if v.contains_key("SPB") {
                rot_y(g("SPB"))
            } else {
                rot_z(g("SPC"))
            };
            f.plane = Some(mul(&f.plane.unwrap_or(IDENTITY), &turn));
        }
        "AXIAL" => return Err(LineError::new(b.spans(0, 1), "`PLANE AXIAL`: the working plane given by the rotary axes' angles (KP \"PLANE AXIAL\") is not supported: mtsim tilts the plane from its spatial angles", "PLANE AXIAL").help("post the plane as PLANE SPATIAL (or CYCL DEF 19) with TURN, or move the rotary axes with L blocks")),
        _ => return Err(state::refusal(b, 0)),
    }
    let how = how.ok_or_else(|| {
        LineError::new(
            b.span(1),
            format!("PLANE {kind} without MOVE, TURN or STAY: expected how the rotary axes move"),
            "no positioning",
        )
    })?;
    apply(r, b)?;
    if how == "STAY" {
        return stay_angles(r, b, kind == "RESET");
    }
    // The rotaries TURN positions: the table's tilt and C, or a kinematic chain's.
    let rotaries = match r.table {
        Some(table) => vec![table.tilt, crate::axis::Axis::C],
        None if !r.chain_rotaries.is_empty() => r.chain_rotaries.clone(),
        None => return Err(LineError::new(b.spans(0, b.toks.len() - 1), format!("PLANE … {how} on a machine with no rotary table mtsim can position (table-table AC or BC, or a kinematic chain with two rotaries): expected STAY, with the rotary axes moved by L blocks"), "no rotary table")
            .help("use STAY, or a table-table five-axis machine")),
    };
    if how == "MOVE" {
        r.note(
            b,
            "PLANE … MOVE positions the rotary axes as TURN does (no compensating linear move)",
        );
    }
    if kind == "RESET" {
        let span = b.span(0);
        r.gword("0", span.clone());
        for axis in rotaries {
            r.word(axis.letter(), 0.0, span.clone());
        }
        r.end_block(b.line);
        return r.sync_position(b);
    }
    let m = r.frames_state.plane.unwrap_or(IDENTITY);
    if seq_minus && m[2][2] < 1.0 - 1e-12 {
        return Err(LineError::new(b.span(1), "SEQ- (the negative tilt solution) is not supported: mtsim turns to the solution with a positive tilt", "SEQ-").help("use SEQ+ or leave SEQ out"));
    }
    r.gword("53.1", b.span(0));
    r.end_block(b.line);
    r.sync_position(b)
}

/// `PLANE … STAY`: the rotary axes stay; the angles that would put the tool normal to the
/// plane go to Q120 (A), Q121 (B), Q122 (C), which posts then move to with `L A+Q120
/// C+Q122` (KP "Automatic positioning: MOVE/TURN/STAY"). On a table-table machine, as
/// G53.1 would turn it (`RESET`: 0); without a table the three have no value, and a block
/// that reads one is refused (the angles are the caller's inverse kinematics, which the
/// front end does not run).
fn stay_angles(r: &mut Reader, b: &Block, reset: bool) -> LineResult<()> {
    let Some(table) = r.table else {
        for n in 120..=122 {
            r.q.unknown(n);
        }
        return Ok(());
    };
    let (tilt, c) = if reset {
        (0.0, 0.0)
    } else {
        let m = r.frames_state.plane.unwrap_or(IDENTITY);
        table.align([m[0][2], m[1][2], m[2][2]], r.path.pos[5])
    };
    let span = b.span(0);
    let tilt_q = if table.tilt == crate::axis::Axis::B {
        "Q121"
    } else {
        "Q120"
    };
    r.q.set_ref(tilt_q, tilt, span.clone())?;
    r.q.set_ref("Q122", c, span)
}

/// `FUNCTION MODE MILL` (the milling mode a mill is in: a notice), `FUNCTION TCPM …` (TCP
/// on) and `FUNCTION RESET TCPM` (off).
pub(super) fn function(r: &mut Reader, b: &Block) -> LineResult<()> {
    if b.is(1, "MODE") {
        if b.is(2, "MILL") {
            r.note(b, "FUNCTION MODE MILL: milling mode, as mtsim always runs");
            return Ok(());
        }
        return Err(LineError::new(b.spans(0, b.toks.len() - 1), format!("`FUNCTION MODE {}`: a mill-turn control's switch to turning (KP \"Switching between milling and turning mode\") is not supported: mtsim simulates milling", b.tok(2)), "turning mode"));
    }
    if b.is(1, "TCPM") {
        tcp(r, b, true);
    } else if b.is(1, "RESET") && b.is(2, "TCPM") {
        tcp(r, b, false);
    } else {
        return Err(state::refusal(b, 0));
    }
    r.sync_position(b)
}

/// TCP on (G43.4 with the tool's length) or off (G49, then G43 again).
pub(super) fn tcp(r: &mut Reader, b: &Block, on: bool) {
    let span = b.span(0);
    let tool = r.tool.0;
    if on {
        r.gword("43.4", span.clone());
        r.word('H', tool as f64, span);
        r.end_block(b.line);
        return;
    }
    r.gword("49", span.clone());
    r.end_block(b.line);
    if tool > 0 {
        r.gword("43", span.clone());
        r.word('H', tool as f64, span);
        r.end_block(b.line);
    }
}

/// Words of a `CYCL DEF 7.x`/`10.x`/`19.x` line after the cycle number: (letters, value).
pub(super) fn axis_words(
    r: &Reader,
    b: &Block,
) -> LineResult<Vec<(String, f64, std::ops::Range<usize>)>> {
    let mut out = Vec::new();
    for k in 3..b.toks.len() {
        let t = b.tok(k);
        if t.starts_with('#') {
            return Err(LineError::new(
                b.span(k),
                format!("`{t}`: datum tables are not supported: expected the shift as X+… Y+… Z+…"),
                "datum table",
            ));
        }
        let (name, rest) = split_word(t);
        if rest.is_empty() {
            continue;
        }
        out.push((
            name.to_ascii_uppercase(),
            value(rest, &r.q, b.span(k))?,
            b.span(k),
        ));
    }
    Ok(out)
}
