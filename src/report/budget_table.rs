//! The report's summary table: the error budget (`summary.json`'s `error_budget`, made by
//! `study::budget`) ranked by share, with a sentence in words on top that says what makes
//! most of G and what to do about it. Nothing is computed here but the ranking.

use std::fmt::Write as _;

use super::escape::esc;
use super::run::{BudgetMechanism, BudgetRow, ErrorBudget};

/// Below this G, µm, the shares are not put into words: projections on so flat a curve are
/// ill-conditioned (two rows of a few µm that cancel can take shares of ±1000).
pub const HEADLINE_G_MIN_UM: f64 = 0.05;

/// The sentence on top of the table: the largest share in words, with the advice for it.
pub fn headline(budget: &ErrorBudget) -> String {
    if !(budget.g_um >= HEADLINE_G_MIN_UM) {
        return format!(
            "G is {:.3} µm: too small to split into parts; the rows' peak-to-valleys say what \
             each mechanism alone would draw.",
            budget.g_um
        );
    }
    let top = budget
        .rows
        .iter()
        .filter(|r| r.share > 0.0)
        .max_by(|a, b| a.share.total_cmp(&b.share));
    let Some(top) = top.filter(|t| t.share >= budget.interaction_share) else {
        return format!(
            "{:.0} % of G is the mechanisms acting together (the runs with one mechanism each \
             do not add up to the full run): look at the largest rows below.",
            100.0 * budget.interaction_share
        );
    };
    format!(
        "{:.0} % of G is {}: {}.",
        100.0 * top.share,
        what(top),
        advice(top)
    )
}

/// A row's mechanism and axis in words.
fn what(row: &BudgetRow) -> String {
    match (&row.axis, row.mechanism) {
        (_, BudgetMechanism::ProgramPath) => "the program's own path".to_string(),
        (None, BudgetMechanism::Servo) => "the servos' common lag".to_string(),
        (Some(a), m) => format!("the {a} axis's {}", m.name()),
        (None, m) => format!("the {}", m.name()),
    }
}

/// A row's mechanism in the table.
fn row_name(row: &BudgetRow) -> String {
    mechanism_label(row.mechanism, row.axis.as_deref())
}

/// A budget row's mechanism in a table (the ball bar's and the cut's): the servo row
/// without an axis is the servos' common lag.
pub fn mechanism_label(mechanism: BudgetMechanism, axis: Option<&str>) -> String {
    match (axis, mechanism) {
        (None, BudgetMechanism::Servo) => "servos' common lag".to_string(),
        (_, m) => m.name().to_string(),
    }
}

/// What to do about a row's mechanism.
fn advice(row: &BudgetRow) -> String {
    let axis = row.axis.as_deref().unwrap_or("the");
    match row.mechanism {
        BudgetMechanism::ProgramPath => "raise the segment count or use TCP".to_string(),
        BudgetMechanism::Servo if row.axis.is_none() => {
            "raise the feedforward of every axis (the same on each), or run at a lower feed"
                .to_string()
        }
        BudgetMechanism::Servo => format!(
            "match the {axis} axis's position-loop gain to the others' or raise its feedforward"
        ),
        BudgetMechanism::Backlash => format!("adjust the {axis} axis's backlash compensation"),
        BudgetMechanism::Friction => format!(
            "check the {axis} axis's guides and lubrication, or its friction (quadrant) compensation"
        ),
        BudgetMechanism::Geometric => {
            "measure and compensate the rotary axes' location errors (mtsim fit)".to_string()
        }
        BudgetMechanism::ErrorTable => {
            format!("check the {axis} axis's pitch or worm-gear compensation")
        }
        BudgetMechanism::Squareness => {
            "measure the squareness of the linear axes (ball-bar circles in XY, YZ and ZX, \
             mtsim fit) and compensate it"
                .to_string()
        }
        BudgetMechanism::ComponentErrors => format!(
            "measure the {axis} axis's straightness and angular errors (laser) and compensate them"
        ),
    }
}

/// The section: the sentence, then every row ranked by share and the interplay's share.
pub fn budget_section(budget: Option<&ErrorBudget>) -> String {
    let Some(budget) = budget else {
        return "<p>What makes G: no error budget in this folder (made before mtsim wrote it, or \
                with <code>--no-budget</code>).</p>\n"
            .to_string();
    };
    let mut out = format!(
        "<p class=\"headline\" data-summary=\"headline\">{}</p>\n",
        esc(&headline(budget))
    );
    out.push_str(
        "<table class=\"budget\">\n<tr><th>rank</th><th>mechanism</th><th>axis</th>\
         <th>peak-to-valley (µm)</th><th>share of G (%)</th></tr>\n",
    );
    let mut rows: Vec<&BudgetRow> = budget.rows.iter().collect();
    rows.sort_by(|a, b| b.share.total_cmp(&a.share));
    for (i, r) in rows.iter().enumerate() {
        let key = format!("{:?}", r.mechanism).to_lowercase();
        let axis = r.axis.as_deref().unwrap_or("–");
        let _ = writeln!(
            out,
            "<tr data-budget=\"{}:{}\"><td>{}</td><td>{}</td><td>{}</td><td class=\"pv\">{:.2}</td>\
             <td class=\"share\">{:.1}</td></tr>",
            esc(&key),
            esc(axis),
            i + 1,
            esc(&row_name(r)),
            esc(axis),
            r.pv_um,
            100.0 * r.share,
        );
    }
    let _ = writeln!(
        out,
        "<tr data-budget=\"interaction:–\"><td></td><td>the mechanisms acting together</td><td>–</td>\
         <td>–</td><td class=\"share\">{:.1}</td></tr>",
        100.0 * budget.interaction_share
    );
    let _ = writeln!(
        out,
        "</table>\n<p class=\"note\">Each row is a counterfactual run: the same setpoints on the ideal \
         machine (actual = commanded) plus that one mechanism (backlash and friction on their axis's \
         servo), less the run it adds to. Share: the row's curve projected on the full run's centred \
         curve over the revolution that gives G ({:.2} µm), so the shares and the interplay add to \
         100 % and a part that works against G is negative.</p>",
        budget.g_um
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(mechanism: BudgetMechanism, axis: Option<&str>, share: f64) -> BudgetRow {
        BudgetRow {
            mechanism,
            axis: axis.map(str::to_string),
            pv_um: 1.0,
            share,
        }
    }

    #[test]
    fn a_flat_curve_is_not_split() {
        let budget = ErrorBudget {
            g_um: 0.001,
            rows: vec![
                row(BudgetMechanism::Servo, Some("X"), 2500.0),
                row(BudgetMechanism::Servo, Some("Y"), -2499.0),
            ],
            interaction_share: 0.0,
        };
        assert!(headline(&budget).starts_with("G is 0.001 µm: too small"));
    }

    #[test]
    fn the_headline_names_the_largest_share() {
        let budget = ErrorBudget {
            g_um: 10.0,
            rows: vec![
                row(BudgetMechanism::ProgramPath, None, 0.62),
                row(BudgetMechanism::Servo, Some("C"), 0.3),
            ],
            interaction_share: 0.08,
        };
        assert_eq!(
            headline(&budget),
            "62 % of G is the program's own path: raise the segment count or use TCP."
        );
    }
}
