//! A trace around the circle: medians (of a buffer, and running around the circle, bit for
//! bit the same) and the regions where a condition holds.

pub(super) fn median(buf: &mut [f64]) -> f64 {
    let mid = buf.len() / 2;
    let (_, m, _) = buf.select_nth_unstable_by(mid, f64::total_cmp);
    *m
}

/// For every i, the median of `v[i + offset .. i + offset + len]` (indices around the
/// circle; the upper median for even `len`), as [`median`] gives it. The window is kept
/// sorted and slid one bin at a time: the values between the leaving value's place and the
/// entering value's move by one. The window holds each value's [`total_order_key`], so that
/// its searches compare integers in the order of [`f64::total_cmp`]: the median is the
/// same value, bit for bit.
pub(super) fn running_circular_median(v: &[f64], offset: isize, len: usize) -> Vec<f64> {
    let n = v.len() as isize;
    let keys: Vec<i64> = v.iter().map(|&x| total_order_key(x)).collect();
    // `k.rem_euclid(n)` without a division for k within a turn of [0, n).
    let at = |k: isize| {
        let i = if k < 0 {
            k + n
        } else if k >= n {
            k - n
        } else {
            k
        };
        keys[if (0..n).contains(&i) {
            i
        } else {
            k.rem_euclid(n)
        } as usize]
    };
    let mut window: Vec<i64> = (0..len as isize).map(|k| at(offset + k)).collect();
    window.sort_unstable();
    let mut out = Vec::with_capacity(v.len());
    for i in 0..n {
        if i > 0 {
            let leaving = at(i - 1 + offset);
            let entering = at(i + offset + len as isize - 1);
            let from = window.partition_point(|&x| x < leaving);
            let to = window.partition_point(|&x| x < entering);
            // Removing `from` and inserting at the entering value's place in what is left.
            if to <= from {
                window.copy_within(to..from, to + 1);
                window[to] = entering;
            } else {
                window.copy_within(from + 1..to, from);
                window[to - 1] = entering;
            }
        }
        out.push(from_total_order_key(window[len / 2]));
    }
    out
}

/// An integer that orders as [`f64::total_cmp`] orders `x`: the bits, with those below the
/// sign flipped for negative values (an involution: [`from_total_order_key`] undoes it).
fn total_order_key(x: f64) -> i64 {
    let bits = x.to_bits() as i64;
    bits ^ (((bits >> 63) as u64) >> 1) as i64
}

/// The value whose [`total_order_key`] is `key`.
fn from_total_order_key(key: i64) -> f64 {
    f64::from_bits((key ^ (((key >> 63) as u64) >> 1) as i64) as u64)
}

/// Contiguous runs (around the circle) of indices where `inside(i)`; each as a list of
/// indices in increasing order from its start.
pub(super) fn circular_regions(n: usize, inside: impl Fn(usize) -> bool) -> Vec<Vec<usize>> {
    let Some(start) = (0..n).find(|&i| !inside(i)) else {
        return Vec::new();
    };
    let mut regions = Vec::new();
    let mut current: Vec<usize> = Vec::new();
    for k in 1..=n {
        let i = (start + k) % n;
        if inside(i) {
            current.push(i);
        } else if !current.is_empty() {
            regions.push(std::mem::take(&mut current));
        }
    }
    regions
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The running median equals the median of each window sorted afresh, bit for bit: on a
    /// trace with repeated values, ±0, infinities and a NaN, windows of odd and even length,
    /// ahead of and behind the bin, and one longer than the trace.
    #[test]
    fn running_median_is_each_windows_median() {
        let mut v: Vec<f64> = (0..500)
            .map(|i| ((i * 7919) % 37) as f64 * 0.5 - 9.0 + ((i * 31) % 5) as f64 * 1e-3)
            .collect();
        (v[3], v[4], v[40], v[41], v[200], v[300]) =
            (0.0, -0.0, f64::INFINITY, f64::NEG_INFINITY, f64::NAN, -0.0);
        let n = v.len() as isize;
        for (offset, len) in [
            (-100, 201),
            (30, 120),
            (-150, 120),
            (0, 1),
            (-7, 4),
            (-20, 600),
        ] {
            let running = running_circular_median(&v, offset, len);
            for i in 0..n {
                let mut w: Vec<f64> = (0..len as isize)
                    .map(|k| v[(i + offset + k).rem_euclid(n) as usize])
                    .collect();
                let m = median(&mut w);
                assert_eq!(
                    running[i as usize].to_bits(),
                    m.to_bits(),
                    "{offset} {len} {i}"
                );
            }
        }
        for x in [0.0, -0.0, 1.5, -1.5, f64::MIN_POSITIVE, -f64::MAX, f64::NAN] {
            assert_eq!(
                from_total_order_key(total_order_key(x)).to_bits(),
                x.to_bits()
            );
        }
    }
}
