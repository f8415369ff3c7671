//! The scene's bodies on a kinematic chain: each body rides on the table or head links up
//! to the one it is attached to (the kinematic-chains spec), and a bound on how far its
//! points move while the axes move linearly between two samples.
//!
//! ```text
//! table body    T_table(q) = M_t1 ⋯ M_tm             the workpiece frame
//! cradle body   M_t1 ⋯ M_tc                          the table axes up to its link
//! head body     M_h1 ⋯ M_hk                          the head axes up to its link
//! tool body     T_head(q) F₀,  F₀ = (g, Rot(z → t₀))  tip at its origin, +Z along the tool
//! ```
//!
//! Every body's parts are given at home, so at q = 0 their frames are the machine frame (the
//! tool's is F₀). Motion bound: a point x carried by links 1..n moves at most
//! `Σ_k |Δq_k| sup |∂x/∂q_k|`; that is 1 per mm for a linear link, and for a rotary k the
//! distance of x from k's line, `|y − p_k|` with `y = M_{k+1} ⋯ M_n x₀` (the links before k
//! move the line and the point together). Each outer link moves p_k's image by at most
//! `2 dist(p_k, line_j)` (a rotary) or its travel (a linear), so
//!
//! ```text
//! B_k = max_x₀ |x₀ − p_k| + Σ_{j>k} (2 dist(p_k, line_j) | travel_j)
//! ```
//!
//! and with the monitor's sums of `|Δq|` over all linear axes (mm) and all rotaries (rad)
//! the part's weights are `(1, max_k B_k, 0)`. The linear travel is the axis's limits: a
//! sample beyond them is a travel violation anyway.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

use crate::input::machine::Machine;
use crate::kinematics::{Chain, Link};
use crate::{Axis, AxisVec};

/// Where a chain's bodies ride.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LinkedBodies {
    /// The actual chain (location errors included).
    chain: Chain,
    /// Table links the cradle boxes ride on.
    cradle_links: usize,
    /// Head links the head boxes ride on.
    head_links: usize,
    /// F₀: the tool body's frame at home.
    pub tool_frame: Isometry3<f64>,
    /// |q| bound of each linear axis (mm), by axis index.
    travel: [f64; 9],
}

/// The bodies a part may ride on, as link lists.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Rides {
    Table,
    Cradle,
    Head,
    Tool,
}

impl LinkedBodies {
    /// The bodies of `machine`'s `chain`, the cradle riding on `cradle_links` table links and
    /// the head boxes on `head_links` head links.
    pub fn new(
        machine: &Machine,
        chain: Chain,
        cradle_links: usize,
        head_links: usize,
    ) -> LinkedBodies {
        let mut travel = [0.0; 9];
        for (_, link) in chain.links() {
            if !link.axis.is_rotary() {
                let a = machine.axis(link.axis);
                travel[link.axis.index()] = a.min.abs().max(a.max.abs());
            }
        }
        let tool_frame = Isometry3::from_parts(
            Translation3::from(chain.gauge_point_mm),
            UnitQuaternion::rotation_between(&Vector3::z(), &chain.tool_direction).unwrap_or_else(
                || {
                    // t₀ = −z: any half turn about a horizontal axis.
                    UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
                },
            ),
        );
        LinkedBodies {
            chain,
            cradle_links,
            head_links,
            tool_frame,
            travel,
        }
    }

    fn links(&self, rides: Rides) -> &[Link] {
        match rides {
            Rides::Table => self.chain.table(),
            Rides::Cradle => &self.chain.table()[..self.cradle_links],
            Rides::Head => &self.chain.head()[..self.head_links],
            Rides::Tool => self.chain.head(),
        }
    }

    /// The pose of the body at `q`: its frame in the machine frame.
    pub fn pose(&self, rides: Rides, q: &AxisVec) -> Isometry3<f64> {
        let product = self.chain.product(self.links(rides), q);
        match rides {
            Rides::Tool => product * self.tool_frame,
            _ => product,
        }
    }

    /// The weights `(per mm of linear motion, per rad of rotary motion, 0)` of a part whose
    /// points lie within the convex hull of `corners` (in the body's frame).
    pub fn weights(&self, rides: Rides, corners: &[Point3<f64>]) -> [f64; 3] {
        let home: Vec<Vector3<f64>> = corners
            .iter()
            .map(|c| match rides {
                Rides::Tool => (self.tool_frame * c).coords,
                _ => c.coords,
            })
            .collect();
        let links = self.links(rides);
        let linear = if links.iter().any(|l| !l.axis.is_rotary()) {
            1.0
        } else {
            0.0
        };
        let rotary = links
            .iter()
            .enumerate()
            .filter(|(_, l)| l.axis.is_rotary())
            .map(|(k, l)| {
                let reach = home
                    .iter()
                    .map(|x| (x - l.point_mm).norm())
                    .fold(0.0, f64::max);
                let outer: f64 = links[k + 1..]
                    .iter()
                    .map(|j| {
                        if j.axis.is_rotary() {
                            let r = l.point_mm - j.point_mm;
                            2.0 * (r - j.direction * j.direction.dot(&r)).norm()
                        } else {
                            self.travel[j.axis.index()]
                        }
                    })
                    .sum();
                reach + outer
            })
            .fold(0.0, f64::max);
        [linear, rotary, 0.0]
    }

    /// The monitor's motion between two samples: Σ|Δq| over the linear axes (mm) and over
    /// the rotaries (rad).
    pub fn motion(&self, a: &AxisVec, b: &AxisVec) -> [f64; 3] {
        let (mut linear, mut rotary) = (0.0, 0.0);
        for (_, link) in self.chain.links() {
            let d = (b[link.axis] - a[link.axis]).abs();
            if link.axis.is_rotary() {
                rotary += d.to_radians();
            } else {
                linear += d;
            }
        }
        [linear, rotary, 0.0]
    }

    /// How many links of `side`'s `links` run from the bed up to and including `axis`.
    pub fn prefix(links: &[Link], axis: Axis) -> Option<usize> {
        links.iter().position(|l| l.axis == axis).map(|i| i + 1)
    }
}
