//! A set of axes as a small `Copy` value, listed in X Y Z A B C U V W order.

use crate::Axis;

/// A set of axes (bit i: `Axis::ALL[i]`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct AxisSet(u16);

/// Every subset of the nine axes, listed in order: `SUBSETS[mask]` holds its axes and count.
static SUBSETS: [([Axis; 9], usize); 512] = subsets();

const fn subsets() -> [([Axis; 9], usize); 512] {
    let mut table = [([Axis::X; 9], 0usize); 512];
    let mut mask = 0;
    while mask < 512 {
        let mut n = 0;
        let mut i = 0;
        while i < 9 {
            if mask & (1 << i) != 0 {
                table[mask].0[n] = Axis::ALL[i];
                n += 1;
            }
            i += 1;
        }
        table[mask].1 = n;
        mask += 1;
    }
    table
}

impl AxisSet {
    /// The set of `axes`.
    pub fn of(axes: &[Axis]) -> AxisSet {
        AxisSet(axes.iter().fold(0, |m, a| m | 1 << a.index()))
    }

    /// Its axes in X Y Z A B C U V W order.
    pub fn axes(self) -> &'static [Axis] {
        let (axes, n) = &SUBSETS[self.0 as usize];
        &axes[..*n]
    }

    pub fn contains(self, axis: Axis) -> bool {
        self.0 & (1 << axis.index()) != 0
    }
}
