//! The machined surface as the lower envelope of every cutter position, streamed onto a fixed
//! θ × height grid.
//!
//! `d(θ_j, z_i) = min over positions k of d_k(θ_j, z_i)` ([`CutGeometry::depths_um`]). Testing
//! every position on every column would cost positions × columns; a position only reaches
//! columns near its own generatrix, and there only by its clearance: with `e_k` the least
//! depth it cuts at its own θ (over the rows) and κ the cutter's clearance per rad²
//! ([`CutGeometry::clearance_um_per_rad2`]),
//!
//! ```text
//! d_k(θ_j, z_i) ≥ e_k + κ (θ_j − θ_k)²
//! ```
//!
//! So each column is computed once the cutter's contact has moved `reach` columns past it
//! (all positions that may reach it have come): first from the position nearest to it, then
//! from every other buffered position whose bound is below the column's deepest row so far.
//! `reach` is where the clearance passes [`REACH_UM`]. Memory: the grid and the positions
//! within `reach` of the contact, whatever the program's length. The contact must move
//! on (as on a test's measured revolution); a position that comes back to columns already
//! computed is applied to them directly, so nothing is lost either way.

use std::cell::Cell;
use std::collections::VecDeque;

use super::geometry::{greater, lesser, CutGeometry, CutterLine, Row, NOT_CUT};
use super::least_bound::{least_depth_bounds_um, Chord};

/// Clearance at which a cutter position stops being tested on other columns, um: a position
/// deeper than the surface its neighbours leave by more than this, this far away, is not
/// seen there.
pub const REACH_UM: f64 = 200.0;

/// Most columns a position is tested on either side of its own.
const MAX_REACH_COLUMNS: usize = 400;

/// A cutter position waiting for its columns.
#[derive(Clone, Debug)]
struct Buffered {
    /// θ of the contact, in columns, unwrapped over the run, and `(cos θ, sin θ)` of it.
    u: f64,
    theta: (f64, f64),
    line: CutterLine,
    /// Bounds of `e_min`, the least depth it cuts at its own θ, um
    /// ([`least_depth_bounds_um`]), and e_min itself once computed (NaN before).
    e_min_lower_um: f64,
    e_min_upper_um: f64,
    e_min_um: Cell<f64>,
}

impl Buffered {
    /// e_min, um: the least of its depths at its own θ, computed (into `scratch`) the first
    /// time it is asked for.
    fn e_min_um(&self, geometry: &CutGeometry, rows: &[Row], scratch: &mut [f64]) -> f64 {
        let known = self.e_min_um.get();
        if !known.is_nan() {
            return known;
        }
        geometry.depths_um(self.theta, rows, &self.line, scratch);
        let e = least(scratch);
        self.e_min_um.set(e);
        e
    }

    /// Whether `e_min + clearance_um ≥ deepest_row_um` (the position cannot lower a row of
    /// the column): from the bounds when they decide it (`fl(x + c)` rises with x, so
    /// `lower + c ≥ deepest` implies it and `upper + c < deepest` its contrary), else from
    /// e_min computed.
    #[inline(always)]
    fn cleared(
        &self,
        clearance_um: f64,
        deepest_row_um: f64,
        geometry: &CutGeometry,
        rows: &[Row],
        scratch: &mut [f64],
    ) -> bool {
        if self.e_min_lower_um + clearance_um >= deepest_row_um {
            return true;
        }
        if self.e_min_upper_um + clearance_um < deepest_row_um {
            return false;
        }
        self.e_min_um(geometry, rows, scratch) + clearance_um >= deepest_row_um
    }
}

/// The lower envelope on the grid, and the run that feeds it.
#[derive(Clone, Debug)]
pub struct Envelope {
    pub step_deg: f64,
    pub rows: Vec<Row>,
    /// `(cos θ_j, sin θ_j)` of each column.
    columns: Vec<(f64, f64)>,
    /// Depth per column and row (column-major: `values[j * rows + i]`), um.
    pub values: Vec<f64>,
    /// Columns a position is tested on either side of its own, and κ per column², um.
    reach: i64,
    clearance_per_column2_um: f64,
    run: RunState,
    /// The rows' chord ([`Chord::of`]); None: e_min is always computed.
    chord: Option<Chord>,
    /// Scratch rows: one position's depths, and a column's envelope.
    scratch: Vec<f64>,
    local: Vec<f64>,
}

#[derive(Clone, Debug, Default)]
struct RunState {
    buffer: VecDeque<Buffered>,
    /// Unwrapped contact of the first and the last position, columns.
    first_u: Option<f64>,
    last_u: f64,
    /// +1 when the contact moves to higher θ, −1 to lower, 0 not yet known.
    sense: i64,
    /// The next column to compute (unwrapped), and the farthest contact so far.
    next_column: i64,
    front_u: f64,
    /// The buffer's order in u: broken once a position came below (above) the one before.
    not_ascending: bool,
    not_descending: bool,
    /// The buffer's least `e_min_lower_um` (a lower bound of its least e_min), as a sliding
    /// minimum: (sequence number, bound) with the bound rising, the front the buffer's
    /// least; positions pushed and popped so far.
    floor: VecDeque<(u64, f64)>,
    pushed: u64,
    popped: u64,
}

impl RunState {
    /// Buffers `b` behind the others.
    fn push(&mut self, b: Buffered) {
        if let Some(last) = self.buffer.back() {
            self.not_ascending |= b.u < last.u;
            self.not_descending |= b.u > last.u;
        }
        if b.u.is_nan() {
            (self.not_ascending, self.not_descending) = (true, true);
        }
        while self
            .floor
            .back()
            .is_some_and(|&(_, e)| e >= b.e_min_lower_um)
        {
            self.floor.pop_back();
        }
        self.floor.push_back((self.pushed, b.e_min_lower_um));
        self.pushed += 1;
        self.buffer.push_back(b);
    }

    /// Drops the first buffered position.
    fn pop(&mut self) {
        if self.buffer.pop_front().is_some() {
            if self.floor.front().is_some_and(|&(k, _)| k == self.popped) {
                self.floor.pop_front();
            }
            self.popped += 1;
        }
    }

    /// +1 (−1) when the buffered contacts never fall (rise) from one to the next, else None.
    fn order(&self) -> Option<f64> {
        match (self.not_ascending, self.not_descending) {
            (false, _) => Some(1.0),
            (true, false) => Some(-1.0),
            (true, true) => None,
        }
    }
}

impl Envelope {
    pub fn new(geometry: &CutGeometry, step_deg: f64, rows: Vec<Row>) -> Envelope {
        let count = (360.0 / step_deg).round() as usize;
        let columns = (0..count)
            .map(|j| {
                let (s, c) = (j as f64 * step_deg).to_radians().sin_cos();
                (c, s)
            })
            .collect();
        let step_rad = step_deg.to_radians();
        let kappa = geometry.clearance_um_per_rad2(&rows);
        let per_column2 = kappa * step_rad * step_rad;
        let reach = if per_column2 > 0.0 {
            ((REACH_UM / per_column2).sqrt().ceil() as usize).clamp(2, MAX_REACH_COLUMNS)
        } else {
            MAX_REACH_COLUMNS
        };
        Envelope {
            step_deg,
            values: vec![NOT_CUT; count * rows.len()],
            scratch: vec![0.0; rows.len()],
            local: vec![0.0; rows.len()],
            chord: Chord::of(&rows),
            rows,
            columns,
            reach: reach as i64,
            clearance_per_column2_um: per_column2,
            run: RunState::default(),
        }
    }

    /// The cutter's least clearance per column² away from its own θ, um (κ Δθ²).
    pub fn clearance_per_column2_um(&self) -> f64 {
        self.clearance_per_column2_um
    }

    pub fn column_count(&self) -> usize {
        self.columns.len()
    }

    /// Depth at column `j`, row `i`, um ([`NOT_CUT`] where no position reached it).
    pub fn depth_um(&self, j: usize, i: usize) -> f64 {
        self.values[j * self.rows.len() + i]
    }

    /// Takes one cutter position of the run.
    pub fn push(&mut self, geometry: &CutGeometry, line: CutterLine) {
        self.push_at(geometry, line, line.contact_rad());
    }

    /// [`Envelope::push`] of a position whose contact θ `line.contact_rad()` is known; its
    /// direction `(cos θ, sin θ)` is [`CutterLine::contact_direction`] (the tip's own
    /// `(x, y)` scaled to 1: one square root and two divisions, where `sin_cos` of the
    /// angle took about 120 instructions).
    pub fn push_at(&mut self, geometry: &CutGeometry, line: CutterLine, contact: f64) {
        let theta = line.contact_direction();
        let bounds = self
            .chord
            .and_then(|chord| least_depth_bounds_um(geometry, theta, &self.rows, &chord, &line));
        let (e_min_lower_um, e_min_upper_um, known) = match bounds {
            Some((lower, upper)) => (lower, upper, f64::NAN),
            None => {
                geometry.depths_um(theta, &self.rows, &line, &mut self.scratch);
                let e = least(&self.scratch);
                (e, e, e)
            }
        };
        if !e_min_upper_um.is_finite() {
            // It cuts no row at its own θ, so none anywhere (the clearance only adds).
            return;
        }
        let n = self.columns.len() as f64;
        let raw = contact.to_degrees() / self.step_deg;
        let run = &mut self.run;
        let u = match run.first_u {
            None => {
                run.first_u = Some(raw);
                run.front_u = raw;
                raw
            }
            Some(_) => run.last_u + wrap_euclid(raw - run.last_u + n / 2.0, n) - n / 2.0,
        };
        run.last_u = u;
        let buffered = Buffered {
            u,
            theta,
            line,
            e_min_lower_um,
            e_min_upper_um,
            e_min_um: Cell::new(known),
        };
        if run.sense == 0 {
            let first = run.first_u.expect("set above");
            if (u - first).abs() >= 1.0 {
                run.sense = if u > first { 1 } else { -1 };
                run.next_column = first.round() as i64 - run.sense * (self.reach + 1);
            }
        } else if (run.sense as f64) * (run.next_column as f64 - u) > -(self.reach as f64 + 1.0) {
            // Back within reach of columns already computed: apply it to them directly.
            self.apply_to_done(geometry, &buffered);
        }
        let run = &mut self.run;
        run.push(buffered);
        if run.sense != 0 && (run.sense as f64) * (u - run.front_u) > 0.0 {
            run.front_u = u;
        }
        while self.run.sense != 0
            && (self.run.sense as f64) * (self.run.front_u - self.run.next_column as f64)
                > (self.reach + 1) as f64
        {
            self.compute_next(geometry);
        }
    }

    /// The run has ended: every column its positions reach is computed.
    pub fn end_run(&mut self, geometry: &CutGeometry) {
        let Some(first) = self.run.first_u else {
            return;
        };
        if self.run.sense == 0 {
            // The contact never left its first column: the columns about it.
            self.run.sense = 1;
            self.run.next_column = first.round() as i64 - self.reach - 1;
        }
        let sense = self.run.sense;
        let last = self.run.front_u.round() as i64 + sense * (self.reach + 1);
        while sense * (last - self.run.next_column) >= 0 {
            self.compute_next(geometry);
        }
        self.run = RunState::default();
    }

    /// Computes column `next_column` from the buffer and moves on; drops the positions no
    /// later column needs.
    fn compute_next(&mut self, geometry: &CutGeometry) {
        let j = self.run.next_column;
        self.compute_column(geometry, j);
        let run = &mut self.run;
        run.next_column += run.sense;
        let keep = (self.reach + 1) as f64;
        while let Some(b) = run.buffer.front() {
            if (run.sense as f64) * (run.next_column as f64 - b.u) > keep {
                run.pop();
            } else {
                break;
            }
        }
    }

    /// The envelope at unwrapped column `j` of the buffered positions, folded into the grid.
    ///
    /// The nearest position first, so that the bound prunes the others, then the others in
    /// the buffer's order: a position is skipped when `e_min + κ du² ≥ deepest_row` (the
    /// deepest row of the column so far, which only falls). With the buffer ordered in u
    /// ([`RunState::order`]), `e_floor + κ du² ≥ deepest_row` after the nearest one (e_floor
    /// the buffer's least e_min) holds on a run of positions at each end, which the loop
    /// would skip one by one: they are left out of it ([`pruned_range`]), and the
    /// same positions are taken in the same order, so the column's bits are the same.
    fn compute_column(&mut self, geometry: &CutGeometry, j: i64) {
        let count = self.columns.len() as i64;
        let column = j.rem_euclid(count) as usize;
        let theta = self.columns[column];
        let jf = j as f64;
        let reach = self.reach as f64;
        let kappa = self.clearance_per_column2_um;
        self.local.fill(NOT_CUT);
        let order = self.run.order();
        let buffer = &self.run.buffer;
        let nearest = match order {
            Some(sign) => nearest_sorted(buffer, jf, reach, sign),
            None => buffer
                .iter()
                .enumerate()
                .filter(|(_, b)| (b.u - jf).abs() <= reach)
                .min_by(|(_, a), (_, b)| (a.u - jf).abs().total_cmp(&(b.u - jf).abs()))
                .map(|(k, _)| k),
        };
        let Some(nearest) = nearest else {
            return;
        };
        let (rows, scratch, local) = (&self.rows, &mut self.scratch, &mut self.local);
        let mut deepest_row = NOT_CUT;
        let mut take = |b: &Buffered, deepest_row: &mut f64| {
            let du = (b.u - jf).abs();
            if du > reach || b.cleared(kappa * du * du, *deepest_row, geometry, rows, scratch) {
                return;
            }
            geometry.depths_um(theta, rows, &b.line, scratch);
            *deepest_row = lower_to(local, scratch);
        };
        take(&buffer[nearest], &mut deepest_row);
        let range = match (order, self.run.floor.front()) {
            (Some(sign), Some(&(_, floor))) => {
                let outside = |b: &Buffered| {
                    let du = (b.u - jf).abs();
                    du > reach || floor + kappa * du * du >= deepest_row
                };
                pruned_range(buffer, jf, sign, outside)
            }
            _ => 0..buffer.len(),
        };
        for k in range.filter(|&k| k != nearest) {
            take(&buffer[k], &mut deepest_row);
        }
        let h = self.rows.len();
        for (v, &l) in self.values[column * h..(column + 1) * h]
            .iter_mut()
            .zip(&self.local)
        {
            *v = v.min(l);
        }
    }

    /// A position that came back within reach of columns already computed, applied to them.
    fn apply_to_done(&mut self, geometry: &CutGeometry, b: &Buffered) {
        let sense = self.run.sense;
        let count = self.columns.len() as i64;
        let h = self.rows.len();
        let next = self.run.next_column;
        // None of lo..=hi computed (the usual case, a position just ahead of the computed
        // columns): `ceil(v) > m` exactly when `v > m`, for an integer m.
        let (below, above) = (b.u - self.reach as f64, b.u + self.reach as f64);
        if (sense == 1 && below > (next - 1) as f64) || (sense != 1 && above < (next + 1) as f64) {
            return;
        }
        let lo = below.ceil() as i64;
        let hi = above.floor() as i64;
        // Computed columns lie behind `next_column`: those of lo..=hi, in the same order.
        let (lo, hi) = match sense {
            1 => (lo, hi.min(next - 1)),
            _ => (lo.max(next + 1), hi),
        };
        for j in lo..=hi {
            let column = j.rem_euclid(count) as usize;
            geometry.depths_um(self.columns[column], &self.rows, &b.line, &mut self.scratch);
            for (v, &d) in self.values[column * h..(column + 1) * h]
                .iter_mut()
                .zip(&self.scratch)
            {
                *v = v.min(d);
            }
        }
    }
}

/// Lanes of [`least`] and [`lower_to`]: the minima and maxima are taken four side by side.
const LANES: usize = 4;

/// The least of the depths `v` ([`NOT_CUT`] for none), [`LANES`] side by side.
fn least(v: &[f64]) -> f64 {
    let mut acc = [NOT_CUT; LANES];
    let mut chunks = v.chunks_exact(LANES);
    for c in &mut chunks {
        for (a, &x) in acc.iter_mut().zip(c) {
            *a = lesser(*a, x);
        }
    }
    let rest = chunks
        .remainder()
        .iter()
        .fold(NOT_CUT, |a, &x| lesser(a, x));
    acc.iter().fold(rest, |a, &x| lesser(a, x))
}

/// Lowers `local` to the depths `d` where they are less (row by row); the deepest row of
/// `local` after (−∞ for none), as [`least`].
#[inline(always)]
fn lower_to(local: &mut [f64], d: &[f64]) -> f64 {
    let mut acc = [f64::NEG_INFINITY; LANES];
    let n = local.len().min(d.len());
    let (local, d) = (&mut local[..n], &d[..n]);
    let mut lc = local.chunks_exact_mut(LANES);
    let mut dc = d.chunks_exact(LANES);
    for (l, x) in (&mut lc).zip(&mut dc) {
        for ((a, l), &x) in acc.iter_mut().zip(l.iter_mut()).zip(x) {
            *l = lesser(*l, x);
            *a = greater(*a, *l);
        }
    }
    let mut deepest = f64::NEG_INFINITY;
    for (l, &x) in lc.into_remainder().iter_mut().zip(dc.remainder()) {
        *l = lesser(*l, x);
        deepest = greater(deepest, *l);
    }
    acc.iter().fold(deepest, |a, &x| greater(a, x))
}

/// `x.rem_euclid(n)` for `n > 0`, bit for bit, without `fmod` where `x` lies in `(−n, 2n)`
/// (a contact's step from the last one, plus n/2): there the remainder is `x`, `x − n`
/// (exact, Sterbenz) or `x + n` (as `rem_euclid` rounds it).
#[inline(always)]
pub fn wrap_euclid(x: f64, n: f64) -> f64 {
    if (0.0..n).contains(&x) {
        x
    } else if x >= n && x < 2.0 * n {
        x - n
    } else if x < 0.0 && x > -n {
        x + n
    } else {
        x.rem_euclid(n)
    }
}

/// In `buffer` ordered by `sign · u` (rising), the first of the positions nearest to column
/// `jf` (least `|u − jf|`, the first of equals as `Iterator::min_by` takes it), if within
/// `reach`. Below `jf` the distance never rises along the buffer, above it it never falls
/// (a subtraction of `jf` is monotone in u), so the nearest is the first of the last equals
/// below or the first above.
fn nearest_sorted(buffer: &VecDeque<Buffered>, jf: f64, reach: f64, sign: f64) -> Option<usize> {
    let du = |k: usize| (buffer[k].u - jf).abs();
    let p = first_false(0, buffer.len(), |k| sign * buffer[k].u < sign * jf);
    let below = (p > 0).then(|| {
        let d = du(p - 1);
        (first_false(0, p, |k| du(k).total_cmp(&d).is_gt()), d)
    });
    let above = (p < buffer.len()).then(|| (p, du(p)));
    let (k, d) = match (below, above) {
        (Some(lo), Some(hi)) if lo.1.total_cmp(&hi.1).is_le() => lo,
        (Some(lo), None) => lo,
        (_, Some(hi)) => hi,
        (None, None) => return None,
    };
    (d <= reach).then_some(k)
}

/// In `buffer` ordered by `sign · u` (rising), the positions between the run at its start and
/// the run at its end for which `outside` holds; `outside` is monotone in `|u − jf|`, which
/// falls to `jf` and rises after it.
fn pruned_range(
    buffer: &VecDeque<Buffered>,
    jf: f64,
    sign: f64,
    outside: impl Fn(&Buffered) -> bool,
) -> std::ops::Range<usize> {
    let n = buffer.len();
    let p = first_false(0, n, |k| sign * buffer[k].u < sign * jf);
    let start = first_false(0, p, |k| outside(&buffer[k]));
    let end = first_false(p, n, |k| !outside(&buffer[k]));
    start..end
}

/// The first k in `lo..hi` where `pred` is false (`hi` if none), `pred` true then false over
/// the range: a binary search, as `slice::partition_point`, by index (the buffer is a ring).
fn first_false(mut lo: usize, mut hi: usize, pred: impl Fn(usize) -> bool) -> usize {
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if pred(mid) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    lo
}
