//! Fanuc and Haas polar coordinate command: G16 on, G15 off (Fanuc 0i-MF operator's manual,
//! "Polar coordinate command (G15, G16)"), as a map of a block's words before the
//! interpreter reads them.
//!
//! In G16 the first axis word of the plane (X in G17, Z in G18, Y in G19) is a radius and
//! the second (Y, X, Z) an angle in deg, counter-clockwise from the first axis. With
//! `(u, v)` the current point in program coordinates (the work or G52 local origin at 0)
//! and `r0 = hypot(u, v)`, `a0 = atan2(v, u)`:
//!
//! ```text
//! G90:  radius r, angle a     → (r cos a, r sin a)        about the work (local) origin
//!       angle only            → r = r0                    (bolt holes: `G16 G81 X50. Y0.`, `Y60.`)
//!       radius only           → a = a0
//! G91:  angle da, no radius   → r = r0, a = a0 + da       about the work (local) origin
//!       with a radius         → refused: the current point as the pole, and the angle's
//!                               reference there, are not modelled
//! ```
//!
//! The block then carries both Cartesian words (absolute under G90, the increments under
//! G91). Not mapped (their words stay Cartesian, as the manual lists): G04, G10, G28/G30,
//! G50.1/G51.1, G51, G52, G53, G65/G66, G68, G92. Refused: G16 with a mirror image or
//! scaling in effect, and a G91 canned cycle with repeats (K/L) in G16.

use crate::axis::Plane;
use crate::lex::{LineError, LineResult, Word};

/// The modal state a block is mapped in (its own G90/G91 and plane first).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Context {
    pub absolute: bool,
    pub plane: Plane,
    /// The current point in program coordinates, X Y Z.
    pub position: [f64; 3],
    /// A canned cycle is the modal motion before this block.
    pub cycle_modal: bool,
    /// A mirror image or scaling is in effect.
    pub mirror_scale: bool,
}

/// G16 is in effect.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct FanucPolar {
    pub on: bool,
}

/// The G code of a word ×10, when written as a number.
fn code(w: &Word) -> Option<u32> {
    w.g_tenths()
}

/// Codes whose axis words are not polar (×10).
const NOT_MAPPED: [u32; 14] = [
    40, 100, 280, 300, 501, 511, 510, 520, 530, 650, 660, 680, 920, 290,
];

impl FanucPolar {
    /// Takes G15 / G16 out of `words` and sets the state (the last one written wins).
    pub(crate) fn command(&mut self, words: &mut Vec<Word>) {
        // Nearly every block has neither: then nothing to take out.
        if !words.iter().any(|w| matches!(code(w), Some(150 | 160))) {
            return;
        }
        words.retain(|w| match code(w) {
            Some(150) => {
                self.on = false;
                false
            }
            Some(160) => {
                self.on = true;
                false
            }
            _ => true,
        });
    }

    /// Maps the plane's radius and angle words to Cartesian words while G16 is in effect.
    pub(crate) fn apply<'l>(
        &self,
        line: &str,
        words: &mut Vec<Word<'l>>,
        c: Context,
    ) -> LineResult<()> {
        if !self.on {
            return Ok(());
        }
        let (u, v, _) = c.plane.axes();
        let (ul, vl) = (u.letter(), v.letter());
        let find = |l: char| words.iter().position(|w| w.letter == l);
        let (ku, kv) = (find(ul), find(vl));
        let Some(first) = ku.or(kv).map(|k| words[k]) else {
            return Ok(());
        };
        if words
            .iter()
            .filter_map(code)
            .any(|g| NOT_MAPPED.contains(&g))
        {
            return Ok(());
        }
        let err = |m: String| LineError::new(first.span(), m, "polar coordinate (G16)");
        if c.mirror_scale {
            return Err(err(
                "polar coordinates (G16) with a mirror image or scaling in effect: not read; expected G50.1/G50 before G16".into(),
            ));
        }
        let cycle = c.cycle_modal
            || words
                .iter()
                .filter_map(code)
                .any(|g| matches!(g, 730 | 740 | 760 | 810..=890));
        let mut absolute = c.absolute;
        for g in words.iter().filter_map(code) {
            match g {
                900 => absolute = true,
                910 => absolute = false,
                _ => {}
            }
        }
        let repeats = words
            .iter()
            .any(|w| matches!(w.letter, 'K' | 'L') && w.value > 1.0);
        if !absolute && cycle && repeats {
            return Err(err(
                "a G91 canned cycle with repeats (K/L) in polar coordinates (G16): not read; expected one block per hole".into(),
            ));
        }
        let p = [c.position[u.index()], c.position[v.index()]];
        let (r0, a0) = (p[0].hypot(p[1]), p[1].atan2(p[0]).to_degrees());
        let radius = ku.map(|k| words[k].value);
        let angle = kv.map(|k| words[k].value);
        let (r, a) = if absolute {
            (radius.unwrap_or(r0), angle.unwrap_or(a0))
        } else {
            if radius.is_some() {
                return Err(err(format!(
                    "`{}`: an incremental (G91) polar radius (the current point as the pole) is not read; expected G90 radii from the work origin",
                    &line[first.span()]
                )));
            }
            (r0, a0 + angle.unwrap_or(0.0))
        };
        let a = a.to_radians();
        let xy = [r * a.cos(), r * a.sin()];
        for (k, (letter, at)) in [(ul, ku), (vl, kv)].into_iter().enumerate() {
            let value = if absolute { xy[k] } else { xy[k] - p[k] };
            let w = Word {
                letter,
                value,
                number: "",
                span: first.span,
            };
            match at {
                Some(i) => {
                    words[i] = Word {
                        span: words[i].span,
                        ..w
                    }
                }
                None => words.push(w),
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn w(letter: char, value: f64) -> Word<'static> {
        Word {
            letter,
            value,
            number: "1.",
            span: (0, 1),
        }
    }

    fn ctx(absolute: bool, position: [f64; 3]) -> Context {
        Context {
            absolute,
            plane: Plane::XY,
            position,
            cycle_modal: false,
            mirror_scale: false,
        }
    }

    fn value(words: &[Word], l: char) -> f64 {
        words
            .iter()
            .find(|w| w.letter == l)
            .map(|w| w.value)
            .unwrap()
    }

    #[test]
    fn radius_and_angle_are_r_cos_a_and_r_sin_a_about_the_work_origin() {
        let mut p = FanucPolar::default();
        let mut words = vec![w('G', 16.0)];
        p.command(&mut words);
        assert!(p.on && words.is_empty());
        let mut words = vec![w('G', 1.0), w('X', 50.0), w('Y', 30.0)];
        p.apply("", &mut words, ctx(true, [7.0, 8.0, 0.0])).unwrap();
        assert!((value(&words, 'X') - 25.0 * 3f64.sqrt()).abs() < 1e-12);
        assert!((value(&words, 'Y') - 25.0).abs() < 1e-12);
        // Angle only: the radius of the current point (30, 40) is 50; 90° → (0, 50).
        let mut words = vec![w('Y', 90.0)];
        p.apply("", &mut words, ctx(true, [30.0, 40.0, 0.0]))
            .unwrap();
        assert!(value(&words, 'X').abs() < 1e-12);
        assert!((value(&words, 'Y') - 50.0).abs() < 1e-12);
        // G91 angle: from 0° at radius 10 by 120° → (−5, 5√3), as increments from (10, 0).
        let mut words = vec![w('G', 91.0), w('Y', 120.0)];
        p.apply("", &mut words, ctx(true, [10.0, 0.0, 0.0]))
            .unwrap();
        assert!((value(&words, 'X') + 15.0).abs() < 1e-12);
        assert!((value(&words, 'Y') - 5.0 * 3f64.sqrt()).abs() < 1e-12);
        // G91 radius: refused.
        let mut words = vec![w('X', 5.0)];
        assert!(p
            .apply("X", &mut words, ctx(false, [10.0, 0.0, 0.0]))
            .is_err());
        // G52's words stay Cartesian.
        let mut words = vec![w('G', 52.0), w('X', 5.0)];
        p.apply("", &mut words, ctx(true, [0.0; 3])).unwrap();
        assert_eq!(words.len(), 2);
        assert_eq!(value(&words, 'X'), 5.0);
        let mut words = vec![w('G', 15.0)];
        p.command(&mut words);
        assert!(!p.on);
    }
}
