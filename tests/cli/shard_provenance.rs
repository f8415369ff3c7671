//! Shards prove where they came from (src/study/shard.rs): each records the scenario hash, the
//! study's parameters, K/N and its row count, and `merge` refuses (exit 2, naming the files
//! and what differs) shards of other scenario contents or parameters, a K twice, and a part
//! whose rows do not match its share.

use crate::common;

use std::path::{Path, PathBuf};

use common::{mtsim, scratch, trt_ac, write_scenario, CONE_15_10};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `sweep` of `scenario`'s center_y over -30..=`to` step 5, shard `shard`, into `dir`;
/// asserts it succeeds and returns the shard file.
pub(crate) fn sweep_shard(scenario: &Path, to: &str, shard: &str, dir: &Path) -> PathBuf {
    let out = mtsim(&[
        "sweep",
        s(scenario),
        "--vary",
        "center_y",
        "--from",
        "-30",
        "--to",
        to,
        "--step",
        "5",
        "--shard",
        shard,
        "-o",
        s(dir),
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (k, n) = shard.split_once('/').unwrap();
    dir.join(format!("sweep-center_y.shard-{k}-of-{n}.json"))
}

fn merge(dir: &Path, shards: &[&Path]) -> (Option<i32>, String) {
    let mut args = vec!["merge", "-o"];
    let merged = dir.join("merged");
    args.push(s(&merged));
    args.extend(shards.iter().map(|p| s(p)));
    let out = mtsim(&args);
    let err = String::from_utf8_lossy(&out.stderr).replace(['\n', '│', ' '], "");
    (out.status.code(), err)
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

#[test]
fn a_shard_records_the_scenario_hash_k_of_n_and_its_share_of_rows() {
    let dir = scratch("shard-provenance", "record");
    let scenario = write_scenario(&dir, &trt_ac(), CONE_15_10);
    // -30..=0 step 5: 7 values; shard K of 3 takes floor(7K/3) - floor(7(K-1)/3) = 2, 2, 3.
    for (k, rows) in [(1, 2), (2, 2), (3, 3)] {
        let file = json(&sweep_shard(&scenario, "0", &format!("{k}/3"), &dir));
        assert_eq!(file["format"], "mtsim-shard/2");
        assert_eq!(file["shard"], serde_json::json!({"index": k, "count": 3}));
        assert_eq!(file["total"], 7);
        assert_eq!(file["rows"], rows);
        assert_eq!(file["part"]["rows"].as_array().unwrap().len(), rows);
        // XXH64 of the scenario and machine files, each followed by its length: the same
        // figure test.json records (report::test_info::files_hash).
        let mut h = xxhash_rust::xxh64::Xxh64::new(0);
        for f in [scenario.clone(), PathBuf::from(trt_ac())] {
            let bytes = std::fs::read(f).unwrap();
            h.update(&bytes);
            h.update(&(bytes.len() as u64).to_le_bytes());
        }
        assert_eq!(file["scenario_hash"], format!("{:016x}", h.digest()));
    }
}

#[test]
fn merge_refuses_shards_of_other_scenario_contents_naming_both_files() {
    let dir = scratch("shard-provenance", "contents");
    let scenario = write_scenario(&dir, &trt_ac(), CONE_15_10);
    let one = sweep_shard(&scenario, "0", "1/2", &dir);
    // The same path, other contents (a slower feed): the parameters are equal, the hash not.
    write_scenario(
        &dir,
        &trt_ac(),
        &format!("{CONE_15_10}feed_mm_min = 500.0\n"),
    );
    let two = sweep_shard(&scenario, "0", "2/2", &dir);
    let (code, err) = merge(&dir, &[&one, &two]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("differentstudies(scenariocontents(scenario_hash)differ)"),
        "{err}"
    );
    assert!(
        err.contains(&s(&one).replace(' ', "")) && err.contains(&s(&two).replace(' ', "")),
        "{err}"
    );
}

#[test]
fn merge_refuses_shards_of_other_parameters_naming_the_parameter() {
    let dir = scratch("shard-provenance", "params");
    let scenario = write_scenario(&dir, &trt_ac(), CONE_15_10);
    let one = sweep_shard(&scenario, "0", "1/2", &dir);
    let other = dir.join("other");
    let two = sweep_shard(&scenario, "5", "2/2", &other);
    let (code, err) = merge(&dir, &[&one, &two]);
    assert_eq!(code, Some(2), "{err}");
    // --to 5 has 8 values, not 7: the size and the grid differ.
    assert!(err.contains("(studysize,griddiffer)"), "{err}");
}

#[test]
fn merge_refuses_a_shard_given_twice_naming_both_copies() {
    let dir = scratch("shard-provenance", "twice");
    let scenario = write_scenario(&dir, &trt_ac(), CONE_15_10);
    let one = sweep_shard(&scenario, "0", "1/2", &dir);
    let copy = dir.join("copy.json");
    std::fs::copy(&one, &copy).unwrap();
    let (code, err) = merge(&dir, &[&one, &copy]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("shard1/2isgivenmorethanonce"), "{err}");
    assert!(err.contains(&s(&copy).replace(' ', "")), "{err}");
}

#[test]
fn merge_refuses_a_shard_whose_rows_do_not_match_its_share() {
    let dir = scratch("shard-provenance", "short");
    let scenario = write_scenario(&dir, &trt_ac(), CONE_15_10);
    let one = sweep_shard(&scenario, "0", "1/2", &dir);
    let two = sweep_shard(&scenario, "0", "2/2", &dir);
    // 7 values: shard 2/2 holds 7 - floor(7/2) = 4 rows. Cut one off, with and without
    // changing the recorded count; and a row of shard 1 moved into shard 2.
    let original = json(&two);
    let cut = |file: &mut serde_json::Value| {
        file["part"]["rows"].as_array_mut().unwrap().pop();
    };
    let mut short = original.clone();
    cut(&mut short);
    let mut short_recounted = short.clone();
    short_recounted["rows"] = 3.into();
    let mut long = original.clone();
    long["part"]["rows"]
        .as_array_mut()
        .unwrap()
        .insert(0, json(&one)["part"]["rows"][1].clone());
    long["rows"] = 5.into();
    for (edited, says, holds) in [(short, 4, 3), (short_recounted, 3, 3), (long, 5, 5)] {
        std::fs::write(&two, edited.to_string()).unwrap();
        let (code, err) = merge(&dir, &[&one, &two]);
        assert_eq!(code, Some(2), "{err}");
        assert!(
            err.contains(&format!(
                "shard2/2ofastudyof7shouldhold4rows;itsays{says}andholds{holds}"
            )),
            "{err}"
        );
        assert!(err.contains(&s(&two).replace(' ', "")), "{err}");
    }
    // Put back, the two merge.
    std::fs::write(&two, original.to_string()).unwrap();
    let (code, err) = merge(&dir, &[&one, &two]);
    assert_eq!(code, Some(0), "{err}");
}

#[test]
fn merge_refuses_batch_shards_of_a_scenario_edited_between_them() {
    let dir = scratch("shard-provenance", "batch");
    let a = write_scenario(&dir, &trt_ac(), CONE_15_10);
    let b = dir.join("b.toml");
    std::fs::write(&b, common::scenario_text(&trt_ac(), CONE_15_10)).unwrap();
    let shards = dir.join("shards");
    let batch = |k: &str| {
        let out = mtsim(&["batch", s(&a), s(&b), "--shard", k, "-o", s(&shards)]);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        shards.join(format!("batch.shard-{}-of-2.json", &k[..1]))
    };
    let one = batch("1/2");
    // Shard 2 runs b.toml only, but a.toml changed: the batch's hash covers every scenario.
    std::fs::write(
        &a,
        common::scenario_text(&trt_ac(), &format!("{CONE_15_10}feed_mm_min = 500.0\n")),
    )
    .unwrap();
    let two = batch("2/2");
    assert_eq!(json(&one)["rows"], 1);
    let (code, err) = merge(&dir, &[&one, &two]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("(scenariocontents(scenario_hash)differ)"),
        "{err}"
    );
}
