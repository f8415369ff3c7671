//! Scale-out: `sweep`, `sweep --feasibility` and `batch` split with `--shard K/N`, joined by
//! `mtsim merge` into files byte-identical to the unsharded run; Parquet beside the CSV.

use crate::common;

use std::path::{Path, PathBuf};

use common::{mtsim, scratch};

use crate::shard_provenance::sweep_shard;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Runs `args` whole into `whole/`, as `shards` shards into `shards/` and merged into
/// `merged/`; asserts every file and the standard output are identical. Returns the
/// whole run's standard output.
fn whole_equals_merged(dir: &Path, args: &[&str], shards: usize) -> Vec<u8> {
    let (whole, parts, merged) = (dir.join("whole"), dir.join("shards"), dir.join("merged"));
    let run = |extra: &[&str]| {
        let mut a: Vec<&str> = args.to_vec();
        a.extend_from_slice(extra);
        mtsim(&a)
    };
    let out = run(&["--json", "-o", s(&whole)]);
    assert!(
        out.status.code().is_some_and(|c| c <= 1),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for k in 1..=shards {
        let shard = format!("{k}/{shards}");
        let o = run(&["--shard", &shard, "-o", s(&parts)]);
        assert_eq!(
            o.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(o.stdout.is_empty(), "a shard prints nothing on stdout");
    }
    let mut files: Vec<PathBuf> = std::fs::read_dir(&parts)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    assert_eq!(files.len(), shards);
    files.reverse(); // any order
    let mut m = vec!["merge", "--json", "-o", s(&merged)];
    m.extend(files.iter().map(|p| s(p)));
    let merged_out = mtsim(&m);
    assert_eq!(merged_out.status.code(), out.status.code());
    assert_eq!(merged_out.stdout, out.stdout, "merged stdout differs");
    let mut names: Vec<_> = std::fs::read_dir(&whole)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .filter(|n| n != "runs")
        .collect();
    names.sort();
    assert!(names.len() >= 2, "{names:?}");
    for name in names {
        let a = std::fs::read(whole.join(&name)).unwrap();
        let b = std::fs::read(merged.join(&name)).unwrap();
        assert!(
            a == b,
            "{name:?} differs between the whole run and the merged shards"
        );
    }
    out.stdout
}

#[test]
fn a_sweep_in_8_shards_merges_byte_identical_and_keeps_the_coincidence() {
    // 31 values; the coincidence near center_y = -22.3 mm (spec: Fig. 16) sits at a shard
    // boundary for some shards, so the halo rows are exercised.
    let dir = scratch("scale", "sweep");
    let args = [
        "sweep",
        "scenarios/cone-15-10.toml",
        "--vary",
        "center_y",
        "--from",
        "-30",
        "--to",
        "-15",
        "--step",
        "0.5",
    ];
    let stdout = whole_equals_merged(&dir, &args, 8);
    let v: serde_json::Value = serde_json::from_slice(&stdout).unwrap();
    assert_eq!(v["rows"].as_array().unwrap().len(), 31);
    let c = v["coincidences"].as_array().unwrap();
    assert_eq!(c.len(), 1, "{c:?}");
    assert!(
        (c[0]["value"].as_f64().unwrap() + 22.3).abs() < 0.11,
        "{c:?}"
    );
    // Other partitions give the same result too.
    for n in [3, 31, 40] {
        let d = scratch("scale", &format!("sweep-{n}"));
        assert_eq!(whole_equals_merged(&d, &args, n), stdout);
    }
}

#[test]
fn a_placement_map_in_3_shards_merges_byte_identical() {
    let dir = scratch("scale", "placement");
    whole_equals_merged(
        &dir,
        &[
            "sweep",
            "scenarios/cone-45-30.toml",
            "--feasibility",
            "--vary",
            "center_x,center_y",
            "--from",
            "-100,-300",
            "--to",
            "100,0",
            "--step",
            "100,150",
        ],
        3,
    );
}

#[test]
fn a_batch_in_2_shards_merges_byte_identical_with_one_row_per_scenario() {
    let dir = scratch("scale", "batch");
    let list = dir.join("list.txt");
    let root = env!("CARGO_MANIFEST_DIR");
    std::fs::write(
        &list,
        format!(
            "# the bundled cones, and one missing file\n{root}/scenarios/cone-15-10.toml\n\n{root}/scenarios/cone-45-30.toml\n{root}/scenarios/no-such.toml\n"
        ),
    )
    .unwrap();
    let stdout = whole_equals_merged(
        &dir,
        &[
            "batch",
            "--list",
            s(&list),
            "scenarios/cone-15-10-yt25.toml",
        ],
        2,
    );
    let v: serde_json::Value = serde_json::from_slice(&stdout).unwrap();
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 4);
    assert!(rows[2]["error"].as_str().unwrap().contains("no-such.toml"));
    // Each row holds what `mtsim check` reports for that scenario on its own.
    for (row, scenario) in [
        (0, "scenarios/cone-15-10.toml"),
        (3, "scenarios/cone-15-10-yt25.toml"),
    ] {
        let c: serde_json::Value =
            serde_json::from_slice(&mtsim(&["check", "--json", scenario]).stdout).unwrap();
        assert_eq!(rows[row]["samples"], c["samples"]);
        assert_eq!(
            rows[row]["violations"].as_u64().unwrap() as usize,
            c["violations"].as_array().unwrap().len()
        );
        assert_eq!(rows[row]["min_clearance_mm"], c["min_clearance_mm"]);
    }
    // 360 analytic reversals of the 15/10 cone: X twice, Y twice, Z twice... at least one each.
    assert!(rows[0]["reversals"].as_u64().unwrap() >= 3);
}

#[test]
fn parquet_holds_the_csv_table_at_full_precision() {
    use parquet::file::reader::{FileReader, SerializedFileReader};
    use parquet::record::RowAccessor;
    let dir = scratch("scale", "parquet");
    let out = mtsim(&[
        "sweep",
        "scenarios/cone-15-10.toml",
        "--vary",
        "center_y",
        "--from",
        "-30",
        "--to",
        "-20",
        "--step",
        "2",
        "-o",
        s(&dir),
    ]);
    assert!(out.status.success());
    let csv = std::fs::read_to_string(dir.join("sweep-center_y.csv")).unwrap();
    let csv_rows: Vec<Vec<String>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    let file = std::fs::File::open(dir.join("sweep-center_y.parquet")).unwrap();
    let reader = SerializedFileReader::new(file).unwrap();
    let meta = reader.metadata().file_metadata();
    assert_eq!(meta.num_rows() as usize, csv_rows.len());
    let names: Vec<String> = meta
        .schema_descr()
        .columns()
        .iter()
        .map(|c| c.name().to_string())
        .collect();
    assert_eq!(names, ["center_y", "axis", "reversal_deg", "spread_deg"]);
    for (row, c) in reader.get_row_iter(None).unwrap().zip(&csv_rows) {
        let row = row.unwrap();
        assert_eq!(row.get_double(0).unwrap().to_string(), c[0]);
        assert_eq!(row.get_string(1).unwrap(), &c[1]);
        // The CSV rounds to 4 decimals; the Parquet keeps the f64.
        assert!((row.get_double(2).unwrap() - c[2].parse::<f64>().unwrap()).abs() <= 5e-5);
    }
}

#[test]
fn merge_refuses_an_incomplete_or_mixed_set_of_shards() {
    let dir = scratch("scale", "refuse");
    let scenario = Path::new("scenarios/cone-15-10.toml");
    let sweep = |shard: &str, to: &str| sweep_shard(scenario, to, shard, &dir);
    let one = sweep("1/3", "-20");
    let two = sweep("2/3", "-20");
    let out = mtsim(&["merge", "-o", s(&dir.join("m")), s(&one), s(&two)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("shard 3/3 is missing"));
    // Shard 3 of a different grid.
    let three = sweep("3/3", "-10");
    let out = mtsim(&[
        "merge",
        "-o",
        s(&dir.join("m")),
        s(&one),
        s(&two),
        s(&three),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("different studies"));
    let out = mtsim(&[
        "sweep",
        "scenarios/cone-15-10.toml",
        "--vary",
        "center_y",
        "--from",
        "0",
        "--to",
        "1",
        "--step",
        "1",
        "--shard",
        "4/3",
        "-o",
        s(&dir),
    ]);
    assert_eq!(out.status.code(), Some(2));
}
