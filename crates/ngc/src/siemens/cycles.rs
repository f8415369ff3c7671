//! Drilling cycles `CYCLE81` to `CYCLE89` as steps at the drilling position, called once
//! or modally (`MCALL`); `CYCLE800` (swivel plane), `CYCLE832` (high-speed settings); and
//! subprogram calls (`L10 P3`, a program called by name).
//!
//! CYCLE81(RTP, RFP, SDIS, DP, DPR) and CYCLE82(.., DTB) (Siemens, "Cycles" programming
//! manual, "Drilling, centering - CYCLE81", "Drilling, counterboring - CYCLE82"): from the
//! drilling position, G0 to the reference plane brought forward by the safety distance
//! (`RFP + SDIS` on the tool axis), G1 at the programmed feed to the depth (`RFP - |DPR|`
//! when DPR is not 0, else `DP`: a left-out value is 0 on the control), dwell DTB s
//! (CYCLE82), G0 to the retraction plane RTP. CYCLE83 is in `deep_hole.rs`, CYCLE86-88 in
//! `boring.rs`; each cycle is a list of steps (`state::CycleStep`) run here.

use std::path::PathBuf;

use super::boring::boring_steps;
use super::deep_hole::{deep_hole_steps, Planes};
use super::expr::{expr, Scan};
use super::source::Source;
use super::state::{Cycle, CycleFeed, CycleStep};
use super::words::number;
use super::{Level, Reader};
use crate::axis::Axis;
use crate::frame::{apply, mul, rot_x, rot_y, rot_z, Mat3};
use crate::lex::{LineError, LineResult};

impl Reader {
    /// `CYCLE8x(..)` among the words of a block: run now.
    pub(super) fn cycle_word(
        &mut self,
        name: &str,
        at: usize,
        sc: &mut Scan,
        line_no: usize,
    ) -> LineResult<()> {
        if name == "CYCLE800" {
            let args = self.arguments(sc, at)?;
            self.iso.clear();
            self.push("G69", at..sc.at);
            self.run_iso(line_no)?;
            if args.iter().any(Option::is_some) {
                self.swivel(&args, at..sc.at, line_no)?;
            }
            return Ok(());
        }
        if name == "CYCLE832" {
            // `CYCLE832(_TOL, _TOLM, ..)`: the tolerance the path may leave the contour by,
            // which the planner blends corners within (as G64 P); the machining type
            // (`_FINISH`, `_ORI_ROUGH` … macros of the control's cycle definitions) and the
            // compressor's settings are not simulated. `CYCLE832()` or a tolerance of 0
            // deselects it.
            let open = sc.at;
            super::block::skip_call(sc, at)?;
            let args = std::str::from_utf8(&sc.s[open..sc.at]).unwrap_or("");
            let first = args
                .trim_start_matches('(')
                .split([',', ')'])
                .next()
                .unwrap_or("");
            self.path_tolerance_mm = first
                .trim()
                .parse::<f64>()
                .ok()
                .filter(|t| *t > 0.0 && t.is_finite());
            if !self.exact_stop {
                self.iso.clear();
                let g64 = self.continuous_path();
                self.push(&g64, at..sc.at);
                self.run_iso(line_no)?;
            }
            self.notice(
                line_no,
                "CYCLE832: its tolerance bounds the corners' blending (as G64 P); the machining type and the compressor's settings are not simulated".into(),
            );
            return Ok(());
        }
        let cycle = self.cycle(name, at, sc)?;
        self.run_cycle(Some(cycle), line_no)
    }

    /// The ISO words of continuous-path mode: G64, with CYCLE832's tolerance as P.
    pub(super) fn continuous_path(&self) -> String {
        match self.path_tolerance_mm {
            Some(t) => format!("G64 P{t}"),
            None => "G64".to_string(),
        }
    }

    /// `CYCLE800(_FR, _TC, _ST, _MODE, _X0, _Y0, _Z0, _A, _B, _C, _X1, _Y1, _Z1, _DIR, ..)`
    /// in mode 57 (axis by axis: about X by A, then the new Y by B, then the newest Z by
    /// C) as a new swivel plane (`_ST` units digit 0): the interpreter's tilted plane
    /// G68.2 with `R = Rx(A) Ry(B) Rz(C)` and origin `X0 + R X1` (the zero point before,
    /// then after the rotation), written as its Euler angles Z-X-Z; `_DIR` ≠ 0 turns the
    /// rotary axes to it (G53.1, which needs the machine's rotary table).
    fn swivel(
        &mut self,
        a: &[Option<f64>],
        span: std::ops::Range<usize>,
        line_no: usize,
    ) -> LineResult<()> {
        let get = |k: usize| a.get(k).copied().flatten().unwrap_or(0.0);
        let (st, mode) = (get(2), get(3));
        if mode != 57.0 || st.rem_euclid(10.0) != 0.0 {
            return Err(LineError::new(span, format!("CYCLE800 swivel mode {mode} with _ST {st}: mtsim reads mode 57 (axis by axis X, Y, Z) as a new plane (_ST units digit 0), and CYCLE800() to reset"), "CYCLE800 swivel mode"));
        }
        let r = mul(&mul(&rot_x(get(7)), &rot_y(get(8))), &rot_z(get(9)));
        let x1 = apply(&r, [get(10), get(11), get(12)]);
        let origin = [get(4) + x1[0], get(5) + x1[1], get(6) + x1[2]];
        let [i, j, k] = euler_zxz_angles(&r);
        self.push(
            &format!(
                "G68.2 X{} Y{} Z{} I{} J{} K{}",
                number(origin[0]),
                number(origin[1]),
                number(origin[2]),
                number(i),
                number(j),
                number(k)
            ),
            span.clone(),
        );
        self.run_iso(line_no)?;
        if get(13) != 0.0 {
            self.push("G53.1", span);
            self.run_iso(line_no)?;
        }
        Ok(())
    }

    /// Reads the cycle `name`'s values (its parentheses follow) into its steps.
    pub(super) fn cycle(&mut self, name: &str, at: usize, sc: &mut Scan) -> LineResult<Cycle> {
        let span = at..sc.at;
        if !matches!(
            name,
            "CYCLE81"
                | "CYCLE82"
                | "CYCLE83"
                | "CYCLE84"
                | "CYCLE85"
                | "CYCLE86"
                | "CYCLE87"
                | "CYCLE88"
                | "CYCLE89"
        ) {
            return Err(LineError::new(span, format!("`{name}` ({}) is not supported by mtsim's Siemens reader: it reads the drilling, tapping and boring cycles CYCLE81 to CYCLE89", cycle_kind(name)), "unsupported cycle"));
        }
        let a = self.arguments(sc, at)?;
        let get = |k: usize| a.get(k).copied().flatten();
        if let Some(m) = operate_modes_refused(name, &a) {
            return Err(sc.err(at, m, "cycle values"));
        }
        let (Some(retract), Some(reference)) = (get(0), get(1)) else {
            return Err(sc.err(
                at,
                format!("{name} without RTP and RFP: expected {name}(RTP, RFP, SDIS, DP, DPR, ..)"),
                "cycle values",
            ));
        };
        // DPR acts when it is not 0 (a left-out value of a cycle is 0 on the control),
        // else DP.
        let depth = match (get(4).filter(|v| *v != 0.0), get(3)) {
            (Some(dpr), _) => reference - dpr.abs(),
            (None, Some(dp)) => dp,
            (None, None) => {
                return Err(sc.err(
                    at,
                    format!("{name} without DP or DPR: expected a drilling depth"),
                    "no depth",
                ))
            }
        };
        let planes = Planes {
            retract,
            reference,
            approach: reference + get(2).unwrap_or(0.0).abs(),
            depth,
        };
        let steps = match name {
            "CYCLE83" => deep_hole_steps(&a, planes, self.normal),
            "CYCLE86" | "CYCLE87" | "CYCLE88" => boring_steps(name, &a, planes),
            _ => simple_steps(name, &a, planes),
        }
        .map_err(|m| sc.err(at, m, "cycle values"))?;
        Ok(Cycle { steps })
    }

    /// `( v, , v ...)`: each value, `None` where left out.
    pub(super) fn arguments(&mut self, sc: &mut Scan, at: usize) -> LineResult<Vec<Option<f64>>> {
        let mut out = Vec::new();
        if !sc.eat(b'(') {
            return Ok(out);
        }
        if sc.eat(b')') {
            return Ok(out);
        }
        loop {
            if matches!(sc.peek(), Some(b',' | b')')) {
                out.push(None);
            } else if sc.peek() == Some(b'"') {
                // A string value (a plane name): skipped.
                sc.at += 1;
                while sc.s.get(sc.at).is_some_and(|c| *c != b'"') {
                    sc.at += 1;
                }
                sc.at += 1;
                out.push(None);
            } else {
                out.push(Some(expr(sc, &self.vars)?));
            }
            if out.len() > 64 {
                return Err(sc.err(at, "more than 64 values in a call", "call"));
            }
            if sc.eat(b')') {
                return Ok(out);
            }
            if !sc.eat(b',') {
                return Err(sc.err(
                    at,
                    "expected `,` or `)` in the cycle's values",
                    "cycle values",
                ));
            }
        }
    }

    /// Runs `cycle` (or the modal call) at the current position, along the tool axis.
    pub(super) fn run_cycle(&mut self, cycle: Option<Cycle>, line_no: usize) -> LineResult<()> {
        let Some(c) = cycle.or_else(|| self.modal_call.clone()) else {
            return Ok(());
        };
        let p = self.interp.program_position();
        let here = self.frame.frame_point([p[Axis::X], p[Axis::Y], p[Axis::Z]]);
        let axis = self.normal;
        // The plane's first and second axes: G17 X Y, G18 Z X, G19 Y Z.
        let [first, second] = [(axis + 1) % 3, (axis + 2) % 3];
        let programmed = self.interp.programmed_feed();
        // The programmed F is written again once a step has fed at a feed of its own.
        let mut own_feed = false;
        for step in c.steps {
            match step {
                CycleStep::Dwell(s) => self.push(&format!("G4 X{}", number(s)), 0..0),
                CycleStep::M(code) => {
                    if code == 0 {
                        self.notice(line_no, "a boring cycle's program stop (M0): mtsim runs on as the control does after NC start; what the operator does by hand in the stop is not simulated".into());
                    }
                    self.push(&format!("M{code}"), 0..0);
                }
                CycleStep::Move { level, aside, feed } => {
                    let mut q = here;
                    q[axis] = level;
                    q[first] += aside[0];
                    q[second] += aside[1];
                    let t = self.frame.work_point(q);
                    let rate = match (feed, programmed) {
                        (Some(CycleFeed::Rate(f)), _) => Some(f),
                        (Some(CycleFeed::Factor(k)), Some(f)) => Some(k * f),
                        (Some(_), Some(f)) if own_feed => Some(f),
                        _ => None,
                    };
                    own_feed |= matches!(feed, Some(CycleFeed::Rate(_) | CycleFeed::Factor(_)));
                    let f = rate.map_or(String::new(), |f| format!(" F{}", number(f)));
                    let motion = u8::from(feed.is_some());
                    self.push(
                        &format!(
                            "G90 G{motion} X{} Y{} Z{}{f}",
                            number(t[0]),
                            number(t[1]),
                            number(t[2])
                        ),
                        0..0,
                    );
                    self.interp_absolute = true;
                    self.interp_motion = motion;
                }
            }
            self.run_iso(line_no)?;
        }
        if let (Some(f), true) = (programmed, own_feed) {
            self.push(&format!("F{}", number(f)), 0..0);
            self.run_iso(line_no)?;
        }
        Ok(())
    }

    /// Calls subprogram `name` (`L10`, or a program name), `repeats` times.
    pub(super) fn call(
        &mut self,
        name: &str,
        args: Vec<f64>,
        repeats: u64,
        span: std::ops::Range<usize>,
    ) -> LineResult<()> {
        if self.levels.len() > self.max_depth {
            return Err(LineError::new(
                span,
                format!("subprograms nested deeper than {}", self.max_depth),
                "too deep",
            ));
        }
        // Every run of the subprogram executes at least one block.
        self.budget.check_passes(
            repeats.saturating_sub(1),
            "this subprogram call",
            span.clone(),
        )?;
        let Some(path) = self.find_program(name) else {
            return Err(LineError::new(span, format!("`{name}` is neither a Sinumerik keyword mtsim reads nor a subprogram it finds ({name}.SPF or {name}.MPF beside the program or on the search path)"), "unknown name or subprogram"));
        };
        let site = (self.line_start.0, self.line_start.1, span.clone());
        self.repeating = Some((self.levels.len() - 1, site));
        let text = crate::side_file::read_side_file(&path).map_err(|e| {
            LineError::new(
                span.clone(),
                format!("subprogram {}: {e}", path.display()),
                "unreadable subprogram",
            )
        })?;
        self.levels.push(Level {
            source: Source::Text(text.into()),
            path,
            offset: 0,
            line: 1,
            start: (0, 1),
            repeats: repeats.saturating_sub(1),
            structures: Vec::new(),
            opened: Vec::new(),
            sections: Vec::new(),
            args,
        });
        self.vars.levels.push(Default::default());
        Ok(())
    }

    fn find_program(&self, name: &str) -> Option<PathBuf> {
        let names = [
            format!("{name}.SPF"),
            format!("{name}.spf"),
            format!("{name}.MPF"),
            format!("{name}.mpf"),
            format!("{}.spf", name.to_ascii_lowercase()),
            format!("{}.mpf", name.to_ascii_lowercase()),
        ];
        self.search_path
            .iter()
            .flat_map(|d| names.iter().map(move |n| d.join(n)))
            .find(|p| p.is_file())
    }
}

/// The steps of CYCLE81, 82, 84, 85 and 89 (module doc): G0 to RFP + SDIS, in to the
/// depth (CYCLE84 at pitch × SST, CYCLE85 at FFR, the others at F), the dwell DTB (not
/// CYCLE81), out at the cycle's feed (CYCLE84 pitch × SST1, CYCLE85 RFF, CYCLE89 F), G0 to
/// RTP.
fn simple_steps(name: &str, a: &[Option<f64>], p: Planes) -> Result<Vec<CycleStep>, String> {
    let get = |k: usize| a.get(k).copied().flatten();
    let (feed_in, feed_out) = match name {
        // CYCLE85(.., DTB, FFR, RFF): in at FFR, out at RFF.
        "CYCLE85" => {
            let (Some(ffr), Some(rff)) = (get(6), get(7)) else {
                return Err("CYCLE85 without FFR and RFF: expected CYCLE85(RTP, RFP, SDIS, DP, DPR, DTB, FFR, RFF)".into());
            };
            (CycleFeed::Rate(ffr), Some(CycleFeed::Rate(rff)))
        }
        // CYCLE89(.., DTB): in and out at the programmed F.
        "CYCLE89" => (CycleFeed::Programmed, Some(CycleFeed::Programmed)),
        // CYCLE84(.., DTB, SDAC, MPIT, PIT, POSS, SST, SST1): in at SST, out at SST1,
        // one pitch a turn.
        "CYCLE84" => {
            let pitch = match (get(8), get(7)) {
                (Some(p), _) if p != 0.0 => p.abs(),
                (_, Some(m)) => metric_coarse_pitch(m).ok_or_else(|| format!("CYCLE84 MPIT {m}: expected a metric thread size 3-48 (M3-M48) or the pitch PIT"))?,
                _ => return Err("CYCLE84 without MPIT or PIT: expected the thread's size or pitch".into()),
            };
            let Some(sst) = get(10).filter(|v| *v > 0.0) else {
                return Err("CYCLE84 without SST: expected the tapping speed (rev/min)".into());
            };
            let sst1 = get(11).filter(|v| *v > 0.0).unwrap_or(sst);
            (
                CycleFeed::Rate(pitch * sst),
                Some(CycleFeed::Rate(pitch * sst1)),
            )
        }
        _ => (CycleFeed::Programmed, None),
    };
    let at = |level: f64, feed: Option<CycleFeed>| CycleStep::Move {
        level,
        aside: [0.0; 2],
        feed,
    };
    let mut steps = vec![at(p.approach, None), at(p.depth, Some(feed_in))];
    let dwell = if name == "CYCLE81" {
        0.0
    } else {
        get(5).unwrap_or(0.0)
    };
    if dwell > 0.0 {
        steps.push(CycleStep::Dwell(dwell));
    }
    if feed_out.is_some() {
        steps.push(at(p.approach, feed_out));
    }
    steps.push(at(p.retract, None));
    Ok(steps)
}

/// The refusal of the later (SINUMERIK Operate) arguments of drilling cycle `name` that
/// change what its values mean, when one is not 0: `_GMODE` (geometry mode) and `_AMODE`
/// (alternative mode: its digits switch depths between absolute and incremental, dwells
/// between seconds and revolutions ...), the last three values with `_DMODE` (display
/// only, not read) between them; and CYCLE84's `_AXN` (tool axis), `_PTAB` (pitch unit
/// other than the program's or mm) and `_VARI` (deep-hole tapping with pecks).
fn operate_modes_refused(name: &str, a: &[Option<f64>]) -> Option<String> {
    let gmode = match name {
        "CYCLE81" => 5,
        "CYCLE82" | "CYCLE87" | "CYCLE89" => 6,
        "CYCLE88" => 7,
        "CYCLE85" => 8,
        "CYCLE86" => 11,
        "CYCLE83" => 17,
        "CYCLE84" => 21,
        _ => return None,
    };
    let zero = |k: usize| a.get(k).copied().flatten().unwrap_or(0.0);
    let mut checks = vec![
        (gmode, "_GMODE", "the geometry mode"),
        (
            gmode + 2,
            "_AMODE",
            "the alternative mode, whose digits change how depths and dwells are read",
        ),
    ];
    if name == "CYCLE84" {
        checks.extend([
            (
                12,
                "_AXN",
                "the tool axis; mtsim taps along the plane's normal",
            ),
            (15, "_VARI", "deep-hole tapping with pecks"),
        ]);
        if zero(13) > 1.0 {
            return Some(format!("CYCLE84 _PTAB {}: a thread pitch in TPI or inch is not read by mtsim; expected 0 (the program's unit) or 1 (mm)", zero(13)));
        }
    }
    checks.into_iter().find(|(k, _, _)| zero(*k) != 0.0).map(|(k, what, means)| {
        format!("{name} {what} {}: {means} (a SINUMERIK Operate cycle argument) is not read by mtsim; expected 0 or nothing", zero(k))
    })
}

/// The Z-X-Z Euler angles (deg) of rotation `r = Rz(i) Rx(j) Rz(k)`: `cos j = r₂₂`,
/// `i = atan2(r₀₂, -r₁₂)`, `k = atan2(r₂₀, r₂₁)`; when `sin j = 0`, `k = 0` and
/// `i = atan2(r₁₀, r₀₀)`.
fn euler_zxz_angles(r: &Mat3) -> [f64; 3] {
    let j = r[2][2].clamp(-1.0, 1.0).acos();
    if j.sin().abs() < 1e-12 {
        return [r[1][0].atan2(r[0][0]).to_degrees(), j.to_degrees(), 0.0];
    }
    [
        r[0][2].atan2(-r[1][2]).to_degrees(),
        j.to_degrees(),
        r[2][0].atan2(r[2][1]).to_degrees(),
    ]
}

/// What a standard cycle the reader refuses is, with its section of the SINUMERIK 840D sl
/// "Cycles" (milling) programming manual.
fn cycle_kind(name: &str) -> &'static str {
    if let Some((_, what)) = super::patterns::UNREAD_CYCLES
        .iter()
        .find(|(n, _)| *n == name)
    {
        return what;
    }
    match name {
        "CYCLE840" => "tapping with a compensating chuck; Cycles, \"Tapping with compensating chuck (CYCLE840)\"",
        "CYCLE71" => "face milling; Cycles, \"Face milling (CYCLE71)\"",
        "CYCLE72" => "contour milling; Cycles, \"Contour milling (CYCLE72)\"",
        "CYCLE76" | "CYCLE77" => "spigot milling; Cycles, \"Rectangular/circular spigot milling (CYCLE76, CYCLE77)\"",
        "CYCLE61" => "face milling; Cycles, \"Face milling (CYCLE61)\"",
        "CYCLE62" | "CYCLE63" | "CYCLE64" => "contour pocket milling; Cycles, \"Contour milling\"",
        "CYCLE78" => "drill thread milling; Cycles, \"Drill thread milling (CYCLE78)\"",
        "CYCLE90" => "thread milling; Cycles, \"Thread milling (CYCLE90)\"",
        "CYCLE899" => "open slot milling; Cycles, \"Open slot (CYCLE899)\"",
        n if n.starts_with("CYCLE9") => "a measuring cycle; Measuring cycles manual",
        _ => "a standard or machine-builder cycle; SINUMERIK Cycles manual",
    }
}

/// The coarse pitch (mm) of metric thread `M size` (ISO 261), as CYCLE84's MPIT gives it.
fn metric_coarse_pitch(size: f64) -> Option<f64> {
    const TABLE: [(f64, f64); 15] = [
        (3.0, 0.5),
        (4.0, 0.7),
        (5.0, 0.8),
        (6.0, 1.0),
        (8.0, 1.25),
        (10.0, 1.5),
        (12.0, 1.75),
        (14.0, 2.0),
        (16.0, 2.0),
        (20.0, 2.5),
        (24.0, 3.0),
        (30.0, 3.5),
        (36.0, 4.0),
        (42.0, 4.5),
        (48.0, 5.0),
    ];
    TABLE
        .iter()
        .find(|(m, _)| *m == size.abs())
        .map(|&(_, p)| p)
}
