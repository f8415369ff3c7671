//! Writing outputs: complete or not at all, and the text tables people read.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::analysis::Analysis;
use crate::check::CheckReport;
use crate::error::{Error, Result};
use crate::limits::ViolationKind;

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

/// Appends `v` with `decimals` digits after the point, as `format!("{v:.decimals$}")` would
/// for |v| < 1e12 (round half away from zero on the scaled value), without the formatting
/// machinery: the trace writes twenty numbers per millisecond of machine time.
pub fn push_fixed(out: &mut String, v: f64, decimals: u32) {
    const SCALE: [f64; 10] = [1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9];
    let scaled = SCALE.get(decimals as usize).map(|s| (v * s).round());
    let Some(scaled) = scaled.filter(|s| s.is_finite() && s.abs() < 9.0e15) else {
        let _ = std::fmt::Write::write_fmt(out, format_args!("{v:.*}", decimals as usize));
        return;
    };
    // Digits from the right into a small buffer, then one append.
    let mut buf = [0u8; 24];
    let mut pos = buf.len();
    let mut n = scaled.abs() as u64;
    let mut written = 0;
    while n > 0 || written <= decimals {
        if written == decimals && decimals > 0 {
            pos -= 1;
            buf[pos] = b'.';
        }
        pos -= 1;
        buf[pos] = b'0' + (n % 10) as u8;
        n /= 10;
        written += 1;
    }
    if scaled < 0.0 {
        pos -= 1;
        buf[pos] = b'-';
    }
    out.push_str(std::str::from_utf8(&buf[pos..]).expect("ASCII digits"));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_fixed_matches_the_standard_formatting() {
        for &v in &[
            0.0,
            -0.0,
            1.5,
            -1.5,
            0.000_049,
            -0.000_051,
            123.456_789_4,
            -184.523_696_2,
            1e-9,
            99.999_999_6,
            7.0,
            -0.3,
        ] {
            for d in [0u32, 1, 4, 6, 7] {
                let mut s = String::new();
                push_fixed(&mut s, v, d);
                let want = format!("{v:.*}", d as usize);
                // The standard library rounds the exact binary value; the scaled rounding can
                // differ in the last digit only at exact ties, which these values avoid.
                let want = if want
                    .trim_start_matches('-')
                    .chars()
                    .all(|c| c == '0' || c == '.')
                {
                    want.trim_start_matches('-').to_string()
                } else {
                    want
                };
                assert_eq!(s, want, "{v} with {d} decimals");
            }
        }
    }
}

/// The text report of `mtsim check`.
pub fn check_table(report: &CheckReport, name: &str) -> String {
    let mut out = format!(
        "{name}: {} samples, {:.2} s of machine time, {} positions{}\n",
        report.samples,
        report.sim_time_s,
        if report.dynamics {
            "actual (servo)"
        } else {
            "commanded"
        },
        report
            .scene_queries
            .map_or(String::new(), |q| format!(", {q} geometric queries"))
    );
    out.push_str(&format!(
        "{:<4} {:>21} {:>21} {:>11} {:>23} {:>23}\n",
        "axis", "used", "available", "margin", "peak velocity/limit", "peak accel./limit"
    ));
    for (axis, u) in &report.axes {
        let unit = if "ABC".contains(axis.as_str()) {
            "deg"
        } else {
            "mm"
        };
        out.push_str(&format!(
            "{axis:<4} {:>9.3}..{:<9.3} {:>9.3}..{:<9.3} {:>11} {:>11.0}/{:<11.0} {:>11.0}/{:<11.0}\n",
            u.min,
            u.max,
            u.limit_min,
            u.limit_max,
            u.margin.map_or("continuous".to_string(), |m| format!("{m:.3} {unit}")),
            u.peak_velocity_per_min,
            u.velocity_limit_per_min,
            u.peak_acceleration_per_s2,
            u.acceleration_limit_per_s2,
        ));
    }
    if let (Some(c), Some(b)) = (report.min_clearance_mm, &report.min_clearance_bodies) {
        out.push_str(&format!(
            "smallest clearance: {c:.3} mm ({} / {})\n",
            b[0], b[1]
        ));
    }
    for e in &report.engagement {
        out.push_str(&format!(
            "cutting: {} in {}, deepest {:.4} mm\n",
            e.bodies[0], e.bodies[1], e.max_depth_mm
        ));
    }
    if report.violations.is_empty() {
        out.push_str("clean: no violations\n");
        return out;
    }
    out.push_str(&format!("{} violation(s):\n", report.violations.len()));
    for v in &report.violations {
        let what = match (&v.axis, &v.bodies) {
            (Some(a), _) => a.to_string(),
            (_, Some(b)) => format!("{} / {}", b[0], b[1]),
            _ => String::new(),
        };
        let span = match (v.theta_start_deg, v.theta_end_deg) {
            (Some(a), Some(b)) => format!("theta {a:.2}..{b:.2} deg"),
            _ => format!("t {:.3}..{:.3} s", v.time_start_s, v.time_end_s),
        };
        let worst = match v.kind {
            ViolationKind::Collision => format!("penetration {:.3} mm", v.worst),
            ViolationKind::NearMiss => format!(
                "clearance {:.3} mm (threshold {:.1})",
                v.worst,
                v.limit.unwrap_or(0.0)
            ),
            _ => {
                let limit = v.limit.unwrap_or(f64::NAN);
                format!(
                    "worst {:.3}, limit {:.3}, excess {:.3}",
                    v.worst,
                    limit,
                    (v.worst - limit).abs()
                )
            }
        };
        out.push_str(&format!(
            "  {:<12} {:<28} {span}, line {}: {worst}\n",
            format!("{:?}", v.kind).to_lowercase(),
            what,
            v.line
        ));
    }
    out
}
