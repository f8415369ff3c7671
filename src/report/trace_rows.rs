//! The raw rows of a trace, read back one at a time with each row's centred deviation:
//! what `trace.csv` ([`super::trace`]) and `trace.parquet` ([`super::trace_parquet`]) are
//! written from, and the write error both report.

use std::io::Read;
use std::path::Path;

use crate::error::{Error, Result};
use crate::input::program::Direction;
use crate::measure::ballbar::Centring;
use crate::measure::BallbarRun;

/// Raw columns besides the three per axis: direction, time, line, θ, sin θ, cos θ (so that
/// the centring needs no second `sin_cos`), the nonlinear signature, dL.
pub(super) const RAW_FIXED_COLUMNS: usize = 8;

pub(super) fn write_error(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Write {
        path: path.to_path_buf(),
        source,
    }
}

/// The raw rows of a trace read back one at a time, each with the centred deviation
/// `dL - (a cos θ + b sin θ)` of its direction's run: what both trace files are made of.
pub(super) struct RawRows<'p, R> {
    reader: R,
    /// The raw rows' file (for messages) and the output's temporary file, removed when a
    /// read fails.
    raw_path: &'p Path,
    tmp: &'p Path,
    bytes: Vec<u8>,
    values: Vec<f64>,
    ccw: Option<Centring>,
    cw: Option<Centring>,
}

impl<'p, R: Read> RawRows<'p, R> {
    pub(super) fn new(
        reader: R,
        width: usize,
        runs: &[BallbarRun],
        raw_path: &'p Path,
        tmp: &'p Path,
    ) -> RawRows<'p, R> {
        let centring = |d: Direction| {
            runs.iter()
                .find(|r| r.direction() == d)
                .map(|r| r.centring())
        };
        RawRows {
            reader,
            raw_path,
            tmp,
            bytes: vec![0u8; 8 * width],
            values: vec![0.0; width],
            ccw: centring(Direction::Ccw),
            cw: centring(Direction::Cw),
        }
    }

    /// The next row's values, whether it is of the cw run, and its centred dL; None at the
    /// end of the rows. A failed read removes the output's temporary file.
    pub(super) fn next_row(&mut self) -> Result<Option<(&[f64], bool, f64)>> {
        match self.reader.read_exact(&mut self.bytes) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return Ok(None),
            Err(e) => {
                let _ = std::fs::remove_file(self.tmp);
                return Err(write_error(self.raw_path)(e));
            }
        }
        let v = &mut self.values;
        for (x, c) in v.iter_mut().zip(self.bytes.chunks_exact(8)) {
            *x = f64::from_le_bytes(c.try_into().expect("8 bytes"));
        }
        let cw_row = v[0] == 1.0;
        let dev = v[v.len() - 1];
        let c = if cw_row { self.cw } else { self.ccw };
        // `offset_um(θ)` from the sine and cosine the ball bar took (the same bits).
        let centred = c.map_or(dev, |c| dev - c.offset_um_at((v[4], v[5])));
        Ok(Some((&self.values, cw_row, centred)))
    }
}
