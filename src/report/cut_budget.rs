//! The cut's error budget as `cut.json` holds it (made by `study::cut_budget`) and as
//! `cut.html` shows it: one row per mechanism and axis, ranked by share, and the interplay.
//! Nothing is computed here but the ranking.

use serde::{Deserialize, Serialize};

use super::budget_table::mechanism_label;
use super::escape::esc;
use super::run::BudgetMechanism;

/// One row of the cut's error budget: what one mechanism (on one axis) changes on the
/// surface, `c(θ, z)`, the grid of its counterfactual cut less the cut it adds to
/// (`study::cut_budget`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CutBudgetRow {
    pub mechanism: BudgetMechanism,
    /// The axis letter; None for the program, the servos' common lag and the geometric errors.
    pub axis: Option<String>,
    /// `sqrt(mean c²)` and `max c − min c` over the points every run cut, µm.
    pub rms_um: f64,
    pub pv_um: f64,
    /// `<c, d> / <d, d>`: the part of the full cut's deviation d the row explains.
    pub share: f64,
    /// The largest change of c along the height at one θ, `max_θ |c(θ, top) − c(θ, bottom)|`
    /// over the grid's highest and lowest rows, µm: what a tilt of the tool axis makes and
    /// a ball bar (one point per θ, at the tip) cannot see.
    pub height_change_um: f64,
    /// c per grid point, µm, in the envelope's order (`values[j * rows + i]`), NaN where a
    /// run did not cut; not written.
    #[serde(skip)]
    pub contribution_um: Vec<f64>,
}

/// The cut's error budget (`study::cut_budget`): the program's own part and each
/// mechanism's, by counterfactual cuts, and what is left to their interplay, so that the
/// shares and `interaction_share` add to 1.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CutBudget {
    /// The full cut's d over the points every run cut: RMS and peak-to-valley, µm.
    pub rms_um: f64,
    pub pv_um: f64,
    /// The points every run cut, of the grid.
    pub points: usize,
    pub rows: Vec<CutBudgetRow>,
    /// `1 − Σ share`.
    pub interaction_share: f64,
}

/// The cut's error budget: one row per mechanism, ranked by share, and the interplay.
pub fn budget_section(budget: Option<&CutBudget>) -> String {
    let Some(b) = budget else {
        return "<h2 id=\"budget\">Error budget</h2>\n<p>No error budget for this cut (cut with \
                <code>--commanded</code> or <code>--no-budget</code>, or one of its runs failed).</p>\n"
            .to_string();
    };
    let mut rows: Vec<&CutBudgetRow> = b.rows.iter().collect();
    rows.sort_by(|a, c| c.share.total_cmp(&a.share));
    let body: String = rows
        .iter()
        .map(|r| {
            let axis = r.axis.as_deref().unwrap_or("–");
            format!(
                "<tr data-budget=\"{}:{}\"><td>{}</td><td>{}</td><td>{:.3}</td><td>{:.3}</td>\
                 <td>{:.3}</td><td>{:.1}</td></tr>",
                esc(&format!("{:?}", r.mechanism).to_lowercase()),
                esc(axis),
                esc(&mechanism_label(r.mechanism, r.axis.as_deref())),
                esc(axis),
                r.rms_um,
                r.pv_um,
                r.height_change_um,
                100.0 * r.share
            )
        })
        .collect();
    format!(
        "<h2 id=\"budget\">Error budget</h2>\n<table class=\"budget\"><tr><th>mechanism</th><th>axis</th>\
         <th>RMS (µm)</th><th>peak-to-valley (µm)</th><th>change along the height (µm)</th>\
         <th>share of d (%)</th></tr>{body}<tr data-budget=\"interaction:–\"><td>the mechanisms acting \
         together</td><td>–</td><td>–</td><td>–</td><td>–</td><td>{:.1}</td></tr></table>\n<p>Each row \
         is a counterfactual cut: the same setpoints on the ideal machine plus that one mechanism \
         (backlash and friction on their axis's servo), less the cut it adds to, at every grid point \
         every run cut ({} points; the full cut's d: RMS {:.3} µm, peak-to-valley {:.3} µm). Share: \
         the row projected on the full cut's d, ⟨c, d⟩ / ⟨d, d⟩, so the shares and the interplay \
         add to 100 %. Change along the height: what the row changes between the lowest and the \
         highest row at one θ, which a ball bar does not see.</p>\n",
        100.0 * b.interaction_share,
        b.points,
        b.rms_um,
        b.pv_um
    )
}
