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

use super::chain::{Chain, Link};
use super::layout::Layout;
use crate::Axis;

/// The chain of `layout` with its rotary lines through `pivot_mm`.
pub fn of_layout(layout: Layout, pivot_mm: Vector3<f64>) -> Option<Chain> {
    let x = Vector3::x();
    let y = Vector3::y();
    let z = Vector3::z();
    let rot = |axis, d| Link::rotary(axis, d, pivot_mm);
    let xyz = [
        Link::linear(Axis::X, x),
        Link::linear(Axis::Y, y),
        Link::linear(Axis::Z, z),
    ];
    let (table, head): (Vec<Link>, Vec<Link>) = match layout {
        Layout::Xyz => (vec![], xyz.to_vec()),
        Layout::Xz => (vec![], vec![xyz[0], xyz[2]]),
        Layout::Xyza => (vec![rot(Axis::A, x)], xyz.to_vec()),
        Layout::TrtAc => (vec![rot(Axis::A, x), rot(Axis::C, z)], xyz.to_vec()),
        Layout::TrtBc => (vec![rot(Axis::B, y), rot(Axis::C, z)], xyz.to_vec()),
        Layout::TrtAb => (vec![rot(Axis::B, -y), rot(Axis::A, -x)], xyz.to_vec()),
        Layout::Xyzabc | Layout::Xyuv | Layout::Xyzabcuvw | Layout::Chain(_) => return None,
    };
    Chain::new(&table, &head, Vector3::zeros(), z).ok()
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
