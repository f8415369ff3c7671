//! Pre-sliding friction: the bristle model of Dahl (1968), with LuGre's bristle damping, for
//! the guides and screw of one axis. It replaces the Coulomb/stiction law on the table when
//! `presliding_um` (`_deg`) is set.
//!
//! # Model
//!
//! The contact is a bristle of stiffness σ0 whose deflection z follows the table travel x:
//!
//! ```text
//! dz/dx = 1 - (σ0 / Fc) z sign(dx)            (Dahl, exponent 1: rate-independent)
//! F     = -(σ0 z + σ1 dz/dt)                   (friction on the table)
//! σ0    = Fc / δ,    σ1 = 2 ζ sqrt(σ0 m_t)
//! ```
//!
//! with δ the pre-sliding displacement (`presliding_um`): the elastic travel at which the
//! bristle carries Fc. In steady sliding `z = δ sign(v)` and `F = -Fc sign(v)`: Coulomb
//! friction. After a reversal at x_r, coming from `z = -δ`, the exact solution is
//!
//! ```text
//! z(x) = δ (1 - 2 exp(-(x - x_r) / δ)),   F = -Fc (1 - 2 exp(-(x - x_r)/δ))
//! ```
//!
//! so the friction force turns over gradually, crossing zero after `δ ln 2` and reaching
//! 95 % of Fc after `δ ln 40 ≈ 3.7 δ` of travel: the elastic, gradual lost motion of real
//! guides, instead of the jump of the Coulomb law. At rest z (and the force) stays: the
//! bristle holds what the approach left.
//!
//! # Integration
//!
//! For a table step Δx of one sign s the Dahl equation is linear in z and is advanced
//! exactly, `z ← s δ + (z - s δ) exp(-|Δx| / δ)`; the force uses the state at the start of
//! the step (explicit), which is stable while `h sqrt(σ0 / m_t) < 2` and
//! `h σ1 / m_t < 2` (about 0.05 and 0.1 for the defaults).
//!
//! # Reversal value
//!
//! [`ReversalValue`] splits the lost motion an axis shows at a reversal (ISO 230-2 B at
//! the table, semi-closed loop, after approaches longer than a few δ) into its parts:
//! the backlash gap b, the elastic wind-up `2 Fc / k` of the drive by the friction held at
//! rest, and the pre-sliding travel `2 δ` over which that friction turns over.

use serde::Serialize;

/// The bristle state and parameters of one axis, SI (m, N, or rad, N m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Presliding {
    /// Pre-sliding displacement δ = Fc / σ0, m or rad.
    delta: f64,
    /// Bristle stiffness σ0, N/m or N m/rad.
    sigma0: f64,
    /// Bristle damping σ1, N s/m or N m s/rad.
    sigma1: f64,
    /// Bristle deflection z, m or rad.
    z: f64,
    /// dz/dt over the last step, m/s or rad/s.
    z_rate: f64,
}

impl Presliding {
    /// A bristle carrying `coulomb` (N or N m) at deflection `delta` (m or rad, > 0), on a
    /// table of mass `table_mass` (kg or kg m^2), damped at ratio `damping_ratio`; relaxed.
    pub fn new(coulomb: f64, delta: f64, table_mass: f64, damping_ratio: f64) -> Presliding {
        let sigma0 = coulomb / delta;
        Presliding {
            delta,
            sigma0,
            sigma1: 2.0 * damping_ratio * (sigma0 * table_mass).sqrt(),
            z: 0.0,
            z_rate: 0.0,
        }
    }

    /// Friction force on the table now, N or N m: `-(σ0 z + σ1 dz/dt)`.
    #[inline]
    pub fn force(&self) -> f64 {
        -(self.sigma0 * self.z + self.sigma1 * self.z_rate)
    }

    /// Bristle deflection z, m or rad.
    pub fn deflection(&self) -> f64 {
        self.z
    }

    /// Advances the bristle over a table step `dx` (m or rad) taken in `dt` (s), exactly.
    #[inline]
    pub fn advance(&mut self, dx: f64, dt: f64) {
        if dx == 0.0 {
            self.z_rate = 0.0;
            return;
        }
        let target = self.delta.copysign(dx);
        let z = target + (self.z - target) * (-dx.abs() / self.delta).exp();
        self.z_rate = (z - self.z) / dt;
        self.z = z;
    }
}

/// An axis's lost motion at a reversal, in its interface unit (mm or deg).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ReversalValue {
    /// The backlash gap b (semi-closed loop; a fully-closed loop closes over it: 0).
    pub backlash: f64,
    /// The drive's elastic wind-up by the friction held at rest, `2 Fc / k` (semi-closed
    /// loop; 0 fully-closed).
    pub elastic: f64,
    /// The table travel over which pre-sliding friction turns over, `2 δ` (0 without
    /// pre-sliding): how gradually the lost motion is taken up, not part of B at rest.
    pub presliding: f64,
    /// ISO 230-2 B at the table after long approaches: `backlash + elastic`.
    pub b: f64,
}

impl ReversalValue {
    /// From the backlash b, Coulomb friction Fc (N or N m), stiffness k (N/unit) and
    /// pre-sliding displacement δ, all in one length unit; `fully_closed` zeroes b and the
    /// wind-up.
    pub fn new(
        backlash: f64,
        coulomb: f64,
        stiffness: f64,
        delta: f64,
        fully_closed: bool,
    ) -> Self {
        let (backlash, elastic) = if fully_closed {
            (0.0, 0.0)
        } else {
            (backlash, 2.0 * coulomb / stiffness)
        };
        ReversalValue {
            backlash,
            elastic,
            presliding: 2.0 * delta,
            b: backlash + elastic,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Fc 150 N, δ 2 um: σ0 = 7.5e7 N/m.
    fn bristle() -> Presliding {
        Presliding::new(150.0, 2e-6, 500.0, 1.0)
    }

    #[test]
    fn steady_sliding_deflects_the_bristle_by_fc_over_sigma0_and_gives_coulomb() {
        let mut p = bristle();
        for _ in 0..1000 {
            p.advance(1e-7, 1e-4); // 100 um at 1 mm/s
        }
        p.advance(0.0, 1e-4);
        assert!((p.deflection() - 150.0 / 7.5e7).abs() < 1e-15);
        assert!((p.force() + 150.0).abs() < 1e-9, "{}", p.force());
    }

    #[test]
    fn after_a_reversal_the_force_follows_fc_1_minus_2_exp_minus_s_over_delta() {
        let mut p = bristle();
        for _ in 0..1000 {
            p.advance(1e-7, 1e-4);
        }
        // Back by s in small steps: F = +Fc (1 - 2 exp(-s/δ)) (friction now opposes -x).
        let mut s: f64 = 0.0;
        for _ in 0..200 {
            p.advance(-5e-8, 1e-4);
            s += 5e-8;
            p.advance(0.0, 1e-4);
            let want = 150.0 * (1.0 - 2.0 * (-s / 2e-6_f64).exp());
            assert!(
                (p.force() - want).abs() < 1e-6,
                "s {s}: {} vs {want}",
                p.force()
            );
        }
        // Zero crossing at δ ln 2.
        let mut q = bristle();
        for _ in 0..1000 {
            q.advance(1e-7, 1e-4);
        }
        q.advance(-2e-6 * 2f64.ln(), 1e-4);
        q.advance(0.0, 1e-4);
        assert!(q.force().abs() < 1e-9, "{}", q.force());
    }

    #[test]
    fn the_reversal_value_is_backlash_plus_twice_the_wind_up() {
        let r = ReversalValue::new(10.0, 150.0, 200.0, 2.0, false);
        assert_eq!(
            (r.backlash, r.elastic, r.presliding, r.b),
            (10.0, 1.5, 4.0, 11.5)
        );
        let f = ReversalValue::new(10.0, 150.0, 200.0, 2.0, true);
        assert_eq!(f.b, 0.0);
    }
}
