//! Seeded coverage of `mtsim fit`: traces made by the simulator's forward model (`simulate`
//! with a machine of known errors), AR(1) noise added from a fixed seed, fitted with the
//! error-free machine. Every parameter flagged identifiable must lie within 3 of its
//! standard errors of the truth, under correlated noise, with a parameter the tests barely
//! see set nonzero (aliasing), and with the table ball 0.05-1 mm from where the scenario
//! says (misplacement). The truth is the machine file's, never the fit's own output.

use crate::common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde_json::Value;

use super::fit::{machine_with_errors, param, simulate_trace, with_noise, Noise};

/// AR(1) noise: correlation 0.9 from point to point (0.2 deg apart), 0.3 um marginal.
const PHI: f64 = 0.9;
const SIGMA: f64 = 0.3;

/// AR(1) noise of marginal `sigma` um and correlation `phi` from point to point.
#[derive(Clone, Copy)]
struct Ar1 {
    sigma: f64,
    phi: f64,
}

/// A cone scenario on `machine` (both directions, F2000, one point in ten), with the
/// table ball `shift_um` from the cone's centre, written as `dir/<name>.toml`.
fn cone(
    dir: &Path,
    name: &str,
    machine: &Path,
    cone: (f64, f64, f64),
    shift_um: [f64; 3],
) -> PathBuf {
    let (alpha, beta, zt) = cone;
    let ball = if shift_um == [0.0; 3] {
        String::new()
    } else {
        format!(
            "[ballbar]\npivot_mm = [{}, {}, {}]\n",
            shift_um[0] * 1e-3,
            shift_um[1] * 1e-3,
            zt + shift_um[2] * 1e-3
        )
    };
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(
        &path,
        format!(
            "machine = {:?}\n{ball}[program.cone]\nhalf_apex_deg = {alpha}\ninclination_deg = {beta}\n\
             center_mm = [0.0, 0.0, {zt}]\nballbar_length_mm = 100.0\nfeed_mm_min = 2000.0\n\
             directions = [\"ccw\", \"cw\"]\n[simulate]\ntrace_every = 10\n",
            machine.display().to_string()
        ),
    )
    .unwrap();
    path
}

/// The clean traces of `tests` ((cone, ball shift um)) on a trt-ac machine with `errors`,
/// and the scenarios to fit them with (the nominal machine, the ball where they say).
struct Case {
    clean: Vec<Vec<(String, f64, String)>>,
    scenarios: Vec<PathBuf>,
    dir: PathBuf,
    noise: Ar1,
}

fn case(
    name: &str,
    errors: &[(&str, f64)],
    tests: &[((f64, f64, f64), [f64; 3])],
    noise: Ar1,
) -> Case {
    let dir = common::scratch("fit-coverage", name);
    let base = PathBuf::from(common::trt_ac());
    let truth = machine_with_errors(&base, &dir, "truth", errors);
    let nominal = machine_with_errors(&base, &dir, "nominal", &[]);
    let mut clean = Vec::new();
    let mut scenarios = Vec::new();
    for (i, (c, shift)) in tests.iter().enumerate() {
        let s_true = cone(&dir, &format!("true{i}"), &truth, *c, *shift);
        clean.push(simulate_trace(&dir, &format!("t{i}"), &s_true));
        scenarios.push(cone(&dir, &format!("fit{i}"), &nominal, *c, [0.0; 3]));
    }
    Case {
        clean,
        scenarios,
        dir,
        noise,
    }
}

/// Fits the case's traces with AR(1) noise of `seed` added; fit.json and stderr.
fn fit_seed(case: &Case, seed: u64, extra: &[&str]) -> (Value, String) {
    let mut args: Vec<String> = vec!["fit".into()];
    for (i, (clean, scenario)) in case.clean.iter().zip(&case.scenarios).enumerate() {
        let mut noise = Noise(0x5eed_0000 + 97 * seed + i as u64);
        let mut e = 0.0;
        // Start in the stationary distribution: marginal σ from the first point on.
        let mut first = true;
        let Ar1 { sigma, phi } = case.noise;
        let mut ar = || {
            let g = noise.gauss();
            e = if first {
                sigma * g
            } else {
                phi * e + (1.0 - phi * phi).sqrt() * sigma * g
            };
            first = false;
            e
        };
        let m = with_noise(&case.dir, &format!("m{i}"), clean, &mut ar);
        args.extend([
            scenario.display().to_string(),
            "--measured".into(),
            m.display().to_string(),
        ]);
    }
    args.extend([
        "-o".into(),
        case.dir.join("fit").display().to_string(),
        "--json".into(),
    ]);
    args.extend(extra.iter().map(|s| s.to_string()));
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let out = common::mtsim(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    (
        common::stdout_json(&out),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Every location error flagged identifiable: (name, value, standard error).
fn identified(fit: &Value) -> Vec<(String, f64, f64)> {
    fit["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| p["identifiable"] == true && p["name"].as_str().unwrap().starts_with('E'))
        .map(|p| {
            (
                p["name"].as_str().unwrap().to_string(),
                p["value"].as_f64().unwrap(),
                p["standard_error"].as_f64().unwrap(),
            )
        })
        .collect()
}

/// Runs `seeds` and checks coverage: every identifiable location error within 3 standard
/// errors of `truth` (absent: 0). Returns the largest |error|/se per parameter, printed.
fn assert_coverage(
    label: &str,
    case: &Case,
    truth: &[(&str, f64)],
    seeds: u64,
    extra: &[&str],
) -> Vec<Value> {
    let truth: BTreeMap<&str, f64> = truth.iter().copied().collect();
    let mut worst: BTreeMap<String, f64> = BTreeMap::new();
    let mut failures = Vec::new();
    let mut fits = Vec::new();
    for seed in 0..seeds {
        let (fit, _) = fit_seed(case, seed, extra);
        for (name, v, se) in identified(&fit) {
            let t = truth.get(name.as_str()).copied().unwrap_or(0.0);
            let z = (v - t) / se;
            let w = worst.entry(name.clone()).or_insert(0.0);
            if z.abs() > w.abs() {
                *w = z;
            }
            if z.abs() > 3.0 {
                failures.push(format!(
                    "seed {seed}: {name} = {v} +- {se}, truth {t} ({z:+.1} se)"
                ));
            }
        }
        fits.push(fit);
    }
    eprintln!("{label}: largest (estimate - truth)/se per identifiable parameter: {worst:?}");
    assert!(
        failures.is_empty(),
        "{label}: identifiable parameters beyond 3 standard errors of the truth:\n{}",
        failures.join("\n")
    );
    fits
}

/// The hidden errors of fit.rs's tests (um, urad).
const HIDDEN: [(&str, f64); 8] = [
    ("EY0A", 6.0),
    ("EZ0A", -9.0),
    ("EB0A", 25.0),
    ("EC0A", -30.0),
    ("EX0C", 8.0),
    ("EY0C", -5.0),
    ("EA0C", -15.0),
    ("EB0C", 20.0),
];

/// The exact model under AR(1) noise: no residual warning, the noise level reported within
/// 30 % of the truth (where the white-noise estimate reads it 3.8 times too small), and
/// coverage over three seeds, with the placement fitted and known.
#[test]
fn correlated_noise_gives_no_warning_and_is_covered() {
    let c = case(
        "ar1",
        &HIDDEN,
        &[
            ((15.0, 10.0, 200.0), [0.0; 3]),
            ((45.0, 30.0, 200.0), [0.0; 3]),
        ],
        Ar1 {
            sigma: SIGMA,
            phi: PHI,
        },
    );
    for extra in [&[][..], &["--placement-known"][..]] {
        let fits = assert_coverage(&format!("AR(1) {extra:?}"), &c, &HIDDEN, 3, extra);
        for fit in &fits {
            assert!(
                fit["warnings"].as_array().unwrap().is_empty(),
                "an exact model warned: {}",
                fit["warnings"]
            );
            for t in fit["traces"].as_array().unwrap() {
                let noise = t["noise"]["noise_um"].as_f64().unwrap();
                assert!(
                    (noise / SIGMA - 1.0).abs() < 0.3,
                    "noise {noise} um reported, {SIGMA} um added"
                );
                let phi = t["noise"]["correlation"].as_f64().unwrap();
                assert!((phi - PHI).abs() < 0.08, "correlation {phi}, {PHI} added");
            }
        }
    }
}

/// Aliasing: on a single 15/10 cone EB0A moves the traces by less than 0.01 um per urad,
/// and 25 urad of it, hidden, used to leak into EC0A and EZ0A (many standard errors off,
/// flagged identifiable). Now whatever is flagged identifiable is covered, and EB0A is
/// named: kept as a nuisance or in a combination, never silently dropped. (AR(1) noise of
/// 0.05 um, correlation 0.9: small enough that the leak stands out.)
#[test]
fn a_barely_seen_parameter_does_not_leak_into_the_others() {
    let truth = [("EB0A", 25.0)];
    let c = case(
        "alias",
        &truth,
        &[((15.0, 10.0, 200.0), [0.0; 3])],
        Ar1 {
            sigma: 0.05,
            phi: 0.9,
        },
    );
    for extra in [&["--placement-known"][..], &[][..]] {
        let fits = assert_coverage(&format!("EB0A alias {extra:?}"), &c, &truth, 3, extra);
        for fit in &fits {
            let p = param(fit, "EB0A");
            if p["identifiable"] == false {
                let named = fit["unidentifiable"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .any(|n| n["direction"].as_object().unwrap().contains_key("EB0A"));
                assert!(named, "EB0A is neither fitted nor named: {fit}");
            }
        }
    }
}

/// Misplacement: the table ball 0.06, 0.4 and 1 mm from where each of three cones says,
/// AR(1) noise of 0.05 um (correlation 0.5). The fit iterates the nonlinear model, so every
/// identifiable parameter is covered (one linearisation at the nominal ball left EY0A
/// 0.3 um off at 1 mm, 5 standard errors).
#[test]
fn a_misplaced_ball_up_to_1_mm_is_fitted_without_bias() {
    let tests = [
        ((15.0, 10.0, 200.0), [50.0, -30.0, 20.0]),
        ((45.0, 30.0, 200.0), [-300.0, 200.0, 150.0]),
        ((15.0, 10.0, 100.0), [700.0, 600.0, -400.0]),
    ];
    let c = case(
        "misplaced",
        &HIDDEN,
        &tests,
        Ar1 {
            sigma: 0.05,
            phi: 0.5,
        },
    );
    let fits = assert_coverage("misplaced 0.05-1 mm", &c, &HIDDEN, 3, &[]);
    for fit in &fits {
        assert!(
            fit["warnings"].as_array().unwrap().is_empty(),
            "{}",
            fit["warnings"]
        );
        // The placement itself comes back (to within 3 standard errors, or where it is
        // inseparable from the bar offset or EZ0A, not at all).
        for (k, (_, shift)) in tests.iter().enumerate() {
            for (i, axis) in ["x", "y", "z"].iter().enumerate() {
                let p = param(fit, &format!("setup_{axis}[{k}]"));
                if p["identifiable"] == true {
                    let (v, se) = (
                        p["value"].as_f64().unwrap(),
                        p["standard_error"].as_f64().unwrap(),
                    );
                    assert!((v - shift[i]).abs() <= 3.0 * se, "{p}: truth {}", shift[i]);
                }
            }
        }
        assert!(identified(fit).len() >= 4, "{fit}");
    }
}
