//! Splitting a study into shards, and joining the shards' results.
//!
//! A study is a work list (sweep values, placement-grid cells, batch scenarios) of `n`
//! items. Shard `K/N` (1-based, `1 <= K <= N`) takes the contiguous items
//! `floor((K-1) n / N) .. floor(K n / N)`: a deterministic partition that any batch engine
//! can hand out by index (a Slurm array task, a Kubernetes Job, a Dask task). A shard writes
//! its part as a [`ShardFile`] (JSON; floats round-trip exactly); [`join`] checks that the
//! files are the N parts of one study and returns the parts in order, from which the study
//! writes exactly what the unsharded run writes.

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

/// Format tag of shard files.
pub const FORMAT: &str = "mtsim-shard/1";

/// One shard's part of a study, as written to disk.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ShardFile<H, P> {
    pub format: String,
    /// `sweep`, `placement` or `batch`.
    pub study: String,
    pub shard: Shard,
    /// Items in the whole study's work list.
    pub total: usize,
    /// What identifies the study (its parameters); equal in every shard of it.
    pub header: H,
    pub part: P,
}

impl<H: Serialize, P: Serialize> ShardFile<H, P> {
    pub fn new(study: &str, shard: Shard, total: usize, header: H, part: P) -> Self {
        ShardFile {
            format: FORMAT.to_string(),
            study: study.to_string(),
            shard,
            total,
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
    std::fs::read_to_string(path)
        .map_err(|e| Error::usage(format!("cannot read shard file {}: {e}", path.display())))
}

fn not_shard(path: &Path, e: &dyn std::fmt::Display) -> Error {
    Error::invalid(
        path,
        format!("not an mtsim shard file ({FORMAT}): {e}; give the .shard-K-of-N.json files that `--shard K/N` wrote"),
    )
}

/// Reads the shard files of one study and returns its header and the parts in shard order.
/// Fails unless the files are exactly shards 1..N of one study with equal headers.
pub fn join<H, P>(paths: &[PathBuf]) -> Result<(H, usize, Vec<P>)>
where
    H: DeserializeOwned + PartialEq,
    P: DeserializeOwned,
{
    let mut files: Vec<(PathBuf, ShardFile<H, P>)> = Vec::new();
    for path in paths {
        let file: ShardFile<H, P> =
            serde_json::from_str(&read(path)?).map_err(|e| not_shard(path, &e))?;
        if file.format != FORMAT {
            return Err(not_shard(path, &format!("format {:?}", file.format)));
        }
        files.push((path.clone(), file));
    }
    let Some((first_path, first)) = files.first() else {
        return Err(Error::usage(
            "mtsim merge needs the shard files of one study",
        ));
    };
    let count = first.shard.count;
    let total = first.total;
    for (path, f) in &files[1..] {
        if f.study != first.study
            || f.shard.count != count
            || f.total != first.total
            || f.header != first.header
        {
            return Err(Error::usage(format!(
                "{} and {} are shards of different studies (study, shard count, size or parameters differ): merge the shards of one run",
                first_path.display(),
                path.display()
            )));
        }
    }
    files.sort_by_key(|(_, f)| f.shard.index);
    for k in 1..=count {
        match files.iter().filter(|(_, f)| f.shard.index == k).count() {
            1 => {}
            0 => {
                return Err(Error::usage(format!(
                    "shard {k}/{count} is missing: give all {count} shard files"
                )))
            }
            _ => {
                return Err(Error::usage(format!(
                    "shard {k}/{count} is given more than once"
                )))
            }
        }
    }
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
