//! Settable frames written by the program (Job planning, "Frames": "Assigning frame
//! variables", "Frame components", "Frame functions CTRANS, CROT, CSCALE, CMIRROR, CFINE"):
//! `$P_UIFR[n] = CTRANS(X,10,Y,20):CROT(Z,30)`, a component `$P_UIFR[n,X,TR] = 10`
//! (`TR` coarse offset, `FI` fine offset, `RT` rotation, `SC` scale, `MI` mirror), and the
//! programmable frame as a whole, `$P_PFRAME = CTRANS(..)`.
//!
//! A settable frame is the zero offset of `G54`-`G57` (n = 1-4), `G505`-`G599` (n = 5-99)
//! and `G500` (n = 0). A written frame is held here and becomes active when its G code is
//! programmed next (Job planning: a settable frame is activated by its G code; writing it
//! does not change the frame in effect). Then its offset (coarse + fine, program units)
//! becomes the interpreter's work offset of that system, and its rotation × scale × mirror
//! `S` turns every programmed point: the frame chain is `o_s + S (o_p + A_p p)`, so the
//! front end's frame is `(S o_p, S A_p)`.
//!
//! The components of a frame are applied as the control stores them: offset, then
//! rotation (`Rz Ry Rx` of the three angles, as `ROT`), then scale, then mirror. A chain
//! of frame functions is reduced to them: an offset after a rotation, scale or mirror is
//! turned into the frame before it; a rotation after another rotation, a scale or a mirror
//! is refused (its components would not be the control's).

use super::expr::{expr, Scan};
use super::frame::{Components, Instruction, ProgFrame, SETTABLE};
use super::Reader;
use crate::frame::{apply, mul, IDENTITY};
use crate::lex::LineResult;

/// The frame axis `X`, `Y` or `Z` at the cursor.
fn axis(sc: &mut Scan, what: &str) -> LineResult<usize> {
    let at = sc.at;
    match sc.ident() {
        Some(("X", _)) => Ok(0),
        Some(("Y", _)) => Ok(1),
        Some(("Z", _)) => Ok(2),
        Some((name, n_at)) => Err(sc.err(
            n_at,
            format!("`{name}` in {what}: mtsim's frames hold X, Y and Z (a rotary or other axis in a frame is not supported)"),
            "frame axis",
        )),
        None => Err(sc.err(at, format!("expected an axis X, Y or Z in {what}"), "frame axis")),
    }
}

impl Reader {
    /// `$P_UIFR[..] = ..` (the cursor after the name, on `[`).
    pub(super) fn settable_write(&mut self, sc: &mut Scan, at: usize) -> LineResult<()> {
        sc.eat(b'[');
        let n = expr(sc, &self.vars)?;
        if !(0.0..SETTABLE as f64).contains(&n) || n.fract() != 0.0 {
            return Err(sc.err(
                at,
                format!("`$P_UIFR[{n}]`: expected a settable frame 0 (G500) to 99 (G599)"),
                "settable frame",
            ));
        }
        let n = n as usize;
        let mut frame = self.settable_frame(n);
        if sc.eat(b',') {
            let k = axis(sc, "a frame component")?;
            if !sc.eat(b',') {
                return Err(sc.err(
                    at,
                    "expected `$P_UIFR[n, axis, TR|FI|RT|SC|MI]`",
                    "frame component",
                ));
            }
            let Some((part, p_at)) = sc.ident() else {
                return Err(sc.err(
                    at,
                    "expected a frame component TR, FI, RT, SC or MI",
                    "frame component",
                ));
            };
            let part = part.to_string();
            if !sc.eat(b']') || !sc.eat(b'=') {
                return Err(sc.err(
                    at,
                    "expected `$P_UIFR[n, axis, component] = value`",
                    "frame component",
                ));
            }
            let v = expr(sc, &self.vars)?;
            match part.as_str() {
                "TR" => frame.coarse[k] = v,
                "FI" => frame.fine[k] = v,
                "RT" => frame.angles[k] = v,
                "SC" if v != 0.0 && v.is_finite() => frame.scale[k] = v,
                "MI" => frame.mirror[k] = v != 0.0,
                "SC" => return Err(sc.err(p_at, "a scale of zero: expected a non-zero factor", "zero scale")),
                _ => {
                    return Err(sc.err(
                        p_at,
                        format!("frame component `{part}`: expected TR (offset), FI (fine offset), RT (rotation), SC (scale) or MI (mirror)"),
                        "frame component",
                    ))
                }
            }
        } else {
            if !sc.eat(b']') || !sc.eat(b'=') {
                return Err(sc.err(
                    at,
                    "expected `$P_UIFR[n] = CTRANS(..)` (a chain of frame functions)",
                    "settable frame",
                ));
            }
            frame = self.frame_chain(sc, at)?;
        }
        self.settable[n] = Some(frame);
        Ok(())
    }

    /// `$P_PFRAME = CTRANS(..):CROT(..)`: the programmable frame as a whole.
    pub(super) fn programmable_write(&mut self, sc: &mut Scan, at: usize) -> LineResult<()> {
        if !sc.eat(b'=') {
            return Err(sc.err(
                at,
                "expected `$P_PFRAME = CTRANS(..)` (a chain of frame functions)",
                "programmable frame",
            ));
        }
        let c = self.frame_chain(sc, at)?;
        self.prog = c.as_frame();
        self.refresh_frame();
        Ok(())
    }

    /// Settable frame `n` as the program last wrote it, or the offset the machine file or
    /// scenario gives its G code (no rotation).
    fn settable_frame(&self, n: usize) -> Components {
        if let Some(c) = self.settable[n] {
            return c;
        }
        let base = crate::interp::coord_parameter(settable_coord(n));
        let scale = self.interp.scale();
        let mut c = Components::default();
        for k in 0..3 {
            c.coarse[k] = self
                .interp
                .params
                .numbered
                .get(base + k)
                .copied()
                .unwrap_or(0.0)
                / scale;
        }
        c
    }

    /// A chain `F1(..):F2(..)…` of CTRANS, CFINE, CROT, CSCALE and CMIRROR, reduced to
    /// components (see the module doc).
    fn frame_chain(&mut self, sc: &mut Scan, at: usize) -> LineResult<Components> {
        let mut c = Components::default();
        let (mut rotated, mut scaled) = (false, false);
        loop {
            let Some((name, n_at)) = sc.ident() else {
                return Err(sc.err(
                    sc.at,
                    "expected a frame function CTRANS, CFINE, CROT, CSCALE or CMIRROR",
                    "frame function",
                ));
            };
            let name = name.to_string();
            if !matches!(
                name.as_str(),
                "CTRANS" | "CFINE" | "CROT" | "CSCALE" | "CMIRROR"
            ) {
                return Err(sc.err(
                    n_at,
                    format!("`{name}` in a frame assignment: mtsim reads the frame functions CTRANS, CFINE, CROT, CSCALE and CMIRROR (a frame variable or another function is not supported)"),
                    "frame function",
                ));
            }
            if !sc.eat(b'(') {
                return Err(sc.err(n_at, format!("expected `(` after {name}"), "frame function"));
            }
            let mut values = [None; 3];
            while !sc.eat(b')') {
                let k = axis(sc, &name)?;
                values[k] = Some(if name == "CMIRROR" {
                    1.0
                } else {
                    if !sc.eat(b',') {
                        return Err(sc.err(
                            n_at,
                            format!("expected `{name}(axis, value, ..)`"),
                            "frame function",
                        ));
                    }
                    expr(sc, &self.vars)?
                });
                if !sc.eat(b',') && sc.peek() != Some(b')') {
                    return Err(sc.err(
                        n_at,
                        format!("expected `,` or `)` in {name}"),
                        "frame function",
                    ));
                }
            }
            let v = values.map(|x| x.unwrap_or(0.0));
            match name.as_str() {
                "CTRANS" | "CFINE" => {
                    // An offset after a rotation, scale or mirror acts in that frame.
                    let d = apply(&c.matrix(), v);
                    let into = if name == "CFINE" {
                        &mut c.fine
                    } else {
                        &mut c.coarse
                    };
                    for (o, d) in into.iter_mut().zip(d) {
                        *o += d;
                    }
                }
                "CROT" => {
                    if rotated || scaled {
                        return Err(sc.err(
                            n_at,
                            "CROT after a CROT, CSCALE or CMIRROR in one frame chain: not supported (write the rotation once, before scale and mirror)",
                            "frame chain",
                        ));
                    }
                    rotated = true;
                    c.angles = v;
                }
                "CSCALE" => {
                    scaled = true;
                    for (k, s) in values.iter().enumerate() {
                        match s {
                            Some(s) if *s == 0.0 || !s.is_finite() => {
                                return Err(sc.err(
                                    n_at,
                                    "a scale of zero: expected non-zero factors",
                                    "zero scale",
                                ))
                            }
                            Some(s) => c.scale[k] *= s,
                            None => {}
                        }
                    }
                }
                _ => {
                    scaled = true;
                    for (k, m) in values.iter().enumerate() {
                        if m.is_some() {
                            c.mirror[k] = !c.mirror[k];
                        }
                    }
                }
            }
            if !sc.eat(b':') {
                break;
            }
        }
        if !sc.done() {
            return Err(sc.err(
                at,
                "expected the end of the block after the frame chain",
                "frame chain",
            ));
        }
        Ok(c)
    }

    /// G54-G57, G500, G505-G599 selects settable frame `n`: a frame the program wrote
    /// becomes the interpreter's work offset and its rotation turns the programmed points.
    pub(super) fn select_settable(&mut self, n: usize) {
        if let Some(c) = self.settable.get(n).copied().flatten() {
            let base = crate::interp::coord_parameter(settable_coord(n));
            let scale = self.interp.scale();
            for (k, o) in c.offset().iter().enumerate() {
                if let Some(slot) = self.interp.params.numbered.get_mut(base + k) {
                    *slot = o * scale;
                }
            }
            self.settable_matrix = c.matrix();
        } else {
            self.settable_matrix = IDENTITY;
        }
        self.refresh_frame();
    }

    /// The front end's frame: the settable frame's rotation × scale × mirror, then the
    /// programmable frame.
    pub(super) fn refresh_frame(&mut self) {
        let s = &self.settable_matrix;
        self.frame = ProgFrame {
            origin: apply(s, self.prog.origin),
            matrix: mul(s, &self.prog.matrix),
        };
    }

    /// A frame instruction (`TRANS`, `AROT` ...) on the programmable frame.
    pub(super) fn programmable(&mut self, i: Instruction, additive: bool) {
        self.prog.apply(i, additive);
        self.refresh_frame();
    }
}

/// The interpreter's work system of settable frame `n`: G54-G57 are 1-4, G505-G599 its
/// extended offsets 1-95 (`G54.1 P1`…), G500 extended offset 96.
pub(super) fn settable_coord(n: usize) -> u32 {
    match n {
        0 => 9 + 96,
        1..=4 => n as u32,
        _ => 9 + (n as u32 - 4),
    }
}
