//! `mtsim sweep`: reversal angles against a parameter, and the placement map (`--feasibility`).

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::{cone_of, print_stdout, progress_bar};
use crate::error::{Error, Result};
use crate::input::scenario::Scenario;
use crate::report::test_info::scenario_hash;
use crate::report::{write_atomic, RunDir};
use crate::study::placement::{placement_cells, PlacementMap};
use crate::study::shard::{Shard, ShardFile};
use crate::study::sweep::{grid, sweep_part, SweepParam, SweepResult};

/// What identifies a sweep, and what its outputs show besides the rows.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct SweepHeader {
    pub scenario: String,
    pub param: SweepParam,
    /// --from, --to, --step.
    pub grid: [f64; 3],
    /// Half apex (deg), inclination (deg) and ball-bar length (mm) of the cone, for the title.
    pub cone: [f64; 3],
}

/// Tells where a shard went (stdout stays empty: the study is printed by `mtsim merge`).
fn wrote_shard(path: &Path) {
    super::note(&format!(
        "wrote {}: join the shards with `mtsim merge`",
        path.display()
    ));
}

fn shard_dir(output: Option<&Path>) -> Result<&Path> {
    output.ok_or_else(|| Error::usage("--shard needs -o DIR, the folder for the shard file"))
}

#[allow(clippy::too_many_arguments)]
pub fn sweep(
    path: &Path,
    param: SweepParam,
    from: f64,
    to: f64,
    step: f64,
    as_json: bool,
    output: Option<&Path>,
    shard: Option<Shard>,
) -> Result<i32> {
    let scenario = Scenario::load(path)?;
    let (cone, _) = cone_of(&scenario, "sweep")?;
    let values = grid(from, to, step)?;
    let header = SweepHeader {
        scenario: path.display().to_string(),
        param,
        grid: [from, to, step],
        cone: [
            cone.half_apex_deg,
            cone.inclination_deg,
            cone.ballbar_length_mm,
        ],
    };
    let range = shard.unwrap_or(Shard::WHOLE).range(values.len());
    let bar = progress_bar(range.len() as u64, "sweep");
    let part = sweep_part(&scenario.machine, &cone, param, &values, range, &|| {
        bar.inc(1)
    })?;
    bar.finish_and_clear();
    if let Some(shard) = shard {
        let file = ShardFile::new(
            "sweep",
            shard,
            values.len(),
            scenario_hash(&scenario),
            header,
            part,
        );
        wrote_shard(&file.write(shard_dir(output)?, &format!("sweep-{}", param.name()))?);
        return Ok(0);
    }
    let result = SweepResult::join(param.name(), vec![part]);
    emit_sweep(&header, &result, as_json, output)
}

/// Writes a sweep's files and prints it: the same for a whole run and for merged shards.
pub(crate) fn emit_sweep(
    header: &SweepHeader,
    result: &SweepResult,
    as_json: bool,
    output: Option<&Path>,
) -> Result<i32> {
    let param = header.param;
    if let Some(dir) = output {
        let run_dir = RunDir::begin(dir)?;
        let stem = format!("sweep-{}", param.name());
        let [csv_name, parquet_name, svg_name] =
            ["csv", "parquet", "svg"].map(|ext| format!("{stem}.{ext}"));
        let staged = |name: &str| run_dir.path().join(name);
        write_atomic(&staged(&csv_name), &result.to_csv()?)?;
        write_atomic(&staged(&parquet_name), &result.to_parquet()?)?;
        let title = format!(
            "Reversal angles vs {} (half apex {} deg, inclination {} deg, L {} mm)",
            param.name(),
            header.cone[0],
            header.cone[1],
            header.cone[2]
        );
        write_atomic(
            &staged(&svg_name),
            result.to_svg(param.unit(), &title)?.as_bytes(),
        )?;
        run_dir.commit()?;
        super::note(&format!(
            "wrote {}, {} and {}",
            dir.join(csv_name).display(),
            dir.join(parquet_name).display(),
            dir.join(svg_name).display()
        ));
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

/// What identifies a placement map.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct PlacementHeader {
    pub scenario: String,
    pub params: [SweepParam; 2],
    /// Per parameter: from, to, step.
    pub grid: [[f64; 3]; 2],
    /// The scenario's own values of the two parameters, marked on the map.
    pub scenario_at: [f64; 2],
    /// Radius of the rotary table, mm (its outline on the map).
    pub table_radius_mm: f64,
}

#[allow(clippy::too_many_arguments)]
pub fn placement(
    path: &Path,
    vary: &[SweepParam],
    from: &[f64],
    to: &[f64],
    step: &[f64],
    as_json: bool,
    output: Option<&Path>,
    shard: Option<Shard>,
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
    let (scenario_at, table_radius_mm) =
        crate::study::placement::scenario_marks(&scenario, [px, py]);
    let header = PlacementHeader {
        scenario: scenario.path.display().to_string(),
        params: [px, py],
        grid: [0, 1].map(|i| [pick(from, i), pick(to, i), pick(step, i)]),
        scenario_at,
        table_radius_mm,
    };
    let n = xs.len() * ys.len();
    let range = shard.unwrap_or(Shard::WHOLE).range(n);
    let bar = progress_bar(range.len() as u64, "placement");
    let cells = placement_cells(&scenario, [px, py], &xs, &ys, range, &|| bar.inc(1))?;
    bar.finish_and_clear();
    if let Some(shard) = shard {
        let file = ShardFile::new(
            "placement",
            shard,
            n,
            scenario_hash(&scenario),
            header,
            cells,
        );
        wrote_shard(&file.write(shard_dir(output)?, "placement")?);
        return Ok(0);
    }
    let map = PlacementMap {
        params: [px.name().to_string(), py.name().to_string()],
        cells,
        scenario_at: header.scenario_at,
        table_radius_mm: header.table_radius_mm,
    };
    emit_placement(&header, &map, as_json, output)
}

/// Writes a placement map's files and prints it: the same for a whole run and for merged shards.
pub(crate) fn emit_placement(
    header: &PlacementHeader,
    map: &PlacementMap,
    as_json: bool,
    output: Option<&Path>,
) -> Result<i32> {
    if let Some(dir) = output {
        let run_dir = RunDir::begin(dir)?;
        let staged = |name: &str| run_dir.path().join(name);
        write_atomic(&staged("placement.csv"), &map.to_csv()?)?;
        write_atomic(&staged("placement.parquet"), &map.to_parquet()?)?;
        let title = format!(
            "Where the test fits: {} (smallest margin, mm)",
            header.scenario
        );
        write_atomic(&staged("placement.svg"), map.to_svg(&title)?.as_bytes())?;
        run_dir.commit()?;
        super::note(&format!(
            "wrote {}, {} and {}",
            dir.join("placement.csv").display(),
            dir.join("placement.parquet").display(),
            dir.join("placement.svg").display()
        ));
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
