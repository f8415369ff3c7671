//! `mtsim fit`: location errors (and optionally backlash, servo gain) from measured traces.

use std::path::{Path, PathBuf};

use super::{print_stdout, spinner};
use crate::error::{Error, Result};
use crate::input::scenario::Scenario;
use crate::study::fit::{
    fit, FitOptions, MeasuredTrace, FIT_JSON, FIT_PAGE, FIT_PLOT, FRAGMENT_FILE,
};

pub fn run(
    scenarios: &[PathBuf],
    measured: &[PathBuf],
    out_dir: &Path,
    options: FitOptions,
    as_json: bool,
) -> Result<i32> {
    if scenarios.len() != measured.len() || scenarios.is_empty() {
        return Err(Error::usage(format!(
            "give one --measured TRACE.csv per scenario, in order (got {} scenarios and {} traces): \
             mtsim fit A.toml --measured a.csv B.toml --measured b.csv -o DIR",
            scenarios.len(),
            measured.len()
        )));
    }
    let mut inputs = Vec::new();
    for (s, m) in scenarios.iter().zip(measured) {
        inputs.push((Scenario::load(s)?, MeasuredTrace::read(m)?));
    }
    let bar = spinner("fitting");
    // The measured traces often sit in the folder of the run that made them: they stay.
    let run_dir = crate::report::RunDir::begin(out_dir)?
        .reads(scenarios)
        .reads(measured);
    let report = fit(&inputs, &options, run_dir.path())?;
    run_dir.commit()?;
    bar.finish_and_clear();
    for w in report.warnings.iter().chain(&report.cautions) {
        eprintln!("warning: {w}");
    }
    for n in &report.notes {
        eprintln!("note: {n}");
    }
    if as_json {
        print_stdout(&format!(
            "{}\n",
            serde_json::to_string_pretty(&report).expect("plain data serializes")
        ));
        return Ok(0);
    }
    let mut out = format!(
        "{:<16} {:>12} {:>12}  {}\n",
        "parameter", "value", "std error", "identifiable"
    );
    for p in &report.parameters {
        let v = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.3}"));
        out.push_str(&format!(
            "{:<16} {:>12} {:>12}  {} {}\n",
            p.name,
            v(p.value),
            v(p.standard_error),
            if p.identifiable { "yes" } else { "no" },
            p.unit
        ));
    }
    for t in &report.traces {
        out.push_str(&format!(
            "{}: residual RMS {:.3} um (noise {:.3} um, correlation {:.2} from point to point, \
             trace RMS {:.3} um), matched {}, bar offset {}\n",
            t.measured.display(),
            t.residual_rms_um,
            t.noise.noise_um,
            t.noise.correlation,
            t.measured_rms_um,
            if t.matched == "weakly" {
                "weakly (no commanded columns)"
            } else {
                "by its commanded columns"
            },
            t.bar_offset_um
                .map_or("not separable".to_string(), |b| format!("{b:+.3} um"))
        ));
    }
    for n in &report.unidentifiable {
        out.push_str(&format!("not separable: {}\n", n.description));
    }
    if let Some(s) = &report.suggestion {
        out.push_str(&format!("next test: {}\n", s.text));
    }
    out.push_str(&format!(
        "wrote {}/{{{FIT_JSON}, {FRAGMENT_FILE}, {FIT_PLOT}, {FIT_PAGE}}}\n",
        out_dir.display()
    ));
    print_stdout(&out);
    Ok(0)
}
