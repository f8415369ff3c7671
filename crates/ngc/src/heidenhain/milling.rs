//! The milling cycles posts write for holes and pockets: 208 BORE MILLING, 251 RECTANGULAR
//! POCKET and 252 CIRCULAR POCKET, as G0/G1/G2/G3 words about the position the cycle is called at (our design, from
//! the geometry the TNC 640 cycle programming manual gives, "Cycles: drilling" and "Cycles:
//! pocket milling"; the iTNC 530 manual's sections are the same).
//!
//! The tool centre runs at the tool radius ρ = (tool table diameter)/2 + `DR` inside the
//! wall; the direction is Q351: +1 climb milling, with M3 inside a bore or pocket
//! counter-clockwise (DR+, G3), −1 up-cut, clockwise (DR−, G2). With the centre c, the
//! surface s = Q203, set-up clearance a = Q200, depth Q201 (< 0):
//!
//! ```text
//! 208: FMAX to s + a ─► semicircle (radius r/2) from c to c + (r, 0) ─► helix about c,
//!      radius r = Q335/2 − ρ, Q334 down per turn, to s + Q201 ─► full circle there ─►
//!      back to c ─► FMAX to s + a, to s + Q204 when Q204 > Q200        (all at F Q206)
//!      (Q335 = 2ρ: straight down at Q206 and back at FMAX)
//! 252: FMAX to s + a ─► per level (Q202 deep, down to Q201 + Q369): F Q206 down at c,
//!      circles of radius k, 2k, … up to R = Q223/2 − Q368 − ρ (k = Q370 ρ), each reached
//!      on a line out from the one before, at F Q207, then back to c ─► walls: circle
//!      of radius Q223/2 − ρ, per finishing infeed Q338 (0: one, at Q201), at F Q385 ─►
//!      floor (Q369 > 0): circles k, 2k, … to Q223/2 − ρ at Q201 ─► FMAX to s + a, Q204
//! 251: as 252 about the pocket's centre (Q367: the call position is the centre or a
//!      corner, the centre then reached first at FMAX at s + a; Q224 turns the pocket
//!      about the call position) with rounded rectangles for circles: the wall path has
//!      half sides Q218/2 − ρ, Q219/2 − ρ and corner radius max(Q220 − ρ, 0); the
//!      clearing rectangles lie k, 2k, … inside it, innermost first, each from the middle
//!      of its +X side
//! ```
//!
//! Our simplifications, which keep every move inside the finished pocket: the tool
//! reaches each circle on a line from the centre (the TNC approaches tangentially), and the
//! clearing is concentric circles (the TNC spirals). Helical (Q366 = 1) and reciprocating
//! plunging need the tool table's plunge angle, which mtsim's tool table does not carry:
//! refused. Feed reference Q439: 0 and 1 (at the cutting edge; run at the tool centre, a
//! notice says so) mm/min, 3 mm/rev (× the `TOOL CALL`'s S); 2, per tooth, refused.

use crate::lex::{LineError, LineResult};

use super::cycle_moves::{
    arc, finishing_levels, levels, line, rapid_xy, rapid_z, rounded_rect, Geometry, MAX_PASSES,
};
use super::state::{Block, Reader};
use super::{slots, studs, threads};

/// One call of cycle `n` (208, 251-254, 256, 257, 262-265 or 267) at the current position.
pub(super) fn call(r: &mut Reader, b: &Block, n: u32) -> LineResult<()> {
    let q = |k| r.q.q(k);
    let depth = q(201);
    let err = |m: String, label: &str| Err(LineError::new(b.span(0), m, label));
    if depth > 0.0 {
        return err(
            format!("cycle {n}: depth Q201 = {depth} is positive: expected a negative depth (down the tool axis)"),
            "positive depth",
        );
    }
    if depth == 0.0 {
        // The manual: depth 0, the cycle is not run.
        return Ok(());
    }
    // 265 has no Q351: its direction is the thread's hand (`threads`).
    let ccw = match q(351) {
        _ if n == 265 => true,
        d if d == 1.0 => true,
        d if d == -1.0 => false,
        d => {
            return err(
                format!("cycle {n}: Q351 = {d}: expected +1 (climb milling) or -1 (up-cut)"),
                "bad Q351",
            )
        }
    };
    if r.path.comp != 0 {
        return err(
            format!("cycle {n} called with radius compensation RL/RR in effect: the cycle mills about the tool's centre, pre-positioned with R0 (TNC 640 cycle programming manual, \"Cycle {n}\")"),
            "radius compensation on",
        );
    }
    // Under a scaling the cycle's dimensions scale, the tool does not: its radius in the
    // program's (unscaled) coordinates is ρ / s (`transform`).
    let Some(s) = r.frames_state.map.xy_factor() else {
        return err(format!("cycle {n} under an axis-specific scaling (cycle 26) with different factors for X and Y: the cycle's arcs would be ellipses; expected equal factors"), "arc under unequal scaling");
    };
    let rho = r.comp_diameter() / 2.0 / s;
    if rho <= 0.0 {
        return err(
            format!("cycle {n} mills at the tool's radius: tool {} has no diameter in the machine's tool table", r.tool.0),
            "no tool radius",
        );
    }
    // Q439 is not among the parameters of the stud cycles' older versions: read only when
    // their block wrote it, never a value a pocket cycle left.
    let q439 = if matches!(n, 256 | 257 | 262..=267) && !r.cycle.written.contains(&439) {
        0.0
    } else {
        q(439)
    };
    let (s203, q200, q204) = (q(203), q(200), q(204));
    let per = match q439 {
        k if k == 0.0 => 1.0,
        k if k == 1.0 => {
            r.note(b, "Q439 = 1 (feed at the cutting edge): mtsim runs the cycle's feeds at the tool centre; on the cycle's circles the TNC's centre feed is lower by R/(R + tool radius)");
            1.0
        }
        k if k == 3.0 && r.spindle_rpm > 0.0 => r.spindle_rpm,
        k => {
            return err(
                format!("cycle {n}: feed reference Q439 = {k}: mtsim reads 0 and 1 (mm/min) and 3 (mm/rev, with the TOOL CALL's S); 2, a feed per tooth, needs the tool table's number of teeth CUT, which mtsim's tool table does not carry (TNC 640 cycle programming manual, \"Cycle {n}\", Q439)"),
                "feed reference",
            )
        }
    };
    let mut g = Geometry {
        c: r.path.xy(),
        s: s203,
        top: s203 + q200,
        bottom: s203 + depth,
        second: s203 + q204.max(q200),
        rho,
        ccw,
        per,
    };
    match n {
        208 => bore_milling(r, b, &g),
        251 => {
            let shape = rectangle(r, b, &mut g)?;
            pocket(r, b, &g, 251, shape)
        }
        252 => {
            let shape = Shape::Circle(r.q.q(223) / 2.0 - g.rho);
            pocket(r, b, &g, 252, shape)
        }
        253 => {
            let slot = slots::straight(r, b, &mut g)?;
            pocket(r, b, &g, 253, Shape::Slot(slot))
        }
        254 => {
            for k in 0..slots::repetitions(r, b)? {
                let slot = slots::circular(r, b, &mut g, k)?;
                pocket(r, b, &g, 254, Shape::Slot(slot))?;
            }
            Ok(())
        }
        256 | 257 => studs::stud(r, b, &mut g, n),
        _ => threads::thread(r, b, &mut g, n),
    }?;
    rapid_z(r, b, g.top);
    if g.second > g.top {
        rapid_z(r, b, g.second);
    }
    r.path.pos[0] = g.c[0];
    r.path.pos[1] = g.c[1];
    r.path.set_z(g.second);
    Ok(())
}

/// Cycle 208 BORE MILLING (TNC 640 cycle programming manual, "Cycle 208"): Q335 the bore's
/// diameter, Q334 the infeed per helix turn, Q206 the feed.
fn bore_milling(r: &mut Reader, b: &Block, g: &Geometry) -> LineResult<()> {
    let (dia, pitch, feed) = (r.q.q(335), r.q.q(334), r.q.q(206) * g.per);
    let err = |m: String, label: &str| Err(LineError::new(b.span(0), m, label));
    if feed <= 0.0 {
        return err(
            format!("cycle 208: feed Q206 = {feed}: expected a positive feed"),
            "no feed",
        );
    }
    let radius = dia / 2.0 - g.rho;
    if radius < -1e-9 {
        return err(format!("cycle 208: bore diameter Q335 = {dia} is smaller than the tool's diameter {}: expected Q335 ≥ the tool's diameter", 2.0 * g.rho), "bore smaller than the tool");
    }
    rapid_z(r, b, g.top);
    let c = g.c;
    if radius <= 1e-9 {
        // The bore is the tool's size: straight down, as the manual says.
        line(r, b, [c[0], c[1], g.bottom], feed);
        return Ok(());
    }
    let drop = g.top - g.bottom;
    if pitch <= 0.0 || drop / pitch > MAX_PASSES {
        return err(format!("cycle 208: infeed per helix Q334 = {pitch}: expected a positive infeed, at most {MAX_PASSES} turns to the depth"), "bad Q334");
    }
    let start = [c[0] + radius, c[1]];
    // Out from the centre on a semicircle in the helix's direction: tangent to it at start.
    arc(
        r,
        b,
        g.ccw,
        [start[0], start[1], g.top],
        [c[0] + radius / 2.0, c[1]],
        feed,
    );
    let turns = drop / pitch;
    let full = (turns - 1e-9).floor().max(0.0) as u64;
    let mut z = g.top;
    for _ in 0..full {
        z -= pitch;
        arc(r, b, g.ccw, [start[0], start[1], z], c, feed);
    }
    let rest = (turns - full as f64) * std::f64::consts::TAU;
    let phi = if g.ccw { rest } else { -rest };
    let end = [c[0] + radius * phi.cos(), c[1] + radius * phi.sin()];
    if rest > 1e-9 {
        arc(r, b, g.ccw, [end[0], end[1], g.bottom], c, feed);
    }
    // A full circle at the depth, then back to the centre.
    arc(r, b, g.ccw, [end[0], end[1], g.bottom], c, feed);
    line(r, b, [c[0], c[1], g.bottom], feed);
    Ok(())
}

/// Cycle 252 CIRCULAR POCKET (TNC 640 cycle programming manual, "Cycle 252"): Q215 0
/// roughing and finishing, 1 roughing, 2 finishing; Q223 the pocket's diameter, Q368 and
/// Q369 the side and floor allowances, Q202 the plunging depth, Q338 the finishing infeed,
/// Q370 the path overlap (stepover Q370 ρ), Q206 / Q207 / Q385 the plunging, milling and
/// finishing feeds.
fn pocket(r: &mut Reader, b: &Block, g: &Geometry, n: u32, shape: Shape) -> LineResult<()> {
    let q = |k| r.q.q(k);
    let err = |m: String, label: &str| Err(LineError::new(b.span(0), m, label));
    let op = q(215);
    if op != 0.0 && op != 1.0 && op != 2.0 {
        return err(
            format!("cycle {n}: Q215 = {op}: expected 0 (roughing and finishing), 1 (roughing) or 2 (finishing)"),
            "bad Q215",
        );
    }
    if q(366) != 0.0 {
        return err(format!("cycle {n} with plunging strategy Q366 = {} (helical or reciprocating): not supported, it needs the tool table's plunge angle ANGLE, which mtsim's tool table does not carry (TNC 640 cycle programming manual, \"Cycle {n}\", Q366): expected Q366 = 0 (vertical plunge)", q(366)), "plunging strategy");
    }
    let (side, floor) = (q(368).max(0.0), q(369).max(0.0));
    let (f_plunge, f_mill) = (q(206) * g.per, q(207) * g.per);
    let f_finish = if q(385) > 0.0 { q(385) * g.per } else { f_mill };
    if f_plunge <= 0.0 || f_mill <= 0.0 {
        return err(format!("cycle {n}: plunging feed Q206 = {f_plunge}, milling feed Q207 = {f_mill}: expected both positive"), "no feed");
    }
    let outer = shape.half_width();
    // A slot may be as wide as the tool (the centre line alone); a pocket may not.
    let slot = matches!(shape, Shape::Slot(_));
    if outer - side < -1e-9 || (outer - side <= 0.0 && !slot) {
        return err(format!("cycle {n}: the pocket less the side allowance Q368 = {side} is not wider than the tool (Ø{}): expected a larger pocket", 2.0 * g.rho), "pocket smaller than the tool");
    }
    // The slots have no path overlap Q370: a stepover of one tool radius.
    let overlap = if n <= 252 && q(370) > 0.0 {
        q(370)
    } else {
        1.0
    };
    let step = (overlap * g.rho).min(2.0 * g.rho);
    let (plunge, fin_infeed) = (q(202), q(338));
    if outer / step > MAX_PASSES {
        return err(
            format!("cycle {n}: path overlap Q370 = {overlap}: more than {MAX_PASSES} circles"),
            "bad Q370",
        );
    }
    rapid_z(r, b, g.top);
    let c = g.c;
    let here = r.path.xy();
    if here != c {
        // Called at a corner (251, Q367), or a slot (253, 254): over the centre (a slot's
        // start) at the set-up clearance first.
        rapid_xy(r, b, c);
    }
    if op != 2.0 {
        let Some(zs) = levels(g.s, g.bottom + floor, plunge) else {
            return err(format!("cycle {n}: plunging depth Q202 = {plunge}: expected a positive depth, at most {MAX_PASSES} levels"), "bad Q202");
        };
        for z in zs {
            line(r, b, [c[0], c[1], z], f_plunge);
            shape.rings(r, b, g, z, side, step, f_mill);
        }
    }
    let finishing = op == 2.0 || (op == 0.0 && (side > 0.0 || floor > 0.0));
    if finishing {
        let zs = finishing_levels(b, g, n, fin_infeed)?;
        for z in zs {
            line(r, b, [c[0], c[1], z], f_plunge);
            shape.rings(r, b, g, z, 0.0, 2.0 * outer, f_finish);
        }
        if op == 2.0 || floor > 0.0 {
            shape.rings(r, b, g, g.bottom, 0.0, step, f_finish);
        }
    }
    Ok(())
}

/// A pocket's wall as the tool centre runs along it (no allowance): a circle of radius
/// Q223/2 − ρ, a rectangle of half sides `a` (along the pocket's X), `b`, corner radius
/// `corner`, turned by `rot_deg` about the centre, or a slot (253, 254).
enum Shape {
    Circle(f64),
    Slot(slots::Slot),
    Rect {
        a: f64,
        b: f64,
        corner: f64,
        rot_deg: f64,
    },
}

impl Shape {
    /// Half the narrowest width of the tool centre's area.
    fn half_width(&self) -> f64 {
        match *self {
            Shape::Circle(radius) => radius,
            Shape::Rect { a, b, .. } => a.min(b),
            Shape::Slot(ref s) => s.half,
        }
    }

    /// The clearing at `z` of the area `allow` inside the wall path, at stepover `step`,
    /// from the centre out and back to the centre.
    fn rings(
        &self,
        r: &mut Reader,
        b: &Block,
        g: &Geometry,
        z: f64,
        allow: f64,
        step: f64,
        f: f64,
    ) {
        match *self {
            Shape::Circle(radius) => rings(r, b, g, z, radius - allow, step, f),
            Shape::Slot(ref s) => s.rings(r, b, z, s.half - allow, step, f),
            Shape::Rect {
                a,
                b: half_b,
                corner,
                rot_deg,
            } => {
                let (a, hb) = (a - allow, half_b - allow);
                let corner = (corner - allow).max(0.0);
                let rot = rot_deg.to_radians();
                let world = |u: f64, v: f64| {
                    let (s, c) = rot.sin_cos();
                    [g.c[0] + c * u - s * v, g.c[1] + s * u + c * v]
                };
                let m = a.min(hb);
                let last = ((m - 1e-9) / step).floor().max(0.0) as u64;
                for j in (0..=last).rev() {
                    let d = j as f64 * step;
                    rounded_rect(
                        r,
                        b,
                        g,
                        z,
                        [a - d, hb - d, (corner - d).max(0.0)],
                        &world,
                        f,
                    );
                }
                line(r, b, [g.c[0], g.c[1], z], f);
            }
        }
    }
}

/// Cycle 251 RECTANGULAR POCKET (TNC 640 cycle programming manual, "Cycle 251"): Q218
/// and Q219 the sides along X and Y, Q220 the corner radius, Q224 the rotation about the
/// call position, Q367 where the call position lies (0 the centre, 1 the lower left, 2 the
/// lower right, 3 the upper right, 4 the upper left corner). Moves `g.c` to the centre.
fn rectangle(r: &mut Reader, b: &Block, g: &mut Geometry) -> LineResult<Shape> {
    let q = |k| r.q.q(k);
    let (len, wid, rot_deg) = (q(218), q(219), q(224));
    let at = match q(367) {
        p if p == 0.0 => [0.0, 0.0],
        p if p == 1.0 => [1.0, 1.0],
        p if p == 2.0 => [-1.0, 1.0],
        p if p == 3.0 => [-1.0, -1.0],
        p if p == 4.0 => [1.0, -1.0],
        p => {
            return Err(LineError::new(
                b.span(0),
                format!(
                    "cycle 251: pocket position Q367 = {p}: expected 0 (centre) or 1-4 (a corner)"
                ),
                "bad Q367",
            ))
        }
    };
    let (u, v) = (at[0] * len / 2.0, at[1] * wid / 2.0);
    let (s, c) = rot_deg.to_radians().sin_cos();
    g.c = [g.c[0] + c * u - s * v, g.c[1] + s * u + c * v];
    let corner = q(220).max(g.rho) - g.rho;
    Ok(Shape::Rect {
        a: len / 2.0 - g.rho,
        b: wid / 2.0 - g.rho,
        corner: corner.min(len.min(wid) / 2.0 - g.rho).max(0.0),
        rot_deg,
    })
}

/// At height `z` from the centre: circles of radius `step`, 2 `step`, … and `max` last,
/// each reached on a line out from the one before; then back to the centre.
fn rings(r: &mut Reader, b: &Block, g: &Geometry, z: f64, max: f64, step: f64, f: f64) {
    let c = g.c;
    let mut radius = 0.0;
    while radius < max - 1e-9 {
        radius = (radius + step).min(max);
        let p = [c[0] + radius, c[1], z];
        line(r, b, p, f);
        arc(r, b, g.ccw, p, c, f);
    }
    line(r, b, [c[0], c[1], z], f);
}
