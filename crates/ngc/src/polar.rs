//! Polar coordinates (LinuxCNC): `@` radius and `^` angle (deg, counter-clockwise from +X)
//! in place of X and Y, in the G17 plane, about the origin of the active work system.
//!
//! ```text
//! G90:  @r ^a      → (r cos a, r sin a)
//!       @r         → radius r at the current angle  atan2(y, x)   (error at the origin)
//!       ^a         → angle a at the current radius  hypot(x, y)
//! G91:  @dr        → radius hypot(x, y) + dr at the current angle  (error at the origin)
//!       ^da        → angle atan2(y, x) + da at the current radius (error at the origin)
//!       @dr ^da    → first the radius, then the angle
//! ```
//!
//! `(x, y)` is the current point in program coordinates (active work system, program
//! units). An incremental polar move turns about the work origin, not about the current
//! point: `G91 ^60` steps along a circle centred on X0 Y0, as rs274 shows (and in a canned
//! cycle, each of L repeats applies the increment again).

/// The polar words of a block: `@` radius (program units) and `^` angle (deg).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Polar {
    pub radius: Option<f64>,
    pub angle_deg: Option<f64>,
}

impl Polar {
    pub fn is_some(&self) -> bool {
        self.radius.is_some() || self.angle_deg.is_some()
    }

    /// The end point in G90 from the current program point `xy`.
    pub fn absolute(&self, xy: [f64; 2]) -> Result<[f64; 2], &'static str> {
        let (x, y) = (xy[0], xy[1]);
        let (r, a) = match (self.radius, self.angle_deg) {
            (Some(r), Some(a)) => (r, a.to_radians()),
            (Some(r), None) => {
                if x == 0.0 && y == 0.0 {
                    return Err("polar radius `@` at the origin without an angle: expected `^` too (LinuxCNC: \"Must specify angle in polar coordinate if at the origin\")");
                }
                (r, y.atan2(x))
            }
            (None, Some(a)) => (y.hypot(x), a.to_radians()),
            (None, None) => return Ok(xy),
        };
        Ok([r * a.cos(), r * a.sin()])
    }

    /// The end point in G91 from the current program point `xy`.
    pub fn incremental(&self, xy: [f64; 2]) -> Result<[f64; 2], &'static str> {
        let [mut x, mut y] = xy;
        let at_origin = "incremental polar move at the work origin: expected a start point off the origin (LinuxCNC: \"Incremental motion with polar coordinates is indeterminate when at the origin\")";
        if let Some(dr) = self.radius {
            if x == 0.0 && y == 0.0 {
                return Err(at_origin);
            }
            let theta = y.atan2(x);
            let r = y.hypot(x) + dr;
            x = r * theta.cos();
            y = r * theta.sin();
        }
        if let Some(da) = self.angle_deg {
            if x == 0.0 && y == 0.0 {
                return Err(at_origin);
            }
            let theta = y.atan2(x) + da.to_radians();
            let r = y.hypot(x);
            x = r * theta.cos();
            y = r * theta.sin();
        }
        Ok([x, y])
    }

    /// One repeat of a G91 canned cycle: as [`Polar::incremental`], except that a zero
    /// increment is skipped (rs274 tests the increment, not the word).
    pub fn cycle_step(&self, xy: [f64; 2]) -> Result<[f64; 2], &'static str> {
        let nonzero = |v: Option<f64>| v.filter(|v| *v != 0.0);
        Polar {
            radius: nonzero(self.radius),
            angle_deg: nonzero(self.angle_deg),
        }
        .incremental(xy)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [f64; 2], b: [f64; 2]) -> bool {
        (a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12
    }

    #[test]
    fn absolute_radius_and_angle_place_the_point_on_a_circle_about_the_origin() {
        let p = Polar {
            radius: Some(2.0),
            angle_deg: Some(90.0),
        };
        assert!(close(p.absolute([5.0, 5.0]).unwrap(), [0.0, 2.0]));
        // Angle only: keeps the radius 5 of (3, 4).
        let a = Polar {
            radius: None,
            angle_deg: Some(180.0),
        };
        assert!(close(a.absolute([3.0, 4.0]).unwrap(), [-5.0, 0.0]));
        // Radius only: keeps the angle of (3, 4), radius 10 → (6, 8).
        let r = Polar {
            radius: Some(10.0),
            angle_deg: None,
        };
        assert!(close(r.absolute([3.0, 4.0]).unwrap(), [6.0, 8.0]));
        assert!(r.absolute([0.0, 0.0]).is_err());
    }

    #[test]
    fn incremental_polar_turns_about_the_origin_not_the_current_point() {
        let p = Polar {
            radius: None,
            angle_deg: Some(90.0),
        };
        assert!(close(p.incremental([10.0, 0.0]).unwrap(), [0.0, 10.0]));
        let q = Polar {
            radius: Some(-1.0),
            angle_deg: Some(180.0),
        };
        // Radius 5 → 4 along (3, 4)/5, then half a turn: (-2.4, -3.2).
        assert!(close(q.incremental([3.0, 4.0]).unwrap(), [-2.4, -3.2]));
        assert!(q.incremental([0.0, 0.0]).is_err());
        // A cycle repeat skips a zero increment, even at the origin.
        let z = Polar {
            radius: Some(0.0),
            angle_deg: None,
        };
        assert!(close(z.cycle_step([0.0, 0.0]).unwrap(), [0.0, 0.0]));
    }
}
