//! The named machine layouts (xyz, trt-ac, ...) and a general chain's axis set: which axes
//! a machine has and what its tool pose needs (formulas in the parent module's docs).
//!
//! This is the one file that names the layouts one by one: their axes, their links as a
//! chain ([`Layout::links`], `layout_chain.rs` builds the chain from them), and the closed
//! forms of their rotation and its inverse that the kinematics runs as a fast path behind
//! the chain's interface ([`Layout::rotation_matrix`], [`Layout::solve_rotaries`],
//! [`Layout::turn_point`], [`Layout::into_table_frames`]). No stage outside `kinematics/`
//! matches on a layout (checked by `tests/architecture.rs`).

use nalgebra::{Matrix3, Rotation3, Vector3};
use serde::{Deserialize, Serialize};

use super::axis_set::AxisSet;
use super::chain::Link;
use super::chain_inverse::unwrap_near;
use crate::numeric::sin_cos_deg_pair;
use crate::{Axis, AxisVec};

/// Which of the two inverse-kinematics solutions to take.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Branch {
    /// Tilt >= 0 (the spec's branch).
    #[default]
    Primary,
    /// Tilt <= 0 and C + 180 deg.
    Secondary,
}

/// `(sin, cos)` of the table axis (`c`: C, or A for trt-ab) and of the tilting axis (A or
/// B; 0 without one), as [`Layout::rotation_matrix`] takes them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RotarySinCos {
    pub c: (f64, f64),
    pub tilt: (f64, f64),
}

/// Below this horizontal length of the tool axis, C is free and kept.
const C_FREE_EPS: f64 = 1e-12;

/// The layout of a machine.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Layout {
    /// Three linear axes, vertical spindle.
    #[serde(rename = "xyz")]
    Xyz,
    /// Tilting rotary table: A tilts about X, C turns the table about its own Z.
    #[serde(rename = "trt-ac")]
    TrtAc,
    /// Tilting rotary table: B tilts about Y, C turns the table about its own Z.
    #[serde(rename = "trt-bc")]
    TrtBc,
    /// Table dual rotary (LinuxCNC xyzab-tdr): B tilts a cradle about Y, A turns the table
    /// about the cradle's X; conventional directions (see the module docs).
    #[serde(rename = "trt-ab")]
    TrtAb,
    /// Two linear axes X and Z (a lathe, LinuxCNC `trivkins coordinates=xz`): the tool tip
    /// at (X, 0, Z).
    #[serde(rename = "xz")]
    Xz,
    /// Three linear axes and a fourth axis A (LinuxCNC `trivkins`, COORDINATES = X Y Z A):
    /// A turns the part about the machine's X axis through the pivot, `R = Rx(A)`.
    #[serde(rename = "xyza")]
    Xyza,
    /// Six independent world axes X Y Z A B C, as LinuxCNC plans a robot's world
    /// coordinates (puma, melfa): A B C are coordinates with no modelled chain (the
    /// robot's joints are not modelled), so TCP, a ball bar and collisions are refused.
    #[serde(rename = "xyzabc")]
    Xyzabc,
    /// Four independent linear axes X Y U V (a hot-wire foam cutter, LinuxCNC `trivkins
    /// coordinates=xyuv`): X Y carry one end of the wire, U V the other.
    #[serde(rename = "xyuv")]
    Xyuv,
    /// Nine independent world axes X Y Z A B C U V W (LinuxCNC's axis_9axis, trivkins):
    /// A B C as in xyzabc, U V W linear axes parallel to X Y Z.
    #[serde(rename = "xyzabcuvw")]
    Xyzabcuvw,
    /// A machine file's own `[kinematics]` chain that no named layout is (a head machine, a
    /// nutating table, ...), with these axes; the chain itself is [`Kinematics::chain`].
    #[serde(skip)]
    Chain(AxisSet),
}

impl Layout {
    /// Every layout.
    pub const ALL: [Layout; 9] = [
        Layout::Xyz,
        Layout::TrtAc,
        Layout::TrtBc,
        Layout::TrtAb,
        Layout::Xz,
        Layout::Xyza,
        Layout::Xyzabc,
        Layout::Xyuv,
        Layout::Xyzabcuvw,
    ];

    /// A machine file's own chain with `axes`, no named layout.
    pub fn chain_of(axes: AxisSet) -> Layout {
        Layout::Chain(axes)
    }

    /// The axes a machine of this layout has, in order.
    pub fn axes(self) -> &'static [Axis] {
        match self {
            Layout::Xyz => &[Axis::X, Axis::Y, Axis::Z],
            Layout::TrtAc => &[Axis::X, Axis::Y, Axis::Z, Axis::A, Axis::C],
            Layout::TrtBc => &[Axis::X, Axis::Y, Axis::Z, Axis::B, Axis::C],
            Layout::TrtAb => &[Axis::X, Axis::Y, Axis::Z, Axis::A, Axis::B],
            Layout::Xz => &[Axis::X, Axis::Z],
            Layout::Xyza => &[Axis::X, Axis::Y, Axis::Z, Axis::A],
            Layout::Xyzabc => &Axis::XYZABC,
            Layout::Xyuv => &[Axis::X, Axis::Y, Axis::U, Axis::V],
            Layout::Xyzabcuvw => &Axis::ALL,
            Layout::Chain(axes) => axes.axes(),
        }
    }

    /// The tilting axis, if any.
    pub fn tilt_axis(self) -> Option<Axis> {
        match self {
            Layout::Xyz
            | Layout::Xz
            | Layout::Xyza
            | Layout::Xyzabc
            | Layout::Xyuv
            | Layout::Xyzabcuvw
            | Layout::Chain(_) => None,
            Layout::TrtAc => Some(Axis::A),
            Layout::TrtBc => Some(Axis::B),
            Layout::TrtAb => Some(Axis::B),
        }
    }

    /// The axis that turns the table on the cradle, if any: C, or A for trt-ab and xyza
    /// (which has no cradle: A turns the part about the machine's X).
    pub fn table_axis(self) -> Option<Axis> {
        match self {
            Layout::Xyz
            | Layout::Xz
            | Layout::Xyzabc
            | Layout::Xyuv
            | Layout::Xyzabcuvw
            | Layout::Chain(_) => None,
            Layout::TrtAc | Layout::TrtBc => Some(Axis::C),
            Layout::TrtAb | Layout::Xyza => Some(Axis::A),
        }
    }

    /// True when the rotary axes are world coordinates with no modelled kinematic chain
    /// (xyzabc): then nothing that needs the tool's orientation or the machine's joints
    /// (TCP, a ball bar through the servo models, the collision scene) can be computed.
    pub fn rotaries_unmodelled(self) -> bool {
        matches!(self, Layout::Xyzabc | Layout::Xyzabcuvw)
    }

    /// True when the layout has secondary linear axes U V W (xyuv, xyzabcuvw): axes with no
    /// place in the tool pose (a foam cutter's far wire end), so nothing that needs the
    /// tool's pose (TCP, a ball bar, the collision scene) can be computed.
    pub fn has_secondary_axes(self) -> bool {
        matches!(self, Layout::Xyuv | Layout::Xyzabcuvw)
    }

    /// Why the tool's pose is unknown on this layout (so TCP, a ball bar and the collision
    /// scene are refused), for messages; `None` when it is modelled.
    pub fn tool_pose_unmodelled(self) -> Option<&'static str> {
        match self {
            Layout::Xyzabc => Some(
                "its A B C are world coordinates (a robot's, as LinuxCNC plans them) with no modelled kinematic chain",
            ),
            Layout::Xyuv => Some(
                "its U V are linear axes with no place in the tool pose (a foam cutter's far wire end)",
            ),
            Layout::Xyzabcuvw => Some(
                "its A B C are world coordinates with no modelled kinematic chain and its U V W linear axes with no place in the tool pose",
            ),
            _ => None,
        }
    }

    /// True when the collision scene (a milling tool along +Z, a table, a cradle) models
    /// this machine: not a lathe (xz: a turning tool and chuck) nor xyzabc (the tool's
    /// orientation is not modelled).
    pub fn has_collision_scene(self) -> bool {
        !matches!(self, Layout::Xz | Layout::Xyzabc | Layout::Chain(_))
            && !self.has_secondary_axes()
    }

    /// +1 when a positive rotary command turns the table positively about its axis line's
    /// direction (+X for A, +Y for B, +Z for C), -1 when negatively (trt-ab).
    pub fn table_turn_sign(self) -> f64 {
        match self {
            Layout::TrtAb => -1.0,
            _ => 1.0,
        }
    }

    /// The layout's table and head links (each from the bed outward) with its rotary lines
    /// through `pivot_mm` (the table of `layout_chain.rs`); `None` for the layouts whose
    /// rotaries or U V W have no place in the tool pose, and for a general chain.
    pub fn links(self, pivot_mm: Vector3<f64>) -> Option<(Vec<Link>, Vec<Link>)> {
        let x = Vector3::x();
        let y = Vector3::y();
        let z = Vector3::z();
        let rot = |axis, d| Link::rotary(axis, d, pivot_mm);
        let xyz = [
            Link::linear(Axis::X, x),
            Link::linear(Axis::Y, y),
            Link::linear(Axis::Z, z),
        ];
        Some(match self {
            Layout::Xyz => (vec![], xyz.to_vec()),
            Layout::Xz => (vec![], vec![xyz[0], xyz[2]]),
            Layout::Xyza => (vec![rot(Axis::A, x)], xyz.to_vec()),
            Layout::TrtAc => (vec![rot(Axis::A, x), rot(Axis::C, z)], xyz.to_vec()),
            Layout::TrtBc => (vec![rot(Axis::B, y), rot(Axis::C, z)], xyz.to_vec()),
            Layout::TrtAb => (vec![rot(Axis::B, -y), rot(Axis::A, -x)], xyz.to_vec()),
            Layout::Xyzabc | Layout::Xyuv | Layout::Xyzabcuvw | Layout::Chain(_) => return None,
        })
    }

    /// Sine and cosine of the table axis (C, or A for trt-ab) and of the tilt at `q`, both
    /// angles in one pass ([`sin_cos_deg_pair`]).
    #[inline]
    pub fn rotary_sin_cos(self, q: &AxisVec) -> RotarySinCos {
        let tilt = self.tilt_axis().map_or(0.0, |t| q[t]);
        let table = self.table_axis().map_or(0.0, |t| q[t]);
        let [c, tilt] = sin_cos_deg_pair(table, tilt);
        RotarySinCos { c, tilt }
    }

    /// R, which turns table-frame vectors into the machine frame, from the sines and cosines
    /// of its angles: `Rx(A) Rz(C)` (trt-ac), `Ry(B) Rz(C)` (trt-bc), `Ry(-B) Rx(-A)`
    /// (trt-ab), `Rx(A)` (xyza); the identity for the others (a general chain's rotations are
    /// its own, `Kinematics::chain`).
    #[inline]
    pub fn rotation_matrix(self, angles: &RotarySinCos) -> Matrix3<f64> {
        // Written out with one sin_cos per angle (the ball bar reads it three times a sample).
        let (sc, cc) = angles.c;
        match self {
            // xyzabc's rotaries carry no modelled chain: its tool tip is the world X Y Z.
            Layout::Xyz
            | Layout::Xz
            | Layout::Xyzabc
            | Layout::Xyuv
            | Layout::Xyzabcuvw
            | Layout::Chain(_) => Matrix3::identity(),
            Layout::Xyza => {
                // Rx(A); the table axis (the `c` slot) is A.
                let (sa, ca) = (sc, cc);
                Matrix3::new(1.0, 0.0, 0.0, 0.0, ca, -sa, 0.0, sa, ca)
            }
            Layout::TrtAb => {
                // For trt-ab the table axis (the `c` slot) is A.
                let (sa, ca) = (sc, cc);
                let (sb, cb) = angles.tilt;
                Matrix3::new(cb, sa * sb, -ca * sb, 0.0, ca, sa, sb, -sa * cb, ca * cb)
            }
            Layout::TrtAc => {
                let (sa, ca) = angles.tilt;
                Matrix3::new(cc, -sc, 0.0, ca * sc, ca * cc, -sa, sa * sc, sa * cc, ca)
            }
            Layout::TrtBc => {
                let (sb, cb) = angles.tilt;
                Matrix3::new(cb * cc, -cb * sc, sb, sc, cc, 0.0, -sb * cc, sb * sc, cb)
            }
        }
    }

    /// `R(q) p` with one `sin_cos` per angle, the rotations applied one after the other:
    /// `Rz(C)` then `Rx(A)` (trt-ac) or `Ry(B)` (trt-bc); trt-ab and xyza through
    /// [`Layout::rotation_matrix`]; `p` itself where R is the identity. mm and deg.
    #[inline]
    pub fn turn_point(self, q: &AxisVec, p: [f64; 3]) -> [f64; 3] {
        let [x, y, z] = p;
        match self {
            Layout::Xyz
            | Layout::Xz
            | Layout::Xyzabc
            | Layout::Xyuv
            | Layout::Xyzabcuvw
            | Layout::Chain(_) => p,
            Layout::TrtAb | Layout::Xyza => {
                let r =
                    Rotation3::from_matrix_unchecked(self.rotation_matrix(&self.rotary_sin_cos(q)));
                let m = r * Vector3::new(x, y, z);
                [m.x, m.y, m.z]
            }
            Layout::TrtAc | Layout::TrtBc => {
                let (sc, cc) = q[Axis::C].to_radians().sin_cos();
                let (x, y) = (cc * x - sc * y, sc * x + cc * y);
                if self == Layout::TrtAc {
                    let (sa, ca) = q[Axis::A].to_radians().sin_cos();
                    [x, ca * y - sa * z, sa * y + ca * z]
                } else {
                    let (sb, cb) = q[Axis::B].to_radians().sin_cos();
                    [cb * x + sb * z, y, -sb * x + cb * z]
                }
            }
        }
    }

    /// `u` (machine frame) in the table frame, `R^T u`, and in the cradle frame (the part the
    /// tilting axis carries), `R_tilt^T u`, with one `sin_cos` per angle; `[u, u]` where R
    /// is the identity, and the cradle frame is the machine's on xyza (no cradle).
    pub fn into_table_frames(self, q: &AxisVec, u: Vector3<f64>) -> [Vector3<f64>; 2] {
        let cradle = match self {
            Layout::Xyz
            | Layout::Xz
            | Layout::Xyzabc
            | Layout::Xyuv
            | Layout::Xyzabcuvw
            | Layout::Chain(_) => return [u, u],
            Layout::Xyza => {
                // Rx(A)^T u; no cradle.
                let (s, c) = q[Axis::A].to_radians().sin_cos();
                return [Vector3::new(u.x, c * u.y + s * u.z, -s * u.y + c * u.z), u];
            }
            Layout::TrtAb => {
                // Ry(-B)^T u, then Rx(-A)^T.
                let (sb, cb) = q[Axis::B].to_radians().sin_cos();
                let cradle = Vector3::new(cb * u.x + sb * u.z, u.y, -sb * u.x + cb * u.z);
                let (sa, ca) = q[Axis::A].to_radians().sin_cos();
                let table = Vector3::new(
                    cradle.x,
                    ca * cradle.y - sa * cradle.z,
                    sa * cradle.y + ca * cradle.z,
                );
                return [table, cradle];
            }
            Layout::TrtAc => {
                let (s, c) = q[Axis::A].to_radians().sin_cos();
                Vector3::new(u.x, c * u.y + s * u.z, -s * u.y + c * u.z)
            }
            Layout::TrtBc => {
                let (s, c) = q[Axis::B].to_radians().sin_cos();
                Vector3::new(c * u.x - s * u.z, u.y, s * u.x + c * u.z)
            }
        };
        let (s, c) = q[Axis::C].to_radians().sin_cos();
        let table = Vector3::new(
            c * cradle.x + s * cradle.y,
            -s * cradle.x + c * cradle.y,
            cradle.z,
        );
        [table, cradle]
    }

    /// The rotary axes that carry the unit tool axis `t` (table frame) onto the machine's +Z,
    /// on `branch`, the table axis unwrapped near `previous_c_deg` (and kept there where it
    /// is free), written into `q` (the closed forms of the parent module's docs). Nothing is
    /// written on a layout without rotaries.
    pub fn solve_rotaries(
        self,
        t: &Vector3<f64>,
        branch: Branch,
        previous_c_deg: f64,
        q: &mut AxisVec,
    ) {
        if self == Layout::TrtAb {
            let b = t.x.clamp(-1.0, 1.0).asin().to_degrees();
            let a = if t.y.hypot(t.z) < C_FREE_EPS {
                previous_c_deg
            } else {
                let a = (-t.y).atan2(t.z).to_degrees();
                let a = match branch {
                    Branch::Primary => a,
                    Branch::Secondary => a + 180.0,
                };
                unwrap_near(a, previous_c_deg)
            };
            q[Axis::B] = match branch {
                Branch::Primary => b,
                Branch::Secondary => 180.0 - b,
            };
            q[Axis::A] = a;
        } else if self == Layout::Xyza {
            // Rx(A) t = z: t = Rx(-A) z = (0, sin A, cos A), so A = atan2(j, k) (reached
            // exactly only when i = 0: a fourth axis cannot tilt the tool about Y).
            q[Axis::A] = if t.y.hypot(t.z) < C_FREE_EPS {
                previous_c_deg
            } else {
                unwrap_near(t.y.atan2(t.z).to_degrees(), previous_c_deg)
            };
        } else if let Some(tilt_axis) = self.tilt_axis() {
            let tilt = t.z.clamp(-1.0, 1.0).acos().to_degrees();
            // Direction (angle about Z) that t's horizontal part must be turned to by C.
            let target = match self {
                Layout::TrtAc => 90.0,
                _ => 180.0,
            };
            let (tilt, target) = match branch {
                Branch::Primary => (tilt, target),
                Branch::Secondary => (-tilt, target + 180.0),
            };
            let horizontal = t.x.hypot(t.y);
            let c = if horizontal < C_FREE_EPS {
                previous_c_deg
            } else {
                unwrap_near(target - t.y.atan2(t.x).to_degrees(), previous_c_deg)
            };
            q[tilt_axis] = tilt;
            q[Axis::C] = c;
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Layout::Xyz => "xyz",
            Layout::TrtAc => "trt-ac",
            Layout::TrtBc => "trt-bc",
            Layout::TrtAb => "trt-ab",
            Layout::Xz => "xz",
            Layout::Xyza => "xyza",
            Layout::Xyzabc => "xyzabc",
            Layout::Xyuv => "xyuv",
            Layout::Xyzabcuvw => "xyzabcuvw",
            Layout::Chain(_) => "chain",
        }
    }
}
