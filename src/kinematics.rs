//! Forward and inverse kinematics of the supported machine layouts.
//!
//! Frames: the machine frame M, in which the tool tip sits at (X, Y, Z) and the tool axis
//! is +Z (vertical spindle), and the table frame T fixed to the rotary table. T's origin is
//! the pivot, where the rotary axes cross; its Z axis is the C axis; at zero rotary angles
//! it is parallel to M. The pivot sits at `pivot_mm` in machine coordinates.
//!
//! A point p fixed to the table appears in the machine frame at
//!
//! ```text
//! m = pivot + R(q) p,   R = Rx(A) Rz(C)  (trt-ac),   Ry(B) Rz(C)  (trt-bc),
//!                       R = Ry(-B) Rx(-A)  (trt-ab)
//! ```
//!
//! trt-ac and trt-bc turn the table by +A (+B, +C) about +X (+Y, +Z), as LinuxCNC's
//! xyzac-trt and xyzbc-trt kinematics do (the opposite of the ISO directions, as LinuxCNC
//! notes). trt-ab is LinuxCNC's table-dual-rotary machine (`xyzab_tdr_kins`): B tilts a
//! cradle about Y, A turns the table about the cradle's X axis, both in the conventional
//! directions (the table turns by -A and -B, so the tool turns by +A and +B relative to the
//! work). Its kinematics, written out with `(sa, ca) = sin/cos A`, `(sb, cb) = sin/cos B`:
//!
//! ```text
//!                     | cb   sa sb   -ca sb |
//! R = Ry(-B) Rx(-A) = | 0    ca       sa    |
//!                     | sb  -sa cb    ca cb |
//! ```
//!
//! which is the matrix of `xyzab_tdr_kins`' inverse (work to joints) with its offsets zero.
//! That component also has an offset of the A axis from the B axis along Z (`z-offset`, -10
//! mm in the sample configuration); mtsim's axes cross at the pivot, so that offset is not
//! modelled (its `x-offset`, along A, does not change the kinematics at all).
//!
//! Inverse kinematics, for a tool tip p and unit tool axis t = (i, j, k) in the table frame
//! (t points from the tip toward the spindle): the tilt must carry t onto +Z, and a rotation
//! about Z keeps k, so `tilt = ±acos(k)`. Then C turns t's horizontal part, at angle
//! `atan2(j, i)`, onto the direction the tilt needs: +Y for A (so `C = atan2(i, j)`, the
//! spec's formula) and -X for B. The primary branch has tilt >= 0; the secondary branch has
//! tilt <= 0 and C + 180 deg. C is unwrapped to stay continuous with the previous value,
//! and kept when i = j = 0, where it is free.
//!
//! For trt-ab, `R t = z` means `Rx(-A) t = Ry(B) z = (sin B, 0, cos B)`: so `B = asin(i)`
//! and A turns (j, k) onto (0, cos B), `A = atan2(-j, k)` (primary branch, |B| <= 90 deg).
//! The secondary branch is `B = 180 deg - B`, `A + 180 deg`. A is unwrapped like C and
//! kept when j = k = 0 (tool along the table's X axis, B = ±90 deg).
//!
//! # Trivial kinematics (LinuxCNC `trivkins`: each axis is its own joint)
//!
//! - xz (a lathe, COORDINATES = X Z): `m = (X, 0, Z)`, no rotaries.
//! - xyza (a fourth axis, COORDINATES = X Y Z A): A turns the part about the machine's X
//!   axis through the pivot, `R = Rx(A)`, in the same direction as trt-ac's A (a point at
//!   radius r on +Y goes to `(0, r cos A, r sin A)`). It has no cradle; A is its table axis.
//!   The tool axis stays +Z: a tool axis t in the part frame is reached by
//!   `A = atan2(j, k)` when `i = 0`.
//! - xyzabc (six world coordinates, as LinuxCNC plans a robot's: puma, melfa): `R = I`,
//!   the tool tip is the world X Y Z. A B C are the tool's orientation in the world, but the
//!   robot's joints are not modelled, so nothing that needs the tool's orientation or the
//!   joint motion is given: TCP, the ball bar and the collision scene are refused
//!   ([`Layout::rotaries_unmodelled`]).
//! - xyuv (a hot-wire foam cutter, LinuxCNC `trivkins coordinates=xyuv`): X Y move one end
//!   of the wire, U V (parallel to X Y) the other; `R = I`, the tool tip is `(X, Y, 0)`.
//! - xyzabcuvw (nine world coordinates, LinuxCNC's axis_9axis): `R = I`, the tool tip is
//!   X Y Z; A B C as for xyzabc.
//!
//!   U V W are linear axes of their own (mm) with no place in the tool pose: a wire's far
//!   end, a second carriage. So where the tool's pose must be known (TCP, the ball bar, the
//!   collision scene) these layouts are refused ([`Layout::has_secondary_axes`]); axis
//!   limits, timing, the servo models and the trace run on every axis.
//!
//! # Nominal and actual
//!
//! The controller plans with the nominal chain above ([`Kinematics::table_to_machine`],
//! [`Kinematics::inverse`]). The machine moves with its actual chain, which carries the
//! ISO 230-7 location errors of the rotary axes ([`location`]):
//! [`Kinematics::actual_table_to_machine`] and [`Kinematics::actual_table_pose`]. The
//! ISO 230-1 errors of the linear axes (squareness and component errors,
//! [`linear_errors`]) act on the links of [`Kinematics::actual_chain`], which a named
//! layout then runs too. Position errors along the axes (pitch and worm-gear error,
//! [`error_table`]) act on the axis positions themselves, before the kinematics.

pub mod axis_set;
pub mod chain;
pub mod chain_events;
pub mod chain_inverse;
pub mod cradle_table;
pub mod error_table;
pub mod layout;
pub mod layout_chain;
pub mod linear_errors;
pub mod location;
pub mod pole;

pub use axis_set::AxisSet;
pub use chain::{Chain, Link, Side, ToolPose};
pub use chain_inverse::unwrap_near;
pub use cradle_table::CradleTablePoses;
pub use layout::{Branch, Layout, RotarySinCos};
pub use location::{AxisLine, ErrorPart, LocationErrors, LocationParam};
pub use pole::{Pole, DEFAULT_POLE_TOLERANCE_DEG};

use nalgebra::{Isometry3, Point3, Rotation3, Translation3, Vector3};

use crate::numeric::{F64x2, LaneOps};
use crate::{Axis, AxisVec};

/// The kinematic chain of a machine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kinematics {
    pub layout: Layout,
    /// Machine coordinates of the pivot (table-frame origin), mm.
    pub pivot_mm: Vector3<f64>,
    /// Location errors of the rotary axes; they act only on the actual chain.
    pub location_errors: LocationErrors,
    /// The machine file's own chain when it is no named layout ([`Layout::Chain`]). Private:
    /// the stages ask the kinematics, which picks the named layout's closed form or this
    /// chain ([`Kinematics::has_closed_form`], [`Kinematics::own_chain`]).
    general: Option<Chain>,
    /// The nominal chain: the machine file's own, or the named layout's written out when the
    /// machine was read ([`layout_chain::of_layout`]); `None` where the tool pose has no
    /// chain (xyzabc, xyuv, xyzabcuvw). A named layout's closed forms
    /// ([`Layout::rotation_matrix`], [`Layout::solve_rotaries`]) are this chain's fast path.
    nominal: Option<Chain>,
    /// Within this angle of the pole (deg) the inner rotary holds ([`pole`]).
    pub pole_tolerance_deg: f64,
}

impl Kinematics {
    pub fn new(layout: Layout, pivot_mm: Vector3<f64>) -> Kinematics {
        Kinematics {
            layout,
            pivot_mm,
            location_errors: LocationErrors::default(),
            general: None,
            nominal: layout_chain::of_layout(layout, pivot_mm),
            pole_tolerance_deg: DEFAULT_POLE_TOLERANCE_DEG,
        }
    }

    /// A machine whose kinematics is `chain`, as its named layout when it is one (so that a
    /// written-out trt-ac runs exactly as `kinematics = "trt-ac"`), else as [`Layout::Chain`].
    pub fn from_chain(chain: Chain) -> Kinematics {
        match layout_chain::named(&chain) {
            Some((layout, pivot_mm)) => Kinematics::new(layout, pivot_mm),
            None => Kinematics {
                layout: Layout::chain_of(AxisSet::of(&chain.axes())),
                pivot_mm: Vector3::zeros(),
                location_errors: LocationErrors::default(),
                general: Some(chain),
                nominal: Some(chain),
                pole_tolerance_deg: DEFAULT_POLE_TOLERANCE_DEG,
            },
        }
    }

    /// Whether the nominal chain is a named layout's, with its closed forms (R(q) written
    /// out, the rotaries solved in closed form, the table and cradle posed by
    /// [`Kinematics::actual_table_pose`]); false on a general chain, whose bodies ride its
    /// links. For the stages that pose bodies or read the bar one way or the other (the
    /// collision scene, the bar's sensitivity); the arithmetic itself is the kinematics'.
    #[inline]
    pub fn has_closed_form(&self) -> bool {
        self.general.is_none()
    }

    /// The machine file's own chain when it is no named layout: what a stage that works on
    /// a general chain's links needs (the fit's location-error parameters per link, the
    /// chain's poles and switches, G53.1's tool aligner, the reader's checks). `None` on a
    /// named layout, whose written-out chain is [`Kinematics::chain`].
    #[inline]
    pub fn own_chain(&self) -> Option<&Chain> {
        self.general.as_ref()
    }

    /// The layout's name, or for a general chain its axes: "chain: table C; head X Y Z B".
    pub fn describe(&self) -> String {
        let Some(chain) = self.general else {
            return self.layout.name().to_string();
        };
        let list = |links: &[Link]| {
            let names: Vec<String> = links.iter().map(|l| l.axis.to_string()).collect();
            if names.is_empty() {
                "-".to_string()
            } else {
                names.join(" ")
            }
        };
        format!(
            "chain: table {}; head {}",
            list(chain.table()),
            list(chain.head())
        )
    }

    /// The chain's geometry in words, a line per axis from the bed outward on each side
    /// ("C on the table: turns about (0, 0, 1) through (0, 0, 0) mm"), then the spindle's
    /// gauge point and tool direction at home (machine frame, mm); empty for a layout
    /// without a chain.
    pub fn chain_geometry(&self) -> Vec<String> {
        let Some(chain) = self.nominal else {
            return Vec::new();
        };
        let mut lines: Vec<String> = chain
            .links()
            .map(|(side, l)| {
                let on = match side {
                    Side::Table => "on the table",
                    Side::Head => "on the head",
                };
                match l.axis.is_rotary() {
                    true => format!(
                        "{} {on}: turns about {} through {} mm",
                        l.axis,
                        triple(&l.direction),
                        triple(&l.point_mm)
                    ),
                    false => format!("{} {on}: moves along {}", l.axis, triple(&l.direction)),
                }
            })
            .collect();
        lines.push(format!(
            "gauge point {} mm, tool along {}",
            triple(&chain.gauge_point_mm),
            triple(&chain.tool_direction)
        ));
        lines
    }

    /// The machine's chain (the kinematic-chains spec): its own, or its named
    /// layout's written out; `None` for layouts whose rotaries or U V W have no place in
    /// the tool pose (xyzabc, xyuv, xyzabcuvw).
    pub fn chain(&self) -> Option<Chain> {
        self.nominal
    }

    /// The actual chain of a general machine, or of a named layout whose linear axes carry
    /// errors: each rotary's line moved and turned by its location errors
    /// ([`LocationErrors::actual_link`]), each linear axis's direction squared
    /// ([`linear_errors::squared_direction`]) and its component errors acting after its
    /// motion. The nominal chain when all are zero; `None` for a named layout with ideal
    /// linear axes (whose actual chain is [`Kinematics::actual_table_pose`]).
    pub fn actual_chain(&self) -> Option<Chain> {
        let errors = &self.location_errors;
        let chain = match self.general {
            Some(chain) => chain,
            None if errors.has_linear() => self.nominal?,
            None => return None,
        };
        if errors.is_zero() {
            return Some(chain);
        }
        let actual = chain.links().fold(chain, |actual, (_, link)| {
            let eps = errors.squareness_rad(link.axis);
            let (direction, point) = if link.axis.is_rotary() {
                errors.actual_link(link.axis, &link.direction, &link.point_mm)
            } else if eps != Vector3::zeros() {
                let squared = linear_errors::squared_direction(&link.direction, &eps);
                (squared, link.point_mm)
            } else {
                // An ideal linear axis keeps its direction bit for bit.
                return actual;
            };
            actual.with_line(link.axis, direction, point)
        });
        Some(actual.with_components(errors.components()))
    }

    /// The same machine with its pole tolerance `deg` (machine file `[kinematics]`).
    pub fn with_pole_tolerance(mut self, deg: f64) -> Kinematics {
        self.pole_tolerance_deg = deg;
        self
    }

    /// The pole of the nominal chain when it has two rotaries ([`Pole`]).
    pub fn pole(&self) -> Option<Pole> {
        self.nominal.as_ref().and_then(Pole::of)
    }

    /// Axis positions `q` with the linear axes set so that the tool tip (tool length 0)
    /// meets the workpiece point `tip`, the rotaries as given: `pivot + R(q) tip` on a
    /// named layout, [`chain_inverse::solve_linear`] on a general chain (unchanged where it
    /// cannot place the tip).
    pub fn with_tip_at(&self, tip: &Point3<f64>, q: &AxisVec) -> AxisVec {
        let mut out = *q;
        if let Some(chain) = &self.general {
            let pose = ToolPose {
                tip: *tip,
                axis: Vector3::z(),
            };
            if chain_inverse::solve_linear(chain, &pose, 0.0, &mut out).is_err() {
                return *q;
            }
            return out;
        }
        let m = self.table_to_machine(q, tip);
        (out[Axis::X], out[Axis::Y], out[Axis::Z]) = (m.x, m.y, m.z);
        out
    }

    /// The same machine with location errors on its rotary axes.
    pub fn with_location_errors(mut self, errors: LocationErrors) -> Kinematics {
        self.location_errors = errors;
        self
    }

    /// The actual line of rotary `axis`, at the home pose, in its parent's frame.
    pub fn actual_line(&self, axis: Axis) -> AxisLine {
        AxisLine::actual(axis, &self.pivot_mm, &self.location_errors)
    }

    /// The actual pose of the cradle (the part the tilting axis carries) at `q`: maps a
    /// point given relative to the pivot at home to the machine frame, `T_tilt(tilt) (pivot + p)`.
    pub fn actual_cradle_pose(&self, q: &AxisVec) -> Isometry3<f64> {
        let home = Isometry3::from_parts(Translation3::from(self.pivot_mm), Default::default());
        let sign = self.layout.table_turn_sign();
        match self.layout.tilt_axis() {
            Some(tilt) => self.actual_line(tilt).turn(sign * q[tilt]) * home,
            None => home,
        }
    }

    /// The actual lines of the tilting and the table axis, taken once, for posing the cradle
    /// and the table sample by sample ([`CradleTablePoses::poses`]: the poses of
    /// [`Kinematics::actual_cradle_pose`] and [`Kinematics::actual_table_pose`]).
    pub fn cradle_table_poses(&self) -> CradleTablePoses {
        let line = |a: Axis| (a.index(), self.actual_line(a));
        CradleTablePoses::new(
            match (self.layout.tilt_axis(), self.layout.table_axis()) {
                (Some(tilt), Some(table)) => Some((line(tilt), line(table))),
                _ => None,
            },
            self.layout.table_turn_sign(),
            self.pivot_mm,
        )
    }

    /// The actual pose of the table at `q`: maps a table-frame point p to the machine
    /// frame, `m = T_tilt(tilt) T_C(C) (pivot + p)` (for trt-ab `T_B(-B) T_A(-A)`). The
    /// nominal pose when all location errors are zero.
    pub fn actual_table_pose(&self, q: &AxisVec) -> Isometry3<f64> {
        let home = Isometry3::from_parts(Translation3::from(self.pivot_mm), Default::default());
        let sign = self.layout.table_turn_sign();
        match (self.layout.tilt_axis(), self.layout.table_axis()) {
            (Some(tilt), Some(table)) => {
                self.actual_line(tilt).turn(sign * q[tilt])
                    * self.actual_line(table).turn(sign * q[table])
                    * home
            }
            (None, Some(table)) => self.actual_line(table).turn(sign * q[table]) * home,
            _ => home,
        }
    }

    /// Machine coordinates of a table-frame point at actual axis positions `q`, through the
    /// actual (errored) chain `T_tilt(tilt) T_C(C) (pivot + p)`.
    pub fn actual_table_to_machine(&self, q: &AxisVec, p: &Point3<f64>) -> Point3<f64> {
        if self.location_errors.is_zero() {
            return self.table_to_machine(q, p);
        }
        let x = Point3::from(self.pivot_mm + p.coords);
        let sign = self.layout.table_turn_sign();
        match (self.layout.tilt_axis(), self.layout.table_axis()) {
            (Some(tilt), Some(table)) => {
                let on_table = self.actual_line(table).turn_point(sign * q[table], &x);
                self.actual_line(tilt).turn_point(sign * q[tilt], &on_table)
            }
            (None, Some(table)) => self.actual_line(table).turn_point(sign * q[table], &x),
            _ => x,
        }
    }

    /// R(q): rotates table-frame vectors into the machine frame.
    pub fn table_rotation(&self, q: &AxisVec) -> Rotation3<f64> {
        self.rotation_of(&self.rotary_sin_cos(q))
    }

    /// Sine and cosine of the table axis (C, or A for trt-ab) and of the tilt at `q`
    /// ([`RotarySinCos`]; both angles in one pass, [`sin_cos_deg_pair`]).
    #[inline]
    pub fn rotary_sin_cos(&self, q: &AxisVec) -> RotarySinCos {
        self.layout.rotary_sin_cos(q)
    }

    /// [`Kinematics::rotary_sin_cos`] at `q` near `reference` (whose values are `at`), by the
    /// angle-addition formulas with `sin δ`, `cos δ` of the small difference δ from their
    /// series: `sin(a + δ) = sin a cos δ + cos a sin δ` ([`add_small_angle`], both angles in
    /// one pass). Within a few ulp of `sin_cos` (the bar's length to 10⁻¹³ mm), at a fraction
    /// of its cost; `sin_cos` itself when the angles are more than 0.01 rad apart.
    #[inline]
    pub fn rotary_sin_cos_near(
        &self,
        q: &AxisVec,
        reference: &AxisVec,
        at: &RotarySinCos,
    ) -> RotarySinCos {
        let (table, tilt) = (self.layout.table_axis(), self.layout.tilt_axis());
        let rad = |a: Option<Axis>, v: &AxisVec| a.map_or(0.0, |a| v[a].to_radians());
        let (a, r) = (
            [rad(table, q), rad(tilt, q)],
            [rad(table, reference), rad(tilt, reference)],
        );
        let d = F64x2::new(a[0], a[1]) - F64x2::new(r[0], r[1]);
        let (sin, cos) = small_angle_added(
            d,
            F64x2::new(at.c.0, at.tilt.0),
            F64x2::new(at.c.1, at.tilt.1),
        );
        let (d, sin, cos) = (d.lanes(), sin.lanes(), cos.lanes());
        // Lane by lane what `add_small_angle` gives; an angle the layout lacks keeps `at`'s.
        let lane = |i: usize, axis: Option<Axis>, at: (f64, f64)| match axis {
            None => at,
            Some(_) => series_or_sin_cos(a[i], d[i], || (sin[i], cos[i])),
        };
        RotarySinCos {
            c: lane(0, table, at.c),
            tilt: lane(1, tilt, at.tilt),
        }
    }

    /// `angles` with rotary `axis`'s sine and cosine replaced by `sin_cos`: the table axis
    /// (C, or A on trt-ab and xyza) fills the `c` slot, the tilting axis the other.
    #[inline]
    pub fn with_rotary_sin_cos(
        &self,
        angles: &RotarySinCos,
        axis: Axis,
        sin_cos: (f64, f64),
    ) -> RotarySinCos {
        let mut out = *angles;
        if Some(axis) == self.layout.table_axis() {
            out.c = sin_cos;
        } else {
            out.tilt = sin_cos;
        }
        out
    }

    /// R from the sines and cosines of its angles ([`Layout::rotation_matrix`]).
    #[inline]
    pub fn rotation_of(&self, angles: &RotarySinCos) -> Rotation3<f64> {
        Rotation3::from_matrix_unchecked(self.layout.rotation_matrix(angles))
    }

    /// Machine coordinates of a table-frame point at axis positions `q`.
    pub fn table_to_machine(&self, q: &AxisVec, p: &Point3<f64>) -> Point3<f64> {
        Point3::from(self.pivot_mm + self.table_rotation(q) * p.coords)
    }

    /// Machine coordinates of the Z point for a tool-centre-point position: `xyz` is the
    /// tip in the table frame with the tool length offset `tool_length_mm` (L) added to its
    /// Z, as the reader adds it. The tip is `(x, y, z - L)` and the machine's Z point sits L
    /// above it along the tool axis (machine +Z): `pivot + R(q) (x, y, z - L) + (0, 0, L)`,
    /// as LinuxCNC's TCP kinematics take their tool offset.
    pub fn tcp_to_machine(
        &self,
        q: &AxisVec,
        xyz: &Point3<f64>,
        tool_length_mm: f64,
    ) -> Point3<f64> {
        let tip = Point3::new(xyz.x, xyz.y, xyz.z - tool_length_mm);
        let mut m = self.table_to_machine(q, &tip);
        m.z += tool_length_mm;
        m
    }

    /// Machine axis positions for a tool-centre-point position `q`: its X Y Z are the tool
    /// tip in the table (workpiece) frame with the tool length offset L added to Z, as the
    /// reader adds it; its rotaries (and any other axis) are the machine's. On a named layout
    /// X Y Z become [`Kinematics::tcp_to_machine`]'s; on a general chain the linear axes are
    /// solved so that the tip `g − L t` of the chain meets `(x, y, z − L)`
    /// ([`chain_inverse::solve_linear`]; a W quill beside Z keeps its value). Unchanged
    /// where the chain's linear axes cannot place the tip (an xz lathe off its plane: least
    /// squares).
    pub fn tcp_axes(&self, q: &AxisVec, tool_length_mm: f64) -> AxisVec {
        let mut out = *q;
        let tip = Point3::new(q[Axis::X], q[Axis::Y], q[Axis::Z] - tool_length_mm);
        if let Some(chain) = &self.general {
            let pose = ToolPose {
                tip,
                axis: Vector3::z(),
            };
            if chain_inverse::solve_linear(chain, &pose, tool_length_mm, &mut out).is_err() {
                return *q;
            }
            return out;
        }
        let m = self.tcp_to_machine(
            q,
            &Point3::new(q[Axis::X], q[Axis::Y], q[Axis::Z]),
            tool_length_mm,
        );
        (out[Axis::X], out[Axis::Y], out[Axis::Z]) = (m.x, m.y, m.z);
        out
    }

    /// [`Kinematics::tcp_axes`] as the interpolator runs it every sample: on a named layout
    /// the rotation written out with one `sin_cos` per angle ([`Kinematics::turned_to_machine`]),
    /// on a general chain `tcp_axes` itself. Within 10⁻¹² mm of `tcp_axes` (the order of
    /// the floating-point operations differs; tests/kinematics/written_out.rs).
    #[inline]
    pub fn tcp_axes_per_sample(&self, q: &AxisVec, tool_length_mm: f64) -> AxisVec {
        if self.general.is_some() {
            // A general chain: its linear axes place the tip, the rotaries as programmed.
            return self.tcp_axes(q, tool_length_mm);
        }
        let l = tool_length_mm;
        let mut out = *q;
        let mut m = self.turned_to_machine(q, [q.0[0], q.0[1], q.0[2] - l]);
        m[2] += l;
        out.0[..3].copy_from_slice(&m);
        out
    }

    /// `pivot + R(q) p` of [`Kinematics::table_to_machine`] with R applied one rotation at a
    /// time ([`Layout::turn_point`]); `pivot + p` on a general chain. mm and deg.
    #[inline]
    pub fn turned_to_machine(&self, q: &AxisVec, p: [f64; 3]) -> [f64; 3] {
        let [x, y, z] = self.layout.turn_point(q, p);
        [
            x + self.pivot_mm.x,
            y + self.pivot_mm.y,
            z + self.pivot_mm.z,
        ]
    }

    /// A machine-frame vector `u` in the table frame, `R(q)ᵀ u`, and in the cradle frame
    /// (the part the tilting axis carries), `R_tilt(q)ᵀ u`, with one `sin_cos` per angle
    /// ([`Layout::into_table_frames`]); `[u, u]` on a general chain (whose bodies ride its
    /// links: `check/scene/linked.rs`).
    #[inline]
    pub fn into_table_frames(&self, q: &AxisVec, u: Vector3<f64>) -> [Vector3<f64>; 2] {
        self.layout.into_table_frames(q, u)
    }

    /// The tool tip (the gauge point, tool length 0) in the table frame, mm, when the linear
    /// axes stand at `xyz_mm` and the rotaries at zero: `xyz − pivot` on a named layout
    /// (R(0) = I), the chain's forward kinematics (workpiece frame) on a general chain.
    pub fn tip_at_home_rotaries(&self, xyz_mm: [f64; 3]) -> Vector3<f64> {
        match &self.general {
            Some(chain) => {
                let q = AxisVec::xyzabc([xyz_mm[0], xyz_mm[1], xyz_mm[2], 0.0, 0.0, 0.0]);
                chain.tool_in_workpiece(&q, 0.0).0.coords
            }
            None => Vector3::from(xyz_mm) - self.pivot_mm,
        }
    }

    /// The rotaries a path must keep within travel when its inverse is chosen (the branch):
    /// every rotary of a general chain; the tilting axis of a named layout (its table axis
    /// is unwrapped along the path).
    pub fn travel_bound_rotaries(&self) -> Vec<Axis> {
        match &self.general {
            Some(chain) => chain.rotaries().map(|(_, l)| l.axis).collect(),
            None => self.layout.tilt_axis().into_iter().collect(),
        }
    }

    /// Axis positions for the first pose of a path on `branch`: on a named layout the
    /// table axis in the spec's `atan2` range ([`C_START_REFERENCE_DEG`]); on a general
    /// chain every rotary nearest zero ([`Kinematics::inverse_after`]).
    pub fn inverse_first(&self, pose: &ToolPose, branch: Branch) -> AxisVec {
        if self.general.is_some() {
            return self.inverse_after(pose, branch, &AxisVec::ZERO);
        }
        self.inverse(pose, branch, C_START_REFERENCE_DEG)
    }

    /// Forward kinematics: axis positions → tool tip and tool axis in the table frame.
    pub fn forward(&self, q: &AxisVec) -> ToolPose {
        if let Some(chain) = &self.general {
            // A general chain's workpiece frame is the table frame (its pivot is the origin);
            // the tool tip is the gauge point (tool length 0).
            let (tip, axis) = chain.tool_in_workpiece(q, 0.0);
            return ToolPose { tip, axis };
        }
        let r_inv = self.rotation_of(&self.rotary_sin_cos(q)).inverse();
        ToolPose {
            tip: self.tip_turned_back(q, &r_inv),
            axis: r_inv * Vector3::z(),
        }
    }

    /// The tool tip of [`Kinematics::forward`] alone, table frame, mm, with the sines and
    /// cosines of `q`'s angles given (the ball bar's θ needs no tool axis).
    #[inline]
    pub fn tip_with(&self, q: &AxisVec, angles: &RotarySinCos) -> Point3<f64> {
        if let Some(chain) = &self.general {
            return chain.tool_in_workpiece(q, 0.0).0;
        }
        self.tip_turned_back(q, &self.rotation_of(angles).inverse())
    }

    /// `R⁻¹ (tip - pivot)`: the machine tip at `q`'s X Y Z in the table frame, `r_inv` = R⁻¹.
    #[inline(always)]
    fn tip_turned_back(&self, q: &AxisVec, r_inv: &Rotation3<f64>) -> Point3<f64> {
        let tip_m = Vector3::new(q[Axis::X], q[Axis::Y], q[Axis::Z]);
        Point3::from(r_inv * (tip_m - self.pivot_mm))
    }

    /// Inverse kinematics on `branch`, with C unwrapped near `previous_c_deg` (and kept
    /// there when the tool axis is along the table's Z). `axis` need not be normalized.
    /// For trt-ab the table axis is A: `previous_c_deg` is then the previous A.
    /// On a general chain, every rotary is unwrapped near `previous_c_deg`
    /// ([`Kinematics::inverse_after`]).
    pub fn inverse(&self, pose: &ToolPose, branch: Branch, previous_c_deg: f64) -> AxisVec {
        if let Some(chain) = &self.general {
            let mut previous = AxisVec::ZERO;
            for (_, link) in chain.rotaries() {
                previous[link.axis] = previous_c_deg;
            }
            return self.inverse_after(pose, branch, &previous);
        }
        let mut q = AxisVec::ZERO;
        self.layout
            .solve_rotaries(&pose.axis.normalize(), branch, previous_c_deg, &mut q);
        let m = self.table_to_machine(&q, &pose.tip);
        q[Axis::X] = m.x;
        q[Axis::Y] = m.y;
        q[Axis::Z] = m.z;
        q
    }
}
impl Kinematics {
    /// Inverse kinematics on `branch`, each rotary unwrapped nearest its value in
    /// `previous` (on a named layout only the table axis's value counts, as in
    /// [`Kinematics::inverse`]). On a general chain: the solution of `branch`
    /// ([`chain_inverse::Solution::branch`] 0 for the primary, 1 for the secondary; the one
    /// there is where they meet), tool length 0, linear axes beyond the first three kept at
    /// `previous`; NaN where the chain cannot reach the pose (a cone is refused on load then).
    pub fn inverse_after(&self, pose: &ToolPose, branch: Branch, previous: &AxisVec) -> AxisVec {
        let Some(chain) = &self.general else {
            let table = self.layout.table_axis().unwrap_or(Axis::C);
            return self.inverse(pose, branch, previous[table]);
        };
        let wanted = match branch {
            Branch::Primary => 0,
            Branch::Secondary => 1,
        };
        match chain_inverse::solutions(chain, pose, 0.0, previous) {
            Ok(all) => all
                .iter()
                .find(|s| s.branch == wanted)
                .or(all.first())
                .map_or(AxisVec([f64::NAN; 9]), |s| s.joints),
            Err(_) => AxisVec([f64::NAN; 9]),
        }
    }
}

/// Largest angle step `|a - r|` (rad) that [`add_small_angle`] takes by its series.
const SMALL_ANGLE_RAD: f64 = 0.01;

/// `(sin a, cos a)` from `(sin r, cos r)` for `a` near `r` (rad): the angle-addition formulas
/// with the series of `sin δ`, `cos δ` for `δ = a - r` (to `δ⁷` and `δ⁶`, whose remainders
/// are below 10⁻²² for `|δ| ≤ 0.01`); `sin_cos` beyond that.
#[inline]
pub fn add_small_angle(a: f64, r: f64, (sin_r, cos_r): (f64, f64)) -> (f64, f64) {
    let d = a - r;
    series_or_sin_cos(a, d, || small_angle_added(d, sin_r, cos_r))
}

/// `series()`, the `(sin a, cos a)` of [`add_small_angle`]'s series, when the step `d` to
/// `a` is at most [`SMALL_ANGLE_RAD`]; `a.sin_cos()` otherwise (a non-finite `d` too).
#[inline(always)]
fn series_or_sin_cos(a: f64, d: f64, series: impl FnOnce() -> (f64, f64)) -> (f64, f64) {
    if d.abs() <= SMALL_ANGLE_RAD {
        series()
    } else {
        a.sin_cos()
    }
}

/// `(sin(r + δ), cos(r + δ))` from `sin r`, `cos r` and the series of `sin δ`, `cos δ`
/// ([`add_small_angle`]), for one angle or two ([`F64x2`]).
#[inline(always)]
fn small_angle_added<T: LaneOps>(d: T, sin_r: T, cos_r: T) -> (T, T) {
    let c = T::from;
    let d2 = d * d;
    // The series' divisions as products by the reciprocals (a rounding each, far below the
    // 10⁻²² truncation; products do not stall the pipeline as divisions do).
    let sin_d = d
        * (c(1.0)
            - d2 * c(1.0 / 6.0) * (c(1.0) - d2 * c(1.0 / 20.0) * (c(1.0) - d2 * c(1.0 / 42.0))));
    // cos δ - 1, kept apart so that the small terms are not lost against 1.
    let cos_d_m1 = -d2 * c(0.5) * (c(1.0) - d2 * c(1.0 / 12.0) * (c(1.0) - d2 * c(1.0 / 30.0)));
    (
        sin_r + (sin_r * cos_d_m1 + cos_r * sin_d),
        cos_r + (cos_r * cos_d_m1 - sin_r * sin_d),
    )
}

/// The first C value of a path: the spec's `atan2` range (-180, 180].
pub const C_START_REFERENCE_DEG: f64 = 0.0;

/// `(x, y, z)` to 4 decimals, without trailing zeros or a negative zero.
fn triple(v: &Vector3<f64>) -> String {
    let one = |x: f64| {
        let r = (x * 1e4).round() / 1e4 + 0.0;
        let t = format!("{r:.4}");
        let t = t.trim_end_matches('0').trim_end_matches('.');
        t.to_string()
    };
    format!("({}, {}, {})", one(v.x), one(v.y), one(v.z))
}
