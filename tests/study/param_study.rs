//! `mtsim study`: figures against closed forms (lost motion, servo mismatch), the Wilson
//! interval against published values, reproducibility, shards, and the errors of bad keys
//! and values.

use std::path::{Path, PathBuf};

use mtsim::study::param::stats::{spearman, wilson, Z95};

use crate::common::{mtsim, scratch};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Writes a study file on the bundled scenario `scenario` with the `[[vary]]` tables `vary`.
fn study_file(dir: &Path, scenario: &str, top: &str, vary: &str) -> PathBuf {
    let path = dir.join("study.toml");
    let base = root().join("scenarios").join(scenario);
    let text = format!("scenario = {:?}\n{top}\n{vary}", base.display().to_string());
    std::fs::write(&path, text).unwrap();
    path
}

/// Runs `mtsim study` and returns the rows of rows.csv as (header, rows).
fn run(study: &Path, out: &Path, extra: &[&str]) -> (Vec<String>, Vec<Vec<String>>) {
    run_with_exit(study, out, extra, 0)
}

/// Runs `mtsim study`, checks its exit code is `code`, and returns rows.csv as (header, rows).
fn run_with_exit(
    study: &Path,
    out: &Path,
    extra: &[&str],
    code: i32,
) -> (Vec<String>, Vec<Vec<String>>) {
    let mut args = vec![
        "study",
        study.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "-q",
    ];
    args.extend_from_slice(extra);
    let o = mtsim(&args);
    assert_eq!(
        o.status.code(),
        Some(code),
        "stderr: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let mut r = csv::Reader::from_path(out.join("rows.csv")).unwrap();
    let header = r.headers().unwrap().iter().map(String::from).collect();
    let rows = r
        .records()
        .map(|rec| rec.unwrap().iter().map(String::from).collect())
        .collect();
    (header, rows)
}

fn column(header: &[String], rows: &[Vec<String>], name: &str) -> Vec<f64> {
    let i = header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name}"));
    rows.iter().map(|r| r[i].parse().unwrap()).collect()
}

/// Runs a study that must be refused (exit 2, no output folder) and returns its stderr.
fn refused(dir: &Path, vary: &str) -> String {
    let study = study_file(dir, "circle-iso230-4.toml", "", vary);
    let out = dir.join("out");
    let o = mtsim(&[
        "study",
        study.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!out.exists());
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Semi-closed loop backlash b on X shifts the two half circles by ±b/2 along X: the step
/// at X's reversals (θ = 0°, 180° on the XY circle, where the bar lies along X) grows by b
/// (docs/servo-and-ballbar.md, "Backlash b on one axis"), on top of friction's lost motion.
/// Y's reversals do not see it.
#[test]
fn the_x_reversal_step_grows_by_the_backlash() {
    let dir = scratch("study", "backlash");
    let study = study_file(
        &dir,
        "circle-iso230-4.toml",
        "",
        "[[vary]]\nkey = \"machine.axes.X.drive.backlash_mm\"\nfrom = 0.0\nto = 0.01\nstep = 0.005\n",
    );
    let (h, rows) = run(&study, &dir.join("out"), &[]);
    let b = column(&h, &rows, "machine.axes.X.drive.backlash_mm");
    let bx = column(&h, &rows, "B_X_um");
    let by = column(&h, &rows, "B_Y_um");
    assert_eq!(b, [0.0, 0.005, 0.01]);
    for i in 1..3 {
        let expected_um = (b[i] - b[0]) * 1e3;
        let grown = bx[i] - bx[0];
        // The step detector's fitted jump takes 0.92 of the lost motion: within 10 %.
        assert!(
            (grown - expected_um).abs() <= 0.10 * expected_um,
            "B_X grew by {grown} um for {expected_um} um of backlash"
        );
        assert!((by[i] - by[0]).abs() < 0.2, "B_Y moved: {by:?}");
    }
    // G rises with the backlash: the two half circles part.
    let g = column(&h, &rows, "G_um");
    assert!(g[0] < g[1] && g[1] < g[2], "{g:?}");
    let status = h.iter().position(|c| c == "status").unwrap();
    assert!(rows.iter().all(|r| r[status] == "ok"));
}

/// Gain mismatch Kvx ≠ Kvy on a circle at speed v: the axes lag by v/Kv each, the trace is
/// an ellipse of peak-to-peak `v |1/Kvx − 1/Kvy|` (docs/servo-and-ballbar.md), which
/// dominates G once it passes the rest of the trace.
#[test]
fn g_follows_the_servo_mismatch_closed_form() {
    let dir = scratch("study", "kv");
    let study = study_file(
        &dir,
        "circle-iso230-4.toml",
        "",
        "[[vary]]\nkey = \"machine.axes.X.servo.kv_per_s\"\nvalues = [24.0, 27.0, 30.0, 36.0]\n",
    );
    let (h, rows) = run(&study, &dir.join("out"), &[]);
    let kv = column(&h, &rows, "machine.axes.X.servo.kv_per_s");
    let g = column(&h, &rows, "G_um");
    let v_mm_s = 1000.0 / 60.0;
    let g_matched = g[2];
    for (k, g) in kv.iter().zip(&g) {
        let pp_um = v_mm_s * (1.0 / k - 1.0 / 30.0).abs() * 1e3;
        if pp_um == 0.0 {
            continue;
        }
        // The rest of the trace (G at matched gains) bounds the difference; the ellipse
        // swamps it: within 2 % of the closed form.
        assert!(
            (g - pp_um).abs() <= g_matched,
            "Kvx {k}: G {g} against {pp_um}"
        );
        assert!(
            (g - pp_um).abs() <= 0.02 * pp_um,
            "Kvx {k}: G {g} against {pp_um}"
        );
    }
}

/// Newcombe (1998), Table I, method 3 (Wilson score interval without continuity correction).
#[test]
fn the_wilson_interval_matches_the_published_values() {
    for (hits, n, low, high) in [
        (81, 263, 0.2553, 0.3662),
        (15, 148, 0.0624, 0.1605),
        (0, 20, 0.0, 0.1611),
        (1, 29, 0.0061, 0.1718),
    ] {
        let s = wilson(hits, n, Z95).unwrap();
        assert!((s.low - low).abs() < 6e-5, "{hits}/{n}: low {}", s.low);
        assert!((s.high - high).abs() < 6e-5, "{hits}/{n}: high {}", s.high);
    }
    assert!(wilson(1, 0, Z95).is_none());
    // Spearman's ρ by hand: ranks (1 2 3 4 5) and (2 1 4 3 5), Σd² = 4, ρ = 1 − 6·4/(5·24) = 0.8.
    let rho = spearman(&[1.0, 2.0, 3.0, 4.0, 5.0], &[20.0, 10.0, 40.0, 30.0, 50.0]).unwrap();
    assert!((rho - 0.8).abs() < 1e-12);
}

const RANDOM: &str =
    "[[vary]]\nkey = \"machine.axes.X.drive.backlash_mm\"\nuniform = [0.0, 0.01]\n\
[[vary]]\nkey = \"machine.axes.Y.servo.kv_per_s\"\nnormal = [30.0, 1.5]\nmin = 27.0\nmax = 33.0\n";

/// Same seed, the same bytes; another seed, other points. The share in study.json is the
/// Wilson interval of the rows' own count.
#[test]
fn a_random_study_is_reproducible_and_its_share_is_counted() {
    let dir = scratch("study", "random");
    let study = study_file(
        &dir,
        "circle-iso230-4.toml",
        "samples = 6\nseed = 5\ng_limit_um = 12.0",
        RANDOM,
    );
    let (h, rows) = run(&study, &dir.join("a"), &[]);
    run(&study, &dir.join("b"), &[]);
    for f in [
        "rows.csv",
        "rows.parquet",
        "study.json",
        "study.html",
        "study-share.svg",
    ] {
        let (a, b) = (
            std::fs::read(dir.join("a").join(f)).unwrap(),
            std::fs::read(dir.join("b").join(f)).unwrap(),
        );
        assert!(a == b, "{f} differs between two runs of one seed");
    }
    let x = column(&h, &rows, "machine.axes.X.drive.backlash_mm");
    let kv = column(&h, &rows, "machine.axes.Y.servo.kv_per_s");
    assert_eq!(rows.len(), 6);
    assert!(x.iter().all(|v| (0.0..0.01).contains(v)));
    assert!(kv.iter().all(|v| (27.0..=33.0).contains(v)));
    let other = study_file(
        &dir,
        "circle-iso230-4.toml",
        "samples = 6\nseed = 6\ng_limit_um = 12.0",
        RANDOM,
    );
    let (_, rows2) = run(&other, &dir.join("c"), &[]);
    assert_ne!(rows, rows2);
    let g = column(&h, &rows, "G_um");
    let hits = g.iter().filter(|&&g| g < 12.0).count() as u64;
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("a/study.json")).unwrap()).unwrap();
    let share = &summary["g_below_limit"];
    assert_eq!(share["hits"], hits);
    let expected = wilson(hits, 6, Z95).unwrap();
    assert_eq!(share["low"].as_f64().unwrap(), expected.low);
    assert_eq!(summary["sensitivity"].as_array().unwrap().len(), 2);
}

/// Three shards joined by `mtsim merge` write the files of the whole run, byte for byte.
#[test]
fn merged_shards_equal_the_whole_study() {
    let dir = scratch("study", "shards");
    let study = study_file(
        &dir,
        "circle-iso230-4.toml",
        "samples = 5\nseed = 9\ng_limit_um = 12.0",
        RANDOM,
    );
    let s = study.to_str().unwrap();
    for k in 1..=3 {
        let shard = format!("{k}/3");
        let o = mtsim(&[
            "study",
            s,
            "--shard",
            &shard,
            "-o",
            dir.join("shards").to_str().unwrap(),
            "-q",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let files: Vec<String> = (1..=3)
        .map(|k| {
            dir.join(format!("shards/study.shard-{k}-of-3.json"))
                .display()
                .to_string()
        })
        .collect();
    let mut args = vec!["merge"];
    args.extend(files.iter().map(String::as_str));
    let merged = dir.join("merged");
    args.extend(["-o", merged.to_str().unwrap(), "-q"]);
    assert!(mtsim(&args).status.success());
    run(&study, &dir.join("whole"), &[]);
    let mut names: Vec<String> = std::fs::read_dir(dir.join("whole"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert!(
        names.contains(&"rows.parquet".to_string()) && names.contains(&"study.html".to_string())
    );
    for f in names {
        let whole = std::fs::read(dir.join("whole").join(&f)).unwrap();
        let joined = std::fs::read(merged.join(&f)).unwrap();
        assert!(
            whole == joined,
            "{f} differs between the merged and the whole study"
        );
    }
}

#[test]
fn a_key_that_names_nothing_is_refused_with_the_nearest_keys() {
    let dir = scratch("study", "badkey");
    let err = refused(
        &dir,
        "[[vary]]\nkey = \"machine.axes.X.drive.bakclash_mm\"\nvalues = [0.0]\n",
    )
    .replace(['\n', '│', ' '], "");
    assert!(err.contains("`machine.axes.X.drive.bakclash_mm`"), "{err}");
    assert!(
        err.contains("nearest:`machine.axes.X.drive.backlash_mm`"),
        "{err}"
    );
}

#[test]
fn a_nan_value_is_a_located_error() {
    let dir = scratch("study", "nan");
    let err = refused(
        &dir,
        "[[vary]]\nkey = \"machine.axes.X.drive.backlash_mm\"\nvalues = [0.0, nan]\n",
    );
    // The line of `values` (line 5: scenario, the empty top keys, [[vary]], key, values).
    assert!(err.contains("study.toml:5:1"), "{err}");
    assert!(err.contains("`vary.values`: is not a number"), "{err}");
}

/// A value the scenario refuses fails its point only; the others run, and the exit code is
/// 1, as `batch`'s when a scenario failed.
#[test]
fn a_failing_point_does_not_stop_the_study() {
    let dir = scratch("study", "failing");
    let study = study_file(
        &dir,
        "circle-iso230-4.toml",
        "",
        "[[vary]]\nkey = \"machine.axes.X.drive.backlash_mm\"\nvalues = [-0.01, 0.0]\n",
    );
    let (h, rows) = run_with_exit(&study, &dir.join("out"), &[], 1);
    let (status, error) = (
        h.iter().position(|c| c == "status").unwrap(),
        h.iter().position(|c| c == "error").unwrap(),
    );
    assert_eq!(rows[0][status], "error");
    assert!(
        rows[0][error].contains("backlash_mm") && rows[0][error].contains(">= 0"),
        "{:?}",
        rows[0]
    );
    assert_eq!(rows[1][status], "ok");
    assert!(column(&h, &rows[1..], "G_um")[0] > 0.0);
}

/// A key path of 20,000 parts is refused with exit 2 (it once overflowed the stack).
#[test]
fn a_key_path_of_twenty_thousand_parts_is_refused() {
    let dir = scratch("study", "deep-key");
    let key = vec!["a"; 20_000].join(".");
    let study = study_file(
        &dir,
        "circle-iso230-4.toml",
        "",
        &format!("[[vary]]\nkey = \"{key}\"\nvalues = [1.0]\n"),
    );
    let o = mtsim(&[
        "study",
        study.to_str().unwrap(),
        "-o",
        dir.join("out").to_str().unwrap(),
    ]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("more than 32 parts"));
}

/// The tolerance study of docs/studies.md, with 20 of its 1,000 points: its table, plots and
/// page are written.
#[test]
fn the_bundled_tolerance_study_runs_a_trial_of_twenty_points() {
    let dir = scratch("study", "tolerance");
    let study = root().join("scenarios/studies/tolerance-cone-15-10.toml");
    let (h, rows) = run(&study, &dir.join("out"), &["--samples", "20"]);
    assert_eq!(rows.len(), 20);
    assert!(
        h.contains(&"B_C_um".to_string())
            && h.contains(&"machine.axes.Y.servo.kv_per_s".to_string())
    );
    let page = std::fs::read_to_string(dir.join("out/study.html")).unwrap();
    for plot in ["study-share", "study-sensitivity"] {
        assert!(
            page.contains(&format!("data-plot=\"{plot}\"")),
            "{plot} missing"
        );
        assert!(dir.join(format!("out/{plot}.svg")).exists());
    }
    let verdict = h.iter().position(|c| c == "verdict").unwrap();
    assert!(rows
        .iter()
        .all(|r| r[verdict] == "clean" || r[verdict] == "violations"));
}

/// A `machine.` key whose next step repeats `machine` is a key the machine lacks, refused
/// with the keys the machine file has (it once sliced its path out of range and panicked).
#[test]
fn a_machine_key_named_twice_is_refused_not_a_panic() {
    let dir = scratch("study", "machine-twice");
    let err = refused(
        &dir,
        "[[vary]]\nkey = \"machine.machine.x\"\nvalues = [1.0]\n",
    )
    .replace(['\n', '│', ' '], "");
    assert!(err.contains("`machine`isnotakeythere"), "{err}");
    assert!(err.contains("nearest:`machine."), "{err}");
}

/// A point's scenario is built from the base's parsed tree (`ScenarioTree::load_with`, no
/// text written, the machine file read once): it is the scenario the point's text gives
/// when read as a file, and a refused value is the same error at the same line, column and
/// key of that text.
#[test]
fn a_point_built_from_the_tree_is_the_scenario_of_its_text() {
    use mtsim::input::overrides::{set, KeyPath, ScenarioTree};
    use mtsim::input::scenario::Scenario;
    let by_text = |tree: &ScenarioTree, keys: &[KeyPath], values: &[f64]| {
        let mut t = tree.tree.clone();
        for (k, &v) in keys.iter().zip(values) {
            set(&mut t, &tree.machine, k, v).unwrap();
        }
        Scenario::from_toml(&tree.path, &toml::to_string(&t).unwrap(), None)
    };
    let keys = |ks: &[&str]| -> Vec<KeyPath> { ks.iter().map(|k| k.parse().unwrap()).collect() };
    let cone = ScenarioTree::read(&root().join("scenarios/cone-15-10.toml")).unwrap();
    let cone_keys = keys(&[
        "machine.axes.X.drive.backlash_mm",
        "machine.axes.Y.servo.kv_per_s",
        "program.cone.center_mm[1]",
        "program.cone.segments",
        "machine.location_errors.EX0C_um",
    ]);
    let values = [0.004, 31.0, 25.0, 720.0, 3.0];
    let point = cone.load_with(&cone_keys, &values).unwrap();
    assert_eq!(
        format!("{point:?}"),
        format!("{:?}", by_text(&cone, &cone_keys, &values).unwrap())
    );
    assert_eq!(
        point.machine.drive(mtsim::Axis::X).backlash_mm_or_deg,
        0.004
    );
    assert_eq!(point.machine.drive(mtsim::Axis::Y).kv_per_s, 31.0);
    assert_eq!(point.cone().unwrap().center_mm.y, 25.0);
    // The circle sizes its lead-in unless `[simulate] lead_deg` is given.
    let circle = ScenarioTree::read(&root().join("scenarios/circle-iso230-4.toml")).unwrap();
    for ks in [&["program.circle.radius_mm"][..], &["simulate.lead_deg"]] {
        let ks = keys(ks);
        let point = circle.load_with(&ks, &[40.0]).unwrap();
        assert_eq!(
            format!("{point:?}"),
            format!("{:?}", by_text(&circle, &ks, &[40.0]).unwrap())
        );
    }
    let given = circle
        .load_with(&keys(&["simulate.lead_deg"]), &[40.0])
        .unwrap();
    assert_eq!(given.simulate.lead_deg, 40.0);
    // Refused: a drive check, a cone check at its line, a number beyond any machine.
    for (key, value, says) in [
        ("machine.axes.X.drive.backlash_mm", -0.01, ">= 0"),
        ("program.cone.segments", 2.0, "between 3 and 1000000"),
        ("program.cone.feed_mm_min", 1e12, "beyond any machine"),
    ] {
        let ks = keys(&[key]);
        let err = cone.load_with(&ks, &[value]).unwrap_err().to_string();
        assert!(err.contains(says), "{err}");
        assert_eq!(err, by_text(&cone, &ks, &[value]).unwrap_err().to_string());
    }
    let err = cone
        .load_with(&keys(&["program.cone.segments"]), &[2.0])
        .unwrap_err();
    assert!(matches!(err, mtsim::error::Error::AtSource(_)), "{err:?}");
}

/// The heat map's cells lie at their values whatever order a grid lists them in: a grid in
/// descending and unsorted order draws the cells of the ascending grid, the largest G at the
/// largest values (right, top) and the smallest at the smallest (left, bottom).
#[test]
fn the_heat_map_places_cells_by_value_in_any_grid_order() {
    use mtsim::study::param::evaluate::Row;
    use mtsim::study::param::plots::heat_map;
    let rows = |xs: &[f64], ys: &[f64]| -> Vec<Row> {
        let mut out = Vec::new();
        for &x in xs {
            for &y in ys {
                out.push(Row {
                    point: out.len() as u64 + 1,
                    values: vec![x, y],
                    error: None,
                    g_um: Some(10.0 * x + y / 10.0),
                    f_max_um: None,
                    f_min_um: None,
                    h_um: None,
                    b_um: Vec::new(),
                    spike_um: Vec::new(),
                    violations: Some(0),
                });
            }
        }
        out
    };
    // The cells: (x, y, width, height, fill) of the rectangles left of the legend (x < 760
    // px), but the white background.
    let cells = |svg: &str| -> Vec<(i64, i64, i64, i64, String)> {
        let attr = |line: &str, name: &str| -> String {
            let start = line.find(&format!(" {name}=\"")).unwrap() + name.len() + 3;
            line[start..].split('"').next().unwrap().to_string()
        };
        let mut out: Vec<_> = svg
            .lines()
            .filter(|l| l.starts_with("<rect") && !l.contains("#FFFFFF"))
            .map(|l| {
                let n = |name: &str| attr(l, name).parse::<i64>().unwrap();
                (n("x"), n("y"), n("width"), n("height"), attr(l, "fill"))
            })
            .filter(|c| c.0 < 760)
            .collect();
        out.sort();
        out
    };
    let keys = ["a", "b"];
    let (xs, ys) = ([1.0, 2.0, 3.0], [10.0, 20.0, 30.0]);
    let sorted = cells(&heat_map(&rows(&xs, &ys), keys, &xs, &ys).unwrap());
    assert_eq!(sorted.len(), 9);
    for (xs, ys) in [
        ([3.0, 2.0, 1.0], [30.0, 20.0, 10.0]),
        ([2.0, 3.0, 1.0], [20.0, 10.0, 30.0]),
    ] {
        let drawn = cells(&heat_map(&rows(&xs, &ys), keys, &xs, &ys).unwrap());
        assert_eq!(drawn, sorted, "grid {xs:?} x {ys:?}");
    }
    // Blue to red: the smallest G (a 1, b 10) is #2028DF, the largest (a 3, b 30) #DF2020.
    let at = |fill: &str| sorted.iter().find(|c| c.4 == fill).unwrap().clone();
    let (small, large) = (at("#2028DF"), at("#DF2020"));
    let (x_min, x_max) = (sorted[0].0, sorted[8].0);
    let y_min = sorted.iter().map(|c| c.1).min().unwrap();
    let y_max = sorted.iter().map(|c| c.1).max().unwrap();
    assert_eq!(
        (small.0, small.1),
        (x_min, y_max),
        "smallest G left, bottom"
    );
    assert_eq!((large.0, large.1), (x_max, y_min), "largest G right, top");
    // Three columns and three rows of cells side by side, none overlapping.
    let mut left: Vec<i64> = sorted.iter().map(|c| c.0).collect();
    left.dedup();
    assert_eq!(left.len(), 3);
    assert!((left[1] - left[0] - sorted[0].2).abs() <= 1, "{sorted:?}");
}

/// A study key may name an element of an array the machine file holds
/// (`machine.pivot_mm[2]`): the point's machine is the file's with that element changed and
/// the others kept, and its run is that of a scenario that writes the whole array out.
#[test]
fn a_study_varies_an_element_of_a_machine_array_as_a_scenario_writing_it_out() {
    use mtsim::input::overrides::{KeyPath, ScenarioTree};
    use mtsim::input::scenario::Scenario;
    use mtsim::study::simulate::run_ballbar;

    let dir = scratch("study", "array-key");
    let base = root().join("scenarios/cone-15-10.toml");
    let tree = ScenarioTree::read(&base).unwrap();
    let key: KeyPath = "machine.pivot_mm[2]".parse().unwrap();
    let g = |s: &Scenario| {
        let study = run_ballbar(s, None, &|_| {}).unwrap();
        study.result().unwrap().unwrap().circular_deviation_um
    };
    let mut gs = Vec::new();
    for z in [0.0, 25.0] {
        let point = tree.load_with(std::slice::from_ref(&key), &[z]).unwrap();
        // The same machine written out by hand: the file's X and Y of the pivot, z.
        let text = std::fs::read_to_string(&base).unwrap().replace(
            "\"../machines/",
            &format!("\"{}/machines/", root().display()),
        );
        let path = dir.join(format!("z{z}.toml"));
        std::fs::write(
            &path,
            format!("{text}\n[machine_overrides]\npivot_mm = [0.0, 0.0, {z:?}]\n"),
        )
        .unwrap();
        let written = Scenario::load(&path).unwrap();
        assert_eq!(
            format!("{:?}", point.machine.kinematics),
            format!("{:?}", written.machine.kinematics)
        );
        let (a, b) = (g(&point), g(&written));
        assert_eq!(
            a.to_bits(),
            b.to_bits(),
            "z {z}: study point {a}, written {b}"
        );
        gs.push(a);
    }
    // The element is read: the pivot's height changes the cone's G.
    assert_ne!(gs[0], gs[1], "{gs:?}");
}
