//! `mtsim fit` of the linear axes' squareness (ISO 230-1 `EC0Y`, `EB0Z`, `EA0Z`) from
//! circles in the three planes, as a Ballbar user measures it: traces made by `simulate`
//! on the three-axis machine with hidden squareness plus 0.2 um of noise, fitted with the
//! square machine.

use crate::common;

use std::path::{Path, PathBuf};

use super::fit::{assert_recovered, machine_with_errors, measure, param, run_fit};

/// The hidden squareness, urad.
const HIDDEN: [(&str, f64); 3] = [("EC0Y", 40.0), ("EB0Z", -25.0), ("EA0Z", 30.0)];

/// A circle of radius 100 mm in `plane` about the origin, both directions, on `machine`,
/// written as `dir/<name>-<plane>.toml`.
fn circle(dir: &Path, name: &str, plane: &str, machine: &Path) -> PathBuf {
    let path = dir.join(format!("{name}-{plane}.toml"));
    let text = format!(
        "machine = {:?}\n[program.circle]\nplane = \"{plane}\"\nradius_mm = 100.0\n\
         feed_mm_min = 2000.0\ndirections = [\"ccw\", \"cw\"]\ncenter_mm = [0.0, 0.0, 0.0]\n\
         [simulate]\ntrace_every = 10\n[check]\ncollisions = false\n",
        machine.display().to_string()
    );
    std::fs::write(&path, text).unwrap();
    path
}

/// Done when: `fit` recovers the three squareness values from circles in XY, YZ and ZX
/// within their standard errors (here: within 3 of them, and within 1 urad).
#[test]
fn circles_in_three_planes_recover_the_squareness() {
    let dir = common::scratch("fit", "squareness");
    let base = Path::new(&common::machine("vmc-3axis")).to_path_buf();
    let hidden = machine_with_errors(&base, &dir, "hidden", &HIDDEN);
    let square = machine_with_errors(&base, &dir, "square", &[]);
    let mut pairs = Vec::new();
    for (k, plane) in ["XY", "YZ", "ZX"].into_iter().enumerate() {
        let made = circle(&dir, "made", plane, &hidden);
        let measured = measure(&dir, &format!("m-{plane}"), &made, 0.2, 11 + k as u64);
        pairs.push((circle(&dir, "fitted", plane, &square), measured));
    }
    let pairs: Vec<(&Path, &Path)> = pairs
        .iter()
        .map(|(s, m)| (s.as_path(), m.as_path()))
        .collect();
    let fit = run_fit(&dir, &pairs);
    for (name, truth) in HIDDEN {
        let p = param(&fit, name);
        let (v, se) = (
            p["value"].as_f64().unwrap(),
            p["standard_error"].as_f64().unwrap(),
        );
        println!("{name}: fitted {v:.3} urad ± {se:.3}, hidden {truth}");
        assert_recovered(&fit, name, truth);
        assert!(
            (v - truth).abs() <= 3.0 * se,
            "{name}: {v} is {} standard errors from {truth}",
            (v - truth).abs() / se
        );
    }
}
