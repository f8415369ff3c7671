//! Machine axes, the small value type that holds one position per axis, and the arc plane.
//!
//! Linear axes are in mm and rotary axes in deg. The secondary linear axes U V W (LinuxCNC's
//! axes 7 to 9, parallel to X Y Z) come after the rotaries, as in LinuxCNC's parameter
//! numbering (`#5221`-`#5229` = G54 X Y Z A B C U V W).

use std::fmt;
use std::ops::{Add, Index, IndexMut, Mul, Sub};

/// One machine axis. Linear axes X, Y, Z move in mm; rotary axes A, B, C turn in deg
/// about X, Y and Z respectively; the secondary linear axes U, V, W move in mm, parallel to
/// X, Y and Z (a foam cutter's second wire carriage, a quill).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Axis {
    X,
    Y,
    Z,
    A,
    B,
    C,
    U,
    V,
    W,
}

impl Axis {
    /// Every axis, in LinuxCNC's order X Y Z A B C U V W.
    pub const ALL: [Axis; 9] = [
        Axis::X,
        Axis::Y,
        Axis::Z,
        Axis::A,
        Axis::B,
        Axis::C,
        Axis::U,
        Axis::V,
        Axis::W,
    ];
    /// The six primary axes X Y Z A B C (a machine without U V W).
    pub const XYZABC: [Axis; 6] = [Axis::X, Axis::Y, Axis::Z, Axis::A, Axis::B, Axis::C];
    /// The three Cartesian axes X Y Z (the tool tip; U V W are linear too but not in this
    /// list).
    pub const LINEAR: [Axis; 3] = [Axis::X, Axis::Y, Axis::Z];
    /// The secondary linear axes U V W.
    pub const SECONDARY: [Axis; 3] = [Axis::U, Axis::V, Axis::W];

    /// Index into [`AxisVec`].
    pub const fn index(self) -> usize {
        self as usize
    }

    /// True for A, B and C.
    pub const fn is_rotary(self) -> bool {
        matches!(self, Axis::A | Axis::B | Axis::C)
    }

    /// True for U, V and W.
    pub const fn is_secondary(self) -> bool {
        matches!(self, Axis::U | Axis::V | Axis::W)
    }

    /// The axis letter as written in G-code and machine files.
    pub const fn letter(self) -> char {
        match self {
            Axis::X => 'X',
            Axis::Y => 'Y',
            Axis::Z => 'Z',
            Axis::A => 'A',
            Axis::B => 'B',
            Axis::C => 'C',
            Axis::U => 'U',
            Axis::V => 'V',
            Axis::W => 'W',
        }
    }

    /// Parses an axis letter (either case).
    pub fn from_letter(letter: char) -> Option<Axis> {
        match letter.to_ascii_uppercase() {
            'X' => Some(Axis::X),
            'Y' => Some(Axis::Y),
            'Z' => Some(Axis::Z),
            'A' => Some(Axis::A),
            'B' => Some(Axis::B),
            'C' => Some(Axis::C),
            'U' => Some(Axis::U),
            'V' => Some(Axis::V),
            'W' => Some(Axis::W),
            _ => None,
        }
    }

    /// Unit of the axis position at interfaces: "mm" or "deg".
    pub const fn unit(self) -> &'static str {
        if self.is_rotary() {
            "deg"
        } else {
            "mm"
        }
    }
}

impl fmt::Display for Axis {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.letter())
    }
}

/// One value per axis (mm for X Y Z U V W, deg for A B C), indexed by [`Axis`].
///
/// Axes a machine does not have stay at 0.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AxisVec(pub [f64; 9]);

impl AxisVec {
    pub const ZERO: AxisVec = AxisVec([0.0; 9]);

    /// X Y Z A B C as given, U V W zero.
    pub const fn xyzabc(v: [f64; 6]) -> AxisVec {
        AxisVec([v[0], v[1], v[2], v[3], v[4], v[5], 0.0, 0.0, 0.0])
    }

    /// X Y Z A B C (U V W left out).
    pub fn to_xyzabc(&self) -> [f64; 6] {
        [
            self.0[0], self.0[1], self.0[2], self.0[3], self.0[4], self.0[5],
        ]
    }

    /// Euclidean norm over all nine entries, with degrees counted as millimetres.
    /// This is the "mixed-unit" length a controller without tool-centre-point control
    /// uses to turn an F word into a block time. Inlined: a vector just computed is then
    /// read where it is, not stored and loaded back whole.
    #[inline]
    pub fn mixed_norm(&self) -> f64 {
        self.0.iter().map(|v| v * v).sum::<f64>().sqrt()
    }

    #[inline]
    pub fn is_finite(&self) -> bool {
        self.0.iter().all(|v| v.is_finite())
    }
}

impl Index<Axis> for AxisVec {
    type Output = f64;
    #[inline]
    fn index(&self, axis: Axis) -> &f64 {
        &self.0[axis.index()]
    }
}

impl IndexMut<Axis> for AxisVec {
    #[inline]
    fn index_mut(&mut self, axis: Axis) -> &mut f64 {
        &mut self.0[axis.index()]
    }
}

impl Add for AxisVec {
    type Output = AxisVec;
    #[inline]
    fn add(self, rhs: AxisVec) -> AxisVec {
        AxisVec(std::array::from_fn(|i| self.0[i] + rhs.0[i]))
    }
}

impl Sub for AxisVec {
    type Output = AxisVec;
    #[inline]
    fn sub(self, rhs: AxisVec) -> AxisVec {
        AxisVec(std::array::from_fn(|i| self.0[i] - rhs.0[i]))
    }
}

impl Mul<f64> for AxisVec {
    type Output = AxisVec;
    #[inline]
    fn mul(self, s: f64) -> AxisVec {
        AxisVec(self.0.map(|v| v * s))
    }
}

/// Arc plane: G17 (XY), G18 (ZX) or G19 (YZ).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Plane {
    XY,
    ZX,
    YZ,
}

impl Plane {
    /// The in-plane axes (u, v) and the normal axis n, ordered so that u × v = n: a
    /// counter-clockwise (G03) arc turns from u towards v.
    pub const fn axes(self) -> (Axis, Axis, Axis) {
        match self {
            Plane::XY => (Axis::X, Axis::Y, Axis::Z),
            Plane::ZX => (Axis::Z, Axis::X, Axis::Y),
            Plane::YZ => (Axis::Y, Axis::Z, Axis::X),
        }
    }

    /// The G code that selects the plane, with its axes, for messages.
    pub fn g_code(self) -> &'static str {
        match self {
            Plane::XY => "G17 (XY)",
            Plane::ZX => "G18 (ZX)",
            Plane::YZ => "G19 (YZ)",
        }
    }
}
