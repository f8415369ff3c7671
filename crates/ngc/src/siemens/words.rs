//! A block of words (Fundamentals, "Motion commands", "Feedrate", "Tool offsets"): G and
//! M codes, axis words `X10`/`X=expr`/`X=AC(..)`/`X=IC(..)`, centres `I J K`, `CR=`,
//! `F S T D`, and assignments `R1=..`/`NAME=..`, collected and then written as one ISO
//! block in Fanuc's codes.
//!
//! Without a programmable frame and without `AC`/`IC`, the words go to the interpreter as
//! written (in the program's G90/G91). Otherwise every target is resolved here: the frame
//! point `q` (current point `A⁻¹(p - o)`, the given coordinates absolute, incremental or
//! modal) becomes the work point `o + A q`, written under G90; a centre `c` (incremental
//! from the start unless `AC`) becomes `o + A c - p`; `CR=r` becomes `R s·r` with `s` the
//! frame's scale in the plane; a mirroring frame turns G2 into G3 and back.

use super::expr::{expr, r_parameter, Scan};
use super::state::Var;
use super::Reader;
use crate::lex::{LineError, LineResult};

/// How a coordinate is given.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Mode {
    /// In the block's G90/G91.
    Modal,
    /// `=AC(..)`.
    Absolute,
    /// `=IC(..)`.
    Incremental,
}

/// One coordinate: value (program units or deg), how it is given, the text as written
/// when it is a plain number, and the span of its word in the source line.
#[derive(Clone, Debug)]
pub(super) struct Coordinate {
    pub value: f64,
    pub mode: Mode,
    pub raw: Option<std::ops::Range<usize>>,
    pub span: std::ops::Range<usize>,
}

impl Coordinate {
    /// The coordinate `c` from `from` (its value where the block has none): absolute as
    /// written (`=AC(..)`, or plain under G90), else an increment (`=IC(..)`, plain under G91).
    pub(super) fn resolve(c: &Option<Coordinate>, from: f64, absolute: bool) -> f64 {
        match c {
            None => from,
            Some(c) => match c.mode {
                Mode::Absolute => c.value,
                Mode::Incremental => from + c.value,
                Mode::Modal if absolute => c.value,
                Mode::Modal => from + c.value,
            },
        }
    }
}

/// The axis letters, in the order of `Axis::ALL`, then the centres.
const AXES: &[u8; 9] = b"XYZABCUVW";
const CENTRES: &[u8; 3] = b"IJK";

/// The words of one block, as collected.
#[derive(Default)]
pub(super) struct Words {
    pub axes: [Option<Coordinate>; 9],
    pub centres: [Option<Coordinate>; 3],
    /// CIP's intermediate point `I1= J1= K1=`.
    pub cip: [Option<Coordinate>; 3],
    /// The tool's direction vector `A3= B3= C3=` (orientation.rs).
    pub orientation: [Option<Coordinate>; 3],
    /// `G75 FP=n X1=0 …` (fixed_point.rs).
    pub fixed_point: Option<FixedPoint>,
    /// `AP=`, `RP=` (polar angle and radius) as given, and a pole code G110-G112.
    pub polar: [Option<Coordinate>; 2],
    pub pole: Option<(u32, std::ops::Range<usize>)>,
    /// `TURN=n`: full turns of a helix.
    pub turn: Option<(u32, std::ops::Range<usize>)>,
    pub cr: Option<(f64, std::ops::Range<usize>)>,
    /// `AR=` (an arc's opening angle) and `ANG=` (a line's angle), deg (contour.rs).
    pub ar: Option<Coordinate>,
    pub ang: Option<Coordinate>,
    /// `CHF= CHR= RND= RNDM=` (corner.rs).
    pub corner: Option<super::state::CornerWord>,
    /// G0-G3 given in the block.
    pub motion: Option<u8>,
    pub dwell: Option<std::ops::Range<usize>>,
    pub feed: Option<(f64, std::ops::Range<usize>)>,
    /// ISO words other than axes, centres, motion and distance: text and source span.
    pub other: Vec<(String, std::ops::Range<usize>)>,
    /// A second ISO block to run before this one (TRAORI, a D0 under TCP ...).
    pub before: Vec<String>,
    /// ISO blocks to run after this one (G64 after a G9 block).
    pub after: Vec<String>,
    /// `M17`/`RET`: return after the block; `M30`/`M2`: the interpreter ends.
    pub ret: bool,
    /// A subprogram call: name, arguments, span (the repeats are `repeats`).
    pub call: Option<(String, Vec<f64>, std::ops::Range<usize>)>,
    pub repeats: Option<u64>,
}

/// A G75 in the block being read (fixed_point.rs).
#[derive(Default)]
pub(super) struct FixedPoint {
    /// The span of `G75`.
    pub span: std::ops::Range<usize>,
    /// `FP=n` and its span.
    pub number: Option<(f64, std::ops::Range<usize>)>,
    /// The axes named, as the ISO reader's letters.
    pub axes: Vec<char>,
}

impl Words {
    pub fn has_motion_words(&self) -> bool {
        self.axes.iter().any(Option::is_some)
            || self.centres.iter().any(Option::is_some)
            || self.cip.iter().any(Option::is_some)
            || self.polar.iter().any(Option::is_some)
            || self.cr.is_some()
            || self.ar.is_some()
            || self.ang.is_some()
    }
}

impl Reader {
    /// Collects the words of the block at `sc` into `w`.
    pub(super) fn collect(
        &mut self,
        sc: &mut Scan,
        w: &mut Words,
        line_no: usize,
    ) -> LineResult<()> {
        while !sc.done() {
            let at = sc.at;
            let c = sc.s[at];
            let next = sc.s.get(at + 1).copied();
            let number_follows =
                next.is_some_and(|n| n.is_ascii_digit() || matches!(n, b'.' | b'-' | b'+'));
            // `A3=`, `I1=`: a Sinumerik name with digits (orientation, CIP point), not a word.
            let digits_then_equals = c != b'R' && {
                let mut k = at + 1;
                while sc.s.get(k).is_some_and(u8::is_ascii_digit) {
                    k += 1;
                }
                k > at + 1 && sc.s.get(k) == Some(&b'=')
            };
            if c.is_ascii_uppercase()
                && (number_follows || next == Some(b'='))
                && is_address(c)
                && !digits_then_equals
            {
                self.address(sc, w, line_no)?;
                continue;
            }
            let Some((name, at)) = sc.ident() else {
                return Err(sc.err(at, "expected a word (a letter and a number, such as `X10`), an assignment or a statement", "unexpected character"));
            };
            self.named(name, at, sc, w, line_no)?;
        }
        Ok(())
    }

    /// The named words of the path's geometry: `CT`, `CIP` (motion codes), `TURN=`,
    /// `AP=`, `RP=`, `I1= J1= K1=`.
    pub(super) fn geometry_word(
        &mut self,
        name: &str,
        at: usize,
        sc: &mut Scan,
        w: &mut Words,
    ) -> LineResult<()> {
        match name {
            "CT" => w.motion = Some(super::state::CT),
            "CIP" => w.motion = Some(super::state::CIP),
            "TURN" => return self.turn_word(at, sc, w),
            "AP" | "RP" => return self.polar_word(usize::from(name == "RP"), at, sc, w),
            _ => {
                let k = usize::from(name.as_bytes()[0].saturating_sub(b'I')).min(2);
                return self.cip_point(k, at, sc, w);
            }
        }
        Ok(())
    }

    /// `AP=` (k = 0) or `RP=` (k = 1), the cursor after the name.
    pub(super) fn polar_word(
        &mut self,
        k: usize,
        at: usize,
        sc: &mut Scan,
        w: &mut Words,
    ) -> LineResult<()> {
        let c = self.assigned(
            sc,
            at,
            "expected `AP=angle` or `RP=radius`",
            "polar coordinate",
        )?;
        put(&mut w.polar[k], c, sc, at)
    }

    /// `=value` after a name at `at` (the cursor after the name), as a coordinate; `expected`
    /// and `label` make the error where `=` is missing.
    pub(super) fn assigned(
        &mut self,
        sc: &mut Scan,
        at: usize,
        expected: &str,
        label: &'static str,
    ) -> LineResult<Coordinate> {
        if !sc.eat(b'=') {
            return Err(sc.err(at, expected, label));
        }
        let (value, mode) = self.value(sc)?;
        Ok(Coordinate {
            value,
            mode,
            raw: None,
            span: at..sc.at,
        })
    }

    /// `I1=`, `J1=`, `K1=` (CIP's intermediate point; the cursor after the name).
    pub(super) fn cip_point(
        &mut self,
        k: usize,
        at: usize,
        sc: &mut Scan,
        w: &mut Words,
    ) -> LineResult<()> {
        let c = self.assigned(
            sc,
            at,
            "expected `I1=value` (CIP's intermediate point)",
            "CIP point",
        )?;
        put(&mut w.cip[k], c, sc, at)
    }

    /// A single-letter address with a number or `=expr`: `G1`, `X-5`, `X=AC(R1)`, `R1=..`.
    fn address(&mut self, sc: &mut Scan, w: &mut Words, line_no: usize) -> LineResult<()> {
        let at = sc.at;
        let letter = sc.s[at];
        sc.at += 1;
        // R parameters: `R1=expr`, `R[k]=expr` is read below with the named words.
        if letter == b'R' {
            sc.at = at;
            let (name, _) = sc.ident().unwrap_or(("", at));
            let Some(Some(k)) = r_parameter(name) else {
                return Err(sc.err(at, "expected an R parameter `R<n>=value`", "R parameter"));
            };
            return self.assign(sc, Var::R(k as usize), at);
        }
        if letter == b'T' && sc.s[sc.at..].starts_with(b"=\"") {
            sc.at += 1;
            return self.named_tool(sc, w, at, line_no);
        }
        let (value, mode, raw) = if sc.eat(b'=') {
            let (v, m) = self.value(sc)?;
            (v, m, None)
        } else {
            let from = sc.at;
            let neg = sc.eat(b'-');
            if !neg {
                sc.eat(b'+');
            }
            let Some((_, v)) = sc.number() else {
                return Err(sc.err(
                    at,
                    format!("`{}`: expected a number after the address", letter as char),
                    "expected a number",
                ));
            };
            (if neg { -v } else { v }, Mode::Modal, Some(from..sc.at))
        };
        let span = at..sc.at;
        let coordinate = |raw| Coordinate {
            value,
            mode,
            raw,
            span: span.clone(),
        };
        if let Some(k) = AXES.iter().position(|&a| a == letter) {
            return put(&mut w.axes[k], coordinate(raw), sc, at);
        }
        if let Some(k) = CENTRES.iter().position(|&a| a == letter) {
            return put(&mut w.centres[k], coordinate(raw), sc, at);
        }
        if mode != Mode::Modal {
            return Err(sc.err(
                at,
                format!(
                    "AC()/IC() on `{}`: expected them on axes and centres only",
                    letter as char
                ),
                "AC/IC not allowed",
            ));
        }
        let text = |raw: &Option<std::ops::Range<usize>>| match raw {
            Some(r) => std::str::from_utf8(&sc.s[r.clone()])
                .unwrap_or("0")
                .to_string(),
            None => number(value),
        };
        match letter {
            b'G' => self.g_code(value, span, w, sc),
            b'M' => self.m_code(value, span, w, sc, line_no),
            b'F' => {
                w.feed = Some((value, span));
                Ok(())
            }
            b'S' | b'T' => {
                let t = format!("{}{}", letter as char, text(&raw));
                if letter == b'T' {
                    self.tool = whole(value, sc, at)? as u32;
                }
                w.other.push((t, span));
                Ok(())
            }
            b'D' => self.d_number(whole(value, sc, at)?, span, w),
            b'L' => {
                let name = format!("L{}", text(&raw));
                w.call = Some((name, Vec::new(), span));
                Ok(())
            }
            b'P' => {
                w.repeats = Some(whole(value, sc, at)?.max(1));
                Ok(())
            }
            b'N' => Ok(()),
            b'H' => {
                self.notice(
                    line_no,
                    format!(
                        "auxiliary function H{} accepted and not simulated",
                        text(&raw)
                    ),
                );
                Ok(())
            }
            _ => Err(sc.err(
                at,
                format!(
                    "address `{}` is not supported by mtsim's Siemens reader",
                    letter as char
                ),
                "unsupported address",
            )),
        }
    }

    /// `T="name"`: a tool called by name, numbered 1001, 1002 ... in order of first call.
    fn named_tool(
        &mut self,
        sc: &mut Scan,
        w: &mut Words,
        at: usize,
        line_no: usize,
    ) -> LineResult<()> {
        sc.eat(b'"');
        let from = sc.at;
        while sc.s.get(sc.at).is_some_and(|c| *c != b'"') {
            sc.at += 1;
        }
        let name = String::from_utf8_lossy(&sc.s[from..sc.at]).into_owned();
        if !sc.eat(b'"') {
            return Err(sc.err(at, "expected `\"` to close the tool name", "unclosed name"));
        }
        let k = match self.tool_names.iter().position(|n| *n == name) {
            Some(k) => k,
            None if self.tool_names.len() < 10_000 => {
                self.tool_names.push(name.clone());
                self.tool_names.len() - 1
            }
            None => return Err(sc.err(at, "more than 10000 tool names", "too many tools")),
        };
        self.tool = 1001 + k as u32;
        self.notice(
            line_no,
            format!(
                "tool \"{name}\" called by name: simulated as tool T{}",
                self.tool
            ),
        );
        w.other.push((format!("T{}", self.tool), at..sc.at));
        Ok(())
    }

    /// `expr`, `AC(expr)` or `IC(expr)` after an `=`.
    pub(super) fn value(&mut self, sc: &mut Scan) -> LineResult<(f64, Mode)> {
        let save = sc.at;
        for (k, mode) in [("AC", Mode::Absolute), ("IC", Mode::Incremental)] {
            if sc.keyword(k) && sc.eat(b'(') {
                let v = expr(sc, &self.vars)?;
                if !sc.eat(b')') {
                    return Err(sc.err(save, format!("expected `)` to close `{k}(`"), "unclosed"));
                }
                return Ok((v, mode));
            }
            sc.at = save;
        }
        Ok((expr(sc, &self.vars)?, Mode::Modal))
    }

    /// `var = expr`.
    pub(super) fn assign(&mut self, sc: &mut Scan, var: Var, at: usize) -> LineResult<()> {
        if !sc.eat(b'=') {
            return Err(sc.err(at, "expected `=` and a value", "expected `=`"));
        }
        let v = expr(sc, &self.vars)?;
        self.set(var, v, sc, at)
    }

    pub(super) fn set(&mut self, var: Var, v: f64, sc: &Scan, at: usize) -> LineResult<()> {
        match var {
            Var::R(k) if k < self.vars.r.len() => self.vars.r[k] = v,
            Var::R(_) => {
                return Err(sc.err(
                    at,
                    format!(
                        "R parameter out of range: expected R0 to R{}",
                        self.vars.r.len() - 1
                    ),
                    "no such R parameter",
                ))
            }
            Var::Named(n) => {
                let level = self.vars.levels.last_mut().expect("a variable level");
                match level.get_mut(&n) {
                    Some(slot) => *slot = v,
                    None => return Err(super::expr::undefined(sc, at, &n)),
                }
            }
        }
        Ok(())
    }

    /// A G code, translated to Fanuc's (or refused by name).
    fn g_code(
        &mut self,
        value: f64,
        span: std::ops::Range<usize>,
        w: &mut Words,
        sc: &Scan,
    ) -> LineResult<()> {
        let code = if value >= 0.0 && value.fract() == 0.0 && value < 1000.0 {
            value as u32
        } else {
            u32::MAX
        };
        let iso: &str = match code {
            0..=3 => {
                w.motion = Some(code as u8);
                return Ok(());
            }
            4 => {
                w.dwell = Some(span);
                return Ok(());
            }
            90 | 91 => {
                self.absolute = code == 90;
                return Ok(());
            }
            17..=19 => {
                // Written by `emit` (a frame may stand an arc's plane up).
                self.normal = (19 - code) as usize;
                return Ok(());
            }
            40 => "G40",
            41 => "G41",
            42 => "G42",
            53 | 153 => "G53",
            54..=57 => {
                self.select_settable(code as usize - 53);
                ["G54", "G55", "G56", "G57"][code as usize - 54]
            }
            500 => {
                self.select_settable(0);
                "G54.1 P96"
            }
            505..=599 => {
                self.select_settable(code as usize - 500);
                w.other.push((format!("G54.1 P{}", code - 504), span));
                return Ok(());
            }
            60 => {
                self.exact_stop = true;
                "G61"
            }
            64 | 641..=645 => {
                self.exact_stop = false;
                w.other.push((self.continuous_path(), span));
                return Ok(());
            }
            // Exact stop for this block only: G61 now, G64 again after it.
            9 => {
                if !self.exact_stop {
                    w.other.push(("G61".into(), span));
                    w.after.push(self.continuous_path());
                }
                return Ok(());
            }
            // G70/G71 switch the geometry's unit, G700/G710 the feed's too: under G70 F
            // stays in mm/min (a metric basic system), so it is written in inch/min.
            70 | 700 => {
                self.feed_in_mm = code == 70;
                "G20"
            }
            71 | 710 => {
                self.feed_in_mm = false;
                "G21"
            }
            75 => {
                w.fixed_point = Some(FixedPoint {
                    span,
                    ..Default::default()
                });
                return Ok(());
            }
            74 => {
                return Err(LineError::new(span, "`G74` (reference point approach: the axes go to the reference point the homing sets) is not supported: mtsim's machine file gives no home position", "reference point approach").help("approach a fixed point with `G75 FP=1 …` (the machine file's g28_mm)"));
            }
            93 => "G93",
            94 => "G94",
            95 => "G95",
            // Exact stop non-modal, exact-stop windows, corner behaviour, speed limits:
            // no effect on the path mtsim reads.
            450 | 451 | 601 | 602 | 603 | 97 => return Ok(()),
            110..=112 => {
                w.pole = Some((code, span));
                return Ok(());
            }
            _ => {
                let text = std::str::from_utf8(&sc.s[span.clone()]).unwrap_or("G");
                return Err(LineError::new(span, format!("`{text}` is not supported by mtsim's Siemens reader (docs/gcode.md lists the Sinumerik G codes it reads)"), "unsupported G code"));
            }
        };
        w.other.push((iso.to_string(), span));
        Ok(())
    }

    /// An M code: the ISO ones passed on, M17 a return, machine functions noted.
    fn m_code(
        &mut self,
        value: f64,
        span: std::ops::Range<usize>,
        w: &mut Words,
        sc: &Scan,
        line_no: usize,
    ) -> LineResult<()> {
        let code = whole(value, sc, span.start)? as u32;
        match code {
            17 => w.ret = true,
            0 | 1 | 2 | 30 | 3 | 4 | 5 | 6 | 7 | 8 | 9 | 19 => w.other.push((format!("M{code}"), span)),
            98 | 99 => return Err(LineError::new(span, format!("M{code} is an ISO-mode (G291) code: expected Sinumerik calls (`L10`, a program name) and M17/RET"), "ISO-mode M code")),
            c if self.user_m.contains(&c) || (100..=199).contains(&c) => w.other.push((format!("M{code}"), span)),
            _ => self.notice(line_no, format!("machine function M{code} accepted and not simulated")),
        }
        Ok(())
    }

    /// `D n`: the tool's length compensation on (`G43`, or kept under TCP), `D0` off.
    fn d_number(&mut self, d: u64, span: std::ops::Range<usize>, w: &mut Words) -> LineResult<()> {
        let on = d > 0;
        if on != self.d_active || on {
            if on && !self.tcp {
                w.other.push(("G43".to_string(), span));
            } else if !on {
                w.before.push("G49".to_string());
                if self.tcp {
                    w.before.push("G43.4".to_string());
                }
            }
        }
        self.d_active = on;
        Ok(())
    }
}

pub(super) fn put(
    slot: &mut Option<Coordinate>,
    c: Coordinate,
    sc: &Scan,
    at: usize,
) -> LineResult<()> {
    if slot.is_some() {
        return Err(sc.err(
            at,
            "repeated word: expected each address at most once per block",
            "repeated word",
        ));
    }
    *slot = Some(c);
    Ok(())
}

/// Addresses read with a number or `=`.
fn is_address(c: u8) -> bool {
    b"GMXYZABCUVWIJKFSTDLPNHR".contains(&c)
}

/// `v` as a non-negative whole number.
pub(super) fn whole(v: f64, sc: &Scan, at: usize) -> LineResult<u64> {
    if v >= 0.0 && v.fract() == 0.0 && v < 1e12 {
        Ok(v as u64)
    } else {
        Err(sc.err(at, "expected a whole number", "not a whole number"))
    }
}

/// `v` written for the ISO block: the shortest text that reads back as `v`.
pub(super) fn number(v: f64) -> String {
    if v == 0.0 {
        "0".to_string()
    } else {
        format!("{v}")
    }
}
