//! LinuxCNC polar coordinates: `@` (radius) and `^` (angle, deg) as X and Y words of the
//! XY plane, absolute from the work origin or incremental from the current point.

use super::Interp;
use crate::axis::{Axis, Plane};
use crate::code::{MotionMode, NonModal};
use crate::lex::{LineError, LineResult, Word};
use crate::polar::Polar;

impl Interp {
    /// Checks the polar words of a block (where LinuxCNC refuses them, measured with rs274)
    /// and turns them into X and Y words in `xy_out`. Returns true when they are left for a G91 canned
    /// cycle to apply at each repeat.
    pub(super) fn polar_words<'l>(
        &self,
        line: &str,
        pw: &Word<'l>,
        get: &dyn Fn(char) -> Option<Word<'l>>,
        nonmodal: Option<(NonModal, Word<'l>)>,
        xy_out: &mut [Option<Word<'l>>; 2],
    ) -> LineResult<bool> {
        let err = |m: &str| LineError::new(pw.span(), m.to_string(), "polar coordinate");
        if !self.dialect.table().polar_words {
            return Err(err(
                "polar coordinates `@` `^` in a Fanuc-family program: expected X and Y",
            )
            .help("polar coordinates are a LinuxCNC feature; set dialect = \"linuxcnc\""));
        }
        if let Some(xy) = get('X').or(get('Y')) {
            return Err(LineError::new(
                xy.span(),
                format!(
                    "`{}` with polar coordinates: expected either X Y or `@` `^`",
                    &line[xy.span()]
                ),
                "X or Y with polar",
            ));
        }
        if self.plane != Plane::XY {
            return Err(err(
                "polar coordinates outside G17: expected the XY plane (G17)",
            ));
        }
        if !self.axes[Axis::X.index()] || !self.axes[Axis::Y.index()] {
            return Err(err("polar coordinates on a machine without X and Y axes"));
        }
        if self.frame().is_some() {
            return Err(err(
                "polar coordinates with G68.2 or G254 active: not supported",
            ));
        }
        match nonmodal {
            Some((NonModal::G53, _)) => {
                return Err(err("polar coordinates with G53: expected program coordinates (LinuxCNC: \"Cannot use polar coordinates with G53\")"));
            }
            Some((NonModal::G10 | NonModal::G92 | NonModal::G52, w)) => {
                return Err(err(&format!(
                    "polar coordinates with `{}`: expected `@` `^` only for a move",
                    &line[w.span()]
                )));
            }
            _ => {}
        }
        let polar = Polar {
            radius: get('@').map(|w| w.value),
            angle_deg: get('^').map(|w| w.value),
        };
        if !self.absolute && matches!(self.motion, Some(MotionMode::Cycle(_))) && nonmodal.is_none()
        {
            return Ok(true);
        }
        let p = self.program_position();
        let cur = [p[Axis::X], p[Axis::Y]];
        let xy = if self.absolute {
            polar.absolute(cur)
        } else {
            polar.incremental(cur)
        }
        .map_err(err)?;
        for (k, letter) in ['X', 'Y'].into_iter().enumerate() {
            xy_out[k] = Some(Word {
                letter,
                value: if self.absolute { xy[k] } else { xy[k] - cur[k] },
                number: "",
                span: pw.span,
            });
        }
        Ok(false)
    }
}
