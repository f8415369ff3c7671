//! The programmable frame: `TRANS`/`ATRANS`, `ROT`/`AROT`, `SCALE`/`ASCALE`,
//! `MIRROR`/`AMIRROR` (Fundamentals, "Coordinate transformations (frames)").
//!
//! A point `p` programmed in the frame is the point `o + A p` of the work system (G54 ...):
//! `o` the origin, `A` rotation × scale × mirror. The absolute instructions replace the
//! whole programmable frame; the additive ones act in the frame as it is, so
//! `ATRANS v`: `o ← o + A v`; `AROT R`: `A ← A R`; `ASCALE S`: `A ← A S`; `AMIRROR M`:
//! `A ← A M`. `ROT X a Y b Z c` turns about Z, then the new Y, then the newest X:
//! `R = Rz(c) Ry(b) Rx(a)`; `ROT RPL=a` turns about the active plane's normal.

use crate::frame::{apply, mul, rot_x, rot_y, rot_z, Mat3, IDENTITY};

/// `o + A p`, in program units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct ProgFrame {
    pub origin: [f64; 3],
    pub matrix: Mat3,
}

impl Default for ProgFrame {
    fn default() -> ProgFrame {
        ProgFrame {
            origin: [0.0; 3],
            matrix: IDENTITY,
        }
    }
}

/// One frame instruction and its values (X Y Z; absent axes 0, or 1 for a scale).
#[derive(Clone, Copy, Debug)]
pub(super) enum Instruction {
    Trans([f64; 3]),
    Rot(Mat3),
    Scale([f64; 3]),
    /// Mirror the axes marked.
    Mirror([bool; 3]),
}

impl ProgFrame {
    /// True when the frame is the identity: programmed points are work points.
    pub fn is_identity(&self) -> bool {
        *self == ProgFrame::default()
    }

    /// Applies `i`, replacing the frame (`additive` false) or acting in it.
    pub fn apply(&mut self, i: Instruction, additive: bool) {
        if !additive {
            *self = ProgFrame::default();
        }
        let a = &self.matrix;
        match i {
            Instruction::Trans(v) => {
                let d = apply(a, v);
                for (o, d) in self.origin.iter_mut().zip(d) {
                    *o += d;
                }
            }
            Instruction::Rot(r) => self.matrix = mul(a, &r),
            Instruction::Scale(s) => self.matrix = mul(a, &diagonal(s)),
            Instruction::Mirror(m) => {
                let s = m.map(|on| if on { -1.0 } else { 1.0 });
                self.matrix = mul(a, &diagonal(s));
            }
        }
    }

    /// The work point of frame point `p`.
    pub fn work_point(&self, p: [f64; 3]) -> [f64; 3] {
        let q = apply(&self.matrix, p);
        [
            q[0] + self.origin[0],
            q[1] + self.origin[1],
            q[2] + self.origin[2],
        ]
    }

    /// The frame point of work point `w`: `A⁻¹ (w - o)`.
    pub fn frame_point(&self, w: [f64; 3]) -> [f64; 3] {
        let d = [
            w[0] - self.origin[0],
            w[1] - self.origin[1],
            w[2] - self.origin[2],
        ];
        apply(&inverse(&self.matrix), d)
    }

    /// The frame mirrors (det A < 0): arcs turn the other way.
    pub fn mirrors(&self) -> bool {
        det(&self.matrix) < 0.0
    }

    /// Where an arc of the plane with normal axis `normal` (0 X, 1 Y, 2 Z) lands: the work
    /// plane's normal axis `k` with `A n = ±s e_k`, the scale `s` (the same for every
    /// in-plane direction, so a circle stays a circle), and whether the arc turns the other
    /// way about `e_k` (`A n` along `-e_k`, or a mirroring frame, but not both). `None` when
    /// the frame tilts the plane off the work axes or stretches it unevenly.
    pub fn arc_plane(&self, normal: usize) -> Option<(usize, f64, bool)> {
        let unit = |k: usize| {
            let mut e = [0.0; 3];
            e[k] = 1.0;
            apply(&self.matrix, e)
        };
        let (an, au, av) = (unit(normal), unit((normal + 1) % 3), unit((normal + 2) % 3));
        let len = |x: [f64; 3]| (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
        let dot = |x: [f64; 3], y: [f64; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
        let s = len(au);
        let tol = 1e-12 * s.max(1.0);
        let k = (0..3).max_by(|&i, &j| an[i].abs().total_cmp(&an[j].abs()))?;
        let along = (0..3).all(|i| i == k || an[i].abs() <= tol);
        let conformal = (len(av) - s).abs() <= tol
            && dot(au, av).abs() <= tol * s
            && dot(au, an).abs() <= tol * s
            && dot(av, an).abs() <= tol * s;
        (along && conformal && s > 0.0).then(|| (k, s, (an[k] < 0.0) != self.mirrors()))
    }
}

/// `Rz(z) Ry(y) Rx(x)`, deg.
pub(super) fn rotation_zyx(x: f64, y: f64, z: f64) -> Mat3 {
    mul(&mul(&rot_z(z), &rot_y(y)), &rot_x(x))
}

fn diagonal(d: [f64; 3]) -> Mat3 {
    [[d[0], 0.0, 0.0], [0.0, d[1], 0.0], [0.0, 0.0, d[2]]]
}

fn det(a: &Mat3) -> f64 {
    a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
        - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
        + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])
}

/// `A⁻¹` by the adjugate (a frame's matrix is never singular: a zero scale is refused).
fn inverse(a: &Mat3) -> Mat3 {
    let d = det(a);
    let c = |r0: usize, r1: usize, c0: usize, c1: usize| {
        (a[r0][c0] * a[r1][c1] - a[r0][c1] * a[r1][c0]) / d
    };
    [
        [c(1, 2, 1, 2), -c(0, 2, 1, 2), c(0, 1, 1, 2)],
        [-c(1, 2, 0, 2), c(0, 2, 0, 2), -c(0, 1, 0, 2)],
        [c(1, 2, 0, 1), -c(0, 2, 0, 1), c(0, 1, 0, 1)],
    ]
}

/// Settable frames (settable.rs): `$P_UIFR[0]` (G500) to `$P_UIFR[99]` (G599).
pub(super) const SETTABLE: usize = 100;

/// A frame by its components, program units and deg.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Components {
    pub coarse: [f64; 3],
    pub fine: [f64; 3],
    pub angles: [f64; 3],
    pub scale: [f64; 3],
    pub mirror: [bool; 3],
}

impl Default for Components {
    fn default() -> Components {
        Components {
            coarse: [0.0; 3],
            fine: [0.0; 3],
            angles: [0.0; 3],
            scale: [1.0; 3],
            mirror: [false; 3],
        }
    }
}

impl Components {
    /// Rotation × scale × mirror.
    pub fn matrix(&self) -> crate::frame::Mat3 {
        let [x, y, z] = self.angles;
        let d: [f64; 3] =
            std::array::from_fn(|k| self.scale[k] * if self.mirror[k] { -1.0 } else { 1.0 });
        let diag = [[d[0], 0.0, 0.0], [0.0, d[1], 0.0], [0.0, 0.0, d[2]]];
        mul(&rotation_zyx(x, y, z), &diag)
    }

    /// The offset, coarse and fine.
    pub fn offset(&self) -> [f64; 3] {
        std::array::from_fn(|k| self.coarse[k] + self.fine[k])
    }

    /// As a programmable frame (`o + A p`).
    pub fn as_frame(&self) -> ProgFrame {
        ProgFrame {
            origin: self.offset(),
            matrix: self.matrix(),
        }
    }
}

/// The direction a move leaves its end point in (X Y Z, any length), or `None` for a
/// dwell or a move of no length (Fundamentals, "Circular interpolation with tangential
/// transition (CT)": the circle continues the path's direction).
pub(super) fn end_tangent(m: &crate::canon::Move) -> Option<[f64; 3]> {
    let (s, e) = (m.start.0, m.end.0);
    let t = match m.motion {
        crate::canon::Motion::Rapid | crate::canon::Motion::Linear => {
            [e[0] - s[0], e[1] - s[1], e[2] - s[2]]
        }
        crate::canon::Motion::Arc {
            clockwise,
            plane,
            center_mm,
        } => {
            let (u, v, _) = plane.axes();
            let (u, v) = (u.index(), v.index());
            let (ru, rv) = (e[u] - center_mm[u], e[v] - center_mm[v]);
            let mut t = [0.0; 3];
            (t[u], t[v]) = if clockwise { (rv, -ru) } else { (-rv, ru) };
            t
        }
        crate::canon::Motion::Dwell { .. } => return None,
    };
    (t.iter().any(|x| x.abs() > 1e-12) && t.iter().all(|x| x.is_finite())).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// TRANS X10 then AROT Z90: frame X1 is work (10, 1); to_frame inverts it; a mirror
    /// about X flips the turn and keeps the plane.
    #[test]
    fn trans_then_arot_puts_frame_points_where_the_manual_draws_them() {
        let mut f = ProgFrame::default();
        f.apply(Instruction::Trans([10.0, 0.0, 0.0]), false);
        f.apply(Instruction::Rot(rotation_zyx(0.0, 0.0, 90.0)), true);
        let w = f.work_point([1.0, 0.0, 0.0]);
        assert!((w[0] - 10.0).abs() < 1e-12 && (w[1] - 1.0).abs() < 1e-12);
        let p = f.frame_point([7.0, 3.0, 2.0]);
        let back = f.work_point(p);
        assert!((back[0] - 7.0).abs() < 1e-12 && (back[1] - 3.0).abs() < 1e-12);
        assert_eq!(
            f.arc_plane(2)
                .map(|(k, s, flip)| (k, (s - 1.0).abs() < 1e-12, flip)),
            Some((2, true, false))
        );
        // AROT Y90 stands the XY plane up as the work YZ plane, turning the same way
        // about +X (Ry(90) e_z = +e_x).
        let mut up = ProgFrame::default();
        up.apply(Instruction::Rot(rotation_zyx(0.0, 90.0, 0.0)), false);
        assert_eq!(
            up.arc_plane(2).map(|(k, _, flip)| (k, flip)),
            Some((0, false))
        );
        up.apply(Instruction::Rot(rotation_zyx(0.0, 30.0, 0.0)), true);
        assert_eq!(up.arc_plane(2), None);
        f.apply(Instruction::Mirror([true, false, false]), true);
        assert!(f.mirrors());
        // ATRANS in the turned frame moves along work Y.
        let mut g = ProgFrame::default();
        g.apply(Instruction::Rot(rotation_zyx(0.0, 0.0, 90.0)), false);
        g.apply(Instruction::Trans([5.0, 0.0, 0.0]), true);
        assert!((g.origin[1] - 5.0).abs() < 1e-12 && g.origin[0].abs() < 1e-12);
    }
}
