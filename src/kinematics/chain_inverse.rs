//! Inverse kinematics of a chain: tool tip and tool direction in the workpiece frame →
//! axis values, both rotary solutions, the nearest within travel, poles and switches.
//!
//! Orientation. With the rotaries R_k = Rot(d_k, q_k) (home directions), the tool direction
//! in the workpiece frame is `t_w = R_table⁻¹ R_head t₀`. For two rotaries r1 before r2 in
//! the chain this is one equation `Rot(u, α) a = Rot(v, β) b`:
//!
//! ```text
//! table r1, r2:       Rot(d1, −q1) t₀ = Rot(d2, q2) t_w
//! table r1, head r2:  Rot(d2, q2) t₀  = Rot(d1, q1) t_w
//! head r1, r2:        Rot(d2, q2) t₀  = Rot(d1, −q1) t_w
//! ```
//!
//! Both sides are the same unit vector c, on the cone about u through a and on the cone
//! about v through b: `c = x u + y v + z (u × v)` with `x + y (u·v) = u·a`,
//! `x (u·v) + y = v·b` and `|c| = 1`, which leaves `z = ±√(…)`: the two solutions (none
//! when the cones miss, one when they touch). Each angle is then the turn about its axis
//! that carries the projection of a (or b) onto that of c. When a (or b) lies along its
//! own axis the angle is free: a pole, where the axis keeps its previous value.
//!
//! Position. With the rotaries fixed, the tip `T_head (g − l t₀)` and the workpiece point
//! `T_table x_w` are affine in the linear axes: axis k adds `±R_before(k) d_k q_k`
//! (R_before: the rotaries before it on its side). The first three linear axes whose
//! columns are independent are solved for (least squares when fewer); any others (a W
//! quill beside Z) keep their previous values.

use nalgebra::{Matrix3, Vector3};

use super::chain::{Chain, Side, ToolPose};
use crate::{Axis, AxisVec};

/// Below this, a projected vector is a point (its angle is free) or cones touch.
const EPS: f64 = 1e-12;

/// One rotary solution of the inverse kinematics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Solution {
    /// Every axis of the chain.
    pub joints: AxisVec,
    /// Which root (0: `z ≥ 0`, 1: `z < 0`); the same index follows the same branch.
    pub branch: usize,
    /// The axis left free by a pole (kept at its previous value), if any.
    pub free_axis: Option<Axis>,
}

/// Why a pose has no joint values.
#[derive(Clone, Debug, PartialEq)]
pub enum InverseError {
    /// The tool direction cannot be reached by the chain's rotaries.
    Unreachable,
    /// Every solution leaves a rotary outside its travel.
    OutOfTravel,
    /// More than two rotaries, or two with parallel lines: no unique inverse.
    Unsupported(&'static str),
}

impl std::fmt::Display for InverseError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            InverseError::Unreachable => {
                f.write_str("the tool direction is out of the chain's reach")
            }
            InverseError::OutOfTravel => {
                f.write_str("every solution leaves a rotary axis outside its travel")
            }
            InverseError::Unsupported(why) => f.write_str(why),
        }
    }
}

/// Every rotary solution for `pose` (workpiece frame) with a tool of `tool_length_mm`,
/// rotaries unwrapped nearest to `previous` (whose values also fill the free and redundant
/// axes). At most two.
pub fn solutions(
    chain: &Chain,
    pose: &ToolPose,
    tool_length_mm: f64,
    previous: &AxisVec,
) -> Result<Vec<Solution>, InverseError> {
    let t_w = pose.axis.normalize();
    let rotaries: Vec<_> = chain.rotaries().map(|(s, l)| (s, *l)).collect();
    let mut out = Vec::new();
    match rotaries.as_slice() {
        [] => out.push(Solution {
            joints: *previous,
            branch: 0,
            free_axis: None,
        }),
        [(side, l)] => {
            // Table: Rot(d, −q) t₀ = t_w; head: Rot(d, q) t₀ = t_w.
            let sign = if *side == Side::Table { -1.0 } else { 1.0 };
            let mut joints = *previous;
            let free = match turn_angle(&l.direction, &chain.tool_direction, &t_w) {
                Some(angle) => {
                    joints[l.axis] = unwrap_near(sign * angle, previous[l.axis]);
                    None
                }
                None => Some(l.axis),
            };
            out.push(Solution {
                joints,
                branch: 0,
                free_axis: free,
            });
        }
        [(s1, l1), (s2, l2)] => {
            let t0 = chain.tool_direction;
            // (u, a, α sign for the axis it gives), (v, b, …): see the module docs.
            let (u, a, v, b, first_is_r2, sign_u, sign_v) = match (s1, s2) {
                (Side::Table, Side::Table) => {
                    (l1.direction, t0, l2.direction, t_w, false, -1.0, 1.0)
                }
                (Side::Table, Side::Head) => (l2.direction, t0, l1.direction, t_w, true, 1.0, 1.0),
                _ => (l2.direction, t0, l1.direction, t_w, true, 1.0, -1.0),
            };
            let cs = common_vectors(&u, &a, &v, &b)?;
            for (branch, c) in cs.iter().enumerate() {
                let (axis_u, axis_v) = if first_is_r2 {
                    (l2.axis, l1.axis)
                } else {
                    (l1.axis, l2.axis)
                };
                let mut joints = *previous;
                let mut free_axis = None;
                match turn_angle(&u, &a, c) {
                    Some(alpha) => joints[axis_u] = unwrap_near(sign_u * alpha, previous[axis_u]),
                    None => free_axis = Some(axis_u),
                }
                match turn_angle(&v, &b, c) {
                    Some(beta) => joints[axis_v] = unwrap_near(sign_v * beta, previous[axis_v]),
                    None => free_axis = Some(axis_v),
                }
                out.push(Solution {
                    joints,
                    branch,
                    free_axis,
                });
            }
        }
        _ => {
            return Err(InverseError::Unsupported(
                "the inverse kinematics takes at most two rotary axes",
            ))
        }
    }
    for s in &mut out {
        solve_linear(chain, pose, tool_length_mm, &mut s.joints)?;
    }
    Ok(out)
}

/// The solution nearest to `previous` (sum of the rotaries' moves, deg) with every rotary
/// within travel (`within(axis, value)`; a rotary outside is tried a turn either way).
pub fn nearest(
    chain: &Chain,
    pose: &ToolPose,
    tool_length_mm: f64,
    previous: &AxisVec,
    within: &dyn Fn(Axis, f64) -> bool,
) -> Result<Solution, InverseError> {
    let mut best: Option<(f64, Solution)> = None;
    for mut s in solutions(chain, pose, tool_length_mm, previous)? {
        if !bring_within(chain, &mut s.joints, within) {
            continue;
        }
        let cost: f64 = chain
            .rotaries()
            .map(|(_, l)| (s.joints[l.axis] - previous[l.axis]).abs())
            .sum();
        if best.as_ref().is_none_or(|(c, _)| cost < *c) {
            best = Some((cost, s));
        }
    }
    let mut chosen = best.map(|(_, s)| s).ok_or(InverseError::OutOfTravel)?;
    // Rotaries moved by whole turns change the linear axes only through rounding: solve again.
    solve_linear(chain, pose, tool_length_mm, &mut chosen.joints)?;
    Ok(chosen)
}

/// Moves each rotary by whole turns into its travel (nearest first); false when one cannot be.
fn bring_within(chain: &Chain, joints: &mut AxisVec, within: &dyn Fn(Axis, f64) -> bool) -> bool {
    chain.rotaries().all(|(_, l)| {
        let v = joints[l.axis];
        let found = [0.0, -360.0, 360.0, -720.0, 720.0]
            .into_iter()
            .map(|k| v + k)
            .find(|&w| within(l.axis, w));
        if let Some(w) = found {
            joints[l.axis] = w;
        }
        found.is_some()
    })
}

/// The right-handed angle (deg) about unit `axis` that carries `from`'s projection onto
/// `to`'s; `None` when `from` lies along the axis (the angle is free).
fn turn_angle(axis: &Vector3<f64>, from: &Vector3<f64>, to: &Vector3<f64>) -> Option<f64> {
    let f = from - axis * axis.dot(from);
    let t = to - axis * axis.dot(to);
    if f.norm() < 1e-9 {
        return None;
    }
    Some(axis.dot(&f.cross(&t)).atan2(f.dot(&t)).to_degrees())
}

/// The unit vectors c with `u·c = u·a` and `v·c = v·b` (none, one or two; `+z` first).
fn common_vectors(
    u: &Vector3<f64>,
    a: &Vector3<f64>,
    v: &Vector3<f64>,
    b: &Vector3<f64>,
) -> Result<Vec<Vector3<f64>>, InverseError> {
    let w = u.cross(v);
    let w2 = w.norm_squared();
    if w2 < EPS {
        return Err(InverseError::Unsupported(
            "the two rotary axes are parallel",
        ));
    }
    let uv = u.dot(v);
    let (ua, vb) = (u.dot(a), v.dot(b));
    let det = 1.0 - uv * uv;
    let x = (ua - uv * vb) / det;
    let y = (vb - uv * ua) / det;
    let base = u * x + v * y;
    let z2 = (1.0 - base.norm_squared()) / w2;
    if z2 < -1e-9 {
        return Err(InverseError::Unreachable);
    }
    let z = z2.max(0.0).sqrt();
    Ok(if z < 1e-9 {
        vec![base + w * z]
    } else {
        vec![base + w * z, base - w * z]
    })
}

/// Sets the chain's linear axes in `joints` (rotaries given) so that the tool tip meets
/// the workpiece point `pose.tip` (`pose.axis` is not read: the rotaries fix the tool
/// direction). The tool-centre-point interpolation runs this at every sample: the program's
/// rotaries are the machine's, the tip is placed by the linear axes.
pub fn solve_linear(
    chain: &Chain,
    pose: &ToolPose,
    tool_length_mm: f64,
    joints: &mut AxisVec,
) -> Result<(), InverseError> {
    // Columns: head axis +R_before d, table axis −R_before d; the rest kept as given.
    let mut columns: Vec<(Axis, Vector3<f64>)> = Vec::new();
    for side in [Side::Table, Side::Head] {
        let links = match side {
            Side::Table => chain.table(),
            Side::Head => chain.head(),
        };
        let mut before = nalgebra::Rotation3::identity();
        for l in links {
            if !l.axis.is_rotary() {
                let col = before * l.direction;
                columns.push((l.axis, if side == Side::Head { col } else { -col }));
            }
            before *= l.rotation(joints[l.axis]);
        }
    }
    let mut chosen: Vec<(Axis, Vector3<f64>)> = Vec::new();
    for (axis, col) in &columns {
        if chosen.len() < 3 && independent(&chosen, col) {
            chosen.push((*axis, *col));
        }
    }
    for (axis, _) in &chosen {
        joints[*axis] = 0.0;
    }
    let residual = |j: &AxisVec| {
        let (tip, _) = chain.tool_in_machine(j, tool_length_mm);
        tip - chain.table_pose(j) * pose.tip
    };
    let f0 = residual(joints);
    let solved = match chosen.len() {
        3 => {
            let m = Matrix3::from_columns(&[chosen[0].1, chosen[1].1, chosen[2].1]);
            m.try_inverse().map(|inv| inv * -f0)
        }
        0 => Some(Vector3::zeros()),
        n => {
            // Least squares over the n < 3 columns: (JᵀJ) x = −Jᵀ f0.
            let mut jtj = Matrix3::identity();
            let mut rhs = Vector3::zeros();
            for i in 0..n {
                for k in 0..n {
                    jtj[(i, k)] = chosen[i].1.dot(&chosen[k].1);
                }
                rhs[i] = -chosen[i].1.dot(&f0);
            }
            jtj.try_inverse().map(|inv| inv * rhs)
        }
    };
    let x = solved.ok_or(InverseError::Unsupported(
        "the linear axes are not independent",
    ))?;
    for (i, (axis, _)) in chosen.iter().enumerate() {
        joints[*axis] = x[i];
    }
    Ok(())
}

fn independent(chosen: &[(Axis, Vector3<f64>)], col: &Vector3<f64>) -> bool {
    match chosen {
        [] => col.norm() > 1e-9,
        [(_, a)] => a.cross(col).norm() > 1e-9,
        [(_, a), (_, b)] => a.cross(b).dot(col).abs() > 1e-9,
        _ => false,
    }
}

/// What the inverse kinematics met along a path (found by
/// [`PoleWatch`](super::chain_events::PoleWatch)).
#[derive(Clone, Debug, PartialEq)]
pub enum PathEvent {
    /// The tool direction passed a pole from `line` to `last_line` (block ends within the
    /// pole tolerance): `axis` was free there and moves by `swing_deg` from the block end
    /// before the passage to the one after (a C swing at the pole, or C holding).
    Pole {
        line: usize,
        last_line: usize,
        axis: Axis,
        swing_deg: f64,
    },
    /// The nearest solution changed branch at `line` (the rotaries flip over).
    Switch { line: usize, from: usize, to: usize },
}

/// `angle_deg` plus the multiple of 360 that brings it nearest to `reference_deg`.
pub fn unwrap_near(angle_deg: f64, reference_deg: f64) -> f64 {
    angle_deg + 360.0 * ((reference_deg - angle_deg) / 360.0).round()
}
