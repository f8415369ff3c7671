//! Polar coordinates (Fundamentals, "Polar coordinates": "Reference point for polar
//! coordinates (G110, G111, G112)", "Travel commands with polar coordinates (G0, G1, G2,
//! G3, AP, RP)"). The pole lies in the working plane, in the programmed (frame)
//! coordinates: `G111` gives it absolute, `G110` relative to the last programmed point,
//! `G112` relative to the last pole, each in a block of its own; before any, the pole is
//! the zero point. `AP=` (polar angle, deg, from the plane's first axis: X in G17, Z in
//! G18, Y in G19, counter-clockwise about the plane's normal) and `RP=` (polar radius) are
//! modal; `=IC(..)` adds to the last value. A move with AP or RP goes to
//! `pole + RP (cos AP, sin AP)` in the plane; an arc G2/G3 so given turns about the pole.

use super::words::{Coordinate, Mode, Words};
use super::Reader;
use crate::axis::Axis;
use crate::lex::{LineError, LineResult};

impl Reader {
    /// A pole block (G110-G112) sets the pole and moves nothing (`Ok(true)`); a block with
    /// AP= or RP= gets its in-plane target (and an arc's centre) as absolute coordinates.
    pub(super) fn polar(&mut self, w: &mut Words) -> LineResult<bool> {
        let (u, v) = ((self.normal + 1) % 3, (self.normal + 2) % 3);
        if let Some((code, span)) = w.pole.clone() {
            if w.polar.iter().any(Option::is_some) || w.motion.is_some() {
                return Err(LineError::new(span, format!("G{code} with AP=/RP= or a motion code: expected the pole alone, as `G{code} X.. Y..` in the plane's axes (a pole given in polar coordinates is not supported)"), "pole"));
            }
            let p = self.interp.program_position();
            let here = self.frame.frame_point([p[Axis::X], p[Axis::Y], p[Axis::Z]]);
            let base = match code {
                110 => here,
                111 => [0.0; 3],
                _ => self.pole,
            };
            for k in [u, v] {
                let value = w.axes[k].as_ref().map(|c| c.value);
                self.pole[k] = match (code, value) {
                    (111, Some(x)) => x,
                    (_, Some(x)) => base[k] + x,
                    (_, None) => base[k],
                };
            }
            w.axes = Default::default();
            return Ok(true);
        }
        if w.polar.iter().all(Option::is_none) {
            return Ok(false);
        }
        for (k, c) in w.polar.iter().enumerate() {
            if let Some(c) = c {
                if c.mode == Mode::Modal && !self.absolute {
                    return Err(LineError::new(c.span.clone(), "AP=/RP= under G91: not supported (whether the value is incremental depends on the word); write `AP=IC(..)` or program them under G90", "polar under G91"));
                }
                self.polar_values[k] = match c.mode {
                    Mode::Incremental => self.polar_values[k] + c.value,
                    _ => c.value,
                };
            }
        }
        let span = w
            .polar
            .iter()
            .flatten()
            .map(|c| c.span.clone())
            .next()
            .unwrap_or(0..0);
        if w.axes[u].is_some() || w.axes[v].is_some() || w.cr.is_some() {
            return Err(LineError::new(span, "AP=/RP= with an axis of the working plane or CR= in the same block: expected the plane's point by its polar coordinates alone", "polar and Cartesian"));
        }
        let [ap, rp] = self.polar_values;
        let (s, c) = ap.to_radians().sin_cos();
        let at = |value: f64| Coordinate {
            value,
            mode: Mode::Absolute,
            raw: None,
            span: span.clone(),
        };
        w.axes[u] = Some(at(self.pole[u] + rp * c));
        w.axes[v] = Some(at(self.pole[v] + rp * s));
        let arc = matches!(w.motion.unwrap_or(self.motion), 2 | 3);
        if arc {
            w.centres = Default::default();
            w.centres[u] = Some(at(self.pole[u]));
            w.centres[v] = Some(at(self.pole[v]));
        }
        Ok(false)
    }
}
