//! `mtsim cut` as a user meets it: the files it writes agree with each other (the CSV, the
//! Parquet table, cut.json and the pictures), and bad input is a clear error with exit 2.

use mtsim::report::parquet::{Column, Table};

use crate::common;

#[test]
fn cut_writes_the_surface_its_figures_and_pictures_that_agree() {
    let dir = common::scratch("cut-cli", "files");
    let out = dir.join("cut");
    let out_str = out.display().to_string();
    let run = common::mtsim(&[
        "cut",
        "scenarios/cone-15-10.toml",
        "-o",
        &out_str,
        "--heights-mm",
        "30,40,50",
        "--json",
    ]);
    let figures = common::stdout_json(&run);
    // cut.json is what --json printed.
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("cut.json")).unwrap()).unwrap();
    assert_eq!(written, figures);
    let heights: Vec<f64> = figures["heights"]
        .as_array()
        .unwrap()
        .iter()
        .map(|h| h["z_mm"].as_f64().unwrap())
        .collect();
    assert_eq!(heights, vec![30.0, 40.0, 50.0]);
    // The default tool of trt-ac: a 20 mm cutter.
    assert_eq!(figures["cutter_radius_mm"], 10.0);
    let csv = std::fs::read_to_string(out.join("surface.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("theta_deg,z_mm,deviation_um"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len() as u64, figures["grid_points"].as_u64().unwrap());
    let empty = rows.iter().filter(|r| r[2].is_empty()).count() as u64;
    assert_eq!(empty, figures["not_cut_points"].as_u64().unwrap());
    // 3,600 columns at the default step, by height then θ.
    assert_eq!(rows[1][0], "0.1000");
    let table = Table::read_parquet(&out.join("surface.parquet"), &|_| true).unwrap();
    let Some(Column::F64(d)) = table.column("deviation_um") else {
        panic!("deviation_um is a float column")
    };
    assert_eq!(d.len(), rows.len());
    for (row, d) in rows.iter().zip(d) {
        match d {
            None => assert!(row[2].is_empty()),
            Some(d) => assert!((row[2].parse::<f64>().unwrap() - d).abs() <= 0.5e-4),
        }
    }
    // The pictures: a polar panel per height, a marker per reversal of the marks.
    let polar = std::fs::read_to_string(out.join("roundness.svg")).unwrap();
    assert_eq!(polar.matches("roundness ").count(), 3);
    let map = std::fs::read_to_string(out.join("surface.svg")).unwrap();
    assert!(map.contains("θ (deg)") && map.contains("d (µm)"));
}

#[test]
fn cut_refuses_a_scenario_without_a_cone_and_heights_off_the_flank() {
    let dir = common::scratch("cut-cli", "bad");
    let out = dir.join("cut").display().to_string();
    let run = common::mtsim(&["cut", "scenarios/circle-iso230-4.toml", "-o", &out]);
    assert_eq!(run.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&run.stderr).contains("no cone to cut"));
    let run = common::mtsim(&[
        "cut",
        "scenarios/cone-15-10.toml",
        "-o",
        &out,
        "--heights-mm",
        "5",
    ]);
    assert_eq!(run.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&run.stderr).contains("on the flank contact"));
    let run = common::mtsim(&[
        "cut",
        "scenarios/cone-15-10.toml",
        "-o",
        &out,
        "--theta-step-deg",
        "0.7",
    ]);
    assert_eq!(run.status.code(), Some(2));
    assert!(!dir.join("cut").exists(), "nothing is written on bad input");
}

/// `simulate --cut` cuts the same piece as `cut`, by `cut`'s own path: its cut in
/// summary.json is `cut`'s cut.json to the bit (figures, marks, error budget), the cut's
/// files are in the run folder and the run's report page has the cut's section.
#[test]
fn simulate_with_cut_reports_what_cut_reports() {
    let dir = common::scratch("cut-cli", "simulate");
    let sim = dir.join("sim");
    let cut = dir.join("cut").display().to_string();
    let s = common::stdout_json(&common::mtsim(&[
        "simulate",
        "scenarios/cone-15-10.toml",
        "-o",
        &sim.display().to_string(),
        "--cut",
        "--html",
        "--json",
    ]));
    let c = common::stdout_json(&common::mtsim(&[
        "cut",
        "scenarios/cone-15-10.toml",
        "-o",
        &cut,
        "--json",
    ]));
    let from_simulate = &s["measurements"]["cut"];
    assert_eq!(from_simulate, &c);
    let marks = c["marks"].as_array().unwrap();
    assert!(
        !marks.is_empty(),
        "trt-ac's friction wind-up marks the cone"
    );
    assert!(c["budget"]["rows"]
        .as_array()
        .is_some_and(|r| !r.is_empty()));
    for f in [
        "cut.json",
        "surface.csv",
        "surface.parquet",
        "cut.html",
        "surface.svg",
        "roundness.svg",
    ] {
        assert!(sim.join(f).exists(), "{f} in the run folder");
    }
    let page = std::fs::read_to_string(sim.join("report.html")).unwrap();
    assert!(
        page.contains("id=\"cut\""),
        "the report has the cut's section"
    );
    assert!(page.contains("href=\"cut.html\""));
}
