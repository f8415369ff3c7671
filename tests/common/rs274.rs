//! LinuxCNC's standalone interpreter `rs274` as a reference: run it the way docs/rs274.md
//! says (private HOME, fresh .var, tool table in inches, stdin closed), and turn its
//! canonical calls into moves in machine coordinates, mm and deg.
//!
//! rs274 prints program coordinates in the program units active at the time. Machine
//! coordinates follow LinuxCNC's `emccanon.cc` (`rotate_and_offset_pos`):
//! `p += G92; (x, y) = rot(R)·(x, y); p += G5x; p += tool length offset`, every offset
//! converted to mm with the units active when it was printed.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The rs274 binary, if installed (`RS274` overrides the path).
pub fn binary() -> Option<PathBuf> {
    if let Ok(p) = std::env::var("RS274") {
        return Some(PathBuf::from(p));
    }
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join("rs274"))
        .find(|p| p.is_file())
}

/// rs274, or `None` after printing why the test is skipped; panics under `CI`, which must
/// install it (`linuxcnc-uspace`).
pub fn require(test: &str) -> Option<PathBuf> {
    match binary() {
        Some(b) => Some(b),
        None if std::env::var_os("CI").is_some() => panic!(
            "{test}: rs274 is not installed but CI is set; install it with \
             `apt-get install -y --no-install-recommends linuxcnc-uspace`"
        ),
        None => {
            eprintln!(
                "SKIPPED {test}: rs274 (LinuxCNC's interpreter, Debian package \
                 linuxcnc-uspace) is not on PATH"
            );
            None
        }
    }
}

/// A move as rs274 emits it, in machine coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct RsMove {
    /// `rapid`, `feed`, `arc` or `dwell`.
    pub kind: &'static str,
    /// X Y Z mm, A B C deg.
    pub end: [f64; 6],
    /// Feed rate in effect, mm/min (G93 already converted by rs274); `None` in G95.
    pub feed_mm_min: Option<f64>,
    pub dwell_s: Option<f64>,
    /// Arc centre in machine coordinates `[X, Y, Z]` (the normal coordinate is NaN).
    pub center: Option<[f64; 3]>,
    /// The 1-based output line of the call, for messages.
    pub call: usize,
}

/// What one rs274 run gave.
#[derive(Clone, Debug)]
pub struct RsRun {
    pub moves: Vec<RsMove>,
    /// Exit code 0 and no message on stderr other than `executing`.
    pub ok: bool,
    pub stderr: String,
    pub timed_out: bool,
}

/// Runs rs274 (block delete on) on `program` with the tool table `tool_table_inch` (rs274 reads it in
/// inches) in a private scratch folder `work`; at most `timeout`.
pub fn run(
    rs274: &Path,
    program: &Path,
    tool_table_inch: &Path,
    work: &Path,
    timeout: Duration,
) -> RsRun {
    std::fs::create_dir_all(work).unwrap();
    let var = work.join("p.var");
    std::fs::write(&var, "").unwrap();
    let out = work.join("out.txt");
    let err = work.join("err.txt");
    let _ = std::fs::remove_file(&out);
    let mut child = Command::new(rs274)
        .env("HOME", work)
        .arg("-t")
        .arg(tool_table_inch)
        .arg("-v")
        .arg(&var)
        // -b: block delete on (`/` blocks skipped), as mtsim reads them.
        .args(["-n", "2", "-b", "-g"])
        .arg(program)
        .arg(&out)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(std::fs::File::create(&err).unwrap())
        .spawn()
        .expect("rs274 starts");
    let started = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break Some(s);
        }
        if started.elapsed() > timeout {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(2));
    };
    let stderr = std::fs::read_to_string(&err).unwrap_or_default();
    let text = std::fs::read_to_string(&out).unwrap_or_default();
    let messages: Vec<&str> = stderr
        .lines()
        .filter(|l| !l.trim().is_empty() && l.trim() != "executing")
        .collect();
    RsRun {
        moves: parse(&text),
        ok: status.is_some_and(|s| s.success()) && messages.is_empty(),
        stderr,
        timed_out: status.is_none(),
    }
}

/// The numbers in `args` (comma or space separated); non-numbers are skipped.
fn numbers(args: &str) -> Vec<f64> {
    args.split([',', ' '])
        .filter_map(|s| s.trim().parse::<f64>().ok())
        .collect()
}

/// Parses rs274's canonical calls into moves in machine coordinates.
pub fn parse(text: &str) -> Vec<RsMove> {
    let mut units = 1.0; // mm per program unit
    let mut g5x = [0.0; 6];
    let mut g92 = [0.0; 6];
    let mut rot_deg = 0.0f64;
    let mut tlo = [0.0; 6];
    let mut feed = Some(0.0);
    let mut per_rev = false;
    let mut plane = "XY";
    let mut moves = Vec::new();
    let to_mm = |v: &[f64], units: f64| -> [f64; 6] {
        std::array::from_fn(|i| if i < 3 { v[i] * units } else { v[i] })
    };
    for (k, line) in text.lines().enumerate() {
        // `%5d N..... NAME(args)` or `%5d N123   NAME(args)`.
        let Some(open) = line.find('(') else { continue };
        let Some(name) = line[..open].split_whitespace().last() else {
            continue;
        };
        let args = line[open + 1..line.rfind(')').unwrap_or(line.len())].trim();
        let machine = |p: [f64; 6], g5x: &[f64; 6], g92: &[f64; 6], tlo: &[f64; 6], rot: f64| {
            let mut q: [f64; 6] = std::array::from_fn(|i| p[i] + g92[i]);
            let (s, c) = rot.to_radians().sin_cos();
            let (x, y) = (q[0], q[1]);
            q[0] = x * c - y * s;
            q[1] = x * s + y * c;
            std::array::from_fn(|i| q[i] + g5x[i] + tlo[i])
        };
        match name {
            "USE_LENGTH_UNITS" => {
                units = if args.contains("INCHES") { 25.4 } else { 1.0 };
            }
            "SET_G5X_OFFSET" => g5x = to_mm(&numbers(args)[1..], units),
            "SET_G92_OFFSET" => g92 = to_mm(&numbers(args), units),
            "SET_XY_ROTATION" => rot_deg = numbers(args)[0],
            "USE_TOOL_LENGTH_OFFSET" => tlo = to_mm(&numbers(args), units),
            "SET_FEED_MODE" => per_rev = numbers(args).get(1) == Some(&1.0),
            "SET_FEED_RATE" => {
                feed = Some(numbers(args)[0] * units);
            }
            "SELECT_PLANE" => {
                plane = if args.contains("XZ") {
                    "XZ"
                } else if args.contains("YZ") {
                    "YZ"
                } else {
                    "XY"
                }
            }
            "STRAIGHT_TRAVERSE" | "STRAIGHT_FEED" => {
                let p = to_mm(&numbers(args), units);
                moves.push(RsMove {
                    kind: if name == "STRAIGHT_TRAVERSE" {
                        "rapid"
                    } else {
                        "feed"
                    },
                    end: machine(p, &g5x, &g92, &tlo, rot_deg),
                    feed_mm_min: (name == "STRAIGHT_FEED" && !per_rev)
                        .then_some(feed)
                        .flatten(),
                    dwell_s: None,
                    center: None,
                    call: k + 1,
                });
            }
            "ARC_FEED" => {
                // first_end, second_end, first_centre, second_centre, rotation, axis_end, a, b, c
                let n = numbers(args);
                let (first, second, normal) = match plane {
                    "XY" => (0, 1, 2),
                    "XZ" => (2, 0, 1),
                    _ => (1, 2, 0),
                };
                let mut p = [0.0; 6];
                p[first] = n[0];
                p[second] = n[1];
                p[normal] = n[5];
                p[3..].copy_from_slice(&n[6..9]);
                let mut c = p;
                c[first] = n[2];
                c[second] = n[3];
                let (p, c) = (to_mm(&p, units), to_mm(&c, units));
                let mut center = machine(c, &g5x, &g92, &tlo, rot_deg);
                center[normal] = f64::NAN;
                moves.push(RsMove {
                    kind: "arc",
                    end: machine(p, &g5x, &g92, &tlo, rot_deg),
                    feed_mm_min: (!per_rev).then_some(feed).flatten(),
                    dwell_s: None,
                    center: Some([center[0], center[1], center[2]]),
                    call: k + 1,
                });
            }
            "DWELL" => {
                let last = moves.last().map_or_else(
                    || machine([0.0; 6], &g5x, &g92, &tlo, rot_deg),
                    |m: &RsMove| m.end,
                );
                moves.push(RsMove {
                    kind: "dwell",
                    end: last,
                    feed_mm_min: None,
                    dwell_s: Some(numbers(args)[0]),
                    center: None,
                    call: k + 1,
                });
            }
            "STRAIGHT_PROBE" | "RIGID_TAP" => {
                moves.push(RsMove {
                    kind: "unsupported",
                    end: [f64::NAN; 6],
                    feed_mm_min: None,
                    dwell_s: None,
                    center: None,
                    call: k + 1,
                });
            }
            _ => {}
        }
    }
    moves
}

/// Writes the inch tool table rs274 needs from a LinuxCNC tool table in mm: the length and
/// diameter words (X Y Z A B C U V W D I J and so on stay as they are for angles: only
/// X Y Z U V W D are lengths) divided by 25.4.
pub fn tool_table_to_inch(mm: &str) -> String {
    let mut out = String::new();
    for line in mm.lines() {
        let (body, comment) = match line.find(';') {
            Some(i) => (&line[..i], &line[i..]),
            None => (line, ""),
        };
        let words: Vec<String> = body
            .split_whitespace()
            .map(|w| {
                let (letter, number) = w.split_at(1);
                match (letter.to_ascii_uppercase().as_str(), number.parse::<f64>()) {
                    ("X" | "Y" | "Z" | "U" | "V" | "W" | "D", Ok(v)) => {
                        format!("{letter}{:.10}", v / 25.4)
                    }
                    _ => w.to_string(),
                }
            })
            .collect();
        out.push_str(&words.join(" "));
        if !comment.is_empty() {
            out.push(' ');
            out.push_str(comment);
        }
        out.push('\n');
    }
    out
}
