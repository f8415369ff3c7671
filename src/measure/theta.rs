//! The angle θ along the measured circle and its bins: every trace of the ball bar is kept in
//! [`N_BINS`] bins of [`BIN_DEG`] over one revolution, bin `i` covering
//! `[i BIN_DEG, (i + 1) BIN_DEG)`.

use crate::numeric::sin_cos_deg;
pub use crate::numeric::wrap_360;

/// Width of one theta bin, deg.
pub const BIN_DEG: f64 = 0.05;
/// Number of theta bins in one revolution.
pub const N_BINS: usize = 7200;

/// Unsigned angle between two directions, deg in [0, 180].
pub fn angle_distance_deg(a: f64, b: f64) -> f64 {
    ((a - b + 180.0).rem_euclid(360.0) - 180.0).abs()
}

/// `(sin θ, cos θ)` of θ in deg, wrapped to [0, 360) first: the terms a run adds per sample
/// and [`super::ballbar::Centring::offset_um`] evaluates.
#[inline]
pub fn theta_sin_cos(theta_deg: f64) -> (f64, f64) {
    sin_cos_deg(wrap_360(theta_deg))
}

/// The bin of θ in [0, 360) deg.
pub fn bin_index(theta_deg: f64) -> usize {
    ((theta_deg / BIN_DEG) as usize).min(N_BINS - 1)
}

/// The number of bins closest to an angle span of `deg`.
pub fn bins(deg: f64) -> usize {
    (deg / BIN_DEG).round() as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The in-range shortcuts of `wrap_360` give the bits of the plain `rem_euclid` form.
    #[test]
    fn wrap_360_matches_rem_euclid_bit_for_bit() {
        let reference = |deg: f64| {
            let t = deg.rem_euclid(360.0);
            if t >= 360.0 {
                0.0
            } else {
                t
            }
        };
        let mut values = vec![
            0.0,
            -0.0,
            360.0,
            -360.0,
            720.0,
            -720.0,
            359.99999999999994,
            -1e-300,
            -5e-324,
            1e-300,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        for k in 0..20_000 {
            let x = (k as f64 - 10_000.0) * 0.0731 + 1e-9 * k as f64;
            values.extend([x, x.next_up(), x.next_down(), -x]);
        }
        for v in values {
            assert_eq!(
                wrap_360(v).to_bits(),
                reference(v).to_bits(),
                "wrap_360({v:e})"
            );
        }
    }
}
