//! `mtsim analyze`: per axis, travel, peak speed and the reversal angles or lines.

use std::path::Path;

use serde_json::{json, Map};

use super::print_stdout;
use crate::error::Result;
use crate::input::scenario::Scenario;
use crate::study::analysis::{analyse_program, ProgramAnalysis};
use crate::study::feed::FeedReport;
use crate::study::reversals::Analysis;

/// What `mtsim analyze` finds in a scenario, before it is printed.
pub struct AnalyzeFindings {
    pub analysis: Analysis,
    pub geometric: Option<crate::study::geometry::GeometricTrace>,
    pub feed: FeedReport,
    /// The reader's notices: warnings, and words accepted with no effect on the motion.
    pub notices: Vec<ngc::Notice>,
    /// Poles and solution switches on a chain with two rotaries; None on other machines.
    pub chain_events: Option<Vec<crate::study::chain_events::ChainEvent>>,
}

impl AnalyzeFindings {
    pub fn of(scenario: &Scenario) -> Result<AnalyzeFindings> {
        // One read of a file program gives the reversals, the feed limits and the notices.
        let ProgramAnalysis {
            analysis,
            geometric,
            feed,
            notices,
        } = analyse_program(scenario)?;
        Ok(AnalyzeFindings {
            analysis,
            geometric,
            feed,
            notices,
            chain_events: crate::study::chain_events::chain_events(scenario)?,
        })
    }

    /// The reader's warnings, `file:line: message`.
    pub fn reader_warnings(&self) -> Vec<String> {
        self.notices
            .iter()
            .filter(|n| n.warning)
            .map(located)
            .collect()
    }

    /// The document `mtsim analyze --json` prints.
    pub fn json(&self) -> serde_json::Value {
        let mut axes = Map::new();
        for a in &self.analysis.axes {
            axes.insert(
                a.axis.to_string(),
                serde_json::to_value(a).expect("plain data serializes"),
            );
        }
        let mut warnings = self.analysis.warnings();
        warnings.extend(self.reader_warnings());
        let mut v = json!({
            "axes": axes,
            "min_linear_separation_deg": self.analysis.min_linear_separation_deg(),
            "warnings": warnings,
            "geometric_trace": self.geometric,
            "feed_limits": self.feed,
        });
        let no_effect: Vec<String> = self
            .notices
            .iter()
            .filter(|n| !n.warning)
            .map(located)
            .collect();
        if !no_effect.is_empty() {
            v["no_motion_effect"] = no_effect.into();
        }
        if let Some(events) = &self.chain_events {
            v["chain_events"] = events.iter().map(|e| e.to_json()).collect();
        }
        v
    }
}

fn located(n: &ngc::Notice) -> String {
    format!("{}:{}: {}", n.path.display(), n.line, n.message)
}

pub fn run(path: &Path, as_json: bool) -> Result<i32> {
    let scenario = super::load_scenario(path)?;
    let found = AnalyzeFindings::of(&scenario)?;
    for w in found.reader_warnings() {
        super::warn(&w);
    }
    if as_json {
        print_stdout(&format!(
            "{}\n",
            serde_json::to_string_pretty(&found.json()).expect("plain data serializes")
        ));
        return Ok(0);
    }
    let AnalyzeFindings {
        analysis,
        geometric,
        feed,
        notices,
        chain_events,
    } = found;
    let no_effect: Vec<_> = notices.iter().filter(|n| !n.warning).collect();
    let mut warnings = analysis.warnings();
    warnings.extend(notices.iter().filter(|n| n.warning).map(located));
    let mut out = format!("{} on {}\n", path.display(), scenario.machine.name);
    out.push_str(&analysis_table(&analysis));
    match analysis.closest_linear_reversals() {
        Some((d, (a, ta), (b, tb))) => out.push_str(&format!(
            "closest reversals of different linear axes: {a} at {ta:.2} deg and {b} at {tb:.2} deg, {d:.2} deg apart\n"
        )),
        None => out.push_str("fewer than two linear axes reverse\n"),
    }
    if let Some(g) = geometric {
        out.push_str(&format!(
            "geometric errors alone (programmed path): ball-bar trace {:+.2} .. {:+.2} um, {:.2} um after centring (their share of G)\n",
            g.min_um, g.max_um, g.circular_deviation_um
        ));
    }
    out.push_str(&feed_table(&feed));
    out.push_str(&super::chain_events::chain_events_text(
        chain_events.as_deref(),
    ));
    if !no_effect.is_empty() {
        out.push_str("accepted with no effect on the motion:\n");
        for n in &no_effect {
            out.push_str(&format!("  line {}: {}\n", n.line, n.message));
        }
    }
    for w in &warnings {
        out.push_str(&format!("warning: {w}\n"));
    }
    print_stdout(&out);
    Ok(0)
}

/// Reversals listed per axis in the table; a longer list gives its count and these first
/// ones (`--json` lists them all).
const REVERSALS_SHOWN: usize = 8;

/// The per-axis table of `mtsim analyze`.
pub fn analysis_table(analysis: &Analysis) -> String {
    let mut out = String::new();
    let with_lines = analysis.axes.iter().any(|a| a.reversal_lines.is_some());
    out.push_str(&format!(
        "{:<4} {:>12} {:>12} {:>11} {:>16}  {}\n",
        "axis",
        "min",
        "max",
        "range",
        "peak speed/min",
        if with_lines {
            "reversals (source lines; deg)"
        } else {
            "reversals (deg)"
        }
    ));
    for a in &analysis.axes {
        let unit = a.axis.unit();
        let reversals = match &a.reversal_lines {
            Some(lines) if lines.is_empty() => "none".to_string(),
            Some(lines) => {
                let mut l = lines
                    .iter()
                    .take(REVERSALS_SHOWN)
                    .map(|l| format!("line {l}"))
                    .collect::<Vec<_>>()
                    .join(", ");
                if lines.len() > REVERSALS_SHOWN {
                    l = format!(
                        "{} reversals, the first {REVERSALS_SHOWN}: {l}, ... (all in --json)",
                        lines.len()
                    );
                }
                if a.reversals_deg.is_empty() {
                    l
                } else {
                    format!("{l}; {}", fmt_angles(&a.reversals_deg))
                }
            }
            None if a.reversals_deg.is_empty() => "none".to_string(),
            None => fmt_angles(&a.reversals_deg),
        };
        let reversals = match a.reversals_not_listed {
            Some(n) => format!("{reversals}; and {n} more not listed"),
            None => reversals,
        };
        out.push_str(&format!(
            "{:<4} {:>9.3} {unit:<3}{:>9.3} {unit:<3}{:>8.3} {unit:<3}{:>8.1} {:<8} {}\n",
            a.axis.to_string(),
            a.min,
            a.max,
            a.range,
            a.peak_speed_per_min,
            format!("{unit}/min"),
            reversals
        ));
    }
    out
}

/// Blocks printed in the feed-limit list before it is cut short.
const FEED_LINES_SHOWN: usize = 20;

/// Where the machine holds the feed below the programmed one, and by which axis.
pub fn feed_table(feed: &FeedReport) -> String {
    if feed.blocks.is_empty() {
        return format!(
            "feed: every one of the {} feed blocks runs at its programmed F\n",
            feed.feed_blocks
        );
    }
    let by_axis = feed
        .limited_by_axis
        .iter()
        .map(|(a, n)| format!("{a} {n}"))
        .collect::<Vec<_>>()
        .join(", ");
    let mut out = format!(
        "feed held to the machine in {} of {} feed blocks (by axis: {by_axis})\n",
        feed.blocks.len(),
        feed.feed_blocks
    );
    for b in feed.blocks.iter().take(FEED_LINES_SHOWN) {
        let kind = match b.limit {
            crate::motion::interpolation::LimitKind::Velocity => "velocity",
            crate::motion::interpolation::LimitKind::Acceleration => "acceleration",
            crate::motion::interpolation::LimitKind::Jerk => "jerk",
        };
        out.push_str(&format!(
            "  line {}: F{:.1} -> {:.1}/min, {} {kind} limit\n",
            b.line, b.programmed_per_min, b.planned_per_min, b.axis
        ));
    }
    if feed.blocks.len() > FEED_LINES_SHOWN {
        out.push_str(&format!(
            "  ... and {} more (all of them with --json)\n",
            feed.blocks.len() - FEED_LINES_SHOWN
        ));
    }
    out
}

fn fmt_angles(angles: &[f64]) -> String {
    let shown = angles
        .iter()
        .take(REVERSALS_SHOWN)
        .map(|t| format!("{t:.2}"))
        .collect::<Vec<_>>()
        .join(", ");
    if angles.len() > REVERSALS_SHOWN {
        format!(
            "{} reversals, the first {REVERSALS_SHOWN}: {shown}, ... (all in --json)",
            angles.len()
        )
    } else {
        shown
    }
}
