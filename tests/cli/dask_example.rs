//! examples/dask/run_study.py on a LocalCluster of 2 workers: the study it runs in shards
//! and merges through the mtsim Python package equals the single-machine run of the binary
//! byte for byte. Needs Python with the package (`pip install .`), `dask.distributed`,
//! pandas and pyarrow: skipped (and said so) without them, failed without them when `CI`
//! is set.

use crate::common;

use std::process::Command;

use common::{mtsim, scratch};

fn dask_available() -> bool {
    Command::new("python3")
        .args(["-c", "import mtsim, dask.distributed, pandas, pyarrow"])
        .output()
        .is_ok_and(|o| o.status.success())
}

#[test]
fn the_dask_example_runs_a_sharded_sweep_and_merges_it_byte_identical() {
    if !dask_available() {
        if std::env::var_os("CI").is_some() {
            panic!("CI is set but python3 cannot import mtsim, dask.distributed, pandas and pyarrow: install them (pip install . \"dask[distributed]\" pandas pyarrow)");
        }
        eprintln!("skipped: python3 cannot import mtsim, dask.distributed, pandas and pyarrow (pip install . \"dask[distributed]\" pandas pyarrow)");
        return;
    }
    let dir = scratch("dask", "sweep");
    let study = [
        "sweep",
        "scenarios/cone-15-10.toml",
        "--vary",
        "center_y",
        "--from",
        "-30",
        "--to",
        "-15",
        "--step",
        "1",
    ];
    let whole = dir.join("whole");
    let mut args = study.to_vec();
    args.extend(["-o", whole.to_str().unwrap()]);
    assert!(mtsim(&args).status.success());

    let out = dir.join("dask");
    let run = Command::new("python3")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .arg("examples/dask/run_study.py")
        .args(["--workers", "2", "--shards", "4"])
        .args(["--out", out.to_str().unwrap(), "--"])
        .args(study)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert_eq!(std::fs::read_dir(out.join("shards")).unwrap().count(), 4);
    for name in [
        "sweep-center_y.csv",
        "sweep-center_y.parquet",
        "sweep-center_y.svg",
    ] {
        let a = std::fs::read(whole.join(name)).unwrap();
        let b = std::fs::read(out.join(name)).unwrap();
        assert!(
            a == b,
            "{name} differs between the single run and the Dask run"
        );
    }
    // pandas read the Parquet table: 16 values, every row.
    let stderr = String::from_utf8_lossy(&run.stderr);
    let csv_rows = std::fs::read_to_string(whole.join("sweep-center_y.csv"))
        .unwrap()
        .lines()
        .count()
        - 1;
    assert!(
        stderr.contains(&format!("sweep-center_y.parquet: {csv_rows} rows")),
        "{stderr}"
    );
}
