//! The G codes a Fanuc or Haas lathe reads otherwise than a mill (Fanuc lathe G-code
//! system A, the control's default, parameter 3401#6 GSB = #7 GSC = 0; Haas lathe operator's
//! manual, G-code reference), on a lathe machine (X and Z, no Y: [`Interp::is_lathe`]):
//!
//! | code | lathe (system A, Haas lathe) | mill |
//! |---|---|---|
//! | G98, G99 | feed per minute, per revolution | canned cycle return level |
//! | G50 X Z | work coordinate system setting (as a mill's G92) | scaling cancel |
//! | G90, G92, G94 | single cycles: turning, threading, facing | absolute, G92 shift, per minute |
//! | G95 | none (Haas: live-tool face tapping) | per revolution |
//!
//! The first two are read as the lathe means them; the single cycles and G95 are refused
//! with what they are, never read as the mill's codes. (A program for G-code system B or C,
//! whose G90/G94/G95 are the mill's, is refused at its first such code.)

use super::Interp;
use crate::axis::Axis;
use crate::block::Block;
use crate::code::{FeedRead, GCode, NonModal};
use crate::lex::{LineError, LineResult};

impl Interp {
    /// A Fanuc-family lathe: a macro-B dialect on a machine with X and Z and no Y.
    pub(crate) fn is_lathe(&self) -> bool {
        self.dialect.table().macro_b
            && self.axes[Axis::X.index()]
            && self.axes[Axis::Z.index()]
            && !self.axes[Axis::Y.index()]
    }

    /// Turns the block's lathe codes into their meaning (module doc), or refuses them. G90,
    /// G92 and G94 without X Z U W only select the cycle (group 01): accepted, and a later
    /// block with axis words and no other motion code (which would run the cycle) refused.
    pub(super) fn lathe_codes(&mut self, b: &mut Block) -> LineResult<()> {
        if !self.is_lathe() {
            return Ok(());
        }
        let axis_words = b
            .words
            .iter()
            .any(|w| matches!(w.letter, 'X' | 'Z' | 'U' | 'W'));
        let name = self.dialect.name();
        let refuse = |text: &str, meaning: &str, mill: &str, at| {
            LineError::new(
                at,
                format!("`{text}` on a {name} lathe (G-code system A) is {meaning}, which mtsim does not read; it is not the mill's {mill}"),
                "lathe code",
            )
            .help("write the cycle out as G00/G01 moves (or G71/G70 for roughing and finishing); a program for G-code system B or C (G90 absolute, G94/G95 feeds) is not read: post it for system A")
        };
        for k in 0..b.g.len() {
            let (code, w) = b.g[k];
            let (meaning, mill) = match code {
                GCode::Distance(true) => (
                    "the outer/inner diameter turning cycle",
                    "absolute mode (a lathe moves incrementally with U and W)",
                ),
                GCode::NonModal(NonModal::G92) => (
                    "the threading cycle (the work coordinate system is set with G50 X Z)",
                    "coordinate shift",
                ),
                GCode::Feed(FeedRead::PerMinute) => (
                    "the end face turning cycle (feed per minute is G98)",
                    "feed per minute",
                ),
                GCode::Feed(FeedRead::PerRevolution) => {
                    return Err(refuse(&b.line[w.span()], "no G-code system A code (feed per revolution is G99; a Haas lathe's G95 is live-tool rigid tapping)", "feed per revolution", w.span()));
                }
                GCode::Motion(_) => {
                    self.lathe_cycle = None;
                    continue;
                }
                _ => continue,
            };
            let text = &b.line[w.span()];
            if axis_words {
                return Err(refuse(text, meaning, mill, w.span()));
            }
            self.lathe_cycle = Some(format!(
                "`{text}` ({meaning} in G-code system A), selected before this block"
            ));
            b.g.remove(k);
            return self.lathe_codes(b);
        }
        if let (Some(cycle), true) = (&self.lathe_cycle, axis_words && b.nonmodal().is_none()) {
            let at = b
                .words
                .iter()
                .find(|w| matches!(w.letter, 'X' | 'Z' | 'U' | 'W'))
                .map_or(0..b.line.len(), |w| w.span());
            return Err(LineError::new(at, format!("axis words with no motion code while the lathe cycle {cycle} is in effect: the control would run the cycle, which mtsim does not read"), "lathe cycle").help("put G00 or G01 in this block (a lathe's G90, G92 and G94 are cycles of the motion group)"));
        }
        let mut mapped = Vec::new();
        for k in (0..b.g.len()).rev() {
            let (code, w) = b.g[k];
            let lathe = match code {
                GCode::Retract(false) => GCode::Feed(FeedRead::PerMinute),
                GCode::Retract(true) => GCode::Feed(FeedRead::PerRevolution),
                GCode::Control(500) if axis_words => GCode::NonModal(NonModal::G92),
                _ => continue,
            };
            b.g.remove(k);
            mapped.push((lathe, w));
        }
        for m in mapped.into_iter().rev() {
            b.g.push(m);
        }
        Ok(())
    }
}
