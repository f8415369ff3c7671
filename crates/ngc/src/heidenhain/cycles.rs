//! `CYCL DEF` and `CYCL CALL`: the drilling cycles 200-203, 205-207, 209 and 240 as G0/G1/G4
//! words along the tool axis, and the coordinate transformation cycles 7 (datum shift),
//! 10 (rotation) and 19 (working plane) through `frames`, 8 (mirror image), 11 (scaling)
//! and 26 (axis-specific scaling) through `transform`.
//!
//! HEIDENHAIN TNC 640 cycle programming manual, "Cycles: drilling" (200 DRILLING, 201
//! REAMING, 203 UNIVERSAL DRILLING, 205 UNIVERSAL PECKING, 207 RIGID TAPPING) and "Cycles: coordinate
//! transformations" (7, 8, 10, 11, 19, 26). With the surface s = Q203, set-up clearance a = Q200,
//! depth Q201 (< 0), plunging depth Q202, second set-up clearance Q204, a drilling cycle
//! at the current X Y runs:
//!
//! ```text
//! FMAX to s + a ─► F Q206 down one plunging depth ─► (not at depth: FMAX up to s + a,
//! dwell Q210, FMAX down to a above the depth reached, and again) ─► dwell Q211 ─►
//! retract to s + a (201: at Q208) ─► FMAX to s + Q204 when Q204 > Q200
//! ```
//!
//! 203 makes each plunge Q212 shorter down to Q205 and retracts at Q208; 205 approaches to
//! Q258 above the depth reached. 240 CENTERING and 206 TAPPING (floating holder) go to the
//! depth in one plunge (206 back at F Q206); 202 BORING and 209 TAPPING WITH CHIP BREAKING
//! are written out below.

use crate::lex::{LineError, LineResult};

use super::state::{self, Block, Reader};
use super::text::value;
use super::{frames, milling, transform};

/// `CYCL DEF …`.
pub(super) fn block(r: &mut Reader, b: &Block) -> LineResult<()> {
    if !b.is(1, "DEF") {
        return Err(state::refusal(b, 0));
    }
    let id = b.tok(2);
    let (major, minor) = id.split_once('.').unwrap_or((id, "0"));
    let major: u32 = major.parse().map_err(|_| {
        LineError::new(
            b.span(2),
            format!("`CYCL DEF {id}`: expected a cycle number"),
            "expected a number",
        )
    })?;
    let minor: u32 = minor.parse().unwrap_or(0);
    match major {
        200..=203 | 205..=209 | 240 | 251..=254 | 256 | 257 | 262..=265 | 267 => define(r, b, major),
        1 | 2 | 17 => old_cycle_value(r, b, major, minor),
        // Oriented spindle stop: the spindle turns to an angle, the axes stay.
        13 => {
            if minor == 0 {
                r.note(
                    b,
                    "cycle 13 ORIENTATION (oriented spindle stop) accepted: no axis moves",
                );
            }
            Ok(())
        }
        7 | 8 | 10 | 11 | 19 | 26 if minor == 0 => Ok(()),
        8 => transform::mirror(r, b),
        11 => transform::scaling(r, b),
        26 => transform::axis_scaling(r, b),
        7 => frames::datum_shift(r, b),
        10 => frames::rotation(r, b),
        19 => frames::working_plane(r, b, minor),
        9 if minor == 0 => Ok(()),
        9 => {
            let t = (3..b.toks.len()).find_map(|k| {
                b.tok(k)
                    .parse::<f64>()
                    .ok()
                    .or_else(|| value(b.tok(k), &r.q, b.span(k)).ok())
            });
            let t = t.ok_or_else(|| {
                LineError::new(
                    b.span(2),
                    "CYCL DEF 9.1 without a dwell time: expected `CYCL DEF 9.1 DWELL 1.5`",
                    "no time",
                )
            })?;
            r.gword("4", b.span(0));
            r.word('P', t, b.span(0));
            r.end_block(b.line);
            Ok(())
        }
        // CYCL DEF 32.1 T: the contour tolerance (mm), the planner's path tolerance as
        // LinuxCNC's G64 P; 32.1 without T: the machine's default again (G64).
        32 if minor == 1 => {
            r.gword("64", b.span(0));
            if let Some(t) = tolerance_t(r, b) {
                r.word('P', t?, b.span(0));
            }
            r.end_block(b.line);
            Ok(())
        }
        // The rest of cycle 32 (HSC mode, TA) and dynamic tuning: no motion.
        32 | 332 | 392 => Ok(()),
        247 => Err(LineError::new(
            b.spans(0, 2),
            "`CYCL DEF 247 DATUM SETTING`: the Heidenhain cycle 247 activates a preset (Q339) of the control's preset table (PRESET.PR), a file mtsim is not given (TNC 640 cycle programming manual, \"Coordinate transformation cycles\", \"Cycle 247\")",
            "preset table not given",
        )
        .help("drop the block and place the workpiece with the scenario's work offsets, or shift the datum with CYCL DEF 7")),
        _ => Err(not_supported(b, id, major)),
    }
}

/// `T0.05` (or `T 0.05`, `T+Q10`) of `CYCL DEF 32.1`: the tolerance, mm; `TA` (the rotary
/// axes' tolerance) is not it.
fn tolerance_t(r: &Reader, b: &Block) -> Option<LineResult<f64>> {
    let k = (3..b.toks.len()).find(|&k| {
        let t = b.tok(k);
        t.starts_with('T') && !t.starts_with("TA")
    })?;
    let tok = b.tok(k);
    let (text, span) = if tok.len() > 1 {
        (&tok[1..], b.span(k))
    } else {
        (b.tok(k + 1), b.span(k + 1))
    };
    Some(value(text, &r.q, span.clone()).and_then(|t| {
        if t >= 0.0 && t.is_finite() {
            Ok(t)
        } else {
            Err(LineError::new(
                span,
                format!("CYCL DEF 32.1 T{t}: expected a tolerance of 0 mm or more"),
                "negative tolerance",
            ))
        }
    }))
}

/// The refusal of cycle `major`: its number, the title the post wrote, the cycle's title
/// and its manual section.
fn not_supported(b: &Block, id: &str, major: u32) -> LineError {
    let name: Vec<&str> = (3..b.toks.len())
        .map(|k| b.tok(k))
        .take_while(|t| !t.contains('=') && !t.starts_with(';'))
        .collect();
    let name = if name.is_empty() {
        title(major).map_or(String::new(), |t| format!(" {t}"))
    } else {
        format!(" {}", name.join(" "))
    };
    let what = match title(major) {
        Some(t) => format!("the Heidenhain cycle {major} {t}"),
        None => format!("the Heidenhain cycle {major}"),
    };
    LineError::new(
        b.spans(0, 2),
        format!("`CYCL DEF {id}{name}`: {what} is not supported ({}, \"Cycle {major}\"): mtsim reads the cycles 1, 2, 17, 200-203, 205-209, 240, 251-254, 256, 257, 262-265, 267 and 7, 8, 9, 10, 11, 13, 19, 26, 32", manual(major)),
        "Heidenhain cycle not supported",
    )
    .help(if matches!(major, 220 | 221) {
        "give the points with PATTERN DEF and call the cycle with CYCL CALL PAT (or CYCL CALL POS at each point)"
    } else {
        "post the cycle as L moves, or see docs/gcode.md"
    })
}

/// The title of the cycles posts write, as the cycle manual heads them.
fn title(n: u32) -> Option<&'static str> {
    Some(match n {
        204 => "BACK BORING",
        241 => "SINGLE-LIP DEEP-HOLE DRILLING",
        220 => "POLAR PATTERN",
        221 => "CARTESIAN PATTERN",
        251 => "RECTANGULAR POCKET",
        253 => "SLOT MILLING",
        254 => "CIRCULAR SLOT",
        256 => "RECTANGULAR STUD",
        257 => "CIRCULAR STUD",
        262 => "THREAD MILLING",
        263 => "THREAD MILLING/COUNTERSINKING",
        264 => "THREAD DRILLING/MILLING",
        265 => "HELICAL THREAD DRILLING/MILLING",
        267 => "OUTSIDE THREAD MILLING",
        14 | 20..=25 | 270..=276 => "(SL contour cycle)",
        230 | 231 | 232 | 233 => "(multipass milling)",
        _ => return None,
    })
}

/// The HEIDENHAIN manual that defines cycle `n`.
fn manual(n: u32) -> &'static str {
    match n {
        1..=29 => "TNC 426/430 User's Manual, \"Fixed cycles\"",
        204 | 241 => "TNC 640 cycle programming manual, \"Cycles: drilling\"",
        220 | 221 => "TNC 640 cycle programming manual, \"Cycles: pattern definitions\"",
        251..=257 => "TNC 640 cycle programming manual, \"Cycles: pocket milling, stud milling and slot milling\"",
        262..=267 => "TNC 640 cycle programming manual, \"Cycles: tapping / thread milling\"",
        _ => "TNC 640 cycle programming manual",
    }
}

/// The cycles of the TNC 426/430 written line by line: `CYCL DEF 1.0 PECKING` (defines
/// the cycle) and `1.1 DIST 2` … `1.5 F80` (set-up clearance, depth, plunging depth, dwell,
/// feed); `2.0 TAPPING`, `2.1` … `2.4` (set-up clearance, depth, dwell, feed); `17.0
/// RIGID TAPPING`, `17.1` … `17.3` (set-up clearance, depth, pitch): the value after the
/// word, kept in line order.
fn old_cycle_value(r: &mut Reader, b: &Block, major: u32, minor: u32) -> LineResult<()> {
    let lines = match major {
        1 => 5,
        2 => 4,
        _ => 3,
    };
    if minor == 0 {
        r.cycle.number = Some(major);
        r.cycle.pecking = [0.0; 5];
        r.modal_cycle = false;
        return Ok(());
    }
    let (Some(first), Some(last)) = (b.toks.get(3), b.toks.last()) else {
        return Err(LineError::new(
            b.span(2),
            format!("`CYCL DEF {major}.{minor}` without a value"),
            "no value",
        ));
    };
    let text = &b.text[first.start..last.end];
    let at = text
        .find(|c: char| c.is_ascii_digit() || matches!(c, '+' | '-' | '.') || c == 'Q')
        .unwrap_or(text.len());
    let span = first.start + at..last.end;
    let v = value(text[at..].trim(), &r.q, span.clone())?;
    if r.cycle.number != Some(major) {
        return Err(LineError::new(
            b.spans(0, 2),
            format!("`CYCL DEF {major}.{minor}` without `CYCL DEF {major}.0` before it"),
            "cycle not defined",
        ));
    }
    match minor as usize {
        k @ 1.. if k <= lines => r.cycle.pecking[k - 1] = v,
        _ => {
            return Err(LineError::new(
                b.spans(0, 2),
                format!("`CYCL DEF {major}.{minor}`: cycle {major} has the lines {major}.1 to {major}.{lines}"),
                "no such line",
            ))
        }
    }
    Ok(())
}

/// `CYCL DEF 2xx … Q200=+2 ;… Q201=-10 …`: sets the Q parameters, remembers the cycle.
fn define(r: &mut Reader, b: &Block, n: u32) -> LineResult<()> {
    r.cycle.written.clear();
    for k in 3..b.toks.len() {
        let t = b.tok(k);
        let Some((name, v)) = t.split_once('=') else {
            continue;
        };
        if !name.starts_with(['Q', 'q']) {
            continue;
        }
        let span = b.span(k);
        let v = value(v, &r.q, span.clone())?;
        r.q.set_ref(name, v, span)?;
        if let Ok(q) = name[1..].parse::<u32>() {
            r.cycle.written.push(q);
        }
    }
    if n == 240 && r.q.q(343) != 0.0 {
        return Err(LineError::new(b.spans(0, 2), "cycle 240 CENTERING with Q343 = 1 (depth from the diameter Q344 and the tool's point angle T-ANGLE) is not supported (TNC 640 cycle programming manual, \"Cycle 240\"): expected Q343 = 0 and the depth Q201", "centering by diameter"));
    }
    r.cycle.number = Some(n);
    r.modal_cycle = false;
    Ok(())
}

/// Runs the defined cycle at the current position.
pub(super) fn call(r: &mut Reader, b: &Block) -> LineResult<()> {
    let Some(n) = r.cycle.number else {
        return Err(LineError::new(
            b.span(0),
            "cycle call with no cycle defined: expected CYCL DEF 1, 2, 17, 200-203, 205-209, 240, 251-254, 256, 257, 262-265 or 267 before it",
            "no cycle",
        ));
    };
    match n {
        1 => return pecking(r, b),
        2 | 17 => return old_tapping(r, b, n),
        208 | 251..=254 | 256 | 257 | 262..=265 | 267 => return milling::call(r, b, n),
        _ => {}
    }
    let q = |k| r.q.q(k);
    let mut p = Params {
        clearance: q(200),
        depth: q(201),
        feed: q(206),
        plunge: q(202),
        dwell_top: q(210),
        surface: q(203),
        second: q(204),
        dwell_depth: q(211),
        retract_feed: q(208),
        decrement: q(212),
        min_plunge: q(205),
    };
    let span = b.span(0);
    if n == 207 || n == 209 {
        // Rigid tapping: in and out at the pitch times the spindle speed.
        p.feed = q(239).abs() * r.spindle_rpm;
        (p.dwell_top, p.dwell_depth) = (0.0, 0.0);
    }
    if p.depth > 0.0 {
        return Err(LineError::new(span, format!("cycle {n}: depth Q201 = {} is positive: expected a negative depth (down the tool axis)", p.depth), "positive depth"));
    }
    if p.depth == 0.0 {
        return Ok(());
    }
    if p.feed <= 0.0 {
        return Err(LineError::new(
            span,
            format!(
                "cycle {n}: feed {} (Q206, or for 207 the pitch Q239 × the TOOL CALL's S): expected a positive feed",
                p.feed
            ),
            "no feed",
        ));
    }
    let plan = match n {
        209 => return tap_chip_breaking(r, b, &p),
        206 | 207 => Plan {
            plunge: -p.depth,
            decrement: 0.0,
            min: 0.0,
            approach: p.clearance,
            retract_feed: Some(p.feed),
        },
        201 => Plan {
            plunge: -p.depth,
            decrement: 0.0,
            min: 0.0,
            approach: p.clearance,
            retract_feed: Some(if p.retract_feed > 0.0 {
                p.retract_feed
            } else {
                p.feed
            }),
        },
        202 | 240 => Plan {
            plunge: -p.depth,
            decrement: 0.0,
            min: 0.0,
            approach: p.clearance,
            retract_feed: (n == 202).then_some(if p.retract_feed > 0.0 {
                p.retract_feed
            } else {
                p.feed
            }),
        },
        200 => Plan {
            plunge: p.plunge,
            decrement: 0.0,
            min: 0.0,
            approach: p.clearance,
            retract_feed: None,
        },
        203 => {
            if q(213) != 0.0 {
                return Err(LineError::new(
                    span,
                    "cycle 203 with chip breaking (Q213 > 0) is not supported: expected Q213 = 0",
                    "chip breaking",
                ));
            }
            Plan {
                plunge: p.plunge,
                decrement: p.decrement,
                min: p.min_plunge,
                approach: p.clearance,
                retract_feed: Some(if p.retract_feed > 0.0 {
                    p.retract_feed
                } else {
                    p.feed
                }),
            }
        }
        _ => {
            if q(257) != 0.0 || q(379) != 0.0 || q(258) != q(259) {
                return Err(LineError::new(span, "cycle 205 with chip breaking (Q257), a deepened start (Q379) or Q258 ≠ Q259 is not supported", "cycle 205 option"));
            }
            Plan {
                plunge: p.plunge,
                decrement: p.decrement,
                min: p.min_plunge,
                approach: q(258),
                retract_feed: None,
            }
        }
    };
    if plan.plunge <= 0.0 {
        return Err(LineError::new(
            span,
            format!(
                "cycle {n}: plunging depth Q202 = {}: expected a positive depth",
                plan.plunge
            ),
            "no plunging depth",
        ));
    }
    if n == 207 {
        r.note(b, "cycle 207 taps at F = pitch Q239 × S; the spindle reversal at the bottom is not simulated");
    }
    if n == 202 {
        return boring(r, b, &p, &plan);
    }
    drill(r, b, &p, &plan);
    r.path.set_z(
        p.surface
            + if p.second > p.clearance {
                p.second
            } else {
                p.clearance
            },
    );
    Ok(())
}

/// Cycle 202 BORING (TNC 640 cycle programming manual, "Cycle 202"): FMAX to s + a, F Q206
/// to the depth, dwell Q211, the spindle oriented to Q336, the cutting edge moved off the
/// wall by 0.2 mm as Q214 gives (1 −X, 2 −Y, 3 +X, 4 +Y; 0 stays), F Q208 (Q208 = 0: Q206)
/// up to s + a, FMAX to s + Q204 when Q204 > Q200, FMAX back over the hole's centre.
fn boring(r: &mut Reader, b: &Block, p: &Params, plan: &Plan) -> LineResult<()> {
    const DISENGAGE_MM: f64 = 0.2;
    let way = r.q.q(214);
    let off = match way as i64 {
        _ if way.fract() != 0.0 => None,
        0 => Some([0.0, 0.0]),
        1 => Some([-1.0, 0.0]),
        2 => Some([0.0, -1.0]),
        3 => Some([1.0, 0.0]),
        4 => Some([0.0, 1.0]),
        _ => None,
    };
    let Some(off) = off else {
        return Err(LineError::new(
            b.span(0),
            format!(
                "cycle 202: Q214 = {way}: expected 0-4 (the direction the tool leaves the wall)"
            ),
            "bad Q214",
        ));
    };
    let span = b.span(0);
    let unit = if r.inch { 25.4 } else { 1.0 };
    let centre = [r.path.pos[0], r.path.pos[1]];
    let xy_rapid = |r: &mut Reader, xy: [f64; 2]| {
        r.gword("0", span.clone());
        r.word('X', xy[0], span.clone());
        r.word('Y', xy[1], span.clone());
        r.end_block(b.line);
    };
    let top = p.surface + p.clearance;
    z_move(r, b, "0", top, None);
    z_move(r, b, "1", p.surface + p.depth, Some(p.feed));
    dwell(r, b, p.dwell_depth);
    let moved = off != [0.0, 0.0];
    if moved {
        let d = DISENGAGE_MM / unit;
        xy_rapid(r, [centre[0] + off[0] * d, centre[1] + off[1] * d]);
    }
    z_move(r, b, "1", top, plan.retract_feed);
    let end = second_clearance(r, b, p);
    if moved {
        xy_rapid(r, centre);
    }
    r.path.set_z(end);
    Ok(())
}

/// Cycle 209 TAPPING WITH CHIP BREAKING (TNC 640 cycle programming manual, "Cycle 209"):
/// FMAX to s + a; at F = pitch Q239 × S down by the infeed Q257 at a time (Q257 = 0: the
/// whole depth), after each infeed back by Q256 × pitch (Q256 = 0: to s + a) at F × Q403
/// and on to the next infeed depth at F; at the depth back to s + a at F × Q403, then FMAX
/// to s + Q204 when Q204 > Q200.
fn tap_chip_breaking(r: &mut Reader, b: &Block, p: &Params) -> LineResult<()> {
    let span = b.span(0);
    let infeed = r.q.q(257);
    let back = r.q.q(256) * r.q.q(239).abs();
    let factor = match r.q.q(403) {
        f if f == 0.0 => 1.0,
        f if f > 0.0 => f,
        f => {
            return Err(LineError::new(
                span,
                format!("cycle 209: RPM factor Q403 = {f}: expected a positive factor"),
                "bad Q403",
            ))
        }
    };
    if infeed < 0.0 || back < 0.0 {
        return Err(LineError::new(
            span,
            "cycle 209: Q257 and Q256 must not be negative",
            "negative infeed",
        ));
    }
    let top = p.surface + p.clearance;
    let bottom = p.surface + p.depth;
    let step = if infeed > 0.0 { infeed } else { -p.depth };
    z_move(r, b, "0", top, None);
    let mut reached = p.surface;
    loop {
        let next = (reached - step).max(bottom);
        z_move(r, b, "1", next, Some(p.feed));
        if next <= bottom {
            break;
        }
        let up = if back > 0.0 {
            (next + back).min(top)
        } else {
            top
        };
        z_move(r, b, "1", up, Some(p.feed * factor));
        reached = next;
    }
    z_move(r, b, "1", top, Some(p.feed * factor));
    let end = second_clearance(r, b, p);
    r.note(
        b,
        "cycle 209 taps at F = pitch Q239 × S; the spindle reversals are not simulated",
    );
    r.path.set_z(end);
    Ok(())
}

/// One move along the tool axis: G0 (rapid) or G1 at `f`.
fn z_move(r: &mut Reader, b: &Block, g: &'static str, z: f64, f: Option<f64>) {
    let span = b.span(0);
    r.gword(g, span.clone());
    r.word('Z', z, span.clone());
    if let Some(f) = f {
        r.word('F', f, span);
    }
    r.end_block(b.line);
}

/// A dwell of `t` s (none when `t` is 0).
fn dwell(r: &mut Reader, b: &Block, t: f64) {
    if t > 0.0 {
        r.gword("4", b.span(0));
        r.word('P', t, b.span(0));
        r.end_block(b.line);
    }
}

/// FMAX to the 2nd set-up clearance s + Q204 when it lies above s + Q200; where the
/// tool ends.
fn second_clearance(r: &mut Reader, b: &Block, p: &Params) -> f64 {
    if p.second > p.clearance {
        z_move(r, b, "0", p.surface + p.second, None);
        p.surface + p.second
    } else {
        p.surface + p.clearance
    }
}

struct Params {
    clearance: f64,
    depth: f64,
    feed: f64,
    plunge: f64,
    dwell_top: f64,
    surface: f64,
    second: f64,
    dwell_depth: f64,
    retract_feed: f64,
    decrement: f64,
    min_plunge: f64,
}

struct Plan {
    plunge: f64,
    decrement: f64,
    min: f64,
    /// Distance above the depth reached for the rapid approach of the next plunge.
    approach: f64,
    /// Retract from the bottom at this feed (rapid when None).
    retract_feed: Option<f64>,
}

fn drill(r: &mut Reader, b: &Block, p: &Params, plan: &Plan) {
    let top = p.surface + p.clearance;
    let bottom = p.surface + p.depth;
    z_move(r, b, "0", top, None);
    let mut reached = p.surface;
    let mut plunge = plan.plunge;
    loop {
        let next = (reached - plunge).max(bottom);
        if reached < p.surface {
            z_move(r, b, "0", reached + plan.approach, None);
        }
        z_move(r, b, "1", next, Some(p.feed));
        if next <= bottom {
            break;
        }
        match plan.retract_feed {
            Some(f) => z_move(r, b, "1", top, Some(f)),
            None => z_move(r, b, "0", top, None),
        }
        dwell(r, b, p.dwell_top);
        reached = next;
        plunge = (plunge - plan.decrement).max(plan.min.max(1e-3));
    }
    dwell(r, b, p.dwell_depth);
    match plan.retract_feed {
        Some(f) => z_move(r, b, "1", top, Some(f)),
        None => z_move(r, b, "0", top, None),
    }
    second_clearance(r, b, p);
}

/// Cycle 2 TAPPING (floating tap holder) and 17 RIGID TAPPING at the current position
/// (TNC 426/430 User's Manual, "TAPPING with a floating tap holder (Cycle 2)", "RIGID
/// TAPPING (Cycle 17)"): the tool stands at the set-up clearance a above the surface; it
/// feeds to the depth in one movement, dwells (cycle 2), and feeds back to where it
/// started. The feed is cycle 2's F, or cycle 17's pitch × the `TOOL CALL`'s S.
fn old_tapping(r: &mut Reader, b: &Block, n: u32) -> LineResult<()> {
    let [clearance, depth, third, fourth, _] = r.cycle.pecking;
    let (dwell, feed) = if n == 2 {
        (third, fourth)
    } else {
        (0.0, third.abs() * r.spindle_rpm)
    };
    let span = b.span(0);
    if depth > 0.0 {
        return Err(LineError::new(span, format!("cycle {n}: depth {depth} is positive: mtsim taps down the tool axis Z only (expected a negative depth)"), "positive depth"));
    }
    if depth == 0.0 {
        return Ok(());
    }
    if feed <= 0.0 {
        return Err(LineError::new(span, format!("cycle {n}: feed {feed} (cycle 2: {n}.4 F; cycle 17: the pitch {n}.3 × S): expected a positive feed"), "no feed"));
    }
    let start = r.path.pos[2];
    let p = Params {
        clearance: clearance.abs(),
        depth,
        feed,
        plunge: -depth,
        dwell_top: 0.0,
        surface: start - clearance.abs(),
        second: 0.0,
        dwell_depth: dwell,
        retract_feed: feed,
        decrement: 0.0,
        min_plunge: 0.0,
    };
    let plan = Plan {
        plunge: -depth,
        decrement: 0.0,
        min: 0.0,
        approach: 0.0,
        retract_feed: Some(feed),
    };
    r.note(b, &format!("cycle {n} taps in and out at F {feed}; the spindle reversal at the depth is not simulated"));
    drill(r, b, &p, &plan);
    r.path.set_z(start);
    Ok(())
}

/// Cycle 1 PECKING at the current position (TNC 426/430 User's Manual, "PECKING (Cycle
/// 1)"): the tool stands at the set-up clearance a above the surface, so the surface is at
/// `s = z − a`. It feeds to the first plunging depth below s, rapids back to where it
/// started, rapids down to t above the depth reached and feeds one plunging depth further,
/// until the depth; dwells; rapids back to the start. The advanced stop distance
/// `t = 0.6 mm` for a hole up to 30 mm deep, `depth / 50` beyond, at most 7 mm.
fn pecking(r: &mut Reader, b: &Block) -> LineResult<()> {
    let [clearance, depth, plunge, dwell, feed] = r.cycle.pecking;
    let span = b.span(0);
    if depth > 0.0 {
        return Err(LineError::new(span, format!("cycle 1: depth {depth} is positive: mtsim drills down the tool axis Z only (expected a negative depth)"), "positive depth"));
    }
    if depth == 0.0 {
        return Ok(());
    }
    if feed <= 0.0 || plunge <= 0.0 {
        return Err(LineError::new(span, format!("cycle 1: feed {feed} and plunging depth {plunge}: expected both positive (CYCL DEF 1.3 and 1.5)"), "no feed or plunge"));
    }
    let start = r.path.pos[2];
    let surface = start - clearance.abs();
    let t = if -depth <= 30.0 {
        0.6
    } else {
        (-depth / 50.0).min(7.0)
    };
    let p = Params {
        clearance: clearance.abs(),
        depth,
        feed,
        plunge,
        dwell_top: 0.0,
        surface,
        second: 0.0,
        dwell_depth: dwell,
        retract_feed: 0.0,
        decrement: 0.0,
        min_plunge: 0.0,
    };
    let plan = Plan {
        plunge,
        decrement: 0.0,
        min: 0.0,
        approach: t,
        retract_feed: None,
    };
    drill(r, b, &p, &plan);
    r.path.set_z(start);
    Ok(())
}
