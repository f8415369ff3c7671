//! The geometric errors of a machine file: `[location_errors]` (ISO 230-7 location errors of
//! the rotary axes, with the ISO 230-1 squareness `EC0Y`, `EB0Z`, `EA0Z` of the linear
//! axes) and `[error_tables]` (per-axis position-error tables in LinuxCNC's
//! compensation-file format). The value types and the math live in
//! [`crate::kinematics::location`] and [`crate::kinematics::error_table`].
//!
//! ```toml
//! [location_errors]
//! EX0C_um = 8.0        # C-axis line offset along X, um
//! EA0C_urad = -15.0    # C-axis line tilt about X, urad
//!
//! [error_tables]
//! C = "c-worm.comp"    # path relative to the file that names it
//! ```

use std::collections::BTreeMap;
use std::path::Path;

use crate::error::{Error, Result};
use crate::input::toml_text::{self, value_error};
use crate::kinematics::error_table::{ErrorTable, PositionErrors};
use crate::kinematics::{Chain, Layout, LocationErrors, LocationParam};
use crate::Axis;

/// Largest location error accepted, um or urad (1 mm, 1 mrad): beyond it the small-error
/// conventions of ISO 230-7 no longer describe the machine.
pub const MAX_LOCATION_ERROR: f64 = 1000.0;

/// A machine's geometric errors, validated.
#[derive(Clone, Debug, Default)]
pub struct GeometryErrors {
    pub location: LocationErrors,
    /// Position-error table per axis.
    pub tables: BTreeMap<Axis, ErrorTable>,
}

impl GeometryErrors {
    /// A fresh applicator of the error tables for one run.
    pub fn position_errors(&self) -> PositionErrors {
        PositionErrors::new(self.tables.iter().map(|(a, t)| (*a, t)))
    }
}

/// Validates `[location_errors]` and `[error_tables]` of a machine of `layout` (its
/// `chain` when it is a general one; the file `path` with contents `text`); table files are
/// read relative to `tables_dir`.
pub fn validate(
    path: &Path,
    text: &str,
    layout: Layout,
    chain: Option<&Chain>,
    location: &BTreeMap<String, f64>,
    tables: &BTreeMap<String, String>,
    tables_dir: &Path,
) -> Result<GeometryErrors> {
    let section = "location_errors";
    let mut errors = LocationErrors::default();
    for (key, &value) in location {
        // A refusal of this key, located at its value.
        let refuse = |message: String| Err(value_error(path, text, section, key, message));
        // A named layout takes the parameters of geometric-errors.md; a general chain's
        // rotaries all six of each ([`LocationParam::EVERY`]).
        // Both take the squareness of the linear axes (ISO 230-1).
        let rotary_names = if chain.is_some() {
            &LocationParam::EVERY[..]
        } else {
            &LocationParam::ALL[..]
        };
        let names: Vec<LocationParam> = rotary_names
            .iter()
            .copied()
            .chain(LocationParam::SQUARENESS)
            .collect();
        let Some(param) = LocationParam::from_key(key).filter(|p| names.contains(p)) else {
            let known: Vec<String> = names
                .iter()
                .filter(|p| layout.axes().contains(&p.axis()))
                .map(|p| p.key())
                .collect();
            return refuse(format!(
                "unknown location error; expected one of {} (ISO 230-7 names with a unit \
                 suffix _um or _urad)",
                known.join(", ")
            ));
        };
        if let Some(link) = chain.and_then(|c| c.link(param.axis())) {
            if link.direction[param.component()].abs() > 1.0 - 1e-12 {
                return refuse(format!(
                    "axis {}'s line lies along this component, which moves or turns it \
                     along itself (no effect): remove this key",
                    param.axis()
                ));
            }
        }
        if param.is_squareness() {
            let linear_in_chain = match chain {
                Some(c) => c.link(param.axis()).is_some(),
                None => layout
                    .links(nalgebra::Vector3::zeros())
                    .is_some_and(|(table, head)| {
                        table.iter().chain(&head).any(|l| l.axis == param.axis())
                    }),
            };
            if !linear_in_chain {
                return refuse(format!(
                    "the {} layout has no {} axis in a kinematic chain, so nothing is out of \
                     square; remove this key",
                    layout.name(),
                    param.axis()
                ));
            }
        } else if layout.rotaries_unmodelled() {
            return refuse(format!(
                "the {} layout's rotaries are world coordinates with no modelled axis lines, \
                 so they carry no location errors; remove this key",
                layout.name()
            ));
        }
        if !layout.axes().contains(&param.axis()) {
            return refuse(format!(
                "the {} layout has no {} axis; remove this key",
                layout.name(),
                param.axis()
            ));
        }
        if !(value.is_finite() && value.abs() <= MAX_LOCATION_ERROR) {
            return refuse(format!(
                "must be a finite number within ±{MAX_LOCATION_ERROR} {}, got {value}",
                param.unit()
            ));
        }
        errors.set(param, value);
    }
    let mut out = BTreeMap::new();
    for (name, file) in tables {
        let axis = match name.chars().collect::<Vec<_>>().as_slice() {
            [c] => Axis::from_letter(*c),
            _ => None,
        };
        let Some(axis) = axis.filter(|a| layout.axes().contains(a)) else {
            return Err(value_error(
                path,
                text,
                "error_tables",
                name,
                format!("the {} layout has no axis `{name}`", layout.name()),
            ));
        };
        let table_path = tables_dir.join(file);
        let table_text = toml_text::read_text(&table_path).map_err(|e| match e {
            Error::Read { source, .. } => value_error(
                path,
                text,
                "error_tables",
                name,
                format!(
                    "cannot read the error table {}: {source}",
                    table_path.display()
                ),
            ),
            other => other,
        })?;
        let table = ErrorTable::parse(&table_path, &table_text, axis.is_rotary())?;
        out.insert(axis, table);
    }
    Ok(GeometryErrors {
        location: errors,
        tables: out,
    })
}
