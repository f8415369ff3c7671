//! **cli** — the `mtsim` command line, one file per command, thin over the library.
//! Inputs: command-line arguments and the scenario files they name.
//! Outputs: tables or JSON on stdout, files, and exit codes: 0 success, 1 violations found, 2 bad input, 3 a run that failed.

use std::io::{IsTerminal, Write};
use std::path::PathBuf;

use clap::{Parser, Subcommand};

use crate::error::{Error, Result};
use crate::input::program::{ConeTest, NcOptions};
use crate::input::scenario::{Program, Scenario};
use crate::study::sweep::SweepParam;

mod analyze;
mod blocks;
mod check;
mod cone;
mod simulate;
mod sweep;

/// Machine-tool motion simulator: five-axis cone-frustum test, servo dynamics, ball bar,
/// axis limits and collisions.
#[derive(Debug, Parser)]
#[command(name = "mtsim", version, about, long_about = None)]
#[command(
    after_help = "Exit codes: 0 success, 1 violations found (check), 2 bad input, 3 run failed.\n\
Scenario and machine formats: docs/scenario-format.md, docs/machine-format.md."
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Write the cone-frustum NC program of a scenario (the paper's post-processor).
    Cone {
        /// Scenario file (TOML) with a [program.cone] table.
        scenario: PathBuf,
        /// Output file; standard output when omitted.
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Inverse-time feed (G93) instead of the mixed-unit F per block.
        #[arg(long)]
        g93: bool,
        /// Tool-centre-point program (G43.4): X Y Z are the tool tip in the table frame.
        #[arg(long)]
        tcp: bool,
    },
    /// Per axis: travel, peak speed, and the angles (or source lines) at which it reverses.
    Analyze {
        /// Scenario file (TOML).
        scenario: PathBuf,
        /// Print one JSON object instead of the table.
        #[arg(long)]
        json: bool,
    },
    /// The interpreter's canonical output: one row per move with its source line, kind
    /// (rapid, feed, arc, dwell), end point in machine coordinates, feed and tool.
    Blocks {
        /// Scenario file (TOML).
        scenario: PathBuf,
        /// Print CSV (exact numbers) instead of the table.
        #[arg(long, conflicts_with = "json")]
        csv: bool,
        /// Print one JSON array instead of the table.
        #[arg(long)]
        json: bool,
    },
    /// Reversal angles against a varied placement or geometry parameter, and the
    /// coincidences where the X, Y and Z reversals meet (the paper's Figs. 16/17).
    Sweep {
        /// Scenario file (TOML) with a [program.cone] table.
        scenario: PathBuf,
        /// The parameter to vary: center_x, center_y, center_z, half_apex, inclination or
        /// ballbar_length; with --feasibility two of them, comma-separated (center_x,center_y).
        #[arg(long, value_delimiter = ',', num_args = 1)]
        vary: Vec<SweepParam>,
        /// First value (mm or deg).
        /// With two parameters, one value for both or two comma-separated values.
        #[arg(long, allow_hyphen_values = true, value_delimiter = ',', num_args = 1)]
        from: Vec<f64>,
        /// Last value (mm or deg).
        #[arg(long, allow_hyphen_values = true, value_delimiter = ',', num_args = 1)]
        to: Vec<f64>,
        /// Step (mm or deg).
        #[arg(long)]
        #[arg(long, value_delimiter = ',', num_args = 1)]
        step: Vec<f64>,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
        /// Folder for sweep-<param>.csv and sweep-<param>.svg (placement.csv and
        /// placement.svg with --feasibility).
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// The placement map: run `check` on a grid of two parameters (cone positions) and
        /// map the smallest margin across travel limits and clearances.
        #[arg(long)]
        feasibility: bool,
    },
    /// Does the program fit the machine? Axis travel, velocity and acceleration on every
    /// sample, and collisions between table, workpiece, tool, holder and spindle.
    /// Exit code 0 when clean, 1 when violations were found.
    Check {
        /// Scenario file (TOML).
        scenario: PathBuf,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
        /// Check the actual axis positions of the servo simulation (catches overshoot)
        /// instead of the commanded ones.
        #[arg(long)]
        dynamics: bool,
        /// Near-miss clearance, mm (default: `near_miss_mm` of the scenario's `[check]`, else the machine's `[scene]`).
        #[arg(long)]
        near_miss: Option<f64>,
    },
    /// Run the program through interpolator, servo models and kinematics, and predict the
    /// ball-bar trace: writes trace.csv, summary.json and ballbar.svg.
    Simulate {
        /// Scenario file (TOML).
        scenario: PathBuf,
        /// Output folder (created if missing).
        #[arg(short, long, default_value = "out")]
        output: PathBuf,
        /// Print the summary as JSON (the contents of summary.json).
        #[arg(long)]
        json: bool,
        /// Leave the wall-clock figures (realtime_factor, wall_time_s) out of summary.json
        /// (null), so that repeated runs give byte-identical files.
        #[arg(long)]
        no_timing: bool,
    },
}

/// Runs the command line and returns the exit code.
pub fn main() -> i32 {
    let cli = Cli::parse();
    match run(cli) {
        Ok(code) => code,
        Err(e) => {
            let code = e.exit_code();
            eprintln!("{:?}", miette::Report::new(e));
            code
        }
    }
}

fn run(cli: Cli) -> Result<i32> {
    match cli.command {
        Command::Check {
            scenario,
            json,
            dynamics,
            near_miss,
        } => check::run(&scenario, json, dynamics, near_miss),
        Command::Simulate {
            scenario,
            output,
            json,
            no_timing,
        } => simulate::run(&scenario, &output, json, !no_timing),
        Command::Cone {
            scenario,
            output,
            g93,
            tcp,
        } => cone::run(&scenario, output.as_deref(), g93, tcp),
        Command::Analyze { scenario, json } => analyze::run(&scenario, json),
        Command::Blocks {
            scenario,
            csv,
            json,
        } => blocks::run(
            &scenario,
            match (csv, json) {
                (true, _) => blocks::Format::Csv,
                (_, true) => blocks::Format::Json,
                _ => blocks::Format::Table,
            },
        ),
        Command::Sweep {
            scenario,
            vary,
            from,
            to,
            step,
            json,
            output,
            feasibility,
        } => {
            if feasibility {
                sweep::placement(&scenario, &vary, &from, &to, &step, json, output.as_deref())
            } else {
                let one = |v: &[f64], what: &str| match v {
                    [x] => Ok(*x),
                    _ => Err(Error::usage(format!(
                        "--{what} takes one value without --feasibility"
                    ))),
                };
                let [param] = vary[..] else {
                    return Err(Error::usage(
                        "--vary takes one parameter without --feasibility (two with it)",
                    ));
                };
                sweep::sweep(
                    &scenario,
                    param,
                    one(&from, "from")?,
                    one(&to, "to")?,
                    one(&step, "step")?,
                    json,
                    output.as_deref(),
                )
            }
        }
    }
}

/// The cone of a scenario with a generated cone program, or an error naming `command`.
fn cone_of(scenario: &Scenario, command: &str) -> Result<(ConeTest, NcOptions)> {
    match &scenario.program {
        Program::Cone { cone, nc, .. } => Ok((*cone, *nc)),
        Program::File { .. } | Program::Circle { .. } => Err(Error::invalid(
            &scenario.path,
            format!("`mtsim {command}` needs a generated cone program ([program.cone])"),
        )
        .with_help("give the scenario a [program.cone] table instead of `file`")),
    }
}

/// A progress bar on stderr when it is a terminal; hidden otherwise (scripts, CI).
pub fn progress_bar(len: u64, what: &str) -> indicatif::ProgressBar {
    if !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len);
    if let Ok(style) = indicatif::ProgressStyle::with_template(&format!(
        "{what} {{bar:40}} {{pos}}/{{len}} {{eta}}"
    )) {
        bar.set_style(style);
    }
    bar
}

/// Prints to stdout; a closed pipe (`| head`) ends quietly instead of panicking.
pub(crate) fn print_stdout(text: &str) {
    let mut out = std::io::stdout().lock();
    let _ = out.write_all(text.as_bytes()).and_then(|_| out.flush());
}

/// A spinner on stderr when it is a terminal; hidden otherwise.
pub(crate) fn spinner(what: &str) -> indicatif::ProgressBar {
    if !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new_spinner();
    bar.set_prefix(what.to_string());
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{spinner} {prefix}: {msg} [{elapsed}]")
    {
        bar.set_style(style);
    }
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    bar
}
