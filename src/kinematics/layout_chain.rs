//! The named layouts written out as chains, and a chain recognised as a named layout.
//!
//! | layout | table (bed outward) | head | rotary lines through `pivot_mm` |
//! |---|---|---|---|
//! | xyz | — | X Y Z | |
//! | xz | — | X Z | |
//! | xyza | A | X Y Z | A [1,0,0] |
//! | trt-ac | A, C | X Y Z | A [1,0,0], C [0,0,1] |
//! | trt-bc | B, C | X Y Z | B [0,1,0], C [0,0,1] |
//! | trt-ab | B, A | X Y Z | B [0,−1,0], A [−1,0,0] (the table turns by −B, −A) |
//!
//! Gauge point at the origin, tool direction +Z. xyzabc, xyuv and xyzabcuvw have no chain:
//! their A B C (U V W) have no place in the tool pose.

use nalgebra::Vector3;

use super::chain::Chain;
use super::layout::Layout;

/// The chain of `layout` with its rotary lines through `pivot_mm` ([`Layout::links`]).
pub fn of_layout(layout: Layout, pivot_mm: Vector3<f64>) -> Option<Chain> {
    let (table, head) = layout.links(pivot_mm)?;
    Chain::new(&table, &head, Vector3::zeros(), Vector3::z()).ok()
}

/// The named layout (and its pivot) that `chain` is written as, if any: the layout's links
/// in its order, its directions, every rotary line through one point, the pivot. A rotary's
/// `point_mm` may sit anywhere along its line (it names the line, not a point of the
/// machine): the pivot is tried at each written point and at the point of the first
/// rotary's line nearest the second's (where they cross), so that the same machine reads the
/// same whichever point of a line is written (one branch choice, one answer).
pub fn named(chain: &Chain) -> Option<(Layout, Vector3<f64>)> {
    let lines: Vec<(Vector3<f64>, Vector3<f64>)> = chain
        .rotaries()
        .map(|(_, l)| (l.point_mm, l.direction))
        .collect();
    let mut pivots: Vec<Vector3<f64>> = lines.iter().map(|(p, _)| *p).collect();
    if let [(p1, d1), (p2, d2), ..] = lines.as_slice() {
        pivots.extend(crossing(p1, d1, p2, d2));
    }
    if pivots.is_empty() {
        pivots.push(Vector3::zeros());
    }
    pivots.into_iter().find_map(|pivot| {
        // Every rotary line must pass through the pivot (to rounding of its written point).
        let on_lines = lines
            .iter()
            .all(|(p, d)| (pivot - p).cross(d).norm() <= 1e-9 * (1.0 + p.norm()));
        if !on_lines {
            return None;
        }
        let moved = chain
            .rotaries()
            .fold(*chain, |c, (_, l)| c.with_line(l.axis, l.direction, pivot));
        Layout::ALL
            .into_iter()
            .find(|layout| of_layout(*layout, pivot).as_ref() == Some(&moved))
            .map(|layout| (layout, pivot))
    })
}

/// The point of line `p1 + t d1` nearest line `p2 + s d2` (unit directions), when they are
/// not parallel: `t = (p2 − p1)·(d1 − (d1·d2) d2) / (1 − (d1·d2)²)`.
fn crossing(
    p1: &Vector3<f64>,
    d1: &Vector3<f64>,
    p2: &Vector3<f64>,
    d2: &Vector3<f64>,
) -> Option<Vector3<f64>> {
    let c = d1.dot(d2);
    let det = 1.0 - c * c;
    (det > 1e-12).then(|| p1 + d1 * ((p2 - p1).dot(&(d1 - d2 * c)) / det))
}
