//! G10 programmable data input of the Fanuc family, whose L numbers mean otherwise than
//! LinuxCNC's (Fanuc 0i-MF operator's manual, "Programmable data input (G10)": "Changing
//! the workpiece coordinate system", "Changing the tool compensation value"; Haas mill
//! operator's manual, "G10 Set Offsets"):
//!
//! | block | Fanuc, Haas | (LinuxCNC) |
//! |---|---|---|
//! | `G10 L2 Pn X..` n 1-6 | work offset G54-G59 = the words | (the same, P0 the active one) |
//! | `G10 L20 Pn X..` | extended work offset n (Fanuc G54.1 Pn, Haas G154 Pn / G110-G129) = the words | (G5x set so the current point reads the words) |
//! | `G10 L10 Pn R..` | tool length offset n (geometry) = R | (tool table from the current point) |
//! | `G10 L11 Pn R..` (Haas also L1) | tool length wear n = R (added to the geometry) | |
//!
//! Under G91 each value is added to the one stored ("For an incremental command, the value
//! is added to the existing offset"), under G90 it replaces it. Tool offset n is tool n's
//! (mtsim keys H by tool number). Refused with what they are: L2 P0 (Fanuc: the external
//! work offset; Haas: G52), L12/L13 (cutter radius offsets, whose value is a radius or a
//! diameter by a control setting), axis words with L10-L13, and other L numbers.

use super::Interp;
use crate::axis::Axis;
use crate::lex::{LineError, LineResult, Word};
use crate::options::Tool;

impl Interp {
    /// G10 in the fanuc and haas dialects (module doc).
    pub(super) fn g10_fanuc<'l>(
        &mut self,
        line: &str,
        get: &dyn Fn(char) -> Option<Word<'l>>,
        axis_words: &[(Axis, Word)],
        l: Word,
        p: Word,
    ) -> LineResult<()> {
        let name = self.dialect.name();
        let haas = name == "haas";
        let n = p.value.round() as u32;
        let scale = self.scale();
        let add = !self.absolute;
        let refuse =
            |at: std::ops::Range<usize>, what: String| Err(LineError::new(at, what, "G10"));
        match l.value.round() as u32 {
            kind @ (2 | 20) => {
                let coord = match (kind, n) {
                    (2, 0) => {
                        return refuse(p.span(), format!("`G10 L2 P0` in the {name} dialect sets {}, which mtsim does not model: expected P1 to P6 (G54 to G59)", if haas { "the G52 work offset" } else { "the external work offset (added to every work system)" }));
                    }
                    (2, n @ 1..=9) => n,
                    (2, _) => {
                        return refuse(p.span(), format!("`G10 L2 {}`: expected P1 to P6 (G54 to G59)", &line[p.span()]));
                    }
                    (_, n @ 1..=99) => 9 + n,
                    _ => {
                        return refuse(p.span(), format!("`G10 L20 {}`: expected P1 to P99, the extended work offset ({})", &line[p.span()], if haas { "G154 P1-P99" } else { "G54.1 P1-P99" }));
                    }
                };
                if let Some(r) = get('R') {
                    return refuse(r.span(), format!("`{}` in G10 L{kind}: a {name} work offset has no rotation (rotate with G68)", &line[r.span()]));
                }
                let base = super::coord_parameter(coord);
                for (a, wd) in axis_words {
                    let v = if a.is_rotary() { wd.value } else { wd.value * scale };
                    let k = base + a.index();
                    self.params.numbered[k] = if add { self.params.numbered[k] + v } else { v };
                }
                self.parameters_changed();
                Ok(())
            }
            kind @ (1 | 10 | 11) if kind != 1 || haas => {
                if let Some((_, o)) = axis_words.first() {
                    return refuse(o.span(), format!("`{}` in G10 L{kind}: a {name} tool offset takes its value in R", &line[o.span()]));
                }
                let Some(r) = get('R') else {
                    return refuse(l.span(), format!("G10 L{kind} without R: expected the offset value in R"));
                };
                let v = r.value * scale;
                let mut tool = self.tools.get(&n).copied().unwrap_or(Tool {
                    number: n,
                    length_mm: 0.0,
                    diameter_mm: 0.0,
                });
                let wear = self.length_wear.get(&n).copied().unwrap_or(0.0);
                if kind == 10 {
                    let geometry = tool.length_mm - wear;
                    tool.length_mm = if add { geometry + v } else { v } + wear;
                } else {
                    let new_wear = if add { wear + v } else { v };
                    tool.length_mm += new_wear - wear;
                    self.length_wear.insert(n, new_wear);
                }
                self.tools.insert(n, tool);
                Ok(())
            }
            kind @ (12 | 13) => refuse(l.span(), format!("`G10 L{kind}` sets a cutter radius offset ({}), which mtsim does not read: its value is a radius or a diameter by a control setting (Fanuc parameter 5004#3, Haas Setting 40); expected the tool table's diameter", if kind == 12 { "geometry" } else { "wear" })),
            other => refuse(l.span(), format!("`G10 L{other}` is not a {name} offset type mtsim reads: expected L2 or L20 (work offsets), L10 or L11{} (tool length)", if haas { ", L1" } else { "" })),
        }
    }
}
