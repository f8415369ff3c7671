//! The `mtsim` command line: argument parsing and the commands, over the library.
//!
//! Exit codes: 0 success; 1 checked and found violations; 2 bad input; 3 a run that failed.

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};

use clap::{Parser, Subcommand};
use serde_json::{json, Map};

use crate::analysis::{analyse_blocks, analyse_cone, Analysis};
use crate::axis::AxisVec;
use crate::cone::{write_program, ConePath};
use crate::error::{Error, Result};
use crate::report::{analysis_table, write_atomic};
use crate::scenario::{Program, Scenario};
use crate::sweep::{grid, sweep, SweepParam};

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
        /// Near-miss clearance, mm (default: the scenario's [check] or the machine's [scene]).
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
        } => cmd_check(&scenario, json, dynamics, near_miss),
        Command::Simulate {
            scenario,
            output,
            json,
            no_timing,
        } => cmd_simulate(&scenario, &output, json, !no_timing),
        Command::Cone {
            scenario,
            output,
            g93,
            tcp,
        } => cmd_cone(&scenario, output.as_deref(), g93, tcp),
        Command::Analyze { scenario, json } => cmd_analyze(&scenario, json),
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
                cmd_placement(&scenario, &vary, &from, &to, &step, json, output.as_deref())
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
                cmd_sweep(
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

fn cone_of(
    scenario: &Scenario,
    command: &str,
) -> Result<(crate::cone::ConeTest, crate::cone::NcOptions)> {
    match &scenario.program {
        Program::Cone { cone, nc, .. } => Ok((*cone, *nc)),
        Program::File { .. } | Program::Circle { .. } => Err(Error::invalid(
            &scenario.path,
            format!("`mtsim {command}` needs a generated cone program ([program.cone])"),
        )
        .with_help("give the scenario a [program.cone] table instead of `file`")),
    }
}

fn cmd_cone(path: &Path, output: Option<&Path>, g93: bool, tcp: bool) -> Result<i32> {
    let scenario = Scenario::load(path)?;
    let (cone, mut nc) = cone_of(&scenario, "cone")?;
    nc.inverse_time |= g93;
    nc.tcp |= tcp;
    let cone_path = ConePath::new(cone, &scenario.machine);
    let (text, _) = write_program(&cone_path, &scenario.machine.name, &nc);
    match output {
        Some(out) => {
            write_atomic(out, text.as_bytes())?;
            eprintln!("wrote {} ({} blocks)", out.display(), nc.segments);
        }
        None => print_stdout(&text),
    }
    Ok(0)
}

/// Analysis of a scenario's program: the exact path for a generated cone, the blocks for a file.
pub fn analyse_scenario(scenario: &Scenario) -> Result<Analysis> {
    match &scenario.program {
        Program::Cone { cone, nc, .. } => Ok(analyse_cone(
            &ConePath::new(*cone, &scenario.machine),
            nc.feed_mm_min,
        )),
        Program::File { path, cone } => {
            let blocks = crate::gcode::read_file(path, AxisVec::ZERO)?;
            analyse_blocks(
                blocks,
                &scenario.machine,
                cone.map(|c| c.circle_frame()).as_ref(),
            )
        }
        Program::Circle { circle, .. } => Ok(crate::analysis::analyse_circle(
            circle,
            scenario.machine.axes(),
        )),
    }
}

fn cmd_analyze(path: &Path, as_json: bool) -> Result<i32> {
    let scenario = Scenario::load(path)?;
    let analysis = analyse_scenario(&scenario)?;
    if as_json {
        let mut axes = Map::new();
        for a in &analysis.axes {
            axes.insert(
                a.axis.to_string(),
                serde_json::to_value(a).expect("plain data serializes"),
            );
        }
        let v = json!({
            "axes": axes,
            "min_linear_separation_deg": analysis.min_linear_separation_deg(),
            "warnings": analysis.warnings(),
        });
        print_stdout(&format!(
            "{}\n",
            serde_json::to_string_pretty(&v).expect("plain data serializes")
        ));
        return Ok(0);
    }
    let mut out = format!("{} on {}\n", path.display(), scenario.machine.name);
    out.push_str(&analysis_table(&analysis));
    match analysis.closest_linear_reversals() {
        Some((d, (a, ta), (b, tb))) => out.push_str(&format!(
            "closest reversals of different linear axes: {a} at {ta:.2} deg and {b} at {tb:.2} deg, {d:.2} deg apart\n"
        )),
        None => out.push_str("fewer than two linear axes reverse\n"),
    }
    for w in analysis.warnings() {
        out.push_str(&format!("warning: {w}\n"));
    }
    print_stdout(&out);
    Ok(0)
}

fn cmd_sweep(
    path: &Path,
    param: SweepParam,
    from: f64,
    to: f64,
    step: f64,
    as_json: bool,
    output: Option<&Path>,
) -> Result<i32> {
    let scenario = Scenario::load(path)?;
    let (cone, _) = cone_of(&scenario, "sweep")?;
    let values = grid(from, to, step)?;
    let bar = progress_bar(values.len() as u64, "sweep");
    let result = sweep(&scenario.machine, &cone, param, &values, &|| bar.inc(1))?;
    bar.finish_and_clear();
    if let Some(dir) = output {
        std::fs::create_dir_all(dir).map_err(|source| Error::Write {
            path: dir.to_path_buf(),
            source,
        })?;
        let stem = format!("sweep-{}", param.name());
        let csv_path = dir.join(format!("{stem}.csv"));
        let svg_path = dir.join(format!("{stem}.svg"));
        write_atomic(&csv_path, &result.to_csv()?)?;
        let title = format!(
            "Reversal angles vs {} (half apex {} deg, inclination {} deg, L {} mm)",
            param.name(),
            cone.half_apex_deg,
            cone.inclination_deg,
            cone.ballbar_length_mm
        );
        write_atomic(&svg_path, result.to_svg(param.unit(), &title)?.as_bytes())?;
        eprintln!("wrote {} and {}", csv_path.display(), svg_path.display());
    }
    if as_json {
        print_stdout(&format!(
            "{}\n",
            serde_json::to_string(&result).expect("plain data serializes")
        ));
    } else {
        let mut out = format!(
            "{:>10}  {:<40} {:>10}\n",
            param.name(),
            "X | Y | Z reversals (deg)",
            "spread"
        );
        for row in &result.rows {
            let fmt = |axis: &str| {
                row.reversals_deg
                    .get(axis)
                    .map(|v| {
                        v.iter()
                            .map(|a| format!("{a:.2}"))
                            .collect::<Vec<_>>()
                            .join(" ")
                    })
                    .unwrap_or_default()
            };
            out.push_str(&format!(
                "{:>10.3}  {:<40} {:>10}\n",
                row.value,
                format!("{} | {} | {}", fmt("X"), fmt("Y"), fmt("Z")),
                row.spread_deg
                    .map(|s| format!("{s:.3}"))
                    .unwrap_or_else(|| "-".into())
            ));
        }
        if result.coincidences.is_empty() {
            out.push_str("no coincidence of the X, Y and Z reversals in this range\n");
        }
        for c in &result.coincidences {
            out.push_str(&format!(
                "coincidence: {} = {:.1} {}, theta = {:.2} deg (spread {:.3} deg)\n",
                param.name(),
                c.value,
                param.unit(),
                c.theta_deg,
                c.spread_deg
            ));
        }
        print_stdout(&out);
    }
    Ok(0)
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
fn print_stdout(text: &str) {
    let mut out = std::io::stdout().lock();
    let _ = out.write_all(text.as_bytes()).and_then(|_| out.flush());
}

fn cmd_simulate(path: &Path, out_dir: &Path, as_json: bool, timing: bool) -> Result<i32> {
    let scenario = Scenario::load(path)?;
    let bar = spinner("simulating");
    let summary = crate::simulation::simulate(&scenario, out_dir, timing, &|t| {
        bar.set_message(format!("{t:.1} s of machine time"))
    })?;
    bar.finish_and_clear();
    if as_json {
        print_stdout(&format!(
            "{}\n",
            serde_json::to_string_pretty(&summary).expect("plain data serializes")
        ));
        return Ok(0);
    }
    let mut out = format!(
        "{}: {:.2} s of machine time ({} setpoints, {})\n",
        path.display(),
        summary.sim_time_s,
        summary.setpoints,
        summary
            .directions
            .iter()
            .map(|d| format!("{d:?}").to_lowercase())
            .collect::<Vec<_>>()
            .join(" + ")
    );
    if let Some(rtf) = summary.realtime_factor {
        out.push_str(&format!(
            "real-time factor: {rtf:.0}x ({:.3} s wall)\n",
            summary.wall_time_s.unwrap_or(0.0)
        ));
    }
    match &summary.ballbar {
        None => out.push_str(
            "no measured circle: give the scenario a cone or circle to get ball-bar figures\n",
        ),
        Some(b) => {
            out.push_str(&format!(
                "ISO 230-4: circular deviation G = {:.2} um, radial deviation F = {:+.2} / {:+.2} um, hysteresis H = {}\n",
                b.circular_deviation_um,
                b.radial_max_um,
                b.radial_min_um,
                b.hysteresis_um.map_or("- (one direction)".to_string(), |h| format!("{h:.2} um"))
            ));
            if b.events.is_empty() {
                out.push_str("no spikes or steps above noise\n");
            } else {
                out.push_str(&format!(
                    "{:>4} {:>6} {:>10} {:>10} {:>6} {:>5} {:>10}\n",
                    "run", "kind", "theta deg", "height um", "axis", "conf", "width deg"
                ));
                for e in &b.events {
                    out.push_str(&format!(
                        "{:>4} {:>6} {:>10.2} {:>10.2} {:>6} {:>5.2} {:>10.2}\n",
                        format!("{:?}", e.direction).to_lowercase(),
                        format!("{:?}", e.kind).to_lowercase(),
                        e.theta_deg,
                        e.height_um,
                        e.axis.map_or("?".to_string(), |a| a.to_string()),
                        e.confidence,
                        e.width_deg
                    ));
                }
            }
        }
    }
    out.push_str(&format!("wrote {}\n", out_dir.display()));
    print_stdout(&out);
    Ok(0)
}

/// A spinner on stderr when it is a terminal; hidden otherwise.
fn spinner(what: &str) -> indicatif::ProgressBar {
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

fn cmd_check(path: &Path, as_json: bool, dynamics: bool, near_miss_mm: Option<f64>) -> Result<i32> {
    if let Some(d) = near_miss_mm {
        if !(d.is_finite() && d >= 0.0) {
            return Err(Error::usage(format!(
                "--near-miss {d}: expected a clearance >= 0 mm"
            )));
        }
    }
    let scenario = Scenario::load(path)?;
    let report = crate::check::check(
        &scenario,
        &crate::check::CheckOptions {
            dynamics,
            near_miss_mm,
        },
    )?;
    let code = if report.is_clean() {
        0
    } else {
        crate::error::EXIT_VIOLATIONS
    };
    if as_json {
        print_stdout(&format!(
            "{}\n",
            serde_json::to_string_pretty(&report).expect("plain data serializes")
        ));
        return Ok(code);
    }
    print_stdout(&crate::report::check_table(
        &report,
        &path.display().to_string(),
    ));
    Ok(code)
}

fn cmd_placement(
    path: &Path,
    vary: &[SweepParam],
    from: &[f64],
    to: &[f64],
    step: &[f64],
    as_json: bool,
    output: Option<&Path>,
) -> Result<i32> {
    let [px, py] = vary[..] else {
        return Err(Error::usage(
            "--feasibility needs two parameters: --vary center_x,center_y",
        ));
    };
    let pick = |v: &[f64], i: usize| v.get(i).or(v.first()).copied().unwrap_or(f64::NAN);
    let xs = grid(pick(from, 0), pick(to, 0), pick(step, 0))?;
    let ys = grid(pick(from, 1), pick(to, 1), pick(step, 1))?;
    let scenario = Scenario::load(path)?;
    let bar = progress_bar((xs.len() * ys.len()) as u64, "placement");
    let map = crate::placement::placement_map(&scenario, [px, py], &xs, &ys, &|| bar.inc(1))?;
    bar.finish_and_clear();
    if let Some(dir) = output {
        std::fs::create_dir_all(dir).map_err(|source| Error::Write {
            path: dir.to_path_buf(),
            source,
        })?;
        write_atomic(&dir.join("placement.csv"), &map.to_csv()?)?;
        let title = format!(
            "Where the test fits: {} (smallest margin, mm)",
            scenario.path.display()
        );
        write_atomic(&dir.join("placement.svg"), map.to_svg(&title)?.as_bytes())?;
        eprintln!(
            "wrote {} and {}",
            dir.join("placement.csv").display(),
            dir.join("placement.svg").display()
        );
    }
    if as_json {
        print_stdout(&format!(
            "{}\n",
            serde_json::to_string(&map).expect("plain data serializes")
        ));
        return Ok(0);
    }
    let fitting = map.cells.iter().filter(|c| c.fits).count();
    let mut out = format!("{} of {} placements fit\n", fitting, map.cells.len());
    match map.fitting_range() {
        Some(((x0, x1), (y0, y1))) => out.push_str(&format!(
            "fitting range: {} {x0} .. {x1} mm, {} {y0} .. {y1} mm\n",
            map.params[0], map.params[1]
        )),
        None => out.push_str("no placement on this grid fits\n"),
    }
    if let Some(best) = map
        .cells
        .iter()
        .filter(|c| c.fits)
        .max_by(|a, b| a.margin_mm.total_cmp(&b.margin_mm))
    {
        out.push_str(&format!(
            "largest margin: {:.1} mm at ({}, {}), limited by {}\n",
            best.margin_mm, best.x, best.y, best.limiting
        ));
    }
    print_stdout(&out);
    Ok(0)
}
