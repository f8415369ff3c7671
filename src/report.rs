//! Writing outputs: complete or not at all, and the text tables people read.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::analysis::Analysis;
use crate::error::{Error, Result};

/// Writes `bytes` to `path` atomically: a temporary file beside it, then a rename, so a
/// reader never sees a partial file and a failure leaves no partial file behind.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = temporary_path(path);
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    result.map_err(|source| {
        let _ = std::fs::remove_file(&tmp);
        Error::Write {
            path: path.to_path_buf(),
            source,
        }
    })
}

/// `<path>.tmp`, in the same folder so that the rename stays on one file system.
pub fn temporary_path(path: &Path) -> PathBuf {
    let mut name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(".tmp");
    path.with_file_name(name)
}

/// The per-axis table of `mtsim analyze`.
pub fn analysis_table(analysis: &Analysis) -> String {
    let mut out = String::new();
    let with_lines = analysis.axes.iter().any(|a| a.reversal_lines.is_some());
    out.push_str(&format!(
        "{:<4} {:>12} {:>12} {:>11} {:>16}  {}\n",
        "axis",
        "min",
        "max",
        "range",
        "peak speed/min",
        if with_lines {
            "reversals (source lines; deg)"
        } else {
            "reversals (deg)"
        }
    ));
    for a in &analysis.axes {
        let unit = a.axis.unit();
        let reversals = match &a.reversal_lines {
            Some(lines) if lines.is_empty() => "none".to_string(),
            Some(lines) => {
                let l = lines
                    .iter()
                    .map(|l| format!("line {l}"))
                    .collect::<Vec<_>>()
                    .join(", ");
                if a.reversals_deg.is_empty() {
                    l
                } else {
                    format!("{l}; {}", fmt_angles(&a.reversals_deg))
                }
            }
            None if a.reversals_deg.is_empty() => "none".to_string(),
            None => fmt_angles(&a.reversals_deg),
        };
        out.push_str(&format!(
            "{:<4} {:>9.3} {unit:<3}{:>9.3} {unit:<3}{:>8.3} {unit:<3}{:>8.1} {:<8} {}\n",
            a.axis.to_string(),
            a.min,
            a.max,
            a.range,
            a.peak_speed_per_min,
            format!("{unit}/min"),
            reversals
        ));
    }
    out
}

fn fmt_angles(angles: &[f64]) -> String {
    angles
        .iter()
        .map(|t| format!("{t:.2}"))
        .collect::<Vec<_>>()
        .join(", ")
}
