//! The cut cone's files: `surface.csv`, `surface.parquet` (θ, z, deviation; empty where not
//! cut) and `cut.json` (what a CMM reports), each written completely or not at all.

use std::path::Path;

use super::parquet::{Column, Table};
use super::write_atomic;
use crate::error::Result;
use crate::measure::cut::{CutFigures, CutSurface};
use crate::numeric::fixed::push_fixed;

pub const SURFACE_CSV: &str = "surface.csv";
pub const SURFACE_PARQUET: &str = "surface.parquet";
pub const CUT_JSON: &str = "cut.json";

/// The grid's points in file order: by height, then θ. `(θ deg, z mm, d um or None)`.
fn points(surface: &CutSurface) -> impl Iterator<Item = (f64, f64, Option<f64>)> + '_ {
    let envelope = &surface.envelope;
    envelope.rows.iter().enumerate().flat_map(move |(i, row)| {
        (0..envelope.column_count()).map(move |j| {
            let d = envelope.depth_um(j, i);
            (
                j as f64 * envelope.step_deg,
                row.z_mm,
                d.is_finite().then_some(d),
            )
        })
    })
}

/// `surface.csv`: fixed decimals (θ 4, z 4, d 4), an empty deviation where not cut. Each
/// column's θ and each row's z are written once and copied ([`push_fixed`]: the grid has
/// tens of thousands of points).
pub fn surface_csv(surface: &CutSurface) -> String {
    let envelope = &surface.envelope;
    let fixed = |v: f64| {
        let mut text = String::new();
        push_fixed(&mut text, v, 4);
        text
    };
    let thetas: Vec<String> = (0..envelope.column_count())
        .map(|j| fixed(j as f64 * envelope.step_deg))
        .collect();
    let mut out = String::with_capacity(32 * envelope.values.len() + 32);
    out.push_str("theta_deg,z_mm,deviation_um\n");
    for (i, row) in envelope.rows.iter().enumerate() {
        let z = fixed(row.z_mm);
        for (j, theta) in thetas.iter().enumerate() {
            out.push_str(theta);
            out.push(',');
            out.push_str(&z);
            out.push(',');
            let d = envelope.depth_um(j, i);
            if d.is_finite() {
                push_fixed(&mut out, d, 4);
            }
            out.push('\n');
        }
    }
    out
}

/// `surface.parquet`: the same columns as f64, null where not cut.
pub fn surface_table(surface: &CutSurface) -> Table {
    let (mut theta, mut z, mut d) = (Vec::new(), Vec::new(), Vec::new());
    for (t, zz, dd) in points(surface) {
        theta.push(Some(t));
        z.push(Some(zz));
        d.push(dd);
    }
    Table::new()
        .with("theta_deg", Column::F64(theta))
        .with("z_mm", Column::F64(z))
        .with("deviation_um", Column::F64(d))
}

/// Writes the surface, `cut.json`, the two pictures (`report::cut_plots`) and `cut.html`
/// (`report::cut_html`, titled `title`) into `dir`.
pub fn write_cut_files(
    dir: &Path,
    title: &str,
    surface: &CutSurface,
    figures: &CutFigures,
) -> Result<()> {
    write_atomic(&dir.join(SURFACE_CSV), surface_csv(surface).as_bytes())?;
    write_atomic(
        &dir.join(SURFACE_PARQUET),
        &surface_table(surface).to_parquet()?,
    )?;
    let json = serde_json::to_string_pretty(figures).expect("plain data serializes");
    write_atomic(&dir.join(CUT_JSON), format!("{json}\n").as_bytes())?;
    let map = super::cut_plots::surface_svg(surface, surface.reversals())?;
    write_atomic(&dir.join(super::cut_plots::SURFACE_SVG), map.as_bytes())?;
    let polar = super::cut_plots::roundness_svg(surface, figures)?;
    write_atomic(&dir.join(super::cut_plots::ROUNDNESS_SVG), polar.as_bytes())?;
    let page = super::cut_html::cut_html(title, surface, figures, &map, &polar);
    write_atomic(&dir.join(super::cut_html::CUT_HTML), page.as_bytes())
}
