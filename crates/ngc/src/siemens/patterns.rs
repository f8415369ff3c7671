//! Hole patterns `HOLES1` (row of holes) and `HOLES2` (circle of holes), which position
//! with G0 in the working plane and run the modal call (`MCALL CYCLE8x(..)`) at each
//! hole (SINUMERIK 840D sl Programming Manual Cycles, "Row of holes (HOLES1)", "Circle of
//! holes (HOLES2)"); and the refusal, with its manual section, of the other pattern and
//! milling cycles.
//!
//! In the plane's first axis `u` and second `v` (program coordinates, through the frame):
//!
//! * `HOLES1(SPCA, SPCO, STA1, FDIS, DBH, NUM)`: hole k (0 .. NUM−1) at
//!   `(SPCA, SPCO) + (|FDIS| + k |DBH|) (cos STA1, sin STA1)`; the row is run from its
//!   first hole, or from its last when that is nearer the current position (the manual:
//!   the cycle decides from the plane axes' position which end to start at, to avoid idle
//!   travel).
//! * `HOLES2(CPA, CPO, RAD, STA1, INDA, NUM)`: hole k at
//!   `(CPA, CPO) + |RAD| (cos(STA1 + k·INDA), sin(STA1 + k·INDA))`, INDA 0 meaning 360°/NUM.
//!
//! Without a modal call the holes are only approached.

use super::expr::Scan;
use super::Reader;
use crate::axis::Axis;
use crate::lex::{LineError, LineResult};

/// The most holes one pattern may have.
const MAX_HOLES: f64 = 100_000.0;

/// Pattern and milling cycles mtsim does not read, with what each is and its section of
/// the SINUMERIK 840D sl Cycles manual.
pub(super) const UNREAD_CYCLES: &[(&str, &str)] = &[
    (
        "CYCLE801",
        "grid of holes; Cycles, \"Grid of holes (CYCLE801)\"",
    ),
    (
        "CYCLE802",
        "drilling at arbitrary positions; Cycles, \"Arbitrary positions (CYCLE802)\"",
    ),
    (
        "POCKET1",
        "rectangular pocket; Cycles, \"Milling rectangular pockets (POCKET1)\"",
    ),
    (
        "POCKET2",
        "circular pocket; Cycles, \"Milling circular pockets (POCKET2)\"",
    ),
    (
        "POCKET3",
        "rectangular pocket; Cycles, \"Milling rectangular pockets (POCKET3)\"",
    ),
    (
        "POCKET4",
        "circular pocket; Cycles, \"Milling circular pockets (POCKET4)\"",
    ),
    (
        "SLOT1",
        "slots on a circle; Cycles, \"Slots on a circle (SLOT1)\"",
    ),
    (
        "SLOT2",
        "circumferential slots; Cycles, \"Circumferential slots (SLOT2)\"",
    ),
    (
        "LONGHOLE",
        "elongated holes on a circle; Cycles, \"Elongated holes on a circle (LONGHOLE)\"",
    ),
];

/// The refusal of `name`, one of [`UNREAD_CYCLES`], at `at`.
pub(super) fn unread_cycle(name: &str, sc: &Scan, at: usize) -> LineError {
    let what = UNREAD_CYCLES
        .iter()
        .find(|(k, _)| *k == name)
        .map_or("", |(_, w)| *w);
    sc.err(at, format!("`{name}` ({what}) is not supported by mtsim's Siemens reader: it reads the hole patterns HOLES1 and HOLES2 and the drilling cycles CYCLE81 to CYCLE89"), "unsupported cycle")
}

impl Reader {
    /// `HOLES1(..)` or `HOLES2(..)` at `at` (the cursor after the name): the positions,
    /// each approached with G0 and drilled by the modal call.
    pub(super) fn hole_pattern(
        &mut self,
        name: &str,
        at: usize,
        sc: &mut Scan,
        line_no: usize,
    ) -> LineResult<()> {
        let a = self.arguments(sc, at)?;
        let span = at..sc.at;
        let refuse = |m: String| LineError::new(span.clone(), m, "hole pattern");
        let get = |k: usize| a.get(k).copied().flatten();
        let zero = |k: usize| get(k).unwrap_or(0.0);
        let num = zero(5);
        if !(1.0..=MAX_HOLES).contains(&num) || num.fract() != 0.0 {
            return Err(refuse(format!("{name} NUM {num}: expected the number of holes, a whole number from 1 to {MAX_HOLES} (the 6th value)")));
        }
        let (Some(pa), Some(po)) = (get(0), get(1)) else {
            return Err(refuse(format!("{name} without its reference point: expected the plane's first and second coordinates as the 1st and 2nd values")));
        };
        self.budget.check_passes(
            num as u64,
            &format!("{name} with {num} holes"),
            span.clone(),
        )?;
        let (u, v) = ((self.normal + 1) % 3, (self.normal + 2) % 3);
        let at_now = |r: &Reader| {
            let p = r.interp.program_position();
            r.frame.frame_point([p[Axis::X], p[Axis::Y], p[Axis::Z]])
        };
        let here = at_now(self);
        let n = num as usize;
        let mut holes: Vec<[f64; 2]> = if name == "HOLES1" {
            let (s, c) = zero(2).to_radians().sin_cos();
            (0..n)
                .map(|k| {
                    let d = zero(3).abs() + k as f64 * zero(4).abs();
                    [pa + d * c, po + d * s]
                })
                .collect()
        } else {
            let step = if zero(4) == 0.0 { 360.0 / num } else { zero(4) };
            (0..n)
                .map(|k| {
                    let (s, c) = (zero(3) + k as f64 * step).to_radians().sin_cos();
                    [pa + zero(2).abs() * c, po + zero(2).abs() * s]
                })
                .collect()
        };
        let dist = |h: &[f64; 2]| (h[0] - here[u]).hypot(h[1] - here[v]);
        if name == "HOLES1" && dist(&holes[n - 1]) < dist(&holes[0]) {
            holes.reverse();
        }
        for h in holes {
            // In the plane only, at the tool axis's level now (RTP after a hole).
            let mut q = at_now(self);
            (q[u], q[v]) = (h[0], h[1]);
            let t = self.frame.work_point(q);
            self.push(
                &format!(
                    "G90 G0 X{} Y{} Z{}",
                    super::words::number(t[0]),
                    super::words::number(t[1]),
                    super::words::number(t[2])
                ),
                span.clone(),
            );
            self.interp_absolute = true;
            self.interp_motion = 0;
            self.run_iso(line_no)?;
            self.run_cycle(None, line_no)?;
        }
        Ok(())
    }
}
