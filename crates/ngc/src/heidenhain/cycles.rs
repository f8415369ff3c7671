//! `CYCL DEF` and `CYCL CALL`: the drilling cycles 200, 201, 203 and 205 as G0/G1/G4
//! words along the tool axis, and the coordinate transformation cycles 7 (datum shift),
//! 10 (rotation) and 19 (working plane) through `frames`.
//!
//! HEIDENHAIN TNC 640 cycle programming manual, "Cycles: drilling" (200 DRILLING, 201
//! REAMING, 203 UNIVERSAL DRILLING, 205 UNIVERSAL PECKING, 207 RIGID TAPPING) and "Cycles: coordinate
//! transformations" (7, 10, 19). With the surface s = Q203, set-up clearance a = Q200,
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
//! Q258 above the depth reached.

use crate::lex::{LineError, LineResult};

use super::frames;
use super::state::{self, Block, Reader};
use super::text::value;

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
        200 | 201 | 203 | 205 | 207 => define(r, b, major),
        1 => pecking_value(r, b, minor),
        7 | 10 | 19 if minor == 0 => Ok(()),
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
        // Tolerance and dynamic tuning: no motion.
        32 | 332 | 392 => Ok(()),
        _ => {
            let name: Vec<&str> = (3..b.toks.len())
                .map(|k| b.tok(k))
                .take_while(|t| !t.contains('='))
                .collect();
            Err(LineError::new(b.spans(0, 2), format!("the Heidenhain cycle `CYCL DEF {id}{}{}` is not supported by mtsim: it reads the drilling cycles 1, 200, 201, 203, 205, 207 and the cycles 7, 9, 10, 19, 32", if name.is_empty() { "" } else { " " }, name.join(" ")), "Heidenhain cycle not supported")
                .help("post the cycle as L moves, or see docs/gcode.md"))
        }
    }
}

/// `CYCL DEF 1.0 PECKING` (defines the cycle) and `1.1 DIST 2` … `1.5 F80` (its set-up
/// clearance, depth, plunging depth, dwell and feed): the value after the word.
fn pecking_value(r: &mut Reader, b: &Block, minor: u32) -> LineResult<()> {
    if minor == 0 {
        r.cycle.number = Some(1);
        r.cycle.pecking = [0.0; 5];
        r.modal_cycle = false;
        return Ok(());
    }
    let (Some(first), Some(last)) = (b.toks.get(3), b.toks.last()) else {
        return Err(LineError::new(
            b.span(2),
            format!("`CYCL DEF 1.{minor}` without a value"),
            "no value",
        ));
    };
    let text = &b.text[first.start..last.end];
    let at = text
        .find(|c: char| c.is_ascii_digit() || matches!(c, '+' | '-' | '.') || c == 'Q')
        .unwrap_or(text.len());
    let span = first.start + at..last.end;
    let v = value(text[at..].trim(), &r.q, span.clone())?;
    match minor {
        1..=5 => r.cycle.pecking[minor as usize - 1] = v,
        _ => {
            return Err(LineError::new(
                b.spans(0, 2),
                format!("`CYCL DEF 1.{minor}`: cycle 1 PECKING has the lines 1.1 to 1.5"),
                "no such line",
            ))
        }
    }
    Ok(())
}

/// `CYCL DEF 2xx … Q200=+2 ;… Q201=-10 …`: sets the Q parameters, remembers the cycle.
fn define(r: &mut Reader, b: &Block, n: u32) -> LineResult<()> {
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
            "cycle call with no cycle defined: expected CYCL DEF 200, 201, 203, 205 or 207 before it",
            "no cycle",
        ));
    };
    if n == 1 {
        return pecking(r, b);
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
    if n == 207 {
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
        207 => Plan {
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
    let span = b.span(0);
    let top = p.surface + p.clearance;
    let bottom = p.surface + p.depth;
    let z_move = |r: &mut Reader, g: &'static str, z: f64, f: Option<f64>| {
        r.gword(g, span.clone());
        r.word('Z', z, span.clone());
        if let Some(f) = f {
            r.word('F', f, span.clone());
        }
        r.end_block(b.line);
    };
    let dwell = |r: &mut Reader, t: f64| {
        if t > 0.0 {
            r.gword("4", span.clone());
            r.word('P', t, span.clone());
            r.end_block(b.line);
        }
    };
    z_move(r, "0", top, None);
    let mut reached = p.surface;
    let mut plunge = plan.plunge;
    loop {
        let next = (reached - plunge).max(bottom);
        if reached < p.surface {
            z_move(r, "0", reached + plan.approach, None);
        }
        z_move(r, "1", next, Some(p.feed));
        if next <= bottom {
            break;
        }
        match plan.retract_feed {
            Some(f) => z_move(r, "1", top, Some(f)),
            None => z_move(r, "0", top, None),
        }
        dwell(r, p.dwell_top);
        reached = next;
        plunge = (plunge - plan.decrement).max(plan.min.max(1e-3));
    }
    dwell(r, p.dwell_depth);
    match plan.retract_feed {
        Some(f) => z_move(r, "1", top, Some(f)),
        None => z_move(r, "0", top, None),
    }
    if p.second > p.clearance {
        z_move(r, "0", p.surface + p.second, None);
    }
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
