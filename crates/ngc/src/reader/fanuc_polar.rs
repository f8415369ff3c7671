//! Fanuc and Haas G16 / G15 polar coordinates in the reader's stream (the map is
//! crate::fanuc_polar): G15 and G16 leave the block, and while G16 is in effect the plane's
//! radius and angle words become Cartesian ones before mirror image and scaling.

use crate::axis::{Axis, Plane};
use crate::fanuc_polar::Context;
use crate::lex::{LineResult, Word};

use super::state::IsoReader;

impl IsoReader {
    /// The letter of the polar angle word when G16 is in effect for the block's words (its
    /// own G15 / G16 first), for their least input increment (0.001°, not a length's).
    pub(super) fn polar_angle_letter(&self, words: &[Word]) -> Option<char> {
        let mut on = self.fanuc_polar.on;
        for w in words.iter().filter(|w| w.letter == 'G') {
            if w.value == 15.0 {
                on = false;
            } else if w.value == 16.0 {
                on = true;
            }
        }
        let (_, v, _) = self.interp.mirror_scale_context().plane.axes();
        on.then(|| v.letter())
    }

    /// Reads G15 / G16 (`codes`: the block may hold one) and maps the block: true when
    /// nothing is left of it.
    pub(super) fn fanuc_polar_block(
        &mut self,
        line: &str,
        words: &mut Vec<Word>,
        codes: bool,
    ) -> LineResult<bool> {
        if codes {
            self.fanuc_polar.command(words);
        }
        if words.is_empty() {
            return Ok(true);
        }
        if !self.fanuc_polar.on {
            return Ok(false);
        }
        let m = self.interp.mirror_scale_context();
        let plane = words
            .iter()
            .rev()
            .find_map(|w| match (w.letter, w.value) {
                ('G', v) if v == 17.0 => Some(Plane::XY),
                ('G', v) if v == 18.0 => Some(Plane::ZX),
                ('G', v) if v == 19.0 => Some(Plane::YZ),
                _ => None,
            })
            .unwrap_or(m.plane);
        let p = self.interp.program_position();
        let context = Context {
            absolute: m.absolute,
            plane,
            position: [p[Axis::X], p[Axis::Y], p[Axis::Z]],
            cycle_modal: m.cycle_modal,
            mirror_scale: self.mirror_scale.active(),
        };
        self.fanuc_polar.apply(line, words, context)?;
        Ok(false)
    }
}
