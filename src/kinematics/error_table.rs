//! Position-dependent axis errors: ball-screw pitch error, worm-gear error of a rotary table.
//!
//! A table in LinuxCNC's compensation-file format: one line per point,
//! `nominal forward reverse`, in mm (linear axis) or deg (rotary axis), ascending in
//! nominal. `forward` and `reverse` are the errors `actual − nominal` while the axis moves
//! in the positive and in the negative direction. Blank lines and text after `#` are
//! ignored. The actual position is
//!
//! ```text
//! actual = commanded + e_dir(commanded),   e_dir linear between the points
//! ```
//!
//! where `dir` is the axis's current direction of motion: the sign of its last change of
//! position larger than [`DIRECTION_DEADBAND`] (positive before the first move). Beyond the
//! first and last points the error holds its end value. A rotary table whose points span
//! exactly one turn (last − first = 360 deg) is periodic: the position is wrapped into it, so
//! that a worm-gear error repeats every turn of a continuous C axis.
//!
//! (LinuxCNC uses the same file to *compensate* a measured error; here it describes the
//! error of an uncompensated machine.)

use std::path::Path;

use crate::error::{Error, Result};

/// Changes of position smaller than this (mm or deg) do not change the direction.
pub const DIRECTION_DEADBAND: f64 = 1e-9;

/// One axis's error table.
#[derive(Clone, Debug, PartialEq)]
pub struct ErrorTable {
    /// (nominal, forward error, reverse error), mm or deg, ascending in nominal.
    points: Vec<[f64; 3]>,
    /// Period (deg) for a table spanning one turn of a rotary axis.
    period: Option<f64>,
}

impl ErrorTable {
    /// A table from its points (nominal, forward, reverse), which must be finite, at least
    /// two, and strictly ascending in nominal. `rotary` allows a periodic table.
    pub fn new(points: Vec<[f64; 3]>, rotary: bool) -> std::result::Result<ErrorTable, String> {
        if points.len() < 2 {
            return Err(format!(
                "an error table needs at least two points, got {}",
                points.len()
            ));
        }
        for w in points.windows(2) {
            if w[1][0] <= w[0][0] {
                return Err(format!(
                    "nominal positions must ascend: {} follows {}",
                    w[1][0], w[0][0]
                ));
            }
        }
        let span = points[points.len() - 1][0] - points[0][0];
        let period = (rotary && (span - 360.0).abs() < 1e-9).then_some(360.0);
        Ok(ErrorTable { points, period })
    }

    /// Parses a compensation file's `text` (the contents of `path`).
    pub fn parse(path: &Path, text: &str, rotary: bool) -> Result<ErrorTable> {
        let mut points = Vec::new();
        let mut offset = 0;
        let mut last_line = 0..0;
        for line in text.split_inclusive('\n') {
            let start = offset;
            offset += line.len();
            let body = line.split('#').next().unwrap_or("");
            let mut values = [0.0; 3];
            let mut count = 0;
            let mut word_start = start;
            for word in body.split_whitespace() {
                let at = start + body.find(word).unwrap_or(0);
                word_start = at;
                let span = at..at + word.len();
                if count == 3 {
                    return Err(Error::at(
                        path,
                        text,
                        span,
                        "a compensation line has three numbers: nominal forward reverse",
                        "unexpected fourth value",
                    ));
                }
                values[count] = match word.parse::<f64>() {
                    Ok(v) if v.is_finite() => v,
                    _ => {
                        return Err(Error::at(
                            path,
                            text,
                            span,
                            "expected a finite number".to_string(),
                            "not a number",
                        ))
                    }
                };
                count += 1;
            }
            match count {
                0 => continue,
                3 => {}
                _ => {
                    return Err(Error::at(
                        path,
                        text,
                        word_start..start + body.trim_end().len(),
                        format!(
                            "a compensation line has three numbers (nominal forward reverse), \
                             got {count}"
                        ),
                        "too few values",
                    ))
                }
            }
            last_line = start..start + body.trim_end().len();
            points.push(values);
        }
        ErrorTable::new(points, rotary).map_err(|message| {
            Error::at(path, text, last_line, message, "here")
                .with_help("write one `nominal forward reverse` line per point, ascending")
        })
    }

    /// The points, (nominal, forward, reverse), mm or deg.
    pub fn points(&self) -> &[[f64; 3]] {
        &self.points
    }

    /// The error `actual − commanded` at `position` while moving `forward` (or in
    /// reverse), mm or deg.
    pub fn error_at(&self, position: f64, forward: bool) -> f64 {
        let col = if forward { 1 } else { 2 };
        let first = self.points[0][0];
        let x = match self.period {
            Some(p) => first + (position - first).rem_euclid(p),
            None => position,
        };
        let k = self.points.partition_point(|p| p[0] <= x);
        if k == 0 {
            return self.points[0][col];
        }
        if k == self.points.len() {
            return self.points[k - 1][col];
        }
        let (a, b) = (self.points[k - 1], self.points[k]);
        a[col] + (b[col] - a[col]) * (x - a[0]) / (b[0] - a[0])
    }

    /// The mean of the forward and reverse errors at `position`: the direction-free part.
    pub fn mean_error_at(&self, position: f64) -> f64 {
        0.5 * (self.error_at(position, true) + self.error_at(position, false))
    }
}

/// The direction of motion of one axis, with a deadband: positive until the first move.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectionState {
    last: Option<f64>,
    forward: bool,
}

impl Default for DirectionState {
    fn default() -> Self {
        DirectionState {
            last: None,
            forward: true,
        }
    }
}

impl DirectionState {
    /// Updates with the axis's new position (mm or deg); returns whether it moves forward.
    pub fn update(&mut self, position: f64) -> bool {
        match self.last {
            None => self.last = Some(position),
            Some(last) => {
                let d = position - last;
                if d.abs() > DIRECTION_DEADBAND {
                    self.forward = d > 0.0;
                    self.last = Some(position);
                }
            }
        }
        self.forward
    }
}

/// The error tables of a machine's axes, applied to a stream of axis positions.
#[derive(Clone, Debug, Default)]
pub struct PositionErrors {
    tables: Vec<(crate::Axis, ErrorTable, DirectionState)>,
}

impl PositionErrors {
    /// One table per axis that has one.
    pub fn new<'a>(tables: impl IntoIterator<Item = (crate::Axis, &'a ErrorTable)>) -> Self {
        PositionErrors {
            tables: tables
                .into_iter()
                .map(|(a, t)| (a, t.clone(), DirectionState::default()))
                .collect(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.tables.is_empty()
    }

    /// The actual positions for the next positions `q` of the stream (mm, deg): each axis
    /// with a table moves by its error for the direction it is moving in.
    pub fn apply(&mut self, q: &crate::AxisVec) -> crate::AxisVec {
        let mut out = *q;
        self.apply_in_place(&mut out);
        out
    }

    /// [`PositionErrors::apply`] on `q` itself (one table per axis, so each table reads its
    /// own axis before changing it).
    #[inline]
    pub fn apply_in_place(&mut self, q: &mut crate::AxisVec) {
        for (axis, table, dir) in &mut self.tables {
            let v = q[*axis];
            let forward = dir.update(v);
            q[*axis] = v + table.error_at(v, forward);
        }
    }

    /// As [`PositionErrors::apply`] with the mean of the forward and reverse errors (no
    /// direction, no state): the direction-free part of the tables.
    pub fn apply_mean(&self, q: &crate::AxisVec) -> crate::AxisVec {
        let mut out = *q;
        self.apply_mean_in_place(&mut out);
        out
    }

    /// [`PositionErrors::apply_mean`] on `q` itself.
    #[inline]
    pub fn apply_mean_in_place(&self, q: &mut crate::AxisVec) {
        for (axis, table, _) in &self.tables {
            let v = q[*axis];
            q[*axis] = v + table.mean_error_at(v);
        }
    }
}
