//! Words that switch the machine's state rather than describe the path: the orientation
//! transformation (`TRAORI`, `TRAFOOF`, `ORIWKS`/`ORIMKS`), machine coordinates for a block
//! (`SUPA`), the feed's mode (`FNORM`) and spindle positioning (`SPOS`).

use super::expr::{expr, Scan};
use super::words::Words;
use super::Reader;
use crate::lex::LineResult;

impl Reader {
    /// One of these words (the cursor after its name): `Ok(true)` when `name` is one.
    pub(super) fn machine_word(
        &mut self,
        name: &str,
        at: usize,
        sc: &mut Scan,
        w: &mut Words,
        line_no: usize,
    ) -> LineResult<bool> {
        match name {
            "SUPA" => {
                w.other.push(("G53".into(), at..sc.at));
                return Ok(true);
            }
            "FNORM" => {
                w.other.push(("G94".into(), at..sc.at));
                return Ok(true);
            }
            "TRAORI" => {
                self.tcp = true;
                w.before.push(if self.d_active {
                    "G43.4 H".to_string() + &self.tool.to_string()
                } else {
                    "G43.4".into()
                });
                return Ok(true);
            }
            "TRAFOOF" => {
                if self.tcp {
                    w.before.push("G49".into());
                    if self.d_active {
                        w.before.push("G43".into());
                    }
                }
                self.tcp = false;
                return Ok(true);
            }
            // Spindle positioning: the spindle turns to an angle; no axis of the path moves.
            "SPOS" | "SPOSA" => {
                if sc.eat(b'[') {
                    expr(sc, &self.vars)?;
                    if !sc.eat(b']') {
                        return Err(sc.err(
                            at,
                            format!("expected `{name}[spindle]=angle`"),
                            "spindle positioning",
                        ));
                    }
                }
                if !sc.eat(b'=') {
                    return Err(sc.err(
                        at,
                        format!("expected `{name}=angle`"),
                        "spindle positioning",
                    ));
                }
                self.value(sc)?;
                self.notice(line_no, format!("`{name}` (spindle positioning, Fundamentals \"Spindle positioning (SPOS, SPOSA, M19)\") accepted: no axis of the path moves; its time is not simulated"));
                return Ok(true);
            }
            "ORIMKS" | "ORIWKS" => {
                self.ori_machine = name == "ORIMKS";
                return Ok(true);
            }
            _ => Ok(false),
        }
    }
}
