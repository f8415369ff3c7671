//! Splitting a study into shards, and joining the shards' results.
//!
//! A study is a work list (sweep values, placement-grid cells, batch scenarios) of `n`
//! items. Shard `K/N` (1-based, `1 <= K <= N`) takes the contiguous items
//! `floor((K-1) n / N) .. floor(K n / N)`: a deterministic partition that any batch engine
//! can hand out by index (a Slurm array task, a Kubernetes Job, a Dask task). A shard writes
//! its part as a [`ShardFile`] (JSON; floats round-trip exactly) that says where it came
//! from: the study, its parameters, the scenario content hash, K/N, the study's size and the
//! part's row count. [`join`] checks that the files are the N parts of one study (same
//! study, parameters, hash, N and size; each K once; each part `len(range(K))` rows) and
//! returns the parts in order, from which the study writes exactly what the unsharded run
//! writes.

use std::collections::BTreeSet;

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Shard `index` of `count`, 1-based.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl Shard {
    /// The whole study as one shard.
    pub const WHOLE: Shard = Shard { index: 1, count: 1 };

    /// This shard's items of a work list of `n`.
    pub fn range(&self, n: usize) -> Range<usize> {
        let at = |k: usize| ((k as u128 * n as u128) / self.count as u128) as usize;
        at(self.index - 1)..at(self.index)
    }

    /// File name of this shard's part of study `stem`: `<stem>.shard-K-of-N.json`.
    pub fn file_name(&self, stem: &str) -> String {
        format!("{stem}.shard-{}-of-{}.json", self.index, self.count)
    }
}

impl FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Shard, String> {
        let bad = || format!("--shard {s:?}: expected K/N with 1 <= K <= N, e.g. 3/8");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count): (usize, usize) = (
            k.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        if count == 0 || index == 0 || index > count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

/// Format tag of shard files (`/2`: with the scenario hash and the row count).
pub const FORMAT: &str = "mtsim-shard/2";

/// A shard's part of a study: its row count is checked against the shard's share.
pub trait ShardPart {
    /// Items (rows, cells, scenarios) in the part.
    fn rows(&self) -> usize;
}

impl<T> ShardPart for Vec<T> {
    fn rows(&self) -> usize {
        self.len()
    }
}

/// One shard's part of a study, as written to disk.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ShardFile<H, P> {
    pub format: String,
    /// `sweep`, `placement` or `batch`.
    pub study: String,
    pub shard: Shard,
    /// Items in the whole study's work list.
    pub total: usize,
    /// Items in this part: `shard.range(total).len()`.
    pub rows: usize,
    /// The scenario content hash (XXH64, `report::test_info::scenario_hash`; for a batch,
    /// of its scenarios' hashes), 16 hex digits.
    pub scenario_hash: String,
    /// What identifies the study (its parameters); equal in every shard of it.
    pub header: H,
    pub part: P,
}

impl<H: Serialize, P: Serialize + ShardPart> ShardFile<H, P> {
    pub fn new(
        study: &str,
        shard: Shard,
        total: usize,
        scenario_hash: String,
        header: H,
        part: P,
    ) -> Self {
        ShardFile {
            format: FORMAT.to_string(),
            study: study.to_string(),
            shard,
            total,
            rows: part.rows(),
            scenario_hash,
            header,
            part,
        }
    }

    /// Writes the file (atomically) into `dir` as [`Shard::file_name`]; returns its path.
    pub fn write(&self, dir: &Path, stem: &str) -> Result<PathBuf> {
        crate::report::create_dir(dir)?;
        let path = dir.join(self.shard.file_name(stem));
        let json = serde_json::to_string(self).expect("plain data serializes");
        crate::report::write_atomic(&path, format!("{json}\n").as_bytes())?;
        Ok(path)
    }
}

#[derive(Deserialize)]
struct Head {
    format: String,
    study: String,
}

/// The study a shard file belongs to (`sweep`, `placement` or `batch`).
pub fn study_of(path: &Path) -> Result<String> {
    let head: Head = serde_json::from_str(&read(path)?).map_err(|e| not_shard(path, &e))?;
    if head.format != FORMAT {
        return Err(not_shard(path, &format!("format {:?}", head.format)));
    }
    Ok(head.study)
}

fn read(path: &Path) -> Result<String> {
    crate::input::toml_text::read_text(path).map_err(|e| match e {
        Error::Read { source, .. } => Error::usage(format!(
            "cannot read shard file {}: {source}",
            path.display()
        )),
        other => other,
    })
}

fn not_shard(path: &Path, e: &dyn std::fmt::Display) -> Error {
    Error::invalid(
        path,
        format!("not an mtsim shard file ({FORMAT}): {e}; give the .shard-K-of-N.json files that `--shard K/N` wrote"),
    )
}

/// What differs between two shard files of supposedly one study: the names of the fields
/// (header fields by their own names).
fn differences<H: Serialize, P>(a: &ShardFile<H, P>, b: &ShardFile<H, P>) -> Vec<String> {
    let mut out = Vec::new();
    let mut differ = |differs: bool, what: &str| {
        if differs {
            out.push(what.to_string());
        }
    };
    differ(a.study != b.study, "study");
    differ(a.shard.count != b.shard.count, "shard count N");
    differ(a.total != b.total, "study size");
    differ(
        a.scenario_hash != b.scenario_hash,
        "scenario contents (scenario_hash)",
    );
    let json = |h: &H| serde_json::to_value(h).expect("plain data serializes");
    match (json(&a.header), json(&b.header)) {
        (serde_json::Value::Object(x), serde_json::Value::Object(y)) => {
            let keys: BTreeSet<&String> = x.keys().chain(y.keys()).collect();
            for key in keys {
                differ(x.get(key) != y.get(key), key);
            }
        }
        (x, y) => differ(x != y, "parameters"),
    }
    out
}

/// Reads the shard files of one study and returns its header, the study's size and the parts
/// in shard order. Fails (exit 2, naming the files and what differs) unless the files are
/// exactly shards 1..N of one study (same study, parameters, scenario hash, N and size), each
/// holding the rows of its share.
pub fn join<H, P>(paths: &[PathBuf]) -> Result<(H, usize, Vec<P>)>
where
    H: DeserializeOwned + Serialize,
    P: DeserializeOwned + ShardPart,
{
    let mut files: Vec<(PathBuf, ShardFile<H, P>)> = Vec::new();
    for path in paths {
        let file: ShardFile<H, P> =
            serde_json::from_str(&read(path)?).map_err(|e| not_shard(path, &e))?;
        if file.format != FORMAT {
            return Err(not_shard(path, &format!("format {:?}", file.format)));
        }
        let Shard { index, count } = file.shard;
        if index == 0 || index > count {
            return Err(not_shard(path, &format!("shard {index}/{count}")));
        }
        let share = file.shard.range(file.total).len();
        if file.rows != share || file.part.rows() != share {
            return Err(Error::invalid(
                path,
                format!(
                    "shard {}/{} of a study of {} should hold {share} rows; it says {} and holds {}: the file is damaged or cut short, run the shard again",
                    file.shard.index, file.shard.count, file.total, file.rows, file.part.rows()
                ),
            ));
        }
        files.push((path.clone(), file));
    }
    let Some((first_path, first)) = files.first() else {
        return Err(Error::usage(
            "mtsim merge needs the shard files of one study",
        ));
    };
    for (path, f) in &files[1..] {
        let differs = differences(first, f);
        if !differs.is_empty() {
            return Err(Error::usage(format!(
                "{} and {} are shards of different studies ({} differ): merge the shards of one run",
                first_path.display(),
                path.display(),
                differs.join(", ")
            )));
        }
    }
    let (count, total) = (first.shard.count, first.total);
    let names = |k: usize| {
        files
            .iter()
            .filter(|(_, f)| f.shard.index == k)
            .map(|(p, _)| p.display().to_string())
            .collect::<Vec<_>>()
    };
    for k in 1..=count {
        let given = names(k);
        match given.len() {
            1 => {}
            0 => {
                let all: Vec<String> = files
                    .iter()
                    .map(|(p, f)| format!("{} ({}/{count})", p.display(), f.shard.index))
                    .collect();
                return Err(Error::usage(format!(
                    "shard {k}/{count} is missing (given: {}): give all {count} shard files",
                    all.join(", ")
                )));
            }
            _ => {
                return Err(Error::usage(format!(
                    "shard {k}/{count} is given more than once: {}",
                    given.join(", ")
                )))
            }
        }
    }
    files.sort_by_key(|(_, f)| f.shard.index);
    let mut parts = Vec::with_capacity(count);
    let mut header = None;
    for (_, f) in files {
        header.get_or_insert(f.header);
        parts.push(f.part);
    }
    Ok((header.expect("at least one shard"), total, parts))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_partition_the_work_list_in_order() {
        for n in [0usize, 1, 7, 8, 9, 100] {
            for count in 1..=9 {
                let mut next = 0;
                for index in 1..=count {
                    let r = Shard { index, count }.range(n);
                    assert_eq!(r.start, next);
                    assert!(r.len() == n / count || r.len() == n / count + 1);
                    next = r.end;
                }
                assert_eq!(next, n);
            }
        }
    }

    #[test]
    fn shard_parses_k_of_n() {
        assert_eq!("3/8".parse::<Shard>(), Ok(Shard { index: 3, count: 8 }));
        for bad in ["0/8", "9/8", "1/0", "3", "a/b", "-1/2"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }
}
