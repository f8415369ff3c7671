//! `mtsim sweep`: reversal angles against a parameter, and the placement map (`--feasibility`).

use std::path::Path;

use super::{cone_of, print_stdout, progress_bar};
use crate::error::{Error, Result};
use crate::input::scenario::Scenario;
use crate::report::{create_dir, write_atomic};
use crate::study::sweep::{grid, sweep as sweep_reversals, SweepParam};

pub fn sweep(
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
    let result = sweep_reversals(&scenario.machine, &cone, param, &values, &|| bar.inc(1))?;
    bar.finish_and_clear();
    if let Some(dir) = output {
        create_dir(dir)?;
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

pub fn placement(
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
    let map =
        crate::study::placement::placement_map(&scenario, [px, py], &xs, &ys, &|| bar.inc(1))?;
    bar.finish_and_clear();
    if let Some(dir) = output {
        create_dir(dir)?;
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
