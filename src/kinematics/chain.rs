//! A machine as a chain of axes: forward kinematics as a product of exponentials.
//!
//! The chain lists the axes that carry the workpiece (`table`) and those that carry the
//! tool (`head`), each from the bed outward, with every axis given at the home pose (all
//! axes at zero) in the machine frame: a unit direction d_k and, for a rotary, a point p_k
//! on its line. Axis k at value q moves the bodies beyond it by
//!
//! ```text
//! linear:  M_k(q) x = x + q d_k
//! rotary:  M_k(q) x = Rot(d_k, q) (x − p_k) + p_k      (right-handed, Rodrigues)
//! T_table = M_t1(q_t1) ⋯ M_tm(q_tm)                    workpiece point → machine frame
//! T_head  = M_h1(q_h1) ⋯ M_hn(q_hn)                    spindle → machine frame
//! tip     = T_head (g − l t₀)                          g: gauge point, t₀: tool direction
//! ```
//!
//! In the workpiece frame (the machine frame at home, carried by the table) the tip is
//! `T_table⁻¹ tip` and the tool direction `R_table⁻¹ R_head t₀`. The inverse kinematics is
//! in [`super::chain_inverse`].

use nalgebra::{Isometry3, Point3, Rotation3, Translation3, Unit, Vector3};

use super::linear_errors::ComponentErrors;
use crate::{Axis, AxisVec};

/// Tool tip and tool axis in the table frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToolPose {
    /// Tool tip, mm, table frame.
    pub tip: Point3<f64>,
    /// Unit tool axis, from the tip toward the spindle, table frame.
    pub axis: Vector3<f64>,
}

/// Most axes a chain holds (one of each letter).
pub const MAX_LINKS: usize = 9;

/// One axis of a chain, at the home pose, in the machine frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Link {
    pub axis: Axis,
    /// Unit direction: a rotary's line (right-handed turn), a linear axis's motion.
    pub direction: Vector3<f64>,
    /// A point on a rotary's line, mm; unused for a linear axis.
    pub point_mm: Vector3<f64>,
}

impl Link {
    /// A linear axis moving along `direction` (normalised here).
    pub fn linear(axis: Axis, direction: Vector3<f64>) -> Link {
        Link {
            axis,
            direction: direction.normalize(),
            point_mm: Vector3::zeros(),
        }
    }

    /// A rotary axis turning about the line through `point_mm` along `direction`.
    pub fn rotary(axis: Axis, direction: Vector3<f64>, point_mm: Vector3<f64>) -> Link {
        Link {
            axis,
            direction: direction.normalize(),
            point_mm,
        }
    }

    /// Rot(d, q) of a rotary at `q_deg`; the identity for a linear axis.
    pub fn rotation(&self, q_deg: f64) -> Rotation3<f64> {
        if self.axis.is_rotary() {
            Rotation3::from_axis_angle(&Unit::new_unchecked(self.direction), q_deg.to_radians())
        } else {
            Rotation3::identity()
        }
    }

    /// M_k(q) as an isometry: `x ↦ R x + (p − R p)` for a rotary, `x ↦ x + q d` for a linear.
    pub fn motion(&self, q: f64) -> Isometry3<f64> {
        if self.axis.is_rotary() {
            let r = self.rotation(q);
            let shift = self.point_mm - r * self.point_mm;
            Isometry3::from_parts(Translation3::from(shift), r.into())
        } else {
            Isometry3::from_parts(Translation3::from(self.direction * q), Default::default())
        }
    }
}

/// Which side of the chain a link is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// Carries the workpiece.
    Table,
    /// Carries the tool.
    Head,
}

/// A machine's kinematic chain (fixed capacity, so that it is `Copy` like the layouts).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Chain {
    links: [Link; MAX_LINKS],
    table_len: usize,
    len: usize,
    /// The spindle gauge point at home, machine frame, mm.
    pub gauge_point_mm: Vector3<f64>,
    /// Unit tool direction at home, from the tip toward the spindle.
    pub tool_direction: Vector3<f64>,
    /// The component errors of the linear axes, on an actual chain
    /// ([`super::linear_errors`]): `E_J(q_J)` right after `M_J(q_J)`.
    components: Option<&'static ComponentErrors>,
}

/// Why a chain is not valid.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ChainError(pub String);

impl Chain {
    /// A chain from its table and head links (each from the bed outward). Every axis once,
    /// at most [`MAX_LINKS`]; directions finite and non-zero (normalised here).
    pub fn new(
        table: &[Link],
        head: &[Link],
        gauge_point_mm: Vector3<f64>,
        tool_direction: Vector3<f64>,
    ) -> Result<Chain, ChainError> {
        let all = table.iter().chain(head);
        let mut seen = [false; MAX_LINKS];
        let mut links = [Link::linear(Axis::X, Vector3::z()); MAX_LINKS];
        for (i, link) in all.enumerate() {
            if seen[link.axis.index()] {
                return Err(ChainError(format!(
                    "axis {} appears twice in the chain",
                    link.axis
                )));
            }
            seen[link.axis.index()] = true;
            if !is_direction(&link.direction) || !link.point_mm.iter().all(|v| v.is_finite()) {
                return Err(ChainError(format!(
                    "axis {}: its direction must be a finite non-zero vector and its point finite",
                    link.axis
                )));
            }
            links[i] = Link {
                direction: link.direction.normalize(),
                ..*link
            };
        }
        if !is_direction(&tool_direction) || !gauge_point_mm.iter().all(|v| v.is_finite()) {
            return Err(ChainError(
                "tool_direction must be a finite non-zero vector and gauge_point_mm finite".into(),
            ));
        }
        Ok(Chain {
            links,
            table_len: table.len(),
            len: table.len() + head.len(),
            gauge_point_mm,
            tool_direction: tool_direction.normalize(),
            components: None,
        })
    }

    /// The axes that carry the workpiece, from the bed outward.
    pub fn table(&self) -> &[Link] {
        &self.links[..self.table_len]
    }

    /// The axes that carry the tool, from the bed outward.
    pub fn head(&self) -> &[Link] {
        &self.links[self.table_len..self.len]
    }

    /// Every link with its side, table first.
    pub fn links(&self) -> impl Iterator<Item = (Side, &Link)> {
        self.links[..self.len].iter().enumerate().map(|(i, l)| {
            let side = if i < self.table_len {
                Side::Table
            } else {
                Side::Head
            };
            (side, l)
        })
    }

    /// The link of `axis`, if the chain has it.
    pub fn link(&self, axis: Axis) -> Option<&Link> {
        self.links[..self.len].iter().find(|l| l.axis == axis)
    }

    /// The axes of the chain in X Y Z A B C U V W order.
    pub fn axes(&self) -> Vec<Axis> {
        Axis::ALL
            .into_iter()
            .filter(|a| self.link(*a).is_some())
            .collect()
    }

    /// T_table(q): workpiece frame → machine frame.
    pub fn table_pose(&self, q: &AxisVec) -> Isometry3<f64> {
        self.product(self.table(), q)
    }

    /// T_head(q): the spindle's home pose → its pose at `q`, machine frame.
    pub fn head_pose(&self, q: &AxisVec) -> Isometry3<f64> {
        self.product(self.head(), q)
    }

    /// The motion of `link` at `q`: `M_k(q_k)`, followed on an actual chain by the
    /// linear axis's component errors `E_k(q_k)` ([`super::linear_errors`]).
    pub fn link_motion(&self, link: &Link, q: &AxisVec) -> Isometry3<f64> {
        let value = q[link.axis];
        let motion = link.motion(value);
        match self.components.and_then(|c| c.motion(link.axis, value)) {
            Some(errors) => motion * errors,
            None => motion,
        }
    }

    /// M_1(q_1) E_1(q_1) ⋯ M_n(q_n) E_n(q_n) of `links` ([`Chain::link_motion`]).
    pub fn product(&self, links: &[Link], q: &AxisVec) -> Isometry3<f64> {
        links
            .iter()
            .fold(Isometry3::identity(), |acc, l| acc * self.link_motion(l, q))
    }

    /// The same chain with the linear axes' component errors `components` acting after
    /// their motions (the actual chain).
    pub fn with_components(mut self, components: Option<&'static ComponentErrors>) -> Chain {
        self.components = components;
        self
    }

    /// Tool tip (mm) and tool direction in the machine frame at `q`, for a tool of length
    /// `tool_length_mm` (0: the gauge point).
    pub fn tool_in_machine(&self, q: &AxisVec, tool_length_mm: f64) -> (Point3<f64>, Vector3<f64>) {
        let head = self.head_pose(q);
        let tip = Point3::from(self.gauge_point_mm - tool_length_mm * self.tool_direction);
        (head * tip, head.rotation * self.tool_direction)
    }

    /// Tool tip (mm) and tool direction in the workpiece frame at `q`.
    pub fn tool_in_workpiece(
        &self,
        q: &AxisVec,
        tool_length_mm: f64,
    ) -> (Point3<f64>, Vector3<f64>) {
        let (tip, direction) = self.tool_in_machine(q, tool_length_mm);
        let table = self.table_pose(q);
        (
            table.inverse_transform_point(&tip),
            table.rotation.inverse_transform_vector(&direction),
        )
    }

    /// The same chain with `axis`'s line through `point_mm` along `direction` (normalised):
    /// the actual chain of a rotary with location errors.
    pub fn with_line(
        mut self,
        axis: Axis,
        direction: Vector3<f64>,
        point_mm: Vector3<f64>,
    ) -> Chain {
        if let Some(link) = self.links[..self.len].iter_mut().find(|l| l.axis == axis) {
            link.direction = direction.normalize();
            link.point_mm = point_mm;
        }
        self
    }

    /// The rotary links, in chain order, with their sides.
    pub fn rotaries(&self) -> impl Iterator<Item = (Side, &Link)> {
        self.links().filter(|(_, l)| l.axis.is_rotary())
    }
}

fn is_direction(v: &Vector3<f64>) -> bool {
    v.iter().all(|c| c.is_finite()) && v.norm() > 1e-9
}
