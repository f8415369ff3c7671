//! ISO 230-7 location errors of the rotary axes, and the actual (errored) table pose.
//!
//! Each rotary axis R turns about an actual line that differs slightly from its nominal
//! one. The line is given at the home pose (all axes at zero) in the frame of R's parent:
//! the machine frame for the tilting axis (A or B), the frame the tilting axis carries for
//! the table axis (C; A on trt-ab). Nominal lines pass through the pivot.
//!
//! | axis | nominal n | position errors (um) | orientation errors (urad) |
//! |---|---|---|---|
//! | A | (1, 0, 0) | EY0A, EZ0A | EB0A, EC0A |
//! | B | (0, 1, 0) | EX0B, EZ0B | EA0B, EC0B |
//! | C | (0, 0, 1) | EX0C, EY0C | EA0C, EB0C |
//!
//! ```text
//! p_R = pivot + (EX0R, EY0R, EZ0R)                  a point on the actual line
//! u_R = unit(n + (EA0R, EB0R, EC0R) × n)            its direction
//! T_R(θ) x = Rot(u_R, θ) (x − p_R) + p_R            turning by θ (Rodrigues, exact)
//! m = T_tilt(tilt) T_C(C) x                         a table point x (home pose, machine
//!                                                   coordinates) in the machine frame
//! m = T_B(−B) T_A(−A) x                             the same on trt-ab (table turns by −A, −B)
//! ```
//!
//! For C this gives u_C ≈ (EB0C, −EA0C, 1); for A, u_A ≈ (1, EC0A, −EB0A). With all errors
//! zero, m is the nominal `pivot + R(q) p` of [`super::Kinematics::table_to_machine`].
//!
//! On a general chain (the kinematic-chains spec) a rotary's line need not lie along its
//! letter's machine axis (a 45° nutating B), so every rotary takes all six parameters
//! (EX0R EY0R EZ0R in um, EA0R EB0R EC0R in urad, [`LocationParam::EVERY`]); on each
//! link, `p_k + e` and `unit(d_k + ε × d_k)` ([`LocationErrors::actual_link`]). Only the
//! component along the line itself has no effect, and is refused on reading when the line
//! lies along that machine axis.

use nalgebra::{Isometry3, Point3, Rotation3, Translation3, Unit, UnitQuaternion, Vector3};
use serde::Serialize;

use super::linear_errors::ComponentErrors;
use crate::Axis;

/// One location-error parameter. Position errors are in um, orientation errors in urad.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[allow(clippy::upper_case_acronyms)]
pub enum LocationParam {
    EY0A,
    EZ0A,
    EB0A,
    EC0A,
    EX0B,
    EZ0B,
    EA0B,
    EC0B,
    EX0C,
    EY0C,
    EA0C,
    EB0C,
    /// The components along the letter's own machine axis: meaningful only on a general
    /// chain whose line for that letter is not along it.
    EX0A,
    EA0A,
    EY0B,
    EB0B,
    EZ0C,
    EC0C,
    /// Squareness of the linear axes (ISO 230-1, [`super::linear_errors`]): Y's line
    /// turned about Z, Z's about Y and about X; X is the reference.
    EC0Y,
    EB0Z,
    EA0Z,
}

impl LocationParam {
    /// Every parameter of a named layout, in table order (A, B, C; positions before
    /// orientations): the first twelve of [`LocationParam::EVERY`].
    pub const ALL: [LocationParam; 12] = {
        let mut all = [LocationParam::EY0A; 12];
        let mut i = 0;
        while i < 12 {
            all[i] = LocationParam::EVERY[i];
            i += 1;
        }
        all
    };

    /// Every parameter a general chain's rotary may carry: [`LocationParam::ALL`], then the
    /// components along each letter's own machine axis.
    pub const EVERY: [LocationParam; 18] = [
        LocationParam::EY0A,
        LocationParam::EZ0A,
        LocationParam::EB0A,
        LocationParam::EC0A,
        LocationParam::EX0B,
        LocationParam::EZ0B,
        LocationParam::EA0B,
        LocationParam::EC0B,
        LocationParam::EX0C,
        LocationParam::EY0C,
        LocationParam::EA0C,
        LocationParam::EB0C,
        LocationParam::EX0A,
        LocationParam::EA0A,
        LocationParam::EY0B,
        LocationParam::EB0B,
        LocationParam::EZ0C,
        LocationParam::EC0C,
    ];

    /// "EX0C".
    pub fn name(self) -> &'static str {
        use LocationParam::*;
        match self {
            EY0A => "EY0A",
            EZ0A => "EZ0A",
            EB0A => "EB0A",
            EC0A => "EC0A",
            EX0B => "EX0B",
            EZ0B => "EZ0B",
            EA0B => "EA0B",
            EC0B => "EC0B",
            EX0C => "EX0C",
            EY0C => "EY0C",
            EA0C => "EA0C",
            EB0C => "EB0C",
            EX0A => "EX0A",
            EA0A => "EA0A",
            EY0B => "EY0B",
            EB0B => "EB0B",
            EZ0C => "EZ0C",
            EC0C => "EC0C",
            EC0Y => "EC0Y",
            EB0Z => "EB0Z",
            EA0Z => "EA0Z",
        }
    }

    /// The squareness errors of the linear axes (ISO 230-1), in `[location_errors]` too.
    pub const SQUARENESS: [LocationParam; 3] = [
        LocationParam::EC0Y,
        LocationParam::EB0Z,
        LocationParam::EA0Z,
    ];

    /// The axis the parameter belongs to: a rotary, or Y and Z for the squareness errors.
    pub fn axis(self) -> Axis {
        match self.name().as_bytes()[3] {
            b'A' => Axis::A,
            b'B' => Axis::B,
            b'Y' => Axis::Y,
            b'Z' => Axis::Z,
            _ => Axis::C,
        }
    }

    /// True for a squareness error of a linear axis ([`LocationParam::SQUARENESS`]).
    pub fn is_squareness(self) -> bool {
        LocationParam::SQUARENESS.contains(&self)
    }

    /// True for a position error (um), false for an orientation error (urad).
    pub fn is_position(self) -> bool {
        matches!(self.name().as_bytes()[1], b'X' | b'Y' | b'Z')
    }

    /// "um" or "urad".
    pub fn unit(self) -> &'static str {
        if self.is_position() {
            "um"
        } else {
            "urad"
        }
    }

    /// The machine-file key: "EX0C_um", "EA0C_urad".
    pub fn key(self) -> String {
        format!("{}_{}", self.name(), self.unit())
    }

    /// The parameter a machine-file key names, if any (of [`LocationParam::EVERY`] and
    /// [`LocationParam::SQUARENESS`]).
    pub fn from_key(key: &str) -> Option<LocationParam> {
        LocationParam::EVERY
            .into_iter()
            .chain(LocationParam::SQUARENESS)
            .find(|p| p.key() == key)
    }

    /// Index of the error component: 0 = X, 1 = Y, 2 = Z (translation along, or rotation
    /// about, that machine axis).
    pub fn component(self) -> usize {
        match self.name().as_bytes()[1] {
            b'X' | b'A' => 0,
            b'Y' | b'B' => 1,
            _ => 2,
        }
    }

    /// Index into [`LocationParam::EVERY`], then [`LocationParam::SQUARENESS`].
    pub fn index(self) -> usize {
        let every = LocationParam::EVERY.len();
        LocationParam::EVERY
            .iter()
            .position(|p| *p == self)
            .or_else(|| {
                LocationParam::SQUARENESS
                    .iter()
                    .position(|p| *p == self)
                    .map(|i| every + i)
            })
            .expect("in EVERY or SQUARENESS")
    }
}

/// A cause among a machine's geometric errors ([`LocationErrors::parts`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorPart {
    /// The location errors of the rotary axes.
    Rotaries,
    /// The squareness of the linear axes (`EC0Y`, `EB0Z`, `EA0Z`).
    Squareness,
    /// One linear axis's component errors (positioning, straightness, angular).
    Components(Axis),
}

/// The location errors of a machine's rotary axes, with the squareness and the component
/// errors of its linear axes ([`super::linear_errors`]): every error the actual chain
/// carries; zero for a perfect machine.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LocationErrors {
    /// Indexed by [`LocationParam::index`]: um or urad.
    values: [f64; 21],
    /// The component-error tables of X, Y and Z, if any.
    components: Option<&'static ComponentErrors>,
}

impl LocationErrors {
    pub fn get(&self, p: LocationParam) -> f64 {
        self.values[p.index()]
    }

    pub fn set(&mut self, p: LocationParam, value: f64) {
        self.values[p.index()] = value;
    }

    /// With `p` set to `value`.
    pub fn with(mut self, p: LocationParam, value: f64) -> LocationErrors {
        self.set(p, value);
        self
    }

    pub fn is_zero(&self) -> bool {
        self.values.iter().all(|v| *v == 0.0) && self.components.is_none()
    }

    /// True when a linear axis carries an error (squareness or a component table): the
    /// actual chain then differs from the nominal one on its linear links too.
    pub fn has_linear(&self) -> bool {
        self.components.is_some()
            || LocationParam::SQUARENESS
                .into_iter()
                .any(|p| self.get(p) != 0.0)
    }

    /// The same errors with the component tables `components` (none when empty).
    pub fn with_components(mut self, components: ComponentErrors) -> LocationErrors {
        self.components = (!components.is_empty()).then(|| components.interned());
        self
    }

    /// The errors split by cause, each alone (the rest zero), for the error budget's
    /// counterfactual runs: the rotaries' location errors, the squareness of the linear
    /// axes, and each linear axis's component errors; the parts that are zero are left out.
    pub fn parts(&self) -> Vec<(ErrorPart, LocationErrors)> {
        let mut parts = Vec::new();
        let mut rotaries = LocationErrors::default();
        for p in LocationParam::EVERY {
            rotaries.set(p, self.get(p));
        }
        if !rotaries.is_zero() {
            parts.push((ErrorPart::Rotaries, rotaries));
        }
        let mut squareness = LocationErrors::default();
        for p in LocationParam::SQUARENESS {
            squareness.set(p, self.get(p));
        }
        if !squareness.is_zero() {
            parts.push((ErrorPart::Squareness, squareness));
        }
        if let Some(tables) = self.components {
            for axis in tables.axes() {
                let one = LocationErrors::default().with_components(tables.only(axis));
                parts.push((ErrorPart::Components(axis), one));
            }
        }
        parts
    }

    /// The component-error tables of X, Y and Z, if any.
    pub fn components(&self) -> Option<&'static ComponentErrors> {
        self.components
    }

    /// The squareness rotation (EA, EB, EC) of linear axis `axis`'s line, rad: Y turns
    /// about Z by EC0Y, Z about X by EA0Z and about Y by EB0Z; zero for any other axis.
    pub fn squareness_rad(&self, axis: Axis) -> Vector3<f64> {
        let mut v = Vector3::zeros();
        for p in LocationParam::SQUARENESS
            .into_iter()
            .filter(|p| p.axis() == axis)
        {
            v[p.component()] = self.get(p) * 1e-6;
        }
        v
    }

    /// The non-zero parameters and their values.
    pub fn nonzero(&self) -> Vec<(LocationParam, f64)> {
        LocationParam::EVERY
            .into_iter()
            .chain(LocationParam::SQUARENESS)
            .filter(|p| self.get(*p) != 0.0)
            .map(|p| (p, self.get(p)))
            .collect()
    }

    /// Position offset of `axis`'s line, mm (machine X, Y, Z components).
    fn offset_mm(&self, axis: Axis) -> Vector3<f64> {
        let mut v = Vector3::zeros();
        for p in LocationParam::EVERY
            .into_iter()
            .filter(|p| p.axis() == axis)
        {
            if p.is_position() {
                v[p.component()] += self.get(p) * 1e-3;
            }
        }
        v
    }

    /// Small-rotation vector (EA0R, EB0R, EC0R) of `axis`'s line, rad.
    fn rotation_rad(&self, axis: Axis) -> Vector3<f64> {
        let mut v = Vector3::zeros();
        for p in LocationParam::EVERY
            .into_iter()
            .filter(|p| p.axis() == axis)
        {
            if !p.is_position() {
                v[p.component()] += self.get(p) * 1e-6;
            }
        }
        v
    }
}

impl LocationErrors {
    /// The actual line of a general chain's rotary `axis` whose nominal line passes through
    /// `point_mm` along the unit `direction` (home pose, machine frame):
    /// `(p + e, unit(d + ε × d))`.
    pub fn actual_link(
        &self,
        axis: Axis,
        direction: &Vector3<f64>,
        point_mm: &Vector3<f64>,
    ) -> (Vector3<f64>, Vector3<f64>) {
        let eps = self.rotation_rad(axis);
        let d = direction + eps.cross(direction);
        (d.normalize(), point_mm + self.offset_mm(axis))
    }
}

/// The line a rotary axis actually turns about, at the home pose, in its parent's frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisLine {
    /// A point on the line, machine coordinates at home, mm.
    pub point_mm: Vector3<f64>,
    /// Unit direction (right-hand rule for positive angles).
    pub direction: Unit<Vector3<f64>>,
}

impl AxisLine {
    /// The actual line of rotary `axis`: `p = pivot + e`, `u = unit(n + ε × n)`.
    pub fn actual(axis: Axis, pivot_mm: &Vector3<f64>, errors: &LocationErrors) -> AxisLine {
        let n = match axis {
            Axis::A => Vector3::x(),
            Axis::B => Vector3::y(),
            _ => Vector3::z(),
        };
        let eps = errors.rotation_rad(axis);
        AxisLine {
            point_mm: pivot_mm + errors.offset_mm(axis),
            direction: Unit::new_normalize(n + eps.cross(&n)),
        }
    }

    /// `T(θ)`: the rigid motion of turning by `angle_deg` about this line,
    /// `x ↦ Rot(u, θ)(x − p) + p`.
    pub fn turn(&self, angle_deg: f64) -> Isometry3<f64> {
        let r = Rotation3::from_axis_angle(&self.direction, angle_deg.to_radians());
        let t = self.point_mm - r * self.point_mm;
        Isometry3::from_parts(
            Translation3::from(t),
            UnitQuaternion::from_rotation_matrix(&r),
        )
    }

    /// The image of `x` (mm) under [`AxisLine::turn`], with the rotation matrix applied
    /// directly (no quaternion round trip).
    pub fn turn_point(&self, angle_deg: f64, x: &Point3<f64>) -> Point3<f64> {
        let r = Rotation3::from_axis_angle(&self.direction, angle_deg.to_radians());
        Point3::from(r * (x.coords - self.point_mm) + self.point_mm)
    }
}
