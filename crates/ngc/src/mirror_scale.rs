//! Programmable mirror image and scaling (Fanuc G51.1/G50.1 and G51/G50, Haas G101/G100
//! and G51/G50), as a map of the program's X Y Z words before the interpreter reads them.
//!
//! Each axis `a` of X Y Z maps a programmed coordinate `v` to
//!
//! ```text
//! mirror about m:        u = 2 m − v
//! then scale about c:    v' = c + s (u − c)
//! together:              v' = k v + b,   k = ±s (− when mirrored),  b = c (1 − s) or c + s (2m − c)
//! ```
//!
//! An absolute word becomes `k v + b`, an increment (G91, an arc's I J K) `k v`, an arc's R
//! `|k| R`. Where the map turns the plane over (`k_u k_v < 0` for the plane's two axes) an
//! arc runs the other way and the cutter is on the other side: G2 and G3, G41 and G42 swap
//! (Fanuc 0i-MF B-64604EN, "Programmable mirror image (G50.1, G51.1)" and "Scaling (G50,
//! G51)": the mirror acts first, then the scaling; Haas mill operator's manual, "G100/G101
//! Mirror Image", "G50/G51 Scaling"). The factor P (or I J K per axis) is in 0.001 when
//! written without a decimal point (Fanuc parameter 5400#7 = 0). Not mapped: Q (a peck's
//! depth, which Fanuc does not scale), offsets and machine coordinates (G10, G52, G53, G92),
//! a dwell's X, and the arguments of G65/G66.

use crate::axis::Plane;
use crate::lex::{LineError, LineResult, Word};

/// One axis's map `v' = k v + b` and how it was made.
#[derive(Clone, Copy, Debug, PartialEq)]
struct AxisMap {
    mirror_at: Option<f64>,
    scale: f64,
    centre: f64,
}

impl AxisMap {
    const IDENTITY: AxisMap = AxisMap {
        mirror_at: None,
        scale: 1.0,
        centre: 0.0,
    };

    /// `(k, b)` of `v' = k v + b`.
    fn linear(&self) -> (f64, f64) {
        let (s, c) = (self.scale, self.centre);
        match self.mirror_at {
            None => (s, c * (1.0 - s)),
            Some(m) => (-s, c + s * (2.0 * m - c)),
        }
    }

    fn is_identity(&self) -> bool {
        self.mirror_at.is_none() && self.scale == 1.0
    }
}

/// The modal state a block's words are mapped in.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Context {
    /// G90 for this block (its own G90/G91 first).
    pub absolute: bool,
    /// The arc plane for this block.
    pub plane: Plane,
    /// G2 or G3 is the modal motion before this block.
    pub arc_modal: bool,
    /// A canned cycle is the modal motion before this block.
    pub cycle_modal: bool,
}

/// The mirror image and scaling in effect.
#[derive(Clone, Debug)]
pub(crate) struct MirrorScale {
    axes: [AxisMap; 3],
    /// The plane was turned over when the modal G2/G3 was last written.
    arc_written_flipped: bool,
}

impl Default for MirrorScale {
    fn default() -> Self {
        MirrorScale {
            axes: [AxisMap::IDENTITY; 3],
            arc_written_flipped: false,
        }
    }
}

/// The G code of a word, ×10 (`G51.1` is 511), when it is written as a number.
fn code(w: &Word) -> Option<u32> {
    w.g_tenths()
}

const XYZ: [char; 3] = ['X', 'Y', 'Z'];

impl MirrorScale {
    /// A mirror image or a scaling is in effect.
    pub(crate) fn active(&self) -> bool {
        self.axes.iter().any(|a| !a.is_identity())
    }

    /// A scaling (a factor other than 1 on an axis) is in effect.
    pub(crate) fn scaling(&self) -> bool {
        self.axes.iter().any(|a| a.scale != 1.0)
    }

    /// Reads a block that sets or cancels the mirror image or the scaling (G51.1 / G50.1,
    /// Haas G101 / G100; G51 / G50 without S) into the state: `Ok(true)` when the block was
    /// one (it moves nothing), `Ok(false)` otherwise.
    pub(crate) fn command(
        &mut self,
        line: &str,
        words: &[Word],
        haas: bool,
        program_xyz: impl Fn() -> [f64; 3],
    ) -> LineResult<bool> {
        let Some(g) = words
            .iter()
            .find(|w| matches!(code(w), Some(500 | 510 | 511 | 501 | 1000 | 1010)))
        else {
            return Ok(false);
        };
        let c = code(g).unwrap_or(0);
        let (mirror_on, mirror_off) = if haas { (1010, 1000) } else { (511, 501) };
        if c == 500 && words.iter().any(|w| w.letter == 'S') {
            // G50 S: a lathe's spindle speed limit, not the scaling cancel.
            return Ok(false);
        }
        if (c == 1000 || c == 1010) && !haas || (c == 501 || c == 511) && haas {
            return Ok(false);
        }
        let letters_ok = |allowed: &[char]| {
            words
                .iter()
                .find(|w| !allowed.contains(&w.letter) && !std::ptr::eq(*w, g) && w.letter != 'N')
        };
        let bad = |w: &Word, what: &str| {
            let own = if w.letter == 'G' || w.letter == 'M' {
                format!(
                    "`{}` in a block of its own (as the manuals ask), with",
                    &line[g.span()]
                )
            } else {
                "only".to_string()
            };
            Err(LineError::new(
                w.span(),
                format!(
                    "`{}` in a `{}` block: expected {own} {what}",
                    &line[w.span()],
                    &line[g.span()]
                ),
                "not a word of the block",
            ))
        };
        let given = |l: char| words.iter().find(|w| w.letter == l).map(|w| w.value);
        if c == mirror_on {
            if let Some(w) = letters_ok(&XYZ) {
                return bad(w, "X Y Z, the positions of the mirror axes");
            }
            for (k, l) in XYZ.into_iter().enumerate() {
                if let Some(m) = given(l) {
                    self.axes[k].mirror_at = Some(m);
                }
            }
        } else if c == mirror_off {
            if let Some(w) = letters_ok(&XYZ) {
                return bad(w, "X Y Z, the axes whose mirror image ends");
            }
            let any = XYZ.iter().any(|&l| given(l).is_some());
            for (k, l) in XYZ.into_iter().enumerate() {
                if !any || given(l).is_some() {
                    self.axes[k].mirror_at = None;
                }
            }
        } else if c == 510 {
            if let Some(w) = letters_ok(&['X', 'Y', 'Z', 'P', 'I', 'J', 'K']) {
                return bad(w, "X Y Z (the centre) and P or I J K (the factors)");
            }
            let factor = |l: char| {
                words.iter().find(|w| w.letter == l).map(|w| {
                    if w.computed() || w.number.contains('.') {
                        w.value
                    } else {
                        w.value * 0.001
                    }
                })
            };
            let p = factor('P');
            let per_axis = [factor('I'), factor('J'), factor('K')];
            if p.is_none() && per_axis.iter().all(Option::is_none) {
                return Err(LineError::new(
                    g.span(),
                    format!("`{}` without P or I J K: the factor is then the control's setting (Fanuc parameter 5411, Haas Setting 71), which a program does not carry", &line[g.span()]),
                    "no scaling factor",
                )
                .help("write the factor as P, e.g. `G51 X0. Y0. P2.` for twice the size"));
            }
            let here = program_xyz();
            for k in 0..3 {
                let s = per_axis[k].or(p).unwrap_or(1.0);
                if s == 0.0 || !s.is_finite() {
                    return Err(LineError::new(
                        g.span(),
                        format!("scaling factor {s}: expected a factor other than zero"),
                        "zero scaling factor",
                    ));
                }
                self.axes[k].scale = s;
                self.axes[k].centre = given(XYZ[k]).unwrap_or(here[k]);
            }
        } else {
            // G50: the scaling ends.
            if let Some(w) = letters_ok(&[]) {
                return bad(w, "no other word (G50 cancels the scaling)");
            }
            for a in &mut self.axes {
                a.scale = 1.0;
                a.centre = 0.0;
            }
        }
        Ok(true)
    }

    /// A block read while nothing is mapped: a G2/G3 written in it is written unflipped.
    pub(crate) fn note_unmapped(&mut self, words: &[Word]) {
        if self.arc_written_flipped && words.iter().any(|w| matches!(code(w), Some(20 | 30))) {
            self.arc_written_flipped = false;
        }
    }

    /// Maps the X Y Z, I J K and R words of a block in `context`, and swaps G2/G3 and
    /// G41/G42 where the plane is turned over.
    pub(crate) fn apply(
        &mut self,
        line: &str,
        words: &mut [Word],
        context: Context,
    ) -> LineResult<()> {
        let codes: Vec<u32> = words.iter().filter_map(code).collect();
        let has = |c: u32| codes.contains(&c);
        // Offsets, machine coordinates, a dwell and macro arguments are not mapped.
        if [40, 100, 520, 530, 920, 650, 660, 661, 280, 300]
            .iter()
            .any(|&c| has(c))
        {
            return Ok(());
        }
        if let Some(w) = words
            .iter()
            .find(|w| matches!(code(w), Some(680 | 682 | 1870)))
        {
            return Err(LineError::new(
                w.span(),
                format!("`{}` while a mirror image or scaling is in effect: mtsim does not combine them; expected G50.1/G50 (G100) first", &line[w.span()]),
                "rotation under a mirror or scaling",
            ));
        }
        let absolute = if has(910) {
            false
        } else if has(900) {
            true
        } else {
            context.absolute
        };
        let plane = if has(170) {
            Plane::XY
        } else if has(180) {
            Plane::ZX
        } else if has(190) {
            Plane::YZ
        } else {
            context.plane
        };
        let (u, v) = match plane {
            Plane::XY => (0, 1),
            Plane::ZX => (2, 0),
            Plane::YZ => (1, 2),
        };
        let lin = self.axes.map(|a| a.linear());
        let flipped = lin[u].0 * lin[v].0 < 0.0;
        let arc_written = has(20) || has(30);
        let motion_written = [0, 10, 20, 30].iter().any(|&c| has(c))
            || codes.iter().any(|&c| (730..=890).contains(&c));
        let arc = arc_written || (context.arc_modal && !motion_written);
        let cycle = codes.iter().any(|&c| (730..=890).contains(&c) && c != 800)
            || (context.cycle_modal && !motion_written);
        if arc {
            if lin[u].0.abs() != lin[v].0.abs() {
                return Err(LineError::new(
                    0..line.len(),
                    format!("an arc under different scale factors on the plane's axes ({} and {}): the control does not cut an ellipse; expected equal factors", lin[u].0.abs(), lin[v].0.abs()),
                    "arc under unequal scaling",
                ));
            }
            if !arc_written && flipped != self.arc_written_flipped {
                return Err(LineError::new(
                    0..line.len(),
                    "a modal G2/G3 across a change of the mirror image: expected G2 or G3 written again after G51.1/G50.1 (G101/G100)",
                    "modal arc across a mirror",
                ));
            }
        }
        if arc_written {
            self.arc_written_flipped = flipped;
        }
        for w in words.iter_mut() {
            match w.letter {
                'X' | 'Y' | 'Z' => {
                    let (k, b) = lin[XYZ.iter().position(|&l| l == w.letter).unwrap_or(0)];
                    w.value = if absolute {
                        k * w.value + b
                    } else {
                        k * w.value
                    };
                }
                'I' | 'J' | 'K' if arc => {
                    let (k, _) = lin[(w.letter as u8 - b'I') as usize];
                    w.value *= k;
                }
                'R' if arc => w.value *= lin[u].0.abs(),
                'R' if cycle => {
                    // A canned cycle's R level, a Z coordinate (an increment in G91).
                    let (k, b) = lin[2];
                    w.value = if absolute {
                        k * w.value + b
                    } else {
                        k * w.value
                    };
                }
                'G' if flipped => {
                    let swapped = match code(w) {
                        Some(20) => 3.0,
                        Some(30) => 2.0,
                        Some(410) => 42.0,
                        Some(420) => 41.0,
                        _ => continue,
                    };
                    w.value = swapped;
                }
                _ => {}
            }
        }
        Ok(())
    }
}
