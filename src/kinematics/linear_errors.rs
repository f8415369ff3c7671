//! ISO 230-1 errors of the linear axes X, Y and Z, as the actual chain carries them.
//!
//! **Squareness** (position-independent; `EC0Y`, `EB0Z`, `EA0Z` in µrad, held with the
//! rotaries' location errors in [`super::LocationErrors`]): X is the reference, Y's line
//! turns about Z by `EC0Y`, Z's about Y by `EB0Z` and about X by `EA0Z`, by the rotaries'
//! rule
//!
//! ```text
//! u = unit(d + (EA, EB, EC) × d)      Y along ≈ (−EC0Y, 1, 0),  Z along ≈ (EB0Z, −EA0Z, 1)
//! ```
//!
//! ([`squared_direction`]). On an XY circle of radius r, `EC0Y` alone gives the radial
//! deviation `−(r EC0Y / 2) sin 2θ` (ISO 230-4's squareness ellipse).
//!
//! **Component errors** (position-dependent, [`ComponentErrors`]): axis J at nominal
//! position u moves its carriage, and all the chain carries beyond it, by
//!
//! ```text
//! E_J(u) x = Rot(ε(u)) (x − r_J) + r_J + δ(u)     ≈ x + δ + ε × (x − r_J)
//! δ = (EXJ, EYJ, EZJ) µm,  ε = (EAJ, EBJ, ECJ) µrad (roll, pitch, yaw about X, Y, Z)
//! ```
//!
//! with `Rot(ε)` the exact rotation by |ε| about ε/|ε| (Rodrigues) and `r_J` the axis's
//! reference point (machine frame, home pose). In the chain's product of exponentials it
//! stands right after J's own motion: `… M_J(q_J) E_J(q_J) …` ([`super::Chain`]). The
//! tables are linear between their rows and hold their end values beyond the ends.
//!
//! The tables are shared by every copy of a machine's kinematics (which is `Copy`): each
//! distinct set is kept once for the process ([`ComponentErrors::interned`]), so a study
//! that reads the same machine many times holds its tables once.

use std::sync::Mutex;

use nalgebra::{Isometry3, Rotation3, Translation3, Vector3};

use crate::Axis;

/// The six error motions of one linear axis against its nominal position.
#[derive(Clone, Debug, PartialEq)]
pub struct ComponentTable {
    /// Nominal positions, mm, strictly ascending (at least one).
    positions_mm: Vec<f64>,
    /// Per row: δ (µm) along X, Y, Z, then ε (µrad) about X, Y, Z.
    rows: Vec<[f64; 6]>,
}

impl ComponentTable {
    /// A table from its rows `(position_mm, [EXJ, EYJ, EZJ µm, EAJ, EBJ, ECJ µrad])`; the
    /// positions must ascend strictly (the reader checks it and says where).
    pub fn new(rows: Vec<(f64, [f64; 6])>) -> ComponentTable {
        ComponentTable {
            positions_mm: rows.iter().map(|r| r.0).collect(),
            rows: rows.iter().map(|r| r.1).collect(),
        }
    }

    /// The six errors at nominal position `u_mm`: linear between rows, the end rows held
    /// beyond the ends. µm and µrad.
    pub fn at(&self, u_mm: f64) -> [f64; 6] {
        let p = &self.positions_mm;
        let k = p.partition_point(|x| *x <= u_mm);
        if k == 0 {
            return self.rows[0];
        }
        if k == p.len() {
            return self.rows[p.len() - 1];
        }
        let f = (u_mm - p[k - 1]) / (p[k] - p[k - 1]);
        let (a, b) = (self.rows[k - 1], self.rows[k]);
        std::array::from_fn(|i| a[i] + f * (b[i] - a[i]))
    }
}

/// The component-error tables of a machine's X, Y and Z, with their reference points.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ComponentErrors {
    /// Indexed by X, Y, Z.
    tables: [Option<ComponentTable>; 3],
    /// `r_J`, machine frame at home, mm.
    reference_mm: [Vector3<f64>; 3],
}

/// Every distinct set of tables read in this process, kept for its length.
static INTERNED: Mutex<Vec<&'static ComponentErrors>> = Mutex::new(Vec::new());

impl ComponentErrors {
    /// With `axis`'s (X, Y or Z) table and reference point; other axes are ignored.
    pub fn with(mut self, axis: Axis, table: ComponentTable, reference_mm: Vector3<f64>) -> Self {
        if let Some(i) = slot(axis) {
            self.tables[i] = Some(table);
            self.reference_mm[i] = reference_mm;
        }
        self
    }

    pub fn is_empty(&self) -> bool {
        self.tables.iter().all(Option::is_none)
    }

    /// The linear axes that have a table, in the order X, Y, Z.
    pub fn axes(&self) -> Vec<Axis> {
        [Axis::X, Axis::Y, Axis::Z]
            .into_iter()
            .filter(|a| slot(*a).is_some_and(|i| self.tables[i].is_some()))
            .collect()
    }

    /// `axis`'s table and reference point alone (empty when it has none).
    pub fn only(&self, axis: Axis) -> ComponentErrors {
        let mut one = ComponentErrors::default();
        if let Some(i) = slot(axis) {
            one.tables[i] = self.tables[i].clone();
            one.reference_mm[i] = self.reference_mm[i];
        }
        one
    }

    /// The one shared copy of these tables (equal sets share one).
    pub fn interned(self) -> &'static ComponentErrors {
        let mut all = INTERNED.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(found) = all.iter().find(|e| ***e == self) {
            return found;
        }
        let leaked: &'static ComponentErrors = Box::leak(Box::new(self));
        all.push(leaked);
        leaked
    }

    /// `E_J(u)` of `axis` at nominal position `u_mm`, if it has a table.
    pub fn motion(&self, axis: Axis, u_mm: f64) -> Option<Isometry3<f64>> {
        let i = slot(axis)?;
        let e = self.tables[i].as_ref()?.at(u_mm);
        let delta = Vector3::new(e[0], e[1], e[2]) * 1e-3;
        let rotation = Rotation3::new(Vector3::new(e[3], e[4], e[5]) * 1e-6);
        let r = self.reference_mm[i];
        let shift = r + delta - rotation * r;
        Some(Isometry3::from_parts(
            Translation3::from(shift),
            rotation.into(),
        ))
    }
}

/// 0, 1, 2 for X, Y, Z; none for any other axis.
fn slot(axis: Axis) -> Option<usize> {
    match axis {
        Axis::X => Some(0),
        Axis::Y => Some(1),
        Axis::Z => Some(2),
        _ => None,
    }
}

/// The actual direction of a linear axis with nominal unit direction `d` turned by the
/// small rotation `eps_rad` (about X, Y, Z): `unit(d + ε × d)`.
pub fn squared_direction(d: &Vector3<f64>, eps_rad: &Vector3<f64>) -> Vector3<f64> {
    (d + eps_rad.cross(d)).normalize()
}
