//! Lathe motion of LinuxCNC 2.9: spindle-synchronised moves G33 and G33.1 and the
//! threading cycle G76 (LinuxCNC's `convert_straight` and `convert_threading_cycle`,
//! `interp_convert.cc`; rs274 is the reference the conformance test holds them to).
//!
//! A spindle-synchronised move advances `pitch` along its path per spindle revolution.
//! mtsim has no spindle model, so such a move is emitted as a feed move at
//! `F = pitch × S` (mm/min, pitch converted from inches under G20): the speed it has when
//! the spindle turns at the programmed S. G95 (feed per revolution) is the same relation.
//!
//! - G33 X Z K: one synchronised feed move to the end point, pitch K.
//! - G33.1 X Z K (rigid tapping): a synchronised feed move to the end point, then one back
//!   to the start (the spindle reverses); the position after it is the start.
//! - G76 P I J K [R Q H E L] X Z: the passes of [`thread_passes`], then a rapid to X Z.
//!
//! All three need the spindle turning (M3 or M4; M5 and M6 stop it, as rs274 does).

use std::collections::VecDeque;

use super::{Interp, MotionMode};
use crate::axis::Axis;
use crate::canon::{FeedMode, Motion, Move};
use crate::g7x::{self, Seg, C};
use crate::lex::{LineError, LineResult, Word};
use crate::AxisVec;

/// Whether `letter` (I J K R) belongs to the lathe motion `mode` rather than to an arc.
pub(super) fn takes_arc_word(mode: MotionMode, letter: char) -> bool {
    match mode {
        MotionMode::Lathe(330 | 331) => letter == 'K',
        MotionMode::Lathe(760) => matches!(letter, 'I' | 'J' | 'K' | 'R'),
        MotionMode::Lathe(700..=722) => matches!(letter, 'I' | 'R'),
        _ => false,
    }
}

/// The words of a G76 block in program units (radius; G7 halves I J K before this).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Thread {
    /// I: distance from the drive line (the start X) to the thread crest; negative for an
    /// external thread, positive for a boring (internal) one. Not zero.
    pub i: f64,
    /// J: depth of the first pass beyond the crest, > 0.
    pub j: f64,
    /// K: full thread depth beyond the crest, > J.
    pub k: f64,
    /// P: pitch, distance per spindle revolution.
    pub pitch: f64,
    /// Q: compound slide angle, degrees (absent: 0).
    pub q_deg: Option<f64>,
    /// H: spring passes after the first pass at full depth (absent: 0).
    pub h: Option<f64>,
    /// R: depth degression (absent or below 1: 1, constant depth per pass).
    pub r: Option<f64>,
    /// E: taper distance along Z (absent or negative: 0).
    pub e: Option<f64>,
    /// L: taper ends, 1 entry, 2 exit, 3 both (absent: none).
    pub l: Option<f64>,
}

/// One move of a threading pass, in program units relative to the cycle's start point
/// (`x` from the start X, `z` from the start Z).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Step {
    Rapid {
        x: f64,
        z: f64,
    },
    /// Spindle-synchronised feed at `pitch` per revolution.
    Sync {
        x: f64,
        z: f64,
        pitch: f64,
    },
}

/// The passes of G76 from the start point to a thread ending `dz` (program units) away in
/// Z, as LinuxCNC 2.9 makes them, without the final rapid to the block's end point.
///
/// With the crest at `|I|` from the start X, the depth of pass n (1, 2, ...) below the start
/// is `d_n = |I| + J·n^(1/R)` while `d_n < |I| + K`; then the full depth `|I| + K` is cut
/// `1 + H` times. Each pass moves in along the compound angle Q: the Z start is shifted by
/// `zoff = (d - |I|)·tan Q` (towards the start when the thread runs towards -Z). A pass is:
/// rapid out to the retract X (`d` back from the full depth, i.e. X = start ∓ d ± (|I|+K)),
/// rapid in to depth `d` (or, with an entry taper E, synchronised in along the taper),
/// synchronised along Z to the end (with an exit taper, out along the taper), rapid out.
pub(crate) fn thread_passes(t: &Thread, dz: f64) -> Vec<Step> {
    let boring = t.i > 0.0;
    let full_dia_depth = t.i.abs();
    let start_depth = t.i.abs() + t.j.abs();
    let cut_increment = t.j.abs();
    let full_threadheight = t.k.abs();
    let end_depth = t.k.abs() + t.i.abs();
    let pitch = t.pitch;
    // rs274 reads an absent Q as -1, which it takes as 0.
    let mut compound = t.q_deg.unwrap_or(-1.0);
    if compound == -1.0 {
        compound = 0.0;
    }
    compound = compound.to_radians();
    if dz > 0.0 {
        compound = -compound;
    }
    // rs274 keeps H as an integer count (truncated) and L as integer flags.
    let spring_cuts = t.h.map_or(0, |h| h as i64);
    let degression = match t.r {
        Some(r) if r >= 1.0 => r,
        _ => 1.0,
    };
    let mut taper_dist = t.e.unwrap_or(0.0).max(0.0);
    let taper_pitch = if taper_dist > 0.0 {
        pitch * taper_dist.hypot(full_threadheight) / taper_dist
    } else {
        pitch
    };
    if dz > 0.0 {
        taper_dist = -taper_dist;
    }
    let flags = t.l.map_or(0, |l| (l as i64).max(0));
    let (entry_taper, exit_taper) = (flags & 1 != 0, flags & 2 != 0);
    let target_z = dz + t.k.abs() * compound.tan();
    let x_at = |d: f64| if boring { d } else { -d };
    let mut steps = Vec::new();
    let pass = |depth: f64, zoff: f64, steps: &mut Vec<Step>| {
        let back = x_at(depth - end_depth);
        steps.push(Step::Rapid { x: back, z: -zoff });
        if taper_dist != 0.0 && entry_taper {
            let crest = x_at(depth - full_threadheight);
            steps.push(Step::Sync {
                x: crest,
                z: -zoff,
                pitch: taper_pitch,
            });
            steps.push(Step::Sync {
                x: x_at(depth),
                z: -zoff - taper_dist,
                pitch: taper_pitch,
            });
        } else {
            steps.push(Step::Rapid {
                x: x_at(depth),
                z: -zoff,
            });
        }
        if taper_dist != 0.0 && exit_taper {
            steps.push(Step::Sync {
                x: x_at(depth),
                z: target_z - zoff + taper_dist,
                pitch,
            });
            steps.push(Step::Sync {
                x: x_at(depth - full_threadheight),
                z: target_z - zoff,
                pitch: taper_pitch,
            });
        } else {
            steps.push(Step::Sync {
                x: x_at(depth),
                z: target_z - zoff,
                pitch,
            });
        }
        steps.push(Step::Rapid {
            x: back,
            z: target_z - zoff,
        });
    };
    let mut n = 1;
    let mut depth = start_depth;
    let mut zoff = (depth - full_dia_depth) * compound.tan();
    while depth < end_depth {
        pass(depth, zoff, &mut steps);
        n += 1;
        depth = full_dia_depth + cut_increment * (n as f64).powf(1.0 / degression);
        zoff = (depth - full_dia_depth) * compound.tan();
    }
    depth = end_depth;
    zoff = (depth - full_dia_depth) * compound.tan();
    for _ in 0..spring_cuts + 1 {
        pass(depth, zoff, &mut steps);
    }
    steps
}

/// Passes of a G76 whose J is so small against K that it would run for ever are refused:
/// at most this many.
pub(crate) const MAX_THREAD_PASSES: usize = 100_000;

impl Interp {
    /// G33, G33.1 or G76 (`code` ×10) to `target` (machine mm).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn lathe<'l>(
        &mut self,
        line: &str,
        code: u32,
        get: &dyn Fn(char) -> Option<Word<'l>>,
        line_no: usize,
        queue: &mut VecDeque<Move>,
        at: std::ops::Range<usize>,
        target: AxisVec,
    ) -> LineResult<()> {
        if (700..=722).contains(&code) {
            return self.g7x_request(code, get, line_no, queue, at, target);
        }
        let name = match code {
            330 => "G33",
            331 => "G33.1",
            _ => "G76",
        };
        if !self.spindle_turning {
            return Err(LineError::new(
                at,
                format!("spindle not turning in {name}: expected M3 or M4 before it"),
                "spindle stopped",
            )
            .help("start the spindle (S.. M3) after the last M5 or tool change"));
        }
        if self.spindle_rpm <= 0.0 {
            return Err(LineError::new(
                at,
                format!("{name} with the spindle speed zero: expected an S word above zero"),
                "no S",
            ));
        }
        let scale = self.scale();
        let start = self.pos;
        let feed =
            |pitch: f64, s: &Interp| (Some(pitch * scale * s.spindle_rpm), FeedMode::PerMinute);
        let path = self.path;
        if code == 330 || code == 331 {
            let k = get('K').ok_or_else(|| {
                LineError::new(
                    at.clone(),
                    format!("{name} without K: expected the pitch K (distance per revolution) in every {name} block"),
                    "no K",
                )
            })?;
            if !(k.value > 0.0) {
                return Err(LineError::new(
                    k.span(),
                    format!(
                        "`{}`: expected a pitch K greater than zero",
                        &line[k.span()]
                    ),
                    "pitch not positive",
                ));
            }
            let f = feed(k.value, self);
            self.emit_with_feed(queue, line_no, Motion::Linear, start, target, path, f);
            if code == 331 {
                // Rigid tapping: the spindle reverses and the tap comes back out.
                self.emit_with_feed(queue, line_no, Motion::Linear, target, start, path, f);
            } else {
                self.pos = target;
            }
            return Ok(());
        }
        // G76.
        let need = |letter: char, what: &str| {
            get(letter).ok_or_else(|| {
                LineError::new(
                    at.clone(),
                    format!("G76 without {letter}: expected {what}"),
                    format!("no {letter}"),
                )
                .help(
                    "G76 P<pitch> Z<end> I<crest offset> J<first depth> K<full depth> [R Q H E L]",
                )
            })
        };
        let p = need('P', "P, the thread pitch")?;
        let i = need('I', "I, the offset of the thread crest from the start X")?;
        let j = need('J', "J, the depth of the first pass")?;
        let k = need('K', "K, the full thread depth")?;
        for a in [Axis::A, Axis::B, Axis::C] {
            if target[a] != start[a] {
                return Err(LineError::new(
                    at,
                    "rotary axis word in a G76 block: expected only X Z (and Y)",
                    "rotary axis in G76",
                ));
            }
        }
        // I J K are radii, halved in G7 by convert_threading_cycle. rs274 2.9 also scales
        // them where the block switches the mode (convert_lathe_diameter_mode: ½ for a G7
        // that turns diameter mode on, 2 for a G8 that turns it off), so `G7 G76 ...` from
        // radius mode quarters them. Measured with rs274 (tests/data/conformance/g76_*.ngc).
        let half = match (self.diameter, self.diameter_switched) {
            (true, Some(true)) => 0.25,
            (false, Some(false)) => 2.0,
            (true, _) => 0.5,
            (false, _) => 1.0,
        };
        let t = Thread {
            i: i.value * half,
            j: j.value * half,
            k: k.value * half,
            pitch: p.value,
            q_deg: get('Q').map(|w| w.value),
            h: get('H').map(|w| w.value),
            r: get('R').map(|w| w.value),
            e: get('E').map(|w| w.value),
            l: get('L').map(|w| w.value),
        };
        if t.i == 0.0 {
            return Err(LineError::new(i.span(), "G76 with I0: expected I other than zero (negative for an outside thread, positive for a bore)", "I zero"));
        }
        if !(t.j > 0.0) {
            return Err(LineError::new(
                j.span(),
                "G76: expected J greater than zero",
                "J not positive",
            ));
        }
        if !(t.k > t.j) {
            return Err(LineError::new(
                k.span(),
                "G76: expected K greater than J",
                "K not beyond J",
            ));
        }
        if !(t.pitch > 0.0) {
            return Err(LineError::new(
                p.span(),
                "G76: expected a pitch P greater than zero",
                "pitch not positive",
            ));
        }
        // Passes: |I| + J·n^(1/R) < |I| + K, so n < (K/J)^R.
        let passes = (t.k / t.j).powf(t.r.unwrap_or(1.0).max(1.0)) + t.h.unwrap_or(0.0).max(0.0);
        if !(passes <= MAX_THREAD_PASSES as f64) {
            return Err(LineError::new(
                at,
                format!(
                    "G76 would cut about {passes:.0} passes: expected at most {MAX_THREAD_PASSES}"
                ),
                "too many passes",
            )
            .help("check J, K, R and H"));
        }
        let dz = (target[Axis::Z] - start[Axis::Z]) / scale;
        let mut pos = start;
        for step in thread_passes(&t, dz) {
            let (x, z, motion, f) = match step {
                Step::Rapid { x, z } => (x, z, Motion::Rapid, self.feed_out()),
                Step::Sync { x, z, pitch } => (x, z, Motion::Linear, feed(pitch, self)),
            };
            let mut end = pos;
            end[Axis::X] = start[Axis::X] + x * scale;
            end[Axis::Z] = start[Axis::Z] + z * scale;
            self.emit_with_feed(queue, line_no, motion, pos, end, path, f);
            pos = end;
        }
        self.emit(queue, line_no, Motion::Rapid, pos, target, path);
        self.pos = target;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn thread(i: f64, j: f64, k: f64) -> Thread {
        Thread {
            i,
            j,
            k,
            pitch: 1.0,
            q_deg: None,
            h: None,
            r: None,
            e: None,
            l: None,
        }
    }

    /// I-1 J0.1 K0.5, no degression: depths 1.1 1.2 1.3 1.4, then 1.5 once; each pass is
    /// rapid back, rapid in, synchronised over, rapid out.
    #[test]
    fn outside_thread_cuts_j_deeper_each_pass_then_full_depth_once() {
        let steps = thread_passes(&thread(-1.0, 0.1, 0.5), -7.0);
        assert_eq!(steps.len(), 5 * 4);
        let depths: Vec<f64> = steps
            .chunks(4)
            .map(|p| match p[2] {
                Step::Sync { x, z, pitch } => {
                    assert_eq!((z, pitch), (-7.0, 1.0));
                    -x
                }
                s => panic!("{s:?}"),
            })
            .collect();
        for (d, want) in depths.iter().zip([1.1, 1.2, 1.3, 1.4, 1.5]) {
            assert!((d - want).abs() < 1e-12, "{depths:?}");
        }
        // Retract X: start - depth + (|I| + K), the same for every pass: +0.4 at the end.
        assert_eq!(
            steps[0],
            Step::Rapid {
                x: -1.1 + 1.5,
                z: 0.0
            }
        );
        assert_eq!(
            steps[3],
            Step::Rapid {
                x: -1.1 + 1.5,
                z: -7.0
            }
        );
    }

    /// Q29.5 moves each pass's start in Z by (depth - |I|)·tan Q, towards the start for a
    /// thread cut towards -Z; degression R2 makes depths |I| + J·√n; H2 adds two passes.
    #[test]
    fn compound_angle_degression_and_spring_passes() {
        let t = Thread {
            q_deg: Some(29.5),
            r: Some(2.0),
            h: Some(2.0),
            ..thread(-1.0, 0.1, 0.3)
        };
        let steps = thread_passes(&t, -10.0);
        // √n·0.1 < 0.3 for n = 1..8; then 3 passes at full depth.
        assert_eq!(steps.len(), (8 + 3) * 4);
        let tan = 29.5f64.to_radians().tan();
        let Step::Rapid { x, z } = steps[4 * 3 + 1] else {
            panic!()
        };
        let d = 0.1 * 4f64.sqrt();
        assert!((x + 1.0 + d).abs() < 1e-12);
        assert!((z + d * tan).abs() < 1e-12);
        let Step::Sync { z, .. } = steps[steps.len() - 2] else {
            panic!()
        };
        assert!((z - (-10.0 + 0.3 * tan - 0.3 * tan)).abs() < 1e-12);
    }

    /// E and L3: the pass enters along the taper (synchronised at the taper's pitch
    /// P·√(E² + K²)/E) and leaves along it.
    #[test]
    fn taper_entry_and_exit() {
        let t = Thread {
            e: Some(0.4),
            l: Some(3.0),
            ..thread(1.0, 0.5, 0.6)
        };
        let steps = thread_passes(&t, -5.0);
        let taper_pitch = 0.4f64.hypot(0.6) / 0.4;
        // A boring thread: X grows with depth. First pass at depth 1.5.
        assert_eq!(
            steps[0],
            Step::Rapid {
                x: 1.5 - 1.6,
                z: 0.0
            }
        );
        assert_eq!(
            steps[1],
            Step::Sync {
                x: 1.5 - 0.6,
                z: 0.0,
                pitch: taper_pitch
            }
        );
        assert_eq!(
            steps[2],
            Step::Sync {
                x: 1.5,
                z: -0.4,
                pitch: taper_pitch
            }
        );
        assert_eq!(
            steps[3],
            Step::Sync {
                x: 1.5,
                z: -5.0 + 0.4,
                pitch: 1.0
            }
        );
        assert_eq!(
            steps[4],
            Step::Sync {
                x: 1.5 - 0.6,
                z: -5.0,
                pitch: taper_pitch
            }
        );
    }
}

/// `G70`, `G71.1`, ... for the code ×10.
fn cycle_name(code: u32) -> String {
    match code % 10 {
        0 => format!("G{}", code / 10),
        k => format!("G{}.{k}", code / 10),
    }
}

/// Whether G71/G72 extend a profile that ends short of the start X (Z) by a line to it, as
/// later LinuxCNC versions do; rs274 2.9 does not (measured), so this stays off.
const EXTEND_PROFILE: bool = false;

/// A G70/G71/G72 block: its words and the profile read so far from the subroutine Q.
#[derive(Clone, Debug)]
pub struct G7xRequest {
    /// 700, 710, 711, 712, 720, 721, 722.
    code: u32,
    /// The subroutine: `o<Q> sub` (Q rounded), `None` once its call has started.
    label: Option<String>,
    line_no: usize,
    span: std::ops::Range<usize>,
    /// The block's X Z (program units, `z + i·x`): the cycle's start point.
    xz: C,
    d: f64,
    e: f64,
    i: f64,
    p: f64,
    r: f64,
    /// Machine position after the rapid to the start, and whether G91 was in effect.
    home: AxisVec,
    incremental: bool,
    /// The profile's current point (program units).
    at: C,
    profile: Vec<Seg>,
}

impl Interp {
    /// A G70-G72 block (LinuxCNC 2.9 `convert_g7x`): checks it, makes the rapid to its X Z
    /// (cutter compensation off), and leaves it in `self.g7x`; the reader then runs the
    /// profile subroutine Q, whose blocks come to [`Interp::g7x_profile_line`] instead of
    /// moving the machine, and calls [`Interp::g7x_run`] when it returns.
    #[allow(clippy::too_many_arguments)]
    fn g7x_request<'l>(
        &mut self,
        code: u32,
        get: &dyn Fn(char) -> Option<Word<'l>>,
        line_no: usize,
        queue: &mut VecDeque<Move>,
        at: std::ops::Range<usize>,
        target: AxisVec,
    ) -> LineResult<()> {
        let name = cycle_name(code);
        let q = get('Q').ok_or_else(|| {
            LineError::new(
                at.clone(),
                format!("{name} without Q: expected Q<n>, the number of the subroutine `o<n> sub` that holds the profile"),
                "no Q",
            )
        })?;
        if self.comp.is_some() && code != 700 {
            return Err(LineError::new(
                at,
                format!("{name} with cutter compensation on: expected G40 first (only G70 may be compensated)"),
                "compensation",
            ));
        }
        if self.plane != crate::axis::Plane::ZX {
            return Err(LineError::new(
                at,
                format!("{name} outside G18: expected the lathe plane ZX (G18)"),
                "not G18",
            )
            .help("select G18 before the cycle"));
        }
        let i = get('I').map_or(1.0, |w| w.value);
        if !(i > 0.0) {
            return Err(LineError::new(
                at,
                format!("{name}: expected I (the depth of cut) greater than zero"),
                "I not positive",
            ));
        }
        // The cycle's start: the block's X Z, added to the current point under G91.
        let p0 = self.program_position();
        let coordinate = |l: char, a: Axis| match get(l) {
            Some(w) if self.absolute => w.value,
            Some(w) => p0[a] + w.value,
            None => p0[a],
        };
        let xz = C {
            re: coordinate('Z', Axis::Z),
            im: coordinate('X', Axis::X),
        };
        // The rapid to the block's X Z taken as absolute (LinuxCNC switches to G90 first);
        // under G70 with cutter compensation on, rs274 2.9 compensates it like any G0 (the
        // entry move when it is the first; measured).
        let start = self.pos;
        if self.comp.is_some() {
            self.comp_element(queue, line_no, Motion::Rapid, start, target)
                .map_err(|m| LineError::new(at.clone(), m, "cutter compensation"))?;
        } else {
            let path = self.path;
            self.emit(queue, line_no, Motion::Rapid, start, target, path);
        }
        self.pos = target;
        self.motion = Some(MotionMode::Rapid);
        let value = |l: char, default: f64| get(l).map_or(default, |w| w.value);
        self.g7x = Some(Box::new(G7xRequest {
            code,
            label: Some(format!("{}", q.value.round() as i64)),
            line_no,
            span: at,
            xz,
            d: value('D', 0.0),
            e: value('E', 0.0),
            i,
            p: value('P', 1.0),
            r: value('R', 0.5),
            home: target,
            incremental: !self.absolute,
            at: xz,
            profile: Vec::new(),
        }));
        Ok(())
    }

    /// The label of the profile subroutine to call, once, after the G70-G72 block.
    pub fn g7x_label(&mut self) -> Option<String> {
        self.g7x.as_mut().and_then(|r| r.label.take())
    }

    /// One block of the profile subroutine, read as LinuxCNC reads it: G0/G1 add a line,
    /// G2/G3 an arc (I K absolute, or incremental under G91.1; or R), A a fillet and C a
    /// chamfer at its end; X Z absolute (incremental under G91); nothing is executed. The
    /// current point (`#5420`, `#<_x>`) follows the profile.
    pub fn g7x_profile_line(&mut self, line: &str, words: &[Word]) -> LineResult<()> {
        let Some(mut req) = self.g7x.take() else {
            return Ok(());
        };
        let result = self.profile_line(&mut req, line, words);
        self.g7x = Some(req);
        result
    }

    fn profile_line(&mut self, req: &mut G7xRequest, line: &str, words: &[Word]) -> LineResult<()> {
        let get = |l: char| words.iter().find(|w| w.letter == l);
        let span_of = |w: &Word| w.span();
        let block_span = words.first().map_or(0..line.len(), span_of);
        for w in words.iter().filter(|w| w.letter == 'G') {
            let code = (w.value * 10.0).round() as u32;
            self.motion = match code {
                0 => Some(MotionMode::Rapid),
                10 => Some(MotionMode::Linear),
                20 => Some(MotionMode::Arc { clockwise: true }),
                30 => Some(MotionMode::Arc { clockwise: false }),
                _ => continue,
            };
        }
        let start = req.at;
        let mut end = if req.incremental {
            C { re: 0.0, im: 0.0 }
        } else {
            start
        };
        let half = if self.diameter { 0.5 } else { 1.0 };
        if let Some(x) = get('X') {
            end.im = x.value * half;
        }
        if let Some(z) = get('Z') {
            end.re = z.value;
        }
        if req.incremental {
            end = end + start;
        }
        let mut center = C { re: 0.0, im: 0.0 };
        if let Some(i) = get('I') {
            center.im = i.value;
        }
        if let Some(k) = get('K') {
            center.re = k.value;
        }
        if start == end {
            return Ok(());
        }
        let mode = self.motion;
        match mode {
            Some(MotionMode::Rapid | MotionMode::Linear) => {
                req.profile.push(Seg::line(start, end));
            }
            Some(MotionMode::Arc { clockwise }) => {
                if let Some(r) = get('R') {
                    if get('I').is_some() || get('K').is_some() {
                        return Err(LineError::new(
                            span_of(r),
                            "arc in a G70-G72 profile with both R and I or K: expected one",
                            "R and I K",
                        ));
                    }
                    let r = r.value;
                    let chord = end - start;
                    let h = ((r * r - chord.norm() / 4.0) / chord.norm()).sqrt();
                    let d = C { re: 0.0, im: h } * chord;
                    center = (start + end) / 2.0;
                    center = if clockwise { center - d } else { center + d };
                } else {
                    if get('I').is_none() && get('K').is_none() {
                        return Err(LineError::new(
                            block_span,
                            "arc in a G70-G72 profile without I K or R: expected either",
                            "no centre",
                        ));
                    }
                    if !self.arc_absolute {
                        center = center + start;
                    }
                }
                req.profile.push(Seg::arc(!clockwise, start, center, end));
            }
            _ => {}
        }
        if matches!(
            mode,
            Some(MotionMode::Rapid | MotionMode::Linear | MotionMode::Arc { .. })
        ) {
            match (get('A'), get('C')) {
                (Some(_), Some(c)) => {
                    return Err(LineError::new(
                        span_of(c),
                        "both A and C on a corner of a G70-G72 profile: expected a fillet (A) or a chamfer (C)",
                        "A and C",
                    ))
                }
                (Some(a), None) => req.profile.push(Seg::fillet(a.value, end)),
                (None, Some(c)) => req.profile.push(Seg::chamfer(c.value, end)),
                (None, None) => {}
            }
        }
        req.at = end;
        // The current point follows the profile (`#<_x>` in the next block).
        let scale = self.scale();
        self.pos[Axis::X] = end.im * scale + self.offset[Axis::X];
        self.pos[Axis::Z] = end.re * scale + self.offset[Axis::Z] + self.tool_length_mm;
        Ok(())
    }

    /// Cuts the profile read (LinuxCNC's `do_g70`, `do_g71`, `do_g72`), emitting its moves
    /// as G0/G1/G2/G3 blocks of the cycle's line.
    pub fn g7x_run(&mut self, queue: &mut VecDeque<Move>) -> LineResult<()> {
        let Some(req) = self.g7x.take() else {
            return Ok(());
        };
        self.pos = req.home;
        if self.comp.is_some() {
            // rs274 2.9 leaves its current point where the profile read ended, and under
            // compensation that point is the compensated one (`comp_get_current`): the next
            // move is compensated from there (measured on lathe_g70_71_demo.ngc).
            let scale = self.scale();
            let mut end = self.pos;
            end[Axis::X] = req.at.im * scale + self.offset[Axis::X];
            end[Axis::Z] = req.at.re * scale + self.offset[Axis::Z] + self.tool_length_mm;
            if let Some(comp) = self.comp.as_mut() {
                comp.set_current(end);
            }
        }
        let name = cycle_name(req.code);
        let fail = |m: String| {
            LineError::new(req.span.clone(), format!("{name}: {m}"), "lathe cycle")
                .help("check the profile subroutine Q (LinuxCNC's rules for G70-G72)")
        };
        // LinuxCNC does nothing with a profile of one move or none.
        if req.profile.len() <= 1 {
            return Ok(());
        }
        let mut segs = req.profile.clone();
        let dfront = segs[0].end() - segs[0].start();
        let last = segs[segs.len() - 1];
        let dback = last.end() - last.start();
        let start = req.at;
        let (x, z) = (req.xz.im, req.xz.re);
        let moves: Vec<g7x::Out> = match req.code {
            700 => g7x::Profile::new(segs)
                .g70(req.xz, req.d, req.e, req.p)
                .map_err(fail)?,
            c => {
                let g72 = c >= 720;
                if EXTEND_PROFILE
                    && !g72
                    && dback.re.abs() > 0.0
                    && dfront.im * (x - start.im) < 0.0
                {
                    segs.push(Seg::line(
                        start,
                        C {
                            re: start.re,
                            im: x,
                        },
                    ));
                }
                if EXTEND_PROFILE && g72 && dback.im.abs() > 0.0 && dfront.re * (z - start.re) < 0.0
                {
                    segs.push(Seg::line(
                        start,
                        C {
                            re: z,
                            im: start.im,
                        },
                    ));
                }
                g7x::Profile::new(segs)
                    .g71(
                        g72,
                        c % 10,
                        req.xz,
                        C { re: 0.0, im: 0.0 },
                        req.d,
                        req.i,
                        req.r,
                    )
                    .map_err(fail)?
            }
        };
        let scale = self.scale();
        let to_machine = |p: C, s: &Interp| {
            let mut m = s.pos;
            m[Axis::X] = p.im * scale + s.offset[Axis::X];
            m[Axis::Z] = p.re * scale + s.offset[Axis::Z] + s.tool_length_mm;
            m
        };
        for mv in moves {
            let start = self.pos;
            let (motion, target) = match mv {
                g7x::Out::Rapid(p) => (Motion::Rapid, to_machine(p, self)),
                g7x::Out::Feed(p) => (Motion::Linear, to_machine(p, self)),
                g7x::Out::Arc { ccw, center, end } => {
                    let target = to_machine(end, self);
                    // LinuxCNC skips an arc that ends where the tool is (within 1e-4).
                    let same = |a: Axis| ((target[a] - start[a]) / scale).abs() < 1e-4;
                    if same(Axis::X) && same(Axis::Z) {
                        continue;
                    }
                    let c = to_machine(center, self);
                    // convert_arc's check of the radii at both ends (docs/gcode.md).
                    let r1 = (start[Axis::X] - c[Axis::X]).hypot(start[Axis::Z] - c[Axis::Z]);
                    let r2 = (target[Axis::X] - c[Axis::X]).hypot(target[Axis::Z] - c[Axis::Z]);
                    let abs_tol = std::f64::consts::SQRT_2
                        * if self.inch {
                            0.002 * crate::units::MM_PER_INCH
                        } else {
                            0.02
                        };
                    let diff = (r1 - r2).abs();
                    if !(diff <= abs_tol || diff / r1 <= 0.001) {
                        return Err(fail(format!("an arc of the cycle has radius {r1:.4} mm at its start but {r2:.4} mm at its end: expected them to agree (check the profile's arcs)")));
                    }
                    (
                        Motion::Arc {
                            clockwise: !ccw,
                            plane: self.plane,
                            center_mm: [c[Axis::X], c[Axis::Y], c[Axis::Z]],
                        },
                        target,
                    )
                }
            };
            if motion != Motion::Rapid && (self.feed.is_none() || self.feed == Some(0.0)) {
                return Err(fail(
                    "feed move with no feed programmed: expected an F word before the cycle".into(),
                ));
            }
            self.motion = Some(match motion {
                Motion::Rapid => MotionMode::Rapid,
                Motion::Linear => MotionMode::Linear,
                Motion::Arc { clockwise, .. } => MotionMode::Arc { clockwise },
                Motion::Dwell { .. } => unreachable!("no dwell in a cycle"),
            });
            let path = self.path;
            if self.comp.is_some() {
                self.comp_element(queue, req.line_no, motion, start, target)
                    .map_err(|m| LineError::new(req.span.clone(), m, "cutter compensation"))?;
            } else {
                let comp = self.comp.take();
                self.emit(queue, req.line_no, motion, start, target, path);
                self.comp = comp;
            }
            self.pos = target;
        }
        Ok(())
    }
}
