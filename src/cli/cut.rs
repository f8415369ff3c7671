//! `mtsim cut`: the machined cone predicted from the actual motion; surface and CMM files.

use std::path::{Path, PathBuf};

use super::{print_stdout, spinner, warn};
use crate::error::Result;
use crate::input::program::Direction;
use crate::measure::cut::{CutOptions, DEFAULT_HEIGHT_STEP_MM, DEFAULT_THETA_STEP_DEG};
use crate::report::budget_table::mechanism_label;
use crate::report::cut::cut_json;
use crate::report::cut_budget::CutBudget;
use crate::report::RunDir;

#[derive(Debug, clap::Args)]
#[command(after_help = "\
The cone is the scenario's [program.cone] (a program file that cuts a cone gives its \
geometry the same way, beside [program] file); the cutter is the machine's [tool] \
(radius = cutter_diameter_mm / 2, flutes flute_length_mm). Heights are mm above the \
base circle along the cone axis; the flank contact runs from the tip height \
(L - R) sin(alpha) to the flutes' end. Definitions and their sources: docs/cut.md.

Examples:
  mtsim cut scenarios/cone-15-10.toml -o cut
  mtsim cut scenarios/cone-15-10.toml -o cut-nominal --commanded
  mtsim cut scenarios/cone-15-10.toml -o cut-fast --no-budget
  mtsim cut scenarios/cone-15-10.toml -o cut --heights-mm 30,40,50 --theta-step-deg 0.05")]
pub struct CutArgs {
    /// Scenario file (TOML) with a cone: [program.cone], or [program] file beside one.
    pub scenario: PathBuf,
    /// Output folder: surface.csv, surface.parquet, cut.json, surface.svg, roundness.svg and
    /// cut.html (written as one unit).
    #[arg(short, long, default_value = "cut")]
    pub output: PathBuf,
    /// Cut with the commanded positions through the nominal kinematics: what the program
    /// alone leaves (its chords), without servo, lost motion or geometric errors.
    #[arg(long)]
    pub commanded: bool,
    /// θ step of the surface grid, deg (must divide 360).
    #[arg(long, default_value_t = DEFAULT_THETA_STEP_DEG, value_name = "DEG")]
    pub theta_step_deg: f64,
    /// Evaluation heights for the CMM figures (least-squares circle, roundness, centre,
    /// diameter), mm, comma-separated; default three spread over the flank contact.
    #[arg(long, value_delimiter = ',', num_args = 1, value_name = "MM")]
    pub heights_mm: Vec<f64>,
    /// Spacing of the grid's other heights over the flank contact, mm.
    #[arg(long, default_value_t = DEFAULT_HEIGHT_STEP_MM, value_name = "MM")]
    pub height_step_mm: f64,
    /// The run that cuts (a generated cone): ccw or cw; default the scenario's first.
    #[arg(long, value_parser = parse_direction)]
    pub direction: Option<Direction>,
    /// Leave out the error budget (the counterfactual cuts that say what each mechanism does
    /// to the surface): faster, and cut.json has no `budget`. A commanded cut has none.
    #[arg(long)]
    pub no_budget: bool,
    /// Print cut.json to standard output.
    #[arg(long)]
    pub json: bool,
}

fn parse_direction(text: &str) -> std::result::Result<Direction, String> {
    match text {
        "ccw" => Ok(Direction::Ccw),
        "cw" => Ok(Direction::Cw),
        _ => Err(format!("expected ccw or cw, got {text}")),
    }
}

pub fn run(args: &CutArgs) -> Result<i32> {
    let scenario = super::load_scenario(&args.scenario)?;
    let options = CutOptions {
        theta_step_deg: args.theta_step_deg,
        heights_mm: args.heights_mm.clone(),
        height_step_mm: args.height_step_mm,
        commanded: args.commanded,
        direction: args.direction,
    };
    let run_dir = RunDir::begin(&args.output)?.reads(&[&args.scenario]);
    let bar = spinner("cutting");
    let name = args
        .scenario
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let title = format!("Cut cone: {name}");
    let (cut, figures) = crate::study::cut::cut_into(
        &scenario,
        options,
        !args.no_budget,
        (run_dir.path(), &title),
        &|t| bar.set_message(format!("{t:.1} s of machine time")),
    )?;
    bar.finish_and_clear();
    for w in &cut.warnings {
        warn(w);
    }
    run_dir.commit()?;
    if args.json {
        print_stdout(&cut_json(&figures, cut.budget.as_ref()));
        return Ok(0);
    }
    let mut text = summary_text(&args.scenario, &figures, cut.sim_time_s);
    if let Some(b) = &cut.budget {
        text.push_str(&budget_text(b));
    }
    text.push_str(&format!("wrote {}\n", args.output.display()));
    print_stdout(&text);
    Ok(0)
}

/// The error budget as a table: rows ranked by share, then the interplay.
fn budget_text(b: &CutBudget) -> String {
    let mut out = format!(
        "error budget of d (RMS {:.3} µm, peak-to-valley {:.3} µm over {} points):\n{:<34} {:>4} {:>9} {:>9} {:>12} {:>8}\n",
        b.rms_um, b.pv_um, b.points, "mechanism", "axis", "RMS (µm)", "p-v (µm)", "height (µm)", "share %"
    );
    let mut rows: Vec<_> = b.rows.iter().collect();
    rows.sort_by(|a, c| c.share.total_cmp(&a.share));
    for r in rows {
        out.push_str(&format!(
            "{:<34} {:>4} {:>9.3} {:>9.3} {:>12.3} {:>8.1}\n",
            mechanism_label(r.mechanism, r.axis.as_deref()),
            r.axis.as_deref().unwrap_or("-"),
            r.rms_um,
            r.pv_um,
            r.height_change_um,
            100.0 * r.share
        ));
    }
    out.push_str(&format!(
        "{:<34} {:>4} {:>9} {:>9} {:>12} {:>8.1}\n",
        "the mechanisms acting together",
        "-",
        "",
        "",
        "",
        100.0 * b.interaction_share
    ));
    out
}

/// The figures as a table, as a CMM prints them.
fn summary_text(scenario: &Path, f: &crate::measure::cut::CutFigures, sim_time_s: f64) -> String {
    let mut out = format!(
        "{}: cut {} with R = {:.3} mm ({:.2} s of machine time{})\n",
        scenario.display(),
        f.direction
            .map_or("-".to_string(), |d| format!("{d:?}").to_lowercase()),
        f.cutter_radius_mm,
        sim_time_s,
        if f.commanded { ", commanded" } else { "" }
    );
    out.push_str(&format!(
        "{:>9} {:>14} {:>22} {:>18}\n",
        "z (mm)", "roundness (µm)", "centre x, y (µm)", "diameter err (µm)"
    ));
    for h in &f.heights {
        out.push_str(&format!(
            "{:>9.3} {:>14.3} {:>10.3}, {:>10.3} {:>18.3}\n",
            h.z_mm,
            h.roundness_um,
            h.centre_offset_um[0],
            h.centre_offset_um[1],
            h.diameter_error_um
        ));
    }
    out.push_str(&match f.cone_angle_error_urad {
        Some(a) => format!("cone angle error: {a:+.2} µrad\n"),
        None => "cone angle error: not measured (fewer than two heights cut)\n".to_string(),
    });
    for m in &f.marks {
        out.push_str(&format!(
            "mark: {} reversal at θ = {:.2}°: step {:+.3} µm (lost motion {} µm, rotary arcsec; read outside θ {:.2} to {:.2}°)\n",
            m.axis,
            m.theta_deg,
            m.step_um,
            m.lost_motion_text(),
            m.take_up_deg[0],
            m.take_up_deg[1]
        ));
    }
    if f.not_cut_points > 0 {
        out.push_str(&format!(
            "{} of {} grid points not cut\n",
            f.not_cut_points, f.grid_points
        ));
    }
    out
}
