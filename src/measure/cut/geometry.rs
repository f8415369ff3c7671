//! The nominal machined cone and the depth a cutter position leaves on it
//! (`docs/cut.md`, the contract `cutting-test.md`).
//!
//! Cone frame: origin the base-circle centre O, +Z the cone axis (the table frame turned by
//! `Ry(-β)`). The nominal surface is the path cone (the tool-axis lines of the nominal path,
//! half angle α, apex at `L / sin α`) offset inward by the cutter radius R:
//!
//! ```text
//! ρ(z)    = ((L − R) / sin α − z) tan α               radius of the frustum at height z
//! S(θ, z) = (ρ cos θ, ρ sin θ, z)                     a surface point
//! n(θ)    = (cos α cos θ, cos α sin θ, sin α)         its outward unit normal
//! z_tip   = (L − R) sin α                             where the flank's end meets the frustum
//! ```
//!
//! A cutter position is the line `p + s t` (tip p, unit axis t toward the spindle,
//! `0 ≤ s ≤ flute length`) with a cylinder of radius R about it. Along the ray `S + d n`,
//! `|(w + d n) × t| = R` with `w = S − p` is the quadratic
//!
//! ```text
//! A d² + 2 B d + C = 0,   A = 1 − (n·t)²,  B = w·n − (w·t)(n·t),  C = |w|² − (w·t)² − R²
//! ```
//!
//! whose smaller root `d = (−B − √(B² − A C)) / A` is where the ray enters the cylinder: the
//! depth that position cuts to (positive: material left). It counts only when the entry
//! lies on the flutes (`0 ≤ (w + d n)·t ≤ flute length`) and the cylinder lies outside the
//! surface along the ray (the chord's middle `−B / A > 0`; the cutter across the part, whose
//! roots are two diameters deeper, is not this side's).

use nalgebra::{Point3, Rotation3, Vector3};

use crate::input::program::ConeTest;

/// Depth of a grid point no cutter position reaches.
pub const NOT_CUT: f64 = f64::INFINITY;

/// Rows [`CutGeometry::depths_um`] takes side by side: one AVX register of f64.
pub const ROW_CHUNK: usize = 4;

/// A cutter position in the cone frame: tip (mm) and unit axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CutterLine {
    pub tip: Vector3<f64>,
    pub axis: Vector3<f64>,
}

impl CutterLine {
    /// θ of the tip about the cone axis, rad: the generatrix the cutter works on.
    pub fn contact_rad(&self) -> f64 {
        self.tip.y.atan2(self.tip.x)
    }

    /// θ's direction `(cos θ, sin θ) = (x, y) / √(x² + y²)` of the tip `(x, y, z)`, without
    /// the angle; `(1, 0)` on the cone axis, where [`CutterLine::contact_rad`] is 0.
    pub fn contact_direction(&self) -> (f64, f64) {
        let (x, y) = (self.tip.x, self.tip.y);
        let r = (x * x + y * y).sqrt();
        if r > 0.0 && r.is_finite() {
            (x / r, y / r)
        } else {
            (1.0, 0.0)
        }
    }
}

/// The nominal cut cone of a test and the cutter that machines it.
#[derive(Clone, Debug)]
pub struct CutGeometry {
    /// Half apex angle α, rad, and its sine and cosine.
    pub alpha_rad: f64,
    sin_a: f64,
    cos_a: f64,
    /// Ball-bar length L (the tool tip's distance from O), mm.
    pub length_mm: f64,
    /// Cutter radius R and flute length, mm.
    pub cutter_radius_mm: f64,
    pub flute_length_mm: f64,
    /// Base-circle centre O, table frame, mm, and the turn from the table frame into the
    /// cone frame (`Ry(β)`).
    origin_mm: Vector3<f64>,
    to_cone: Rotation3<f64>,
}

impl CutGeometry {
    pub fn new(cone: &ConeTest, cutter_radius_mm: f64, flute_length_mm: f64) -> CutGeometry {
        let alpha_rad = cone.half_apex_deg.to_radians();
        CutGeometry {
            alpha_rad,
            sin_a: alpha_rad.sin(),
            cos_a: alpha_rad.cos(),
            length_mm: cone.ballbar_length_mm,
            cutter_radius_mm,
            flute_length_mm,
            origin_mm: cone.center_mm,
            to_cone: cone.frame_rotation().inverse(),
        }
    }

    /// `z_tip = (L − R) sin α`, mm.
    pub fn tip_height_mm(&self) -> f64 {
        (self.length_mm - self.cutter_radius_mm) * self.sin_a
    }

    /// Height where the flutes' end meets the frustum, `z_tip + flute cos α`, mm.
    pub fn flute_end_height_mm(&self) -> f64 {
        self.tip_height_mm() + self.flute_length_mm * self.cos_a
    }

    /// Height of the frustum's apex, `(L − R) / sin α`, mm (ρ = 0 there).
    pub fn apex_height_mm(&self) -> f64 {
        (self.length_mm - self.cutter_radius_mm) / self.sin_a
    }

    /// ρ(z), mm.
    pub fn radius_at(&self, z_mm: f64) -> f64 {
        (self.apex_height_mm() - z_mm) * self.sin_a / self.cos_a
    }

    /// `cos α`: a depth d along n moves the radius at a height by `d / cos α`.
    pub fn cos_alpha(&self) -> f64 {
        self.cos_a
    }

    /// A tool pose of the table frame (tip mm, axis) in the cone frame.
    pub fn line_of(&self, tip_table_mm: &Point3<f64>, axis_table: &Vector3<f64>) -> CutterLine {
        CutterLine {
            tip: self.to_cone * (tip_table_mm.coords - self.origin_mm),
            axis: (self.to_cone * axis_table).normalize(),
        }
    }

    /// The unit direction of θ (cos θ, sin θ) and the rows' heights and radii: the depth of
    /// `line` at every row, um ([`NOT_CUT`] where it does not cut), into `out`.
    ///
    /// Compiled for AVX where the CPU has it (checked at run time), so that the rows go
    /// [`ROW_CHUNK`] at a time; Rust fuses no multiplication and addition, so the bits are
    /// the plain build's whatever the width. (Eight rows a register with AVX-512 took as
    /// long: the square roots bound it, and they cost as much per row.)
    pub fn depths_um(&self, theta: (f64, f64), rows: &[Row], line: &CutterLine, out: &mut [f64]) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx") {
            // SAFETY: the CPU has AVX, checked at run time just above.
            return unsafe { self.depths_um_avx(theta, rows, line, out) };
        }
        self.depths_um_inline::<ROW_CHUNK>(theta, rows, line, out)
    }

    /// [`CutGeometry::depths_um`] compiled for AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn depths_um_avx(
        &self,
        theta: (f64, f64),
        rows: &[Row],
        line: &CutterLine,
        out: &mut [f64],
    ) {
        self.depths_um_inline::<ROW_CHUNK>(theta, rows, line, out)
    }

    /// [`CutGeometry::depths_um`] with `CHUNK` rows side by side (any width, the same bits):
    /// for tests that compare the widths.
    pub fn depths_um_by<const CHUNK: usize>(
        &self,
        theta: (f64, f64),
        rows: &[Row],
        line: &CutterLine,
        out: &mut [f64],
    ) {
        self.depths_um_inline::<CHUNK>(theta, rows, line, out)
    }

    /// The rows `CHUNK` at a time, the last chunk ending at the last row (below `CHUNK`
    /// rows, filled up with the last row, whose depths are dropped), so that no row is left
    /// to a scalar tail. Without branches: every
    /// row's root is taken and the rows that do not cut are masked after (a negative
    /// discriminant's NaN root, like every other NaN, fails the flute test); each row by
    /// [`RowFrame::depth_um`], the per-row formula's bits.
    #[inline(always)]
    fn depths_um_inline<const CHUNK: usize>(
        &self,
        (c, s): (f64, f64),
        rows: &[Row],
        line: &CutterLine,
        out: &mut [f64],
    ) {
        let Some(frame) = RowFrame::new(self, (c, s), line) else {
            out.fill(NOT_CUT);
            return;
        };
        let depth = |radius: f64, z: f64| frame.depth_um(radius, z);
        let count = rows.len().min(out.len());
        // Full chunks only, each stored as one fixed-size copy (a copy of fewer rows is a
        // call of `memcpy`): the last one ends at the last row, overlapping the one before,
        // whose rows it computes again to the same bits. Below `CHUNK` rows, one chunk
        // filled up with the last row.
        let mut k = 0;
        while k < count {
            let start = k.min(count.saturating_sub(CHUNK));
            let row = |i: usize| rows[(start + i).min(count - 1)];
            let radius: [f64; CHUNK] = std::array::from_fn(|i| row(i).radius_mm);
            let z: [f64; CHUNK] = std::array::from_fn(|i| row(i).z_mm);
            let mut d = [0.0; CHUNK];
            for i in 0..CHUNK {
                d[i] = depth(radius[i], z[i]);
            }
            if count >= CHUNK {
                out[start..start + CHUNK].copy_from_slice(&d);
            } else {
                out[..count].copy_from_slice(&d[..count]);
            }
            k += CHUNK;
        }
    }

    /// A lower bound of how far (um) the nominal cutter at θ clears the surface at θ + Δθ,
    /// per rad² of Δθ, over `rows`: κ with `gap ≥ κ Δθ²` (the cutter's and the cone's
    /// curvatures across the generatrix, `gap ≈ (ρ Δθ)² (1/R + cos α / ρ) / 2`), from the exact
    /// nominal gap at Δθ from 0.01 to 8 deg, less a fifth for the machine's errors.
    pub fn clearance_um_per_rad2(&self, rows: &[Row]) -> f64 {
        let nominal = CutterLine {
            tip: Vector3::new(
                self.length_mm * self.cos_a,
                0.0,
                self.length_mm * self.sin_a,
            ),
            axis: Vector3::new(-self.sin_a, 0.0, self.cos_a),
        };
        let mut out = vec![0.0; rows.len()];
        let mut kappa = f64::INFINITY;
        for dtheta_deg in [0.01, 0.03, 0.1, 0.3, 1.0, 2.0, 4.0, 8.0] {
            let dtheta = f64::to_radians(dtheta_deg);
            self.depths_um(dtheta.sin_cos().rev(), rows, &nominal, &mut out);
            for &gap in &out {
                // A row the cutter no longer reaches at this Δθ clears it entirely.
                if gap.is_finite() {
                    kappa = kappa.min(gap / (dtheta * dtheta));
                }
            }
        }
        0.8 * kappa.max(0.0)
    }
}

/// The quantities of the depth formula shared by every row at one θ for one cutter line:
/// n(θ), the axis t, `n·t`, `A = 1 − (n·t)²` and `1/A`, R², the flute length, the tip.
#[derive(Clone, Copy, Debug)]
pub(super) struct RowFrame {
    pub c: f64,
    pub s: f64,
    pub n: (f64, f64, f64),
    pub t: (f64, f64, f64),
    pub tip: (f64, f64, f64),
    pub nt: f64,
    pub a: f64,
    pub inv_a: f64,
    r2: f64,
    flute: f64,
}

/// One row's formula before the cut test: `w = S − p`, `w·t`, B, the discriminant
/// `B² − A C` and its root, the smaller root d (mm; NaN for a negative discriminant) and
/// whether it cuts.
#[derive(Clone, Copy, Debug)]
pub(super) struct RowTerms {
    pub w: (f64, f64, f64),
    pub wt: f64,
    pub b: f64,
    pub disc: f64,
    pub root: f64,
    pub d: f64,
    pub cuts: bool,
}

impl RowFrame {
    /// The frame at `(cos θ, sin θ)` for `line`; None where `A < 10⁻¹²` (the axis along
    /// n: no row is cut).
    #[inline(always)]
    pub fn new(geometry: &CutGeometry, (c, s): (f64, f64), line: &CutterLine) -> Option<RowFrame> {
        let n = Vector3::new(geometry.cos_a * c, geometry.cos_a * s, geometry.sin_a);
        let t = &line.axis;
        let nt = n.dot(t);
        let a = 1.0 - nt * nt;
        if a < 1e-12 {
            return None;
        }
        Some(RowFrame {
            c,
            s,
            n: (n.x, n.y, n.z),
            t: (t.x, t.y, t.z),
            tip: (line.tip.x, line.tip.y, line.tip.z),
            nt,
            a,
            inv_a: 1.0 / a,
            r2: geometry.cutter_radius_mm * geometry.cutter_radius_mm,
            flute: geometry.flute_length_mm,
        })
    }

    /// The formula at the row of radius ρ and height z, mm. Each expression is nalgebra's
    /// `dot` and `norm_squared` in their order ((x + y) + z; the `0 + ` before a square's
    /// sum changes no bit), so the depths are the per-row formula's bits.
    #[inline(always)]
    pub fn terms(&self, radius: f64, z: f64) -> RowTerms {
        let (c, s, nt) = (self.c, self.s, self.nt);
        let ((nx, ny, nz), (tx, ty, tz), (px, py, pz)) = (self.n, self.t, self.tip);
        let (wx, wy, wz) = (radius * c - px, radius * s - py, z - pz);
        let wt = wx * tx + wy * ty + wz * tz;
        let b = (wx * nx + wy * ny + wz * nz) - wt * nt;
        let cc = (wx * wx + wy * wy + wz * wz) - wt * wt - self.r2;
        let disc = b * b - self.a * cc;
        let root = disc.sqrt();
        let d = (-b - root) * self.inv_a;
        let along = wt + d * nt;
        let cuts = (disc >= 0.0) & (b < 0.0) & (along >= 0.0) & (along <= self.flute);
        RowTerms {
            w: (wx, wy, wz),
            wt,
            b,
            disc,
            root,
            d,
            cuts,
        }
    }

    /// The row's depth, um ([`NOT_CUT`] where it is not cut).
    #[inline(always)]
    pub fn depth_um(&self, radius: f64, z: f64) -> f64 {
        let r = self.terms(radius, z);
        if r.cuts {
            r.d * 1e3
        } else {
            NOT_CUT
        }
    }
}

/// One height of the grid: z and ρ(z), mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row {
    pub z_mm: f64,
    pub radius_mm: f64,
}

/// `(sin, cos)` → `(cos, sin)`.
trait Rev {
    fn rev(self) -> (f64, f64);
}

impl Rev for (f64, f64) {
    fn rev(self) -> (f64, f64) {
        (self.1, self.0)
    }
}

/// The lesser of `a` and `x`: `f64::min` for depths, which are never NaN nor −0 (a root is
/// NaN only where it does not cut, and `x − x` is +0), so a plain comparison (one `minpd`)
/// gives its bits, and the order of the minima changes none.
#[inline(always)]
pub(super) fn lesser(a: f64, x: f64) -> f64 {
    if x < a {
        x
    } else {
        a
    }
}

/// The greater of `a` and `x`, as [`lesser`].
#[inline(always)]
pub(super) fn greater(a: f64, x: f64) -> f64 {
    if x > a {
        x
    } else {
        a
    }
}
