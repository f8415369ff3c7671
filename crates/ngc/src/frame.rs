//! Tilted work planes (Fanuc G68.2) and work offsets that follow the rotary table (Haas
//! G254, and G68.2 on a machine with a rotary table): the map from program coordinates to
//! machine axes.
//!
//! Frames, as in mtsim's `kinematics.rs`: the machine frame M (tool axis +Z), and the table
//! frame fixed to the rotary table, which coincides with M at rotary zero. A point fixed to
//! the table at machine position x₀ when all rotary axes are at zero appears at
//!
//! ```text
//! m = pivot + R_t(q) (x₀ - pivot),   R_t = Rx(A) Rz(C) (table-table AC) or Ry(B) Rz(C) (BC)
//! ```
//!
//! A program point p (mm) in the feature frame of `G68.2 X Y Z I J K` (origin o in the work
//! coordinate system, Euler angles I J K in deg, ZXZ: `R_f = Rz(I) Rx(J) Rz(K)`) sits at
//! `w = o + R_f p` in work coordinates, so at `x₀ = w + W` (W the linear work offset, machine
//! coordinates at rotary zero). Without G68.2, `R_f = I` and `o = 0`. The controlled point is
//! then `m`, with the tool length offset added on machine Z.
//!
//! G53.1 turns the table so that the feature frame's Z axis `t = R_f e_z` (in the table
//! frame) becomes the tool axis +Z: `tilt = acos(t_z)` (the branch with tilt >= 0) and C
//! turns t's horizontal part, at angle `atan2(t_y, t_x)`, onto +Y (AC: `C = 90° - atan2`)
//! or -X (BC: `C = 180° - atan2`), unwrapped next to the current C. When t is along Z, C
//! keeps its value.

use std::sync::Arc;

use crate::axis::{Axis, AxisVec};

/// A 3×3 rotation matrix, row-major.
pub type Mat3 = [[f64; 3]; 3];

/// The identity.
pub const IDENTITY: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// The rotary table of a table-table five-axis machine, as the reader needs it.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct RotaryTable {
    /// The tilting axis: `Axis::A` (tilts about X, AC layout) or `Axis::B` (about Y, BC).
    /// C turns the table about its own Z.
    pub tilt: Axis,
    /// Machine coordinates of the pivot, where the rotary axes cross, mm.
    pub pivot_mm: [f64; 3],
}

impl RotaryTable {
    /// `R_t(q)`: rotates table-frame vectors into the machine frame.
    pub fn rotation(&self, q: &AxisVec) -> Mat3 {
        let c = rot_z(q[Axis::C]);
        if self.tilt == Axis::B {
            mul(&rot_y(q[Axis::B]), &c)
        } else {
            mul(&rot_x(q[Axis::A]), &c)
        }
    }

    /// The tilt and C (deg) that carry the table-frame unit vector `t` onto +Z, C unwrapped
    /// next to `previous_c_deg` and kept when t is along Z.
    pub fn align(&self, t: [f64; 3], previous_c_deg: f64) -> (f64, f64) {
        let tilt = t[2].clamp(-1.0, 1.0).acos().to_degrees();
        let target = if self.tilt == Axis::B { 180.0 } else { 90.0 };
        let c = if t[0].hypot(t[1]) < 1e-12 {
            previous_c_deg
        } else {
            let c = target - t[1].atan2(t[0]).to_degrees();
            c + 360.0 * ((previous_c_deg - c) / 360.0).round()
        };
        (tilt, c)
    }
}

/// Rotation about X by `deg`.
pub fn rot_x(deg: f64) -> Mat3 {
    let (s, c) = deg.to_radians().sin_cos();
    [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]
}

/// Rotation about Y by `deg`.
pub fn rot_y(deg: f64) -> Mat3 {
    let (s, c) = deg.to_radians().sin_cos();
    [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
}

/// Rotation about Z by `deg`.
pub fn rot_z(deg: f64) -> Mat3 {
    let (s, c) = deg.to_radians().sin_cos();
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}

/// Euler ZXZ: `Rz(i) Rx(j) Rz(k)`, deg (Fanuc G68.2 I J K).
pub fn euler_zxz(i: f64, j: f64, k: f64) -> Mat3 {
    mul(&mul(&rot_z(i), &rot_x(j)), &rot_z(k))
}

/// Matrix product `a b`.
pub fn mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut m = [[0.0; 3]; 3];
    for (r, row) in m.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|k| a[r][k] * b[k][c]).sum();
        }
    }
    m
}

/// `a v`.
pub fn apply(a: &Mat3, v: [f64; 3]) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (r, o) in out.iter_mut().enumerate() {
        *o = (0..3).map(|k| a[r][k] * v[k]).sum();
    }
    out
}

/// `aᵀ v` (the inverse rotation).
pub fn apply_t(a: &Mat3, v: [f64; 3]) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (r, o) in out.iter_mut().enumerate() {
        *o = (0..3).map(|k| a[k][r] * v[k]).sum();
    }
    out
}

/// The rotary positions that put the tool along a direction, on a machine that is no
/// table-table AC or BC (a kinematic chain the caller models): given the unit direction in
/// the workpiece frame and the axis positions now, the axis positions with the rotaries
/// turned (the others as they are), or why the direction cannot be reached. G53.1 on such a
/// machine turns the rotaries with the tool tip held (the move and the moves under G68.2
/// run under tool-centre-point control, their X Y Z the tip in the workpiece frame).
#[derive(Clone)]
pub struct ToolAligner(
    pub Arc<dyn Fn([f64; 3], &AxisVec) -> Result<AxisVec, String> + Send + Sync>,
);

impl std::fmt::Debug for ToolAligner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("ToolAligner")
    }
}

/// The program-to-machine map of a tilted plane and/or table-following work offset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// Feature origin o in work coordinates, mm (zero without G68.2).
    pub origin_mm: [f64; 3],
    /// Feature rotation `R_f` (identity without G68.2).
    pub rotation: Mat3,
    /// The table the work offset follows (`None`: the map ignores the rotary axes).
    pub table: Option<RotaryTable>,
}

impl Frame {
    /// Machine X Y Z (before the tool length offset) of program point `p` (mm) with work
    /// offset `offset` and rotary axes at `q`.
    pub fn to_machine(&self, p: [f64; 3], offset: &AxisVec, q: &AxisVec) -> [f64; 3] {
        let r = apply(&self.rotation, p);
        let x0 = [0, 1, 2].map(|k| self.origin_mm[k] + r[k] + offset.0[k]);
        match self.table {
            None => x0,
            Some(t) => {
                let d = [0, 1, 2].map(|k| x0[k] - t.pivot_mm[k]);
                let m = apply(&t.rotation(q), d);
                [0, 1, 2].map(|k| t.pivot_mm[k] + m[k])
            }
        }
    }

    /// The program point (mm) at machine X Y Z `m` (before the tool length offset): the
    /// inverse of [`Frame::to_machine`].
    pub fn to_program(&self, m: [f64; 3], offset: &AxisVec, q: &AxisVec) -> [f64; 3] {
        let x0 = match self.table {
            None => m,
            Some(t) => {
                let d = [0, 1, 2].map(|k| m[k] - t.pivot_mm[k]);
                let r = apply_t(&t.rotation(q), d);
                [0, 1, 2].map(|k| t.pivot_mm[k] + r[k])
            }
        };
        let w = [0, 1, 2].map(|k| x0[k] - offset.0[k] - self.origin_mm[k]);
        apply_t(&self.rotation, w)
    }

    /// The combined rotation from program to machine directions at rotary position `q`.
    pub fn direction_rotation(&self, q: &AxisVec) -> Mat3 {
        match self.table {
            None => self.rotation,
            Some(t) => mul(&t.rotation(q), &self.rotation),
        }
    }
}
