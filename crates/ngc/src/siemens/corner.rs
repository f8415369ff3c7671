//! Chamfers and roundings between two G1 lines (Fundamentals, "Chamfer, rounding (CHF,
//! CHR, RND, RNDM, FRC, FRCM)"): the word stands in the block whose line ends at the
//! corner, and the element is inserted between that line and the next block's line.
//!
//! * `RND=r`: an arc of radius r tangent to both lines (as Fanuc's `,R`; the geometry is
//!   `crate::corner`, tangent points `r tan(θ/2)` from the corner, θ the turn).
//! * `CHR=c`: a chamfer whose legs, along each line from the corner, are c long (as
//!   Fanuc's `,C`).
//! * `CHF=l`: a chamfer l long: its legs are `l / (2 cos(θ/2))` (the isosceles triangle of
//!   the corner, apex angle 180° − θ).
//! * `RNDM=r`: RND=r at the end of this and every later line until `RNDM=0`.
//!
//! The line is held until the next block's first move is known (blocks without a move in
//! between are passed over). Refused, naming the word: the word in a block whose last move
//! is not a G1 line, a next move that is not a G1 line in the plane (an arc, a rapid, a
//! move off the plane: mtsim inserts elements only between two lines), an element longer
//! than either line, a frame that scales the plane unevenly or tilts it, cutter radius
//! compensation on, and a program that ends before the next move.

use super::expr::{expr, Scan};
use super::state::{CornerKind, CornerWord, Held};
use super::words::Words;
use super::Reader;
use crate::axis::{Axis, Plane};
use crate::corner::{join, Pending};
use crate::lex::{LineError, LineResult};

impl Reader {
    /// `CHF=`, `CHR=`, `RND=` or `RNDM=` (`name`) at `at`, the cursor after the name.
    pub(super) fn corner_word(
        &mut self,
        name: &str,
        at: usize,
        sc: &mut Scan,
        w: &mut Words,
    ) -> LineResult<()> {
        let label = "chamfer or rounding";
        if !sc.eat(b'=') {
            return Err(sc.err(at, format!("expected `{name}=value`"), label));
        }
        let size = expr(sc, &self.vars)?;
        let kind = match name {
            "CHF" => CornerKind::Chf,
            "CHR" => CornerKind::Chr,
            "RND" => CornerKind::Rnd,
            _ => CornerKind::Rndm,
        };
        if size < 0.0 || !size.is_finite() || (size == 0.0 && kind != CornerKind::Rndm) {
            return Err(sc.err(
                at,
                format!("`{name}={size}`: expected a length over 0"),
                label,
            ));
        }
        if w.corner.is_some() {
            return Err(sc.err(at, "a second chamfer or rounding word in one block: expected one of CHF= CHR= RND= RNDM=", label));
        }
        w.corner = Some(CornerWord {
            kind,
            size,
            span: at..sc.at,
        });
        Ok(())
    }

    /// After a block's moves: join a held line to the block's first move, then hold the
    /// block's last line when it has a chamfer or rounding word (or RNDM is on).
    pub(super) fn corner_after_block(
        &mut self,
        word: Option<CornerWord>,
        moved: bool,
        line_no: usize,
    ) -> LineResult<()> {
        if let Some(CornerWord {
            kind: CornerKind::Rndm,
            size,
            ..
        }) = word
        {
            self.rounding_modal = (size > 0.0).then_some(size);
        }
        let (size, kind, span) = match (&word, self.rounding_modal) {
            (Some(w), _) if w.kind != CornerKind::Rndm => (w.size, w.kind, w.span.clone()),
            (_, Some(r)) if moved => (r, CornerKind::Rndm, 0..0),
            _ => return Ok(()),
        };
        let word_text = format!("{}={}", kind.name(), super::words::number(size));
        let refuse = |m: String| LineError::new(span.clone(), m, "chamfer or rounding");
        if self.interp.compensating() {
            return Err(refuse(format!("`{word_text}` under cutter radius compensation (G41/G42): not read by mtsim; program the chamfer or rounding without it, or as lines and arcs")));
        }
        let (plane, scale) = if self.frame.is_identity() {
            (self.normal, 1.0)
        } else {
            let Some((plane, scale, _)) = self.frame.arc_plane(self.normal) else {
                return Err(refuse(format!("`{word_text}` in a frame that tilts the plane or scales it unevenly: expected rotations in 90° steps off the plane and a uniform scale")));
            };
            (plane, scale)
        };
        self.join_held().map_err(|m| refuse(m))?;
        let is_line = self
            .queue
            .back()
            .is_some_and(|m| m.motion == crate::canon::Motion::Linear);
        if !is_line {
            return Err(refuse(format!("`{word_text}` in a block whose move is not a G1 line: mtsim inserts chamfers and roundings only between two G1 lines in the working plane")));
        }
        let held = self.queue.pop_back().expect("a line");
        let units = self.interp.scale();
        let size_mm = size * scale * units;
        self.held = Some(Held {
            pending: Pending {
                round: matches!(kind, CornerKind::Rnd | CornerKind::Rndm),
                size_mm,
                plane: [Plane::YZ, Plane::ZX, Plane::XY][plane],
                held,
                word: word_text,
                at: crate::source::Cursor {
                    file: 0,
                    offset: self.line_start.0,
                    line: line_no,
                },
                span,
                text: String::new(),
            },
            chamfer_length: (kind == CornerKind::Chf).then_some(size_mm),
            fresh: true,
        });
        Ok(())
    }

    /// Joins the held line to the first move in the queue (the next block's): the line cut
    /// short, the element, the next line from the element's end. Nothing when no line is
    /// held, it is the current block's, or the queue is empty.
    pub(super) fn join_held(&mut self) -> Result<(), String> {
        let Some(h) = self.held.as_ref() else {
            return Ok(());
        };
        if h.fresh || self.queue.is_empty() {
            return Ok(());
        }
        let h = self.held.take().expect("held");
        let next = self.queue.pop_front().expect("a move");
        let mut p = h.pending;
        if let Some(length) = h.chamfer_length {
            p.size_mm = length / (2.0 * (turn(&p, &next) / 2.0).cos());
        }
        let (a, b, c) = join(&p, &next).map_err(|m| sinumerik_words(&m))?;
        self.queue.push_front(c);
        if let Some(b) = b {
            self.queue.push_front(b);
        }
        self.queue.push_front(a);
        Ok(())
    }
}

/// The turn θ (rad, 0 ≤ θ ≤ π) from the held line to `next` in the plane; 0 when either
/// has no length there (the join refuses it).
fn turn(p: &Pending, next: &crate::canon::Move) -> f64 {
    let (u, v, _) = p.plane.axes();
    let d = |m: &crate::canon::Move, a: Axis| m.end[a] - m.start[a];
    let (a, b) = ([d(&p.held, u), d(&p.held, v)], [d(next, u), d(next, v)]);
    let cross = a[0] * b[1] - a[1] * b[0];
    let dot = a[0] * b[0] + a[1] * b[1];
    cross.abs().atan2(dot)
}

/// The shared corner geometry's message with its Fanuc notes left out (this is a
/// Sinumerik program) and G01 written as Sinumerik writes it.
fn sinumerik_words(m: &str) -> String {
    let mut out = String::with_capacity(m.len());
    let mut rest = m;
    while let Some(k) = rest.find(" (Fanuc:") {
        out.push_str(&rest[..k]);
        rest = rest[k..].find(')').map_or("", |e| &rest[k + e + 1..]);
    }
    out.push_str(rest);
    out.replace("G01", "G1")
        .replace("G00", "G0")
        .replace("G02/G03", "G2/G3")
}
