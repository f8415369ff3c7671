//! The map of the X Y Z, I J K and R words the front end emits under cycles 8, 11 and 26
//! (`transform`), before the interpreter reads them: `v' = k v + b` per axis, G2/G3 and
//! G41.1/G42.1 swapped where a plane is turned over, an arc refused where its plane's axes
//! scale differently.

use crate::lex::{LineError, LineResult, Word};

/// The mirror image and scaling in effect.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Map {
    /// Cycle 8: X, Y mirrored about the datum.
    pub(super) mirror: [bool; 2],
    /// Cycle 11: SCL.
    pub(super) scl: f64,
    /// Cycle 26: the factors of X Y Z and the centre.
    pub(super) factor: [f64; 3],
    pub(super) centre: [f64; 3],
}

impl Default for Map {
    fn default() -> Self {
        Map {
            mirror: [false; 2],
            scl: 1.0,
            factor: [1.0; 3],
            centre: [0.0; 3],
        }
    }
}

impl Map {
    fn identity(&self) -> bool {
        *self == Map::default()
    }

    /// `(k, b)` of `v' = k v + b` for X, Y, Z.
    fn linear(&self) -> [(f64, f64); 3] {
        std::array::from_fn(|a| {
            let (f, c) = (self.factor[a], self.centre[a]);
            let m = if a < 2 && self.mirror[a] { -1.0 } else { 1.0 };
            (m * self.scl * f, m * self.scl * c * (1.0 - f))
        })
    }

    /// One of X, Y is mirrored: the plane X Y is turned over (and cycle 10 turns the
    /// other way).
    pub(super) fn flips_xy(&self) -> bool {
        self.mirror[0] != self.mirror[1]
    }

    /// The program position of an interpreter position (the inverse map).
    pub(super) fn inverse(&self, p: [f64; 3]) -> [f64; 3] {
        let lin = self.linear();
        std::array::from_fn(|a| (p[a] - lin[a].1) / lin[a].0)
    }

    /// The uniform factor of X and Y (the tool radius's divisor in the milling cycles), or
    /// `None` where X and Y scale differently.
    pub(super) fn xy_factor(&self) -> Option<f64> {
        let lin = self.linear();
        (lin[0].0.abs() == lin[1].0.abs()).then_some(lin[0].0.abs())
    }

    /// Maps one interpreter block's words (`text` the Klartext block, for spans).
    pub(super) fn apply(&self, words: &mut [Word]) -> LineResult<()> {
        if self.identity() {
            return Ok(());
        }
        let has = |c: &str| words.iter().any(|w| w.letter == 'G' && w.number == c);
        // Frames, machine coordinates, the reference point, a dwell: not mapped.
        if ["52", "68.2", "69", "53", "53.1", "28", "4", "10", "92"]
            .iter()
            .any(|c| has(c))
        {
            return Ok(());
        }
        let (u, v) = if has("18") {
            (2, 0)
        } else if has("19") {
            (1, 2)
        } else {
            (0, 1)
        };
        let lin = self.linear();
        let arc = has("2") || has("3");
        if arc && lin[u].0.abs() != lin[v].0.abs() {
            let span = words.first().map_or(0..0, |w| w.span.0..w.span.1);
            return Err(LineError::new(span, format!("an arc in a plane whose axes are scaled by different factors ({} and {}, cycle 26): the TNC does not cut an ellipse (TNC 640 cycle programming manual, \"Cycle 26\"): expected equal factors on the arc's axes", lin[u].0.abs(), lin[v].0.abs()), "arc under unequal scaling"));
        }
        let absolute = !has("91");
        let flipped = lin[u].0 * lin[v].0 < 0.0;
        let comp_flipped = lin[0].0 * lin[1].0 < 0.0;
        for w in words.iter_mut() {
            match w.letter {
                'X' | 'Y' | 'Z' => {
                    let (k, b) = lin[(w.letter as u8 - b'X') as usize];
                    w.value = if absolute {
                        k * w.value + b
                    } else {
                        k * w.value
                    };
                }
                'I' | 'J' | 'K' if arc => w.value *= lin[(w.letter as u8 - b'I') as usize].0,
                'R' if arc => w.value *= lin[u].0.abs(),
                'G' => {
                    let swapped = match w.number {
                        "2" if flipped => "3",
                        "3" if flipped => "2",
                        "41.1" if comp_flipped => "42.1",
                        "42.1" if comp_flipped => "41.1",
                        _ => continue,
                    };
                    w.number = swapped;
                    w.value = swapped.parse().unwrap_or(w.value);
                }
                _ => {}
            }
        }
        Ok(())
    }
}
