//! Which axis left a mark on the ball-bar trace: the bar's sensitivity to each axis, and
//! the attribution of a spike or step to the axes reversing where it starts.
//!
//! # Sensitivity
//!
//! The bar reads `L(q) = |p_tool(q) - p_pivot(q)|` (see [`super::bar::deviation_mm`]). A
//! lost motion `δq_a` of axis a at a reversal moves the reading by `∂L/∂q_a · δq_a`, so an
//! axis whose partial derivative is small at that angle cannot be what the bar shows there.
//! The derivative is taken through the kinematics by central differences,
//!
//! ```text
//! s_a = ∂L/∂q_a ≈ (L(q + h e_a) - L(q - h e_a)) / 2h,   h = 1e-4 mm or deg
//! ```
//!
//! in mm/mm for a linear axis (the cosine between the bar and the axis) and mm/deg for a
//! rotary one (the lever arm of the table ball about that axis, projected on the bar, times
//! π/180). To compare both kinds it is normalised: linear `|s_a|`, rotary
//! `|s_a| · (180/π) / L`, i.e. the bar's response to a rotary error as a fraction of the
//! arc that error would sweep at the bar's own length. On the cone test the bar stays
//! perpendicular to the tool axis, machine Z, so `s_Z = 0` everywhere.
//!
//! # Attribution
//!
//! A mark is matched against the *sensitive* reversals (normalised sensitivity at least
//! [`SENSITIVITY_MIN`]):
//! - a reversal has a *slow zone*: the arc about it where the axis moves slower than its
//!   Stribeck velocity (velocity-weakening friction, stick-slip), so that its friction marks
//!   can come before and after the reversal itself ([`sites_from_map`]);
//! - a reversal's distance to the mark is the distance between its slow zone and the arc
//!   the mark covers from its onset to its peak, 0 when they overlap; a step is a point;
//! - each axis's distance `d_a` is that of its nearest sensitive reversal;
//! - the candidates are the axes with `d_a <= ATTRIBUTION_MAX_DEG` and
//!   `d_a <= d_min + TIE_DEG`: reversals closer together than the onset can be located
//!   cannot be told apart, so the mark is *ambiguous* and lists them all;
//! - the leading axis is the nearest one; distances equal within [`ANGLE_EPS_DEG`] (the
//!   analytic roots of two axes reversing at one angle differ by rounding only) are a tie,
//!   decided by the larger sensitivity, never by the rounding;
//! - the confidence is the Gaussian likelihood share of the leading axis,
//!   `w(d) = exp(-d²/2σ²)`, σ = [`ONSET_SIGMA_DEG`], among the sensitive axes' nearest
//!   reversals and "no axis" at [`ATTRIBUTION_MAX_DEG`].

use nalgebra::Point3;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::bar::deviation_mm;
use super::theta::{angle_distance_deg, BIN_DEG, N_BINS};
use crate::kinematics::{Kinematics, RotarySinCos};
use crate::numeric::sin_cos_deg;
use crate::{Axis, AxisVec};

/// Standard uncertainty of an event's onset angle, deg.
pub const ONSET_SIGMA_DEG: f64 = 0.5;
/// An event farther than this from every sensitive reversal is attributed to no axis, deg.
pub const ATTRIBUTION_MAX_DEG: f64 = 3.0;
/// Reversals of two axes within this of each other, as seen from a mark, are candidates
/// alike (twice the onset uncertainty), deg.
pub const TIE_DEG: f64 = 1.0;
/// Angles closer than this are equal, deg.
pub const ANGLE_EPS_DEG: f64 = 1e-6;
/// Below this normalised sensitivity the bar cannot see an axis (5 % of its error reaches
/// the bar: 0.5 um of 10 um backlash, the spike floor).
pub const SENSITIVITY_MIN: f64 = 0.05;
/// Central-difference step of [`bar_sensitivity`], mm or deg.
const DIFF_STEP: f64 = 1e-4;

/// `∂L/∂q_a` for every axis in `axes`, mm/mm (linear) or mm/deg (rotary), at actual
/// positions `q`; other entries 0.
pub fn bar_sensitivity(
    kin: &Kinematics,
    axes: &[Axis],
    q: &AxisVec,
    pivot_table_mm: &Point3<f64>,
    length_mm: f64,
) -> AxisVec {
    bar_sensitivity_at(
        kin,
        axes,
        q,
        &kin.rotary_sin_cos(q),
        pivot_table_mm,
        length_mm,
    )
}

/// [`bar_sensitivity`] with the sines and cosines of the rotary angles at `q` already known
/// (`base`, as [`Kinematics::rotary_sin_cos`] gives them): the ball bar has them from its
/// reading of the same sample.
pub fn bar_sensitivity_at(
    kin: &Kinematics,
    axes: &[Axis],
    q: &AxisVec,
    base: &RotarySinCos,
    pivot_table_mm: &Point3<f64>,
    length_mm: f64,
) -> AxisVec {
    let mut s = AxisVec::ZERO;
    if !kin.has_closed_form() {
        // A general chain: every axis by the central difference of the chain's reading.
        for &a in axes {
            let (mut up, mut down) = (*q, *q);
            up[a] += DIFF_STEP;
            down[a] -= DIFF_STEP;
            s[a] = (deviation_mm(kin, &up, pivot_table_mm, length_mm)
                - deviation_mm(kin, &down, pivot_table_mm, length_mm))
                / (2.0 * DIFF_STEP);
        }
        return s;
    }
    let base = *base;
    // The table ball moves with the rotary axes only: one evaluation serves the linear ones
    // (the same arithmetic as `deviation_mm`; on the nominal chain that of
    // `Kinematics::table_to_machine`, from the sines and cosines at hand).
    let pivot = if kin.location_errors.is_zero() {
        Point3::from(kin.pivot_mm + kin.rotation_of(&base) * pivot_table_mm.coords)
    } else {
        kin.actual_table_to_machine(q, pivot_table_mm)
    };
    let linear =
        |q: &AxisVec| (Point3::new(q[Axis::X], q[Axis::Y], q[Axis::Z]) - pivot).norm() - length_mm;
    for &a in axes {
        let (mut up, mut down) = (*q, *q);
        up[a] += DIFF_STEP;
        down[a] -= DIFF_STEP;
        let difference = if a.is_rotary() && kin.location_errors.is_zero() {
            // Only the perturbed angle's sine and cosine change: the other one's are shared
            // (the arithmetic of `deviation_mm` on the nominal chain, term for term).
            let rotated = |q: &AxisVec| {
                let angles = kin.with_rotary_sin_cos(&base, a, sin_cos_deg(q[a]));
                let r = kin.rotation_of(&angles);
                let pivot = Point3::from(kin.pivot_mm + r * pivot_table_mm.coords);
                (Point3::new(q[Axis::X], q[Axis::Y], q[Axis::Z]) - pivot).norm() - length_mm
            };
            rotated(&up) - rotated(&down)
        } else if a.is_rotary() {
            deviation_mm(kin, &up, pivot_table_mm, length_mm)
                - deviation_mm(kin, &down, pivot_table_mm, length_mm)
        } else {
            linear(&up) - linear(&down)
        };
        s[a] = difference / (2.0 * DIFF_STEP);
    }
    s
}

/// The normalised sensitivity of [`bar_sensitivity`]'s entry `s` for `axis` (see the
/// module docs): `|s|` for a linear axis, `|s| (180/π) / L` for a rotary one.
pub fn normalised_sensitivity(axis: Axis, s: f64, length_mm: f64) -> f64 {
    if axis.is_rotary() {
        s.abs() * 180.0 / std::f64::consts::PI / length_mm
    } else {
        s.abs()
    }
}

/// A set of axes, serialized as a list of letters in X Y Z A B C U V W order.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AxisSet(u16);

impl AxisSet {
    pub const EMPTY: AxisSet = AxisSet(0);

    pub fn insert(&mut self, a: Axis) {
        self.0 |= 1 << a.index();
    }

    pub fn contains(&self, a: Axis) -> bool {
        self.0 & (1 << a.index()) != 0
    }

    pub fn len(&self) -> usize {
        self.0.count_ones() as usize
    }

    pub fn is_empty(&self) -> bool {
        self.0 == 0
    }

    pub fn iter(&self) -> impl Iterator<Item = Axis> + '_ {
        Axis::ALL.into_iter().filter(|a| self.contains(*a))
    }
}

impl std::fmt::Display for AxisSet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let letters: Vec<String> = self.iter().map(|a| a.to_string()).collect();
        write!(f, "{}", letters.join("/"))
    }
}

impl Serialize for AxisSet {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(self.iter().map(|a| a.to_string()))
    }
}

impl<'de> Deserialize<'de> for AxisSet {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<AxisSet, D::Error> {
        let mut set = AxisSet::EMPTY;
        Vec::<Axis>::deserialize(d)?
            .into_iter()
            .for_each(|a| set.insert(a));
        Ok(set)
    }
}

/// One reversal of one axis, with the bar's normalised sensitivity to that axis there
/// (`None`: unknown, taken as sensitive).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ReversalSite {
    pub axis: Axis,
    pub theta_deg: f64,
    pub sensitivity: Option<f64>,
    /// The slow zone about the reversal, where the axis moves slower than its Stribeck
    /// velocity (velocity-weakening friction: stick-slip): from this angle up by
    /// `zone_span_deg`, deg. A point (span 0) when unknown.
    pub zone_from_deg: f64,
    pub zone_span_deg: f64,
}

impl ReversalSite {
    /// Whether the bar can see this axis here.
    pub fn visible(&self) -> bool {
        self.sensitivity.is_none_or(|s| s >= SENSITIVITY_MIN)
    }

    /// Sites of unknown sensitivity from `(axis, reversal angles)`.
    pub fn unweighted(reversals: &[(Axis, Vec<f64>)]) -> Vec<ReversalSite> {
        reversals
            .iter()
            .flat_map(|(axis, angles)| {
                angles.iter().map(|&theta_deg| ReversalSite {
                    axis: *axis,
                    theta_deg,
                    sensitivity: None,
                    zone_from_deg: theta_deg,
                    zone_span_deg: 0.0,
                })
            })
            .collect()
    }
}

/// To which axes a mark belongs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Attribution {
    /// The leading axis: the nearest sensitive reversal (ties: the more sensitive axis).
    pub axis: Option<Axis>,
    /// Every axis the mark may come from (the leading one included).
    pub candidates: AxisSet,
    /// The leading axis's likelihood share, 0..1.
    pub confidence: f64,
}

/// Attributes a mark at `theta_deg` (see the module docs).
pub fn attribute_to_sites(theta_deg: f64, sites: &[ReversalSite]) -> Attribution {
    attribute_arc(theta_deg, 0.0, sites)
}

/// Distance from `theta_deg` to the arc from `from_deg` going up by `span_deg`, deg: 0 inside.
pub fn distance_to_arc_deg(theta_deg: f64, from_deg: f64, span_deg: f64) -> f64 {
    if (theta_deg - from_deg).rem_euclid(360.0) <= span_deg {
        0.0
    } else {
        angle_distance_deg(theta_deg, from_deg)
            .min(angle_distance_deg(theta_deg, from_deg + span_deg))
    }
}

/// Distance between two arcs (each from an angle up by a span), deg: 0 when they overlap.
pub fn arc_distance_deg(a_from: f64, a_span: f64, b_from: f64, b_span: f64) -> f64 {
    distance_to_arc_deg(a_from, b_from, b_span)
        .min(distance_to_arc_deg(a_from + a_span, b_from, b_span))
        .min(distance_to_arc_deg(b_from, a_from, a_span))
}

/// Attributes a mark that covers the arc from `from_deg` up by `span_deg` (its onset to its
/// peak, in increasing θ): a reversal inside the arc is at distance 0 (see the module docs).
pub fn attribute_arc(from_deg: f64, span_deg: f64, sites: &[ReversalSite]) -> Attribution {
    let weight = |d: f64| (-0.5 * (d / ONSET_SIGMA_DEG).powi(2)).exp();
    // Per axis: (distance of its nearest visible reversal, sensitivity there).
    let mut nearest: Vec<(Axis, f64, f64)> = Vec::new();
    for site in sites
        .iter()
        .filter(|s| s.visible() && s.theta_deg.is_finite())
    {
        let d = arc_distance_deg(site.zone_from_deg, site.zone_span_deg, from_deg, span_deg);
        let s = site.sensitivity.unwrap_or(1.0);
        match nearest.iter_mut().find(|(a, _, _)| *a == site.axis) {
            Some(n) if d < n.1 => *n = (site.axis, d, s),
            Some(_) => {}
            None => nearest.push((site.axis, d, s)),
        }
    }
    let total = weight(ATTRIBUTION_MAX_DEG) + nearest.iter().map(|n| weight(n.1)).sum::<f64>();
    let leading = nearest.iter().copied().reduce(|best, n| {
        let closer = n.1 < best.1 - ANGLE_EPS_DEG;
        let tie = (n.1 - best.1).abs() <= ANGLE_EPS_DEG;
        if closer || (tie && n.2 > best.2) {
            n
        } else {
            best
        }
    });
    match leading {
        Some((axis, d, _)) if d <= ATTRIBUTION_MAX_DEG => {
            let mut candidates = AxisSet::EMPTY;
            for n in &nearest {
                if n.1 <= ATTRIBUTION_MAX_DEG && n.1 <= d + TIE_DEG {
                    candidates.insert(n.0);
                }
            }
            Attribution {
                axis: Some(axis),
                candidates,
                confidence: weight(d) / total,
            }
        }
        _ => Attribution {
            axis: None,
            candidates: AxisSet::EMPTY,
            confidence: 0.0,
        },
    }
}

/// One axis vector per θ bin of [`BIN_DEG`] along the measured circle,
/// taken at the first sample that falls in the bin: the commanded position (where the bar's
/// sensitivity is evaluated, only at the bins a reversal site asks for) or the commanded
/// speed. Its [`N_BINS`] bins (576 kB) are allocated at the first value set: a run that
/// fills no map (a study's later runs) allocates nothing.
#[derive(Clone, Debug, Default)]
pub struct ThetaMap {
    /// Empty until a value is set, then [`N_BINS`] long.
    bins: Vec<Option<AxisVec>>,
}

impl ThetaMap {
    /// Whether `bin` still needs a value ([`super::theta::bin_index`] of θ in [0, 360) is
    /// its bin).
    #[inline]
    pub fn wants_bin(&self, bin: usize) -> bool {
        self.bins.get(bin).is_none_or(Option::is_none)
    }

    /// Sets the value of `bin`.
    #[inline]
    pub fn set_bin(&mut self, bin: usize, s: AxisVec) {
        if self.bins.is_empty() {
            self.bins = vec![None; N_BINS];
        }
        self.bins[bin] = Some(s);
    }

    /// The value of bin `i`, if it was set.
    pub fn bin(&self, i: usize) -> Option<AxisVec> {
        self.bins.get(i).copied().flatten()
    }

    /// The value of the filled bin nearest `theta_deg` (within 5 deg), if any.
    pub fn at(&self, theta_deg: f64) -> Option<AxisVec> {
        if self.bins.is_empty() {
            return None;
        }
        let n = self.bins.len() as isize;
        let i = bin_of(theta_deg) as isize;
        let reach = (5.0 / BIN_DEG) as isize;
        (0..=reach).find_map(|k| {
            self.bins[(i + k).rem_euclid(n) as usize].or(self.bins[(i - k).rem_euclid(n) as usize])
        })
    }
}

fn bin_of(theta_deg: f64) -> usize {
    let t = theta_deg.rem_euclid(360.0);
    ((t / BIN_DEG) as usize).min(N_BINS - 1)
}

/// Sites for each axis's reversal angles, with the normalised sensitivity
/// `sensitivity_at(q)` at the commanded position `q` of the filled bin of `commanded`
/// nearest each site (evaluated here, for the sites alone) and,
/// given the commanded speeds `speed` (mm/s, deg/s per bin) and each axis's Stribeck
/// velocity `slow(axis)`, the slow zone: the bins about the reversal where the axis moves
/// slower than that, at most [`MAX_ZONE_DEG`] each way.
pub fn sites_from_map(
    reversals: &[(Axis, Vec<f64>)],
    commanded: &ThetaMap,
    sensitivity_at: &dyn Fn(&AxisVec) -> AxisVec,
    length_mm: f64,
    speed: Option<(&ThetaMap, &dyn Fn(Axis) -> f64)>,
) -> Vec<ReversalSite> {
    let mut sites = ReversalSite::unweighted(reversals);
    for site in &mut sites {
        site.sensitivity = commanded
            .at(site.theta_deg)
            .map(|q| normalised_sensitivity(site.axis, sensitivity_at(&q)[site.axis], length_mm));
        if let Some((speed, slow)) = speed {
            let limit = slow(site.axis);
            let step = BIN_DEG;
            let reach = (MAX_ZONE_DEG / step) as usize;
            let slow_at = |theta: f64| speed.at(theta).is_some_and(|v| v[site.axis].abs() < limit);
            let walk = |sign: f64| {
                (1..=reach)
                    .take_while(|&k| slow_at(site.theta_deg + sign * k as f64 * step))
                    .count() as f64
                    * step
            };
            let (before, after) = (walk(-1.0), walk(1.0));
            site.zone_from_deg = site.theta_deg - before;
            site.zone_span_deg = before + after;
        }
    }
    sites
}

/// The reversal sites of the points of a study pass, which share the reversals, the
/// command maps and the bar: [`sites_from_map`] once for each set of slow-zone limits
/// (`slow` of each reversing axis, by its bits; a point's friction sets its own), the same
/// sites as each point's own call gives.
#[derive(Default)]
pub struct SharedSites(std::cell::RefCell<Vec<(Vec<u64>, Vec<ReversalSite>)>>);

impl SharedSites {
    /// [`sites_from_map`] with `speed`, made at the first point with its limits.
    pub fn get(
        &self,
        reversals: &[(Axis, Vec<f64>)],
        commanded: &ThetaMap,
        sensitivity_at: &dyn Fn(&AxisVec) -> AxisVec,
        length_mm: f64,
        speed: (&ThetaMap, &dyn Fn(Axis) -> f64),
    ) -> Vec<ReversalSite> {
        let key: Vec<u64> = reversals
            .iter()
            .map(|(a, _)| speed.1(*a).to_bits())
            .collect();
        if let Some((_, sites)) = self.0.borrow().iter().find(|(k, _)| *k == key) {
            return sites.clone();
        }
        let sites = sites_from_map(reversals, commanded, sensitivity_at, length_mm, Some(speed));
        self.0.borrow_mut().push((key, sites.clone()));
        sites
    }
}

/// Largest extent of a slow zone on either side of its reversal, deg.
pub const MAX_ZONE_DEG: f64 = 15.0;

#[cfg(test)]
mod tests {
    use super::*;

    fn site(axis: Axis, theta_deg: f64, s: f64) -> ReversalSite {
        ReversalSite {
            axis,
            theta_deg,
            sensitivity: Some(s),
            zone_from_deg: theta_deg,
            zone_span_deg: 0.0,
        }
    }

    #[test]
    fn rounding_noise_is_a_tie_decided_by_sensitivity_and_blind_axes_drop_out() {
        let sites = [
            site(Axis::Y, 180.0000000000227, 0.3),
            site(Axis::Z, 179.99999999987, 0.0),
            site(Axis::A, 179.9999999999858, 0.9),
        ];
        let a = attribute_to_sites(180.5, &sites);
        assert_eq!(a.axis, Some(Axis::A));
        assert_eq!(a.candidates.to_string(), "Y/A");
    }

    #[test]
    fn reversals_farther_apart_than_the_tie_are_resolved() {
        let sites = [site(Axis::Y, 165.5, 0.5), site(Axis::X, 180.0, 0.5)];
        let a = attribute_to_sites(166.0, &sites);
        assert_eq!((a.axis, a.candidates.len()), (Some(Axis::Y), 1));
        assert!(a.confidence > 0.99);
        let none = attribute_to_sites(172.0, &sites);
        assert_eq!((none.axis, none.candidates.len()), (None, 0));
    }
}
