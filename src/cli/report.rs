//! `mtsim report`: report.html for each run folder.

use std::path::{Path, PathBuf};

use super::print_stdout;
use crate::error::{Error, Result};
use crate::report::html;
use crate::report::run::{RunFolder, SUMMARY_FILE};
use crate::report::run_dir::FolderLock;

/// Checks a `--date` value: YYYY-MM-DD.
pub fn check_date(date: &str) -> Result<()> {
    let b = date.as_bytes();
    let digits = |r: std::ops::Range<usize>| b[r].iter().all(u8::is_ascii_digit);
    let ok = b.len() == 10
        && b[4] == b'-'
        && b[7] == b'-'
        && digits(0..4)
        && digits(5..7)
        && digits(8..10);
    let month: u32 = if ok {
        date[5..7].parse().unwrap_or(0)
    } else {
        0
    };
    let day: u32 = if ok {
        date[8..10].parse().unwrap_or(0)
    } else {
        0
    };
    if ok && (1..=12).contains(&month) && (1..=31).contains(&day) {
        Ok(())
    } else {
        Err(Error::usage(format!(
            "--date {date}: expected a date as YYYY-MM-DD, e.g. 2026-11-23"
        )))
    }
}

/// Writes `report.html` into the finished output folder `dir`, under its lock (no run swaps
/// the folder while its page is written from it), and returns its path.
pub fn write_report(dir: &Path, date: Option<&str>) -> Result<PathBuf> {
    if !dir.is_dir() {
        return Err(Error::usage(format!(
            "{}: not a folder; give the output folder of `mtsim simulate` or `mtsim sweep`",
            dir.display()
        )));
    }
    let lock = FolderLock::take(dir)?;
    lock.may_write(html::REPORT_FILE)?;
    let path = write_page(dir, date)?;
    lock.record(html::REPORT_FILE)?;
    Ok(path)
}

/// Writes `report.html` into `dir` and returns its path: the page of a run folder (read
/// back, diagnosed by `study::diagnose`, rendered), or the study page of a `sweep` folder
/// (no summary.json, but sweep or placement plots). `dir` is one this process owns (a run
/// being staged) or holds the lock of.
pub fn write_page(dir: &Path, date: Option<&str>) -> Result<PathBuf> {
    if !dir.join(SUMMARY_FILE).exists() {
        if let Some(path) = html::write_study_page(dir)? {
            return Ok(path);
        }
    }
    let folder = RunFolder::read(dir)?;
    let diagnosis = crate::study::diagnose::diagnose_run(&folder);
    html::write_run_page(&folder, &diagnosis, date)
}

pub fn run(dirs: &[PathBuf], date: Option<&str>) -> Result<i32> {
    if let Some(d) = date {
        check_date(d)?;
    }
    let mut out = String::new();
    for dir in dirs {
        let path = write_report(dir, date)?;
        out.push_str(&format!("wrote {}\n", path.display()));
    }
    print_stdout(&out);
    Ok(0)
}
