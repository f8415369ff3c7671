//! Identifiability: the column-scaled SVD of the sensitivity matrix, its truncated
//! pseudo-inverse, and the null directions named by parameter.
//! Inputs: the Jacobian. Outputs: steps, covariances, what the tests cannot separate.

use std::collections::BTreeMap;

use nalgebra::{DMatrix, DVector};

use serde::Serialize;

use super::params::{round_sig, Param, MIN_VISIBILITY, NULL_ENTRY, NULL_TOLERANCE, NUMERICAL_ZERO};

/// A direction in parameter space that the tests cannot see.
#[derive(Clone, Debug, Serialize)]
pub struct NullDirection {
    /// Parameter → coefficient (per unit of the pivot parameter, which has 1).
    pub direction: BTreeMap<String, f64>,
    pub description: String,
}

/// The column-scaled SVD of a sensitivity matrix.
pub(super) struct Decomposition {
    pub scale: DVector<f64>,
    pub u: DMatrix<f64>,
    pub s: DVector<f64>,
    pub v: DMatrix<f64>, // columns are right singular vectors (scaled coordinates)
    pub relative: Vec<f64>,
    pub rank: usize,
}

impl Decomposition {
    /// Decomposes `j` with the columns marked in `dropped` left out (zeroed: they join the
    /// null space on their own).
    pub fn new(j: &DMatrix<f64>, dropped: &[bool]) -> Decomposition {
        let np = j.ncols();
        let mut js = j.clone();
        for c in 0..np {
            if dropped[c] {
                js.column_mut(c).fill(0.0);
            }
        }
        let scale = DVector::from_iterator(
            np,
            (0..np).map(|c| {
                let n = js.column(c).norm();
                if n > 0.0 {
                    n
                } else {
                    1.0
                }
            }),
        );
        for c in 0..np {
            let s = scale[c];
            js.column_mut(c).scale_mut(1.0 / s);
        }
        let svd = js.svd(true, true);
        let (u, vt, s) = (
            svd.u.expect("asked for U"),
            svd.v_t.expect("asked for V"),
            svd.singular_values,
        );
        // Sort descending (nalgebra does not promise an order).
        let mut order: Vec<usize> = (0..s.len()).collect();
        order.sort_by(|a, b| s[*b].total_cmp(&s[*a]));
        let u = DMatrix::from_columns(
            &order
                .iter()
                .map(|&i| u.column(i).into_owned())
                .collect::<Vec<_>>(),
        );
        let v = DMatrix::from_columns(
            &order
                .iter()
                .map(|&i| vt.row(i).transpose())
                .collect::<Vec<_>>(),
        );
        let s = DVector::from_iterator(s.len(), order.iter().map(|&i| s[i]));
        let smax = s.iter().cloned().fold(0.0, f64::max).max(f64::MIN_POSITIVE);
        let relative: Vec<f64> = s.iter().map(|v| v / smax).collect();
        let rank = relative.iter().filter(|r| **r >= NULL_TOLERANCE).count();
        Decomposition {
            scale,
            u,
            s,
            v,
            relative,
            rank,
        }
    }

    pub fn null_dim(&self) -> usize {
        self.v.ncols() - self.rank
    }

    /// Truncated pseudo-inverse solution of `J dx = r`, in parameter units.
    pub fn solve(&self, r: &DVector<f64>) -> DVector<f64> {
        let mut dx = DVector::zeros(self.v.nrows());
        for i in 0..self.rank {
            let c = self.u.column(i).dot(r) / self.s[i];
            dx += self.v.column(i) * c;
        }
        dx.component_div(&self.scale)
    }

    pub fn covariance(&self, sigma2: f64) -> DMatrix<f64> {
        let np = self.v.nrows();
        let mut c = DMatrix::zeros(np, np);
        for i in 0..self.rank {
            let v = self.v.column(i).component_div(&self.scale);
            c += &v * v.transpose() * (sigma2 / (self.s[i] * self.s[i]));
        }
        c
    }

    /// The columns to leave out of `j`: every parameter that moves the traces by less than
    /// [`NUMERICAL_ZERO`] (RMS, per unit), and a servo parameter below [`MIN_VISIBILITY`]
    /// (its sensitivity, from re-simulation, is then mostly the simulation's own rounding).
    /// A location error or placement between the two is kept: a nuisance (see `fit`).
    pub fn dropped(j: &DMatrix<f64>, params: &[Param]) -> Vec<bool> {
        let rows = (j.nrows().max(1) as f64).sqrt();
        params
            .iter()
            .enumerate()
            .map(|(c, p)| {
                let rms = j.column(c).norm() / rows;
                rms < NUMERICAL_ZERO || (p.is_servo() && rms < MIN_VISIBILITY)
            })
            .collect()
    }

    /// A parameter is identifiable when its unit vector has no part in the null space.
    pub fn identifiable(&self) -> Vec<bool> {
        (0..self.v.nrows())
            .map(|j| {
                let part: f64 = (self.rank..self.v.ncols())
                    .map(|i| self.v[(j, i)].powi(2))
                    .sum();
                part.sqrt() < 1e-3
            })
            .collect()
    }

    /// The null space in reduced row-echelon form, in parameter units: each row has 1 at
    /// its pivot and 0 at the other rows' pivots. Orientation errors are preferred as pivots.
    pub fn null_rref(&self, params: &[Param]) -> (Vec<DVector<f64>>, Vec<usize>) {
        let mut rows: Vec<DVector<f64>> = (self.rank..self.v.ncols())
            .map(|i| self.v.column(i).into_owned())
            .collect(); // scaled coordinates
        let mut pivots = Vec::new();
        for r in 0..rows.len() {
            let row = rows[r].clone();
            let max = row.amax();
            let candidates =
                (0..row.len()).filter(|j| !pivots.contains(j) && row[*j].abs() > 0.05 * max);
            let Some(pv) = candidates.min_by(|a, b| {
                params[*a]
                    .pivot_class()
                    .cmp(&params[*b].pivot_class())
                    .then(row[*b].abs().total_cmp(&row[*a].abs()))
            }) else {
                continue;
            };
            let lead = row[pv];
            rows[r] /= lead;
            let pivot_row = rows[r].clone();
            for (o, other) in rows.iter_mut().enumerate() {
                if o != r {
                    let f = other[pv];
                    *other -= &pivot_row * f;
                }
            }
            pivots.push(pv);
        }
        // Back to parameter units: x = D⁻¹ x_s, normalised so the pivot's coefficient is 1.
        // Entries below NULL_ENTRY of the row (scaled) are numerical noise.
        let rows = rows
            .into_iter()
            .zip(&pivots)
            .map(|(mut row, &pv)| {
                let max = row.amax();
                row.apply(|v| {
                    if v.abs() < NULL_ENTRY * max {
                        *v = 0.0
                    }
                });
                let phys = row.component_div(&self.scale);
                let lead = phys[pv];
                phys / lead
            })
            .collect();
        (rows, pivots)
    }
}

pub(super) fn describe_null(row: &DVector<f64>, pivot: usize, params: &[Param]) -> NullDirection {
    let mut direction = BTreeMap::new();
    let mut others = Vec::new();
    for (j, p) in params.iter().enumerate() {
        let c = row[j];
        if j != pivot && c == 0.0 {
            continue;
        }
        direction.insert(p.name(), round_sig(c));
        if j != pivot {
            others.push((j, c));
        }
    }
    let piv = &params[pivot];
    let description = match others.as_slice() {
        [] if piv.is_servo() => format!(
            "{} does not change the traces measurably (less than {MIN_VISIBILITY} um RMS per {}): these tests do not see it",
            piv.name(),
            piv.unit()
        ),
        [] => format!(
            "{} does not change the traces at all (less than {NUMERICAL_ZERO} um RMS per {}): these tests do not see it",
            piv.name(),
            piv.unit()
        ),
        [(j, c)] => {
            // Invariant: other − c · pivot is what the traces see.
            let other = &params[*j];
            let lever = if piv.unit() == "urad" && other.unit() == "um" {
                format!(" (a lever of {:.1} mm)", (c * 1e3).abs())
            } else {
                String::new()
            };
            format!(
                "{} and {} cannot be separated: only {} {:+.6} {}/{} x {}{} is seen",
                other.name(),
                piv.name(),
                other.name(),
                round_sig(-c),
                other.unit(),
                piv.unit(),
                piv.name(),
                lever
            )
        }
        _ => format!(
            "moving {} by 1 {} together with {} leaves every trace unchanged: the tests cannot separate them",
            piv.name(),
            piv.unit(),
            others
                .iter()
                .map(|(j, c)| format!("{:+.6} {} {}", round_sig(*c), params[*j].unit(), params[*j].name()))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    NullDirection {
        direction,
        description,
    }
}
