//! `test.json`: the test parameters ISO 230-4 (clause 5.2, "test parameters") asks a
//! circular-test report to state, taken from the scenario a run was made from.
//!
//! Machine, test and its geometry, feed, directions, plane and position, start and overshoot
//! arcs, compensation state (feedforward and backlash per axis), sample period, date, mtsim
//! version and a hash of the inputs. The hash is XXH64 over the bytes of the scenario,
//! machine and program files, each followed by its length, so two runs with the same hash
//! ran the same inputs.
//!
//! The date is the only wall-clock figure: it is recorded only when asked for (`date`
//! argument), so that `simulate --no-timing` stays byte-identical between runs.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::input::scenario::Scenario;
use crate::program::test_of;
use crate::program::tests::TestDescription;

/// The test parameters of one run.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct TestParameters {
    /// Machine name and file.
    pub machine: String,
    pub machine_file: String,
    /// Kinematic layout ("trt-ac", ...).
    pub kinematics: String,
    /// The chain's geometry, a line per axis and the gauge point
    /// ([`crate::kinematics::Kinematics::chain_geometry`]); empty for folders written before it.
    #[serde(default)]
    pub chain_geometry: Vec<String>,
    /// "cone frustum (ISO 10791-6 / NAS 979)", "circular test (ISO 230-4)" or "G-code file".
    pub test: String,
    /// The scenario file.
    pub scenario: String,
    /// The G-code file, for a file program.
    pub program_file: Option<String>,
    /// Geometry in words: radius, or cone half apex, inclination and bar length.
    pub geometry: String,
    /// Ball-bar (measured circle) radius, mm.
    pub radius_mm: Option<f64>,
    /// Programmed contouring feed, mm/min.
    pub feed_mm_min: Option<f64>,
    /// Directions run ("ccw", "cw").
    pub directions: Vec<String>,
    /// Measuring plane (circle) or cone inclination plane, and the centre position, mm.
    pub plane: String,
    pub position_mm: Option<[f64; 3]>,
    /// Start arc (before the measured revolution) and overshoot arc (after it), deg.
    pub start_arc_deg: Option<f64>,
    pub overshoot_arc_deg: Option<f64>,
    /// The measured blocks of a file program, source lines (first, last), when set.
    pub measure_lines: Option<[usize; 2]>,
    /// Per axis: servo model, Kv, feedforward and backlash (compensation state).
    pub compensation: Vec<String>,
    /// Interpolation (sample) period, ms, and every how many samples the trace keeps.
    pub sample_period_ms: f64,
    pub trace_every: usize,
    /// Tool-centre-point interpolation.
    pub tcp: bool,
    /// Date of the test (YYYY-MM-DD), when recorded.
    pub date: Option<String>,
    /// mtsim version.
    pub mtsim_version: String,
    /// XXH64 of the scenario, machine and program files ([`files_hash`]), hex.
    pub scenario_hash: String,
}

/// The file `test.json` in a run folder.
pub const TEST_FILE: &str = "test.json";

/// The scenario hash of files with contents `chunks`: XXH64 (seed 0, `xxhash_rust`) of each
/// file's bytes followed by its length (8 bytes, little-endian), so that moving bytes from
/// one file to the next changes the hash.
pub fn files_hash(chunks: &[&[u8]]) -> u64 {
    let mut h = xxhash_rust::xxh64::Xxh64::new(0);
    for chunk in chunks {
        h.update(chunk);
        h.update(&(chunk.len() as u64).to_le_bytes());
    }
    h.digest()
}

/// The scenario hash of `scenario`: [`files_hash`] of the scenario, machine and program
/// files, as 16 hex digits.
pub fn scenario_hash(scenario: &Scenario) -> String {
    let mut files = vec![scenario.path.as_path(), scenario.machine.path.as_path()];
    let test = test_of(scenario);
    if let Some(path) = test.file() {
        files.push(path);
    }
    format!("{:016x}", files_hash_of_paths(&files))
}

/// [`files_hash`] of the files at `paths` (a file that cannot be read counts as empty),
/// read in 64 KiB pieces: memory stays flat however long the program file is.
pub fn files_hash_of_paths(paths: &[&Path]) -> u64 {
    use std::io::Read;
    let mut h = xxhash_rust::xxh64::Xxh64::new(0);
    let mut buf = vec![0u8; 64 * 1024];
    for path in paths {
        let mut length = 0u64;
        if let Ok(mut file) = std::fs::File::open(path) {
            loop {
                match file.read(&mut buf) {
                    Ok(0) => break,
                    Ok(n) => {
                        h.update(&buf[..n]);
                        length += n as u64;
                    }
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                    // As `std::fs::read` then: an unreadable file counts as empty. (A read
                    // that fails part way keeps what it read; the hash is a fingerprint.)
                    Err(_) => break,
                }
            }
        }
        h.update(&length.to_le_bytes());
    }
    h.digest()
}

/// Today's date, UTC, as YYYY-MM-DD (civil calendar from the Unix day number).
pub fn today_utc() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    civil_date((secs / 86_400) as i64)
}

/// The proleptic Gregorian date of Unix day `days` (H. Hinnant's `civil_from_days`).
pub fn civil_date(days: i64) -> String {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!("{y:04}-{m:02}-{d:02}")
}

fn axis_unit(axis: crate::Axis) -> &'static str {
    if axis.is_rotary() {
        "deg"
    } else {
        "mm"
    }
}

impl TestParameters {
    /// The parameters of `scenario`; `date` as given (None: not recorded).
    pub fn of(scenario: &Scenario, date: Option<String>) -> Result<TestParameters> {
        let machine = &scenario.machine;
        let kinematics = machine.kinematics.describe();
        let sim = &scenario.simulate;
        let TestDescription {
            test,
            geometry,
            radius_mm,
            feed_mm_min: feed,
            directions,
            plane,
            position_mm: position,
            start_arc_deg: start,
            overshoot_arc_deg: overshoot,
            program_file,
        } = test_of(scenario).description(sim.lead_deg);
        let compensation = machine
            .axes()
            .iter()
            .map(|&axis| {
                let d = machine.drive(axis);
                let unit = axis_unit(axis);
                format!(
                    "{axis}: {} servo, Kv {} 1/s, velocity feedforward {:.0} %, acceleration feedforward {:.0} %, {} feedback, backlash {} {unit} (not compensated)",
                    d.model_name(),
                    d.kv_per_s,
                    100.0 * d.velocity_feedforward,
                    100.0 * d.acceleration_feedforward,
                    d.feedback_name(),
                    d.backlash_mm_or_deg,
                )
            })
            .collect();
        Ok(TestParameters {
            machine: machine.name.clone(),
            machine_file: machine.path.display().to_string(),
            kinematics,
            chain_geometry: machine.kinematics.chain_geometry(),
            test,
            scenario: scenario.path.display().to_string(),
            program_file,
            geometry,
            radius_mm,
            feed_mm_min: feed,
            directions,
            plane,
            position_mm: position,
            start_arc_deg: start,
            overshoot_arc_deg: overshoot,
            measure_lines: sim.measure_lines,
            compensation,
            sample_period_ms: machine.interpolation_period_s * 1e3,
            trace_every: sim.trace_every,
            tcp: sim.tcp,
            date,
            mtsim_version: env!("CARGO_PKG_VERSION").to_string(),
            scenario_hash: scenario_hash(scenario),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn civil_dates_of_known_days() {
        assert_eq!(civil_date(0), "1970-01-01");
        // 2000-03-01 is day 11017; 2024-02-29 is day 19782.
        assert_eq!(civil_date(11_017), "2000-03-01");
        assert_eq!(civil_date(19_782), "2024-02-29");
    }

    #[test]
    fn the_hash_of_files_is_xxh64_of_each_file_and_its_length() {
        // No file: XXH64 of nothing, the published value.
        assert_eq!(files_hash(&[]), 0xef46_db37_51d8_e999);
        // One file "abc": XXH64 of "abc" and 3 as 8 bytes (from xxHash's Python binding,
        // `xxhash.xxh64(b"abc" + (3).to_bytes(8, "little"), 0)`).
        assert_eq!(files_hash(&[b"abc"]), 0x0e9c_b9c4_b235_41b5);
        assert_ne!(files_hash(&[b"ab", b"c"]), files_hash(&[b"a", b"bc"]));
        assert_ne!(files_hash(&[b"abc", b""]), files_hash(&[b"", b"abc"]));
    }

    /// Files hashed in 64 KiB pieces give the hash of their whole contents, a missing one
    /// counts as empty.
    #[test]
    fn files_hashed_piece_by_piece_hash_as_their_contents() {
        let dir = std::env::temp_dir().join(format!("mtsim-hash-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let big: Vec<u8> = (0..200_000u32).map(|i| (i * 7 % 251) as u8).collect();
        let (a, b) = (dir.join("a"), dir.join("b"));
        std::fs::write(&a, &big).unwrap();
        std::fs::write(&b, b"G1 X1\n").unwrap();
        let missing = dir.join("missing");
        let got = files_hash_of_paths(&[a.as_path(), missing.as_path(), b.as_path()]);
        assert_eq!(got, files_hash(&[&big, b"", b"G1 X1\n"]));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
