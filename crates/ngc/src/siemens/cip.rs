//! `CIP X.. Y.. Z.. I1=.. J1=.. K1=..`: the circle through the start point, an
//! intermediate point and the end point (Fundamentals, "Circular interpolation with
//! intermediate and end points (CIP)"). The intermediate point is absolute under G90 and
//! incremental from the start under G91 (either by `=AC(..)`/`=IC(..)`); CIP is modal
//! (motion code 5 here) until G0-G3.
//!
//! The three points, through the frames, are the work points `S`, `M`, `E`; the circle's
//! plane has the normal `n = (M - S) × (E - S)`, which must lie along a work axis (the
//! canonical arc lies in XY, ZX or YZ), and the arc runs counter-clockwise about `+n`'s
//! axis when `n` points along it (G3), clockwise otherwise (G2). Its centre is the
//! circumcentre of the three points in that plane.
//!
//! `CT X.. Y..` (motion code 6, modal too): the arc from the start, tangent there to the
//! direction the path had at the end of the move before, to the end point.

use super::words::{number, Coordinate, Mode, Words};
use super::Reader;
use crate::axis::Axis;
use crate::lex::{LineError, LineResult};

impl Reader {
    /// The ISO words of a CIP block (see the module doc).
    pub(super) fn cip_words(&mut self, w: &Words, span: std::ops::Range<usize>) -> LineResult<()> {
        let p = self.interp.program_position();
        let start = [p[Axis::X], p[Axis::Y], p[Axis::Z]];
        let here = self.frame.frame_point(start);
        if w.cip.iter().all(Option::is_none) {
            return Err(LineError::new(
                span,
                "CIP without its intermediate point: expected I1= J1= K1= (Fundamentals, \"Circular interpolation with intermediate and end points (CIP)\")",
                "CIP without I1 J1 K1",
            ));
        }
        let (mut m, mut e) = (here, here);
        for k in 0..3 {
            m[k] = Coordinate::resolve(&w.cip[k], here[k], self.absolute);
            e[k] = Coordinate::resolve(&w.axes[k], here[k], self.absolute);
        }
        let (m, e) = (self.frame.work_point(m), self.frame.work_point(e));
        let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        let (a, b) = (sub(m, start), sub(e, start));
        let n = [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ];
        let len = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        let size = len(a).max(len(b));
        let k = (0..3)
            .max_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs()))
            .unwrap_or(2);
        if n[k].abs() <= 1e-12 * size * size || !size.is_finite() {
            return Err(LineError::new(
                span,
                "CIP with its start, intermediate and end points on one line (or two of them the same): no circle passes through them",
                "CIP points in line",
            ));
        }
        if (0..3).any(|i| i != k && n[i].abs() > 1e-9 * n[k].abs()) {
            return Err(LineError::new(
                span,
                "CIP through points whose circle lies in a plane other than XY, ZX or YZ: not supported (mtsim's arcs lie in the work planes)",
                "CIP in an inclined plane",
            )
            .help("post the arc as lines, or as G2/G3 in a work plane"));
        }
        // In-plane axes (u, v) with u × v = +e_k, and the circumcentre there.
        let (u, v) = ((k + 1) % 3, (k + 2) % 3);
        let (au, av, bu, bv) = (a[u], a[v], b[u], b[v]);
        let d = 2.0 * (au * bv - av * bu);
        let (a2, b2) = (au * au + av * av, bu * bu + bv * bv);
        let cu = (bv * a2 - av * b2) / d;
        let cv = (au * b2 - bu * a2) / d;
        self.push("G90", span.clone());
        self.interp_absolute = true;
        self.plane_code(k, span.clone());
        let code = if n[k] > 0.0 { "G3" } else { "G2" };
        self.push(code, span.clone());
        self.interp_motion = u8::MAX;
        for (i, l) in ["X", "Y", "Z"].iter().enumerate() {
            self.push(&format!("{l}{}", number(e[i])), span.clone());
        }
        for (i, axis) in Axis::ALL.iter().enumerate().skip(3) {
            if w.axes[i].is_some() {
                let val = Coordinate::resolve(&w.axes[i], p[*axis], self.absolute);
                self.push(&format!("{}{}", axis.letter(), number(val)), span.clone());
            }
        }
        let mut centre = [0.0; 3];
        centre[u] = cu;
        centre[v] = cv;
        for (i, l) in ["I", "J", "K"].iter().enumerate() {
            if i != k {
                self.push(&format!("{l}{}", number(centre[i])), span.clone());
            }
        }
        Ok(())
    }
}

impl Reader {
    /// The ISO words of a CT block: the arc from the start, tangent there to the path
    /// before, to the end point. Its centre lies on the start's normal to the tangent
    /// `n = e_k × t` (k the plane's normal axis) at `λ = |d|² / (2 d·n)`, `d` the chord;
    /// `λ > 0` puts it on the left of the path: counter-clockwise (G3).
    pub(super) fn ct_words(&mut self, w: &Words, span: std::ops::Range<usize>) -> LineResult<()> {
        let refuse = |m: &str, label: &str| {
            Err(LineError::new(span.clone(), format!("{m} (Fundamentals, \"Circular interpolation with tangential transition (CT)\")"), label))
        };
        if self.tcp || self.interp.frame().is_some() {
            return refuse("CT under TRAORI or a swivelled plane: not supported", "CT");
        }
        let Some(t) = self.tangent else {
            return refuse(
                "CT with no path before it to be tangent to",
                "CT without a tangent",
            );
        };
        let Some((k, _, _)) = self.frame.arc_plane(self.normal) else {
            return refuse(
                "CT in a frame that tilts its plane off the work axes",
                "arc in a tilted frame",
            );
        };
        let p = self.interp.program_position();
        let start = [p[Axis::X], p[Axis::Y], p[Axis::Z]];
        let here = self.frame.frame_point(start);
        let mut q = here;
        for (i, q) in q.iter_mut().enumerate() {
            *q = match &w.axes[i] {
                None => here[i],
                Some(c) => match c.mode {
                    Mode::Absolute => c.value,
                    Mode::Incremental => here[i] + c.value,
                    Mode::Modal if self.absolute => c.value,
                    Mode::Modal => here[i] + c.value,
                },
            };
        }
        let end = self.frame.work_point(q);
        let mut tp = t;
        tp[k] = 0.0;
        let len = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if len(tp) <= 1e-9 * len(t) {
            return refuse(
                "CT after a move along the plane's normal: no tangent in the plane",
                "CT without a tangent",
            );
        }
        let mut e_k = [0.0; 3];
        e_k[k] = 1.0;
        let n = [
            e_k[1] * tp[2] - e_k[2] * tp[1],
            e_k[2] * tp[0] - e_k[0] * tp[2],
            e_k[0] * tp[1] - e_k[1] * tp[0],
        ];
        let n = n.map(|x| x / len(tp));
        let mut d = [end[0] - start[0], end[1] - start[1], end[2] - start[2]];
        d[k] = 0.0;
        let dn = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
        if dn.abs() <= 1e-9 * len(d) || len(d) == 0.0 {
            return refuse(
                "CT to an end point on the tangent's line (or at the start): no circle",
                "CT end on the tangent",
            );
        }
        let lambda = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) / (2.0 * dn);
        self.push("G90", span.clone());
        self.interp_absolute = true;
        self.plane_code(k, span.clone());
        let code = if lambda > 0.0 { 3 } else { 2 };
        self.push(&format!("G{code}"), span.clone());
        self.interp_motion = code;
        for (i, l) in ["X", "Y", "Z"].iter().enumerate() {
            self.push(&format!("{l}{}", number(end[i])), span.clone());
        }
        for (i, l) in ["I", "J", "K"].iter().enumerate() {
            if i != k {
                self.push(&format!("{l}{}", number(lambda * n[i])), span.clone());
            }
        }
        Ok(())
    }
}
