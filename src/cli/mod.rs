//! **cli** — the `mtsim` command line, one file per command, thin over the library.
//! Inputs: command-line arguments and the scenario files they name.
//! Outputs: tables or JSON on stdout, files, and exit codes: 0 success, 1 violations found, 2 bad input, 3 a run that failed.

use std::path::PathBuf;

use clap::{Parser, Subcommand};

use crate::check::CheckOptions;
use crate::error::{Error, Result};
use crate::study::shard::Shard;
use crate::study::sweep::SweepParam;

mod analyze;
mod batch;
mod blocks;
mod chain_events;
mod check;
mod cone;
mod cut;
mod fit;
mod man;
mod merge;
mod report;
mod scenario;
mod simulate;
mod study;
mod sweep;
mod terminal;

// What the Python package (crates/mtsim-py) takes of the commands: their `--json` documents.
pub use analyze::AnalyzeFindings;
pub use blocks::{block_rows, BlockRow};

// The helpers every command uses, named here for the command files (`super::note`).
use scenario::{cone_of, load_scenario};
use terminal::{detail, note, print_stdout, progress_bar, spinner, warn};

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
    /// No progress bars and no warnings on stderr (errors still go there).
    #[arg(short, long, global = true)]
    pub quiet: bool,
    /// More detail on stderr: what each stage did, and for `simulate` how long each stage
    /// took (-vv: more, e.g. the check's table).
    #[arg(short, long, global = true, action = clap::ArgAction::Count)]
    pub verbose: u8,
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
        /// Step (mm or deg), > 0.
        #[arg(
            long,
            allow_negative_numbers = true,
            value_delimiter = ',',
            num_args = 1
        )]
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
        /// Also write report.html into the output folder (needs --output).
        #[arg(long, requires = "output")]
        html: bool,
        /// Run only shard K of N (1 <= K <= N) of the work list and write
        /// <output>/<name>.shard-K-of-N.json; join the N shards with `mtsim merge`.
        #[arg(long, value_name = "K/N")]
        shard: Option<Shard>,
    },
    /// Many scenarios (or programs) in parallel: one row per scenario with the analyze,
    /// check and (with --simulate) simulate figures, in batch.csv and batch.parquet.
    /// Exit code 1 when a scenario has violations or fails.
    Batch(batch::BatchArgs),
    /// The servo simulation over any scenario or machine key, by dotted path: a grid in
    /// one or two keys or random samples over many (docs/studies.md). One row per point
    /// (G, F, H, each axis's B and spikes, check verdict, status) in rows.csv and
    /// rows.parquet, study.json, plots and study.html.
    Study(study::StudyArgs),
    /// Join the shard files of one `sweep`, `sweep --feasibility`, `batch` or `study` run into the
    /// files the unsharded run writes, byte for byte.
    Merge(merge::MergeArgs),
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
        /// Sample the program at the timing its words ask for (no feed planning) instead of
        /// the planner's: what the program demands. A junction is then a velocity step, so
        /// accelerations at junctions are not measured.
        #[arg(long, conflicts_with = "dynamics")]
        programmed: bool,
        /// Near-miss clearance, mm (default: `near_miss_mm` of the scenario's `[check]`, else the machine's `[scene]`).
        /// A near miss is a span of samples in which two bodies that must not touch are closer
        /// than this but not touching; each span is listed once, with its smallest clearance.
        #[arg(long, allow_negative_numbers = true)]
        near_miss: Option<f64>,
        /// Also write an HTML report of the check to this file.
        #[arg(long, value_name = "FILE")]
        html: Option<PathBuf>,
    },
    /// Write report.html into each run folder (what `simulate -o` wrote): one
    /// self-contained page with the test parameters, the plots, figures, marks, diagnoses
    /// and the limits summary. Inline SVG and CSS, no network, no JavaScript.
    Report {
        /// Run folders.
        #[arg(required = true)]
        run_dirs: Vec<PathBuf>,
        /// Date of the test for the report (YYYY-MM-DD); default: the one the run recorded.
        #[arg(long)]
        date: Option<String>,
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
        /// Also write report.html into the output folder (see `mtsim report`).
        #[arg(long)]
        html: bool,
        /// The trace's file: trace.csv (text, fixed decimals) or trace.parquet (the same
        /// columns as f64, for Spark, Dask, pandas and Polars). Overrides the scenario's
        /// `[simulate] trace_format` (default csv).
        #[arg(long, value_enum, value_name = "FORMAT")]
        trace_format: Option<crate::input::scenario::TraceFormat>,
        /// Leave out the error budget (the counterfactual runs that say what makes G, and
        /// B per axis from them): faster, and summary.json has no `error_budget`.
        #[arg(long)]
        no_budget: bool,
        /// Also predict the cut cone, as `mtsim cut` at its default grid does (the first
        /// direction's piece, with its reversal marks and, unless --no-budget, its error
        /// budget): cut.json's document goes into summary.json under `measurements.cut`, the
        /// cut's files (surface, pictures, cut.html) into the output folder, and its
        /// section onto the report page.
        #[arg(long)]
        cut: bool,
    },
    /// Predict the machined cone as a CMM will measure it: the cutter moved by the actual
    /// motion (servo, lost motion, geometric errors) or, with --commanded, the program alone.
    /// Writes surface.csv, surface.parquet (theta_deg, z_mm, deviation_um; empty where not
    /// cut) and cut.json (roundness, centre and diameter per height, cone angle, reversal marks).
    Cut(cut::CutArgs),
    /// Print a shell completion script: `mtsim completions bash > /etc/bash_completion.d/mtsim`.
    Completions {
        /// The shell: bash, elvish, fish, powershell or zsh.
        shell: clap_complete::Shell,
    },
    /// Print the man page (roff): `mtsim man > mtsim.1; man ./mtsim.1`. With `-o DIR`,
    /// write `DIR/mtsim.1` and a page `DIR/mtsim-NAME.1` for every subcommand it names.
    Man {
        /// Folder for mtsim.1 and the subcommands' pages (created if missing).
        #[arg(short, long, value_name = "DIR")]
        output: Option<PathBuf>,
    },
    /// Identify the location errors of the rotary axes from measured ball-bar traces:
    /// `mtsim fit A.toml --measured a.csv [B.toml --measured b.csv ...] -o DIR`. Writes
    /// fit.json, location-errors.toml, fit.svg and fit.html; fits the table ball's placement
    /// per trace unless --placement-known; names what the tests cannot separate; refuses a
    /// trace that does not belong to its scenario.
    Fit {
        /// Scenario files (TOML), one per measured trace, in order.
        #[arg(required = true)]
        scenarios: Vec<PathBuf>,
        /// Measured trace (CSV: theta_deg, deviation_um, optional direction), one per scenario.
        #[arg(long, required = true)]
        measured: Vec<PathBuf>,
        /// Output folder (created if missing).
        #[arg(short, long, default_value = "fit")]
        output: PathBuf,
        /// The table ball sits exactly where each scenario says: do not fit its placement
        /// (three translations per trace, fitted by default).
        #[arg(long, conflicts_with = "setup")]
        placement_known: bool,
        /// The placement is fitted by default; kept so that older command lines still run.
        #[arg(long, hide = true)]
        setup: bool,
        /// Also fit each axis's backlash (re-simulates the servo models).
        #[arg(long)]
        backlash: bool,
        /// Also fit each axis's position-loop gain kv (servo mismatch).
        #[arg(long)]
        servo_gain: bool,
        /// Print fit.json to standard output.
        #[arg(long)]
        json: bool,
    },
}

/// Runs the command line and returns the exit code.
pub fn main() -> i32 {
    main_with(std::env::args_os())
}

/// The command line run on `args` (the program name first), in this process: what the
/// `mtsim` binary does, returning its exit code (the Python package's `run_command`).
pub fn main_with<I, T>(args: I) -> i32
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    // As `Cli::parse`, without ending the process: the message (or help) and its code.
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return e.exit_code();
        }
    };
    // `sweep --html`: the study page of the output folder, once the sweep has written it.
    let sweep_html = match &cli.command {
        Command::Sweep {
            html: true,
            output: Some(dir),
            ..
        } => Some(dir.clone()),
        _ => None,
    };
    let result = run(cli).and_then(|code| {
        if let Some(dir) = &sweep_html {
            report::write_report(dir, None)?;
        }
        Ok(code)
    });
    match result {
        Ok(code) => code,
        Err(e) => {
            let code = e.exit_code();
            eprintln!("{:?}", miette::Report::new(e));
            code
        }
    }
}

fn run(cli: Cli) -> Result<i32> {
    terminal::set_flags(cli.quiet, cli.verbose);
    match cli.command {
        Command::Completions { shell } => {
            let mut out = Vec::new();
            clap_complete::generate(
                shell,
                &mut <Cli as clap::CommandFactory>::command(),
                "mtsim",
                &mut out,
            );
            print_stdout(&String::from_utf8_lossy(&out));
            Ok(0)
        }
        Command::Man { output } => {
            man::run(<Cli as clap::CommandFactory>::command(), output.as_deref())
        }
        Command::Check {
            scenario,
            json,
            dynamics,
            programmed,
            near_miss,
            html,
        } => check::run(
            &scenario,
            json,
            CheckOptions {
                dynamics,
                programmed,
                near_miss_mm: near_miss,
                collision_poses: if html.is_some() {
                    crate::check::scene::snapshot::SHOWN_DEFAULT
                } else {
                    0
                },
            },
            html.as_deref(),
        ),
        Command::Simulate {
            scenario,
            output,
            json,
            no_timing,
            html,
            trace_format,
            no_budget,
            cut,
        } => simulate::run(
            &scenario,
            &output,
            json,
            (!no_timing, !no_budget),
            html,
            (trace_format, cut),
        ),
        Command::Cut(args) => cut::run(&args),
        Command::Report { run_dirs, date } => report::run(&run_dirs, date.as_deref()),
        Command::Cone {
            scenario,
            output,
            g93,
            tcp,
        } => cone::run(&scenario, output.as_deref(), g93, tcp),
        Command::Analyze { scenario, json } => analyze::run(&scenario, json),
        Command::Fit {
            scenarios,
            measured,
            output,
            placement_known,
            setup: _,
            backlash,
            servo_gain,
            json,
        } => fit::run(
            &scenarios,
            &measured,
            &output,
            crate::study::fit::FitOptions {
                placement_known,
                backlash,
                servo_gain,
            },
            json,
        ),
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
            shard,
            ..
        } => {
            if feasibility {
                sweep::placement(
                    &scenario,
                    &vary,
                    &from,
                    &to,
                    &step,
                    json,
                    output.as_deref(),
                    shard,
                )
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
                    shard,
                )
            }
        }
        Command::Batch(args) => batch::run(&args),
        Command::Merge(args) => merge::run(&args),
        Command::Study(args) => study::run(&args),
    }
}
