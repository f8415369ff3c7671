//! Drilling cycles `CYCLE81` (drilling, centring) and `CYCLE82` (with a dwell at depth),
//! called once or modally (`MCALL`), `CYCLE800()` (swivel plane reset), and subprogram
//! calls (`L10 P3`, a program called by name).
//!
//! CYCLE81(RTP, RFP, SDIS, DP, DPR) and CYCLE82(.., DTB) (Siemens, "Cycles" programming
//! manual, "Drilling, centering - CYCLE81", "Drilling, counterboring - CYCLE82"): from the
//! drilling position, G0 to the reference plane brought forward by the safety distance
//! (`RFP + SDIS` on the tool axis), G1 at the programmed feed to the depth (`RFP - DPR`
//! when DPR is given, else `DP`), dwell DTB s (CYCLE82), G0 to the retraction plane RTP.

use std::path::PathBuf;

use super::expr::{expr, Scan};
use super::source::Source;
use super::state::Cycle;
use super::words::number;
use super::{Level, Reader};
use crate::axis::Axis;
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
            if args.iter().any(Option::is_some) {
                return Err(sc.err(at, "CYCLE800 with a swivel plane: mtsim reads `CYCLE800()` (swivel reset) only; post the tilted plane as TRAORI moves or frames", "CYCLE800 swivel"));
            }
            self.iso.clear();
            self.push("G69", at..sc.at);
            return self.run_iso(line_no).map(|_| ());
        }
        if name == "CYCLE832" {
            self.arguments(sc, at)?;
            self.notice(
                line_no,
                "CYCLE832 (high-speed settings) accepted and not simulated".into(),
            );
            return Ok(());
        }
        let cycle = self.cycle(name, at, sc)?;
        self.run_cycle(Some(cycle), line_no)
    }

    /// Reads the cycle `name`'s values (its parentheses follow).
    pub(super) fn cycle(&mut self, name: &str, at: usize, sc: &mut Scan) -> LineResult<Cycle> {
        let span = at..sc.at;
        if !matches!(name, "CYCLE81" | "CYCLE82") {
            return Err(LineError::new(span, format!("`{name}` is not supported by mtsim's Siemens reader: it reads the drilling cycles CYCLE81 and CYCLE82"), "unsupported cycle"));
        }
        let a = self.arguments(sc, at)?;
        let get = |k: usize| a.get(k).copied().flatten();
        let (Some(retract), Some(reference)) = (get(0), get(1)) else {
            return Err(sc.err(
                at,
                format!(
                    "{name} without RTP and RFP: expected {name}(RTP, RFP, SDIS, DP, DPR{})",
                    if name == "CYCLE82" { ", DTB" } else { "" }
                ),
                "cycle values",
            ));
        };
        let depth = match (get(4), get(3)) {
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
        Ok(Cycle {
            retract,
            approach: reference + get(2).unwrap_or(0.0).abs(),
            depth,
            dwell_s: if name == "CYCLE82" {
                get(5).unwrap_or(0.0)
            } else {
                0.0
            },
        })
    }

    /// `( v, , v ...)`: each value, `None` where left out.
    fn arguments(&mut self, sc: &mut Scan, at: usize) -> LineResult<Vec<Option<f64>>> {
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
        let Some(c) = cycle.or(self.modal_call) else {
            return Ok(());
        };
        let p = self.interp.program_position();
        let here = self.frame.to_frame([p[Axis::X], p[Axis::Y], p[Axis::Z]]);
        let axis = self.normal;
        let mut steps = vec![(0u8, c.approach), (1, c.depth)];
        if c.dwell_s > 0.0 {
            steps.push((4, c.dwell_s));
        }
        steps.push((0, c.retract));
        for (motion, v) in steps {
            if motion == 4 {
                self.push(&format!("G4 X{}", number(v)), 0..0);
            } else {
                let mut q = here;
                q[axis] = v;
                let t = self.frame.to_work(q);
                self.push(
                    &format!(
                        "G90 G{motion} X{} Y{} Z{}",
                        number(t[0]),
                        number(t[1]),
                        number(t[2])
                    ),
                    0..0,
                );
                self.interp_absolute = true;
                self.interp_motion = motion;
            }
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
        let Some(path) = self.find_program(name) else {
            return Err(LineError::new(span, format!("`{name}` is neither a Sinumerik keyword mtsim reads nor a subprogram it finds ({name}.SPF or {name}.MPF beside the program or on the search path)"), "unknown name or subprogram"));
        };
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
