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

/// The named layout (and its pivot) that `chain` is written exactly as, if any: the
/// layout's links in its order, its directions, every rotary line through the same point.
pub fn named(chain: &Chain) -> Option<(Layout, Vector3<f64>)> {
    let pivot = chain
        .rotaries()
        .map(|(_, l)| l.point_mm)
        .next()
        .unwrap_or_else(Vector3::zeros);
    Layout::ALL
        .into_iter()
        .find(|layout| of_layout(*layout, pivot).as_ref() == Some(chain))
        .map(|layout| (layout, pivot))
}
