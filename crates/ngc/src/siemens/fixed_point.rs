//! `G75 FP=n X1=0 Z1=0`: approach fixed point n with the machine axes named (Fundamentals,
//! "Fixed point approach (G75, G751)"). The fixed points are machine data
//! (`MD30600 $MA_FIX_POINT_POS[n-1]`, machine coordinates); mtsim takes fixed points 1 and 2
//! from the machine file's reference positions `g28_mm` and `g30_mm` (the positions a
//! Fanuc's G28 and G30 go to, on most machines Z at the top of its travel), and refuses the
//! block, naming the setting, where the machine file does not give them. The axes named
//! travel at rapid, each straight to its fixed point (the value after `X1=` only names the
//! axis), as the ISO block `G91 G28 X0 Z0` (`G30` for FP=2).
//!
//! Refused: FP=3 and FP=4 (no machine-file setting holds them), a fixed point without axes,
//! and `G74` (reference point approach: the machine's home is not in its file).

use super::expr::{expr, Scan};
use super::words::Words;
use super::Reader;
use crate::lex::{LineError, LineResult};

/// The machine axis names a fixed point approach names (`X1` …, the channel's first
/// machine axes in the usual configuration).
const MACHINE_AXES: [(&str, char); 6] = [
    ("X1", 'X'),
    ("Y1", 'Y'),
    ("Z1", 'Z'),
    ("A1", 'A'),
    ("B1", 'B'),
    ("C1", 'C'),
];

impl Reader {
    /// `FP=` or a machine axis name (`Z1=0`) in a `G75` block; `Ok(false)` when `name` is
    /// neither or the block has no G75 (the cursor after the name).
    pub(super) fn fixed_point_word(
        &mut self,
        name: &str,
        at: usize,
        sc: &mut Scan,
        w: &mut Words,
    ) -> LineResult<bool> {
        let Some(fp) = w.fixed_point.as_mut() else {
            return Ok(false);
        };
        let axis = MACHINE_AXES.iter().find(|(n, _)| *n == name).map(|a| a.1);
        if name != "FP" && axis.is_none() {
            return Ok(false);
        }
        if !sc.eat(b'=') {
            return Err(sc.err(at, format!("expected `{name}=value`"), "fixed point"));
        }
        let v = expr(sc, &self.vars)?;
        match axis {
            Some(a) => fp.axes.push(a),
            None => fp.number = Some((v, at..sc.at)),
        }
        Ok(true)
    }

    /// Runs the block's fixed point approach, if it has one.
    pub(super) fn approach_fixed_point(&mut self, w: &mut Words, line_no: usize) -> LineResult<()> {
        let Some(fp) = w.fixed_point.take() else {
            return Ok(());
        };
        let (n, n_span) = fp.number.clone().unwrap_or((1.0, fp.span.clone()));
        let code = if n == 1.0 {
            "G28"
        } else if n == 2.0 {
            "G30"
        } else {
            return Err(LineError::new(n_span, format!("`FP={n}`: fixed points 3 and 4 are machine data (MD30600 $MA_FIX_POINT_POS) no machine-file setting holds; mtsim takes FP=1 and FP=2 from the machine file's g28_mm and g30_mm"), "fixed point not given"));
        };
        if fp.axes.is_empty() {
            return Err(LineError::new(fp.span, "G75 without axes: expected the machine axes that approach the fixed point, e.g. `G75 FP=1 Z1=0`", "fixed point without axes"));
        }
        let mut iso = format!("G91 {code}");
        for a in &fp.axes {
            iso.push_str(&format!(" {a}0"));
        }
        self.push(&iso, fp.span.start..n_span.end.max(fp.span.end));
        self.run_iso(line_no)?;
        if self.interp_absolute {
            self.push("G90", fp.span.clone());
            self.run_iso(line_no)?;
        }
        Ok(())
    }
}
