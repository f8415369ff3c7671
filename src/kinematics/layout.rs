//! The named machine layouts (xyz, trt-ac, ...) and a general chain's axis set: which axes
//! a machine has and what its tool pose needs (formulas in the parent module's docs).

use serde::{Deserialize, Serialize};

use super::axis_set::AxisSet;
use crate::Axis;

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
