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
        return Some(PathBuf::from(p)).filter(|p| p.is_file());
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
    /// How far the printed figures may be from the exact ones, mm: half a unit of the 4th
    /// decimal of the position and of each offset added to it, in the units each was
    /// printed in (0.00005 in = 0.00127 mm per figure under G20).
    pub rounding_mm: f64,
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
    run_with(rs274, program, tool_table_inch, &[], work, timeout)
}

/// [`run`] in a LinuxCNC configuration: rs274 gets the INI file `ini` (written by the
/// caller, e.g. a configuration's own with some keys left out), runs in `cwd` (the
/// configuration's folder, which relative paths in it are taken from, as LinuxCNC does),
/// and starts from the parameters `var_inch` (a `.var` file's text, lengths in inches).
pub fn run_in_config(
    rs274: &Path,
    program: &Path,
    ini: &Path,
    cwd: &Path,
    tool_table_inch: &Path,
    var_inch: &str,
    work: &Path,
    timeout: Duration,
) -> RsRun {
    std::fs::create_dir_all(work).unwrap();
    let mut cmd = Command::new(rs274);
    cmd.arg("-i").arg(ini).current_dir(cwd);
    run_cmd(cmd, program, tool_table_inch, var_inch, work, timeout)
}

/// [`run`] with `[RS274NGC]SUBROUTINE_PATH` set to `subroutine_path` (through an INI file).
pub fn run_with(
    rs274: &Path,
    program: &Path,
    tool_table_inch: &Path,
    subroutine_path: &[PathBuf],
    work: &Path,
    timeout: Duration,
) -> RsRun {
    std::fs::create_dir_all(work).unwrap();
    let mut cmd = Command::new(rs274);
    if !subroutine_path.is_empty() {
        let ini = work.join("rs274.ini");
        let dirs: Vec<String> = subroutine_path
            .iter()
            .map(|d| d.display().to_string())
            .collect();
        std::fs::write(
            &ini,
            format!("[RS274NGC]\nSUBROUTINE_PATH = {}\n", dirs.join(":")),
        )
        .unwrap();
        cmd.arg("-i").arg(ini);
    }
    run_cmd(cmd, program, tool_table_inch, "", work, timeout)
}

fn run_cmd(
    mut cmd: Command,
    program: &Path,
    tool_table_inch: &Path,
    var_inch: &str,
    work: &Path,
    timeout: Duration,
) -> RsRun {
    let var = work.join("p.var");
    std::fs::write(&var, var_inch).unwrap();
    let out = work.join("out.txt");
    let err = work.join("err.txt");
    let _ = std::fs::remove_file(&out);
    let mut child = cmd
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
    // The Python plugin of a configuration echoes the ini's `[PYTHON]` code
    // (`file.ini:N: executing '...'`, possibly over several lines) and its start-up: not
    // messages about the program.
    let mut in_echo = false;
    let messages: Vec<&str> = stderr
        .lines()
        .filter(|l| {
            let t = l.trim();
            if in_echo {
                in_echo = !t.ends_with('\'');
                return false;
            }
            if t.contains(": executing '") {
                in_echo = !t.ends_with('\'');
                return false;
            }
            !(t.is_empty()
                || t == "executing"
                || t.starts_with("PythonPlugin:")
                || t.starts_with("is_callable("))
        })
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
    // Half a unit of the last printed decimal of each offset, mm.
    let (mut g5x_r, mut g92_r, mut tlo_r) = (0.0, 0.0, 0.0);
    let mut feed = Some(0.0);
    let mut per_rev = false;
    // Inside START_SPEED_FEED_SYNC ... STOP_SPEED_FEED_SYNCH (G33, G33.1, G76) the feed is
    // pitch × S, and rs274 prints the pitch to 6 decimals only: such moves carry no feed
    // here (crates/ngc/tests/interp/lathe.rs compares their feeds within that rounding).
    let mut sync = false;
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
            "SET_G5X_OFFSET" => {
                g5x = to_mm(&numbers(args)[1..], units);
                g5x_r = 5e-5 * units;
            }
            "SET_G92_OFFSET" => {
                g92 = to_mm(&numbers(args), units);
                g92_r = 5e-5 * units;
            }
            "SET_XY_ROTATION" => rot_deg = numbers(args)[0],
            "USE_TOOL_LENGTH_OFFSET" => {
                tlo = to_mm(&numbers(args), units);
                tlo_r = 5e-5 * units;
            }
            "SET_FEED_MODE" => per_rev = numbers(args).get(1) == Some(&1.0),
            "START_SPEED_FEED_SYNC" | "START_SPEED_FEED_SYNCH" => sync = true,
            "STOP_SPEED_FEED_SYNCH" => sync = false,
            "RIGID_TAP" => {
                // G33.1: to the end point and back to the start, synchronised.
                let n = numbers(args);
                let from = moves.last().map_or([0.0; 6], |m: &RsMove| m.end);
                let mut p = [0.0; 6];
                p[..3].copy_from_slice(&n[..3]);
                let mut end = machine(to_mm(&p, units), &g5x, &g92, &tlo, rot_deg);
                end[3..].copy_from_slice(&from[3..]);
                for to in [end, from] {
                    moves.push(RsMove {
                        kind: "feed",
                        end: to,
                        feed_mm_min: None,
                        dwell_s: None,
                        center: None,
                        call: k + 1,
                        rounding_mm: 5e-5 * units + g5x_r + g92_r + tlo_r,
                    });
                }
            }
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
                    feed_mm_min: (name == "STRAIGHT_FEED" && !per_rev && !sync)
                        .then_some(feed)
                        .flatten(),
                    dwell_s: None,
                    center: None,
                    call: k + 1,
                    rounding_mm: 5e-5 * units + g5x_r + g92_r + tlo_r,
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
                let end = machine(p, &g5x, &g92, &tlo, rot_deg);
                // `rotation` n (sign: +1 counter-clockwise): |n| − 1 full turns before the
                // arc, which mtsim emits as moves of their own. With the one-turn sweep θ₁
                // and θ = θ₁ + 2π(|n| − 1), after turn k the in-plane axes are back at the
                // start and the others at start + (end − start)·2πk/θ.
                let turns = n[4].abs().round() as usize;
                if turns > 1 {
                    let start = moves.last().map_or([0.0; 6], |m: &RsMove| m.end);
                    let angle =
                        |q: &[f64; 6]| (q[second] - center[second]).atan2(q[first] - center[first]);
                    let tau = std::f64::consts::TAU;
                    let mut sweep = (angle(&end) - angle(&start)) * n[4].signum();
                    while sweep <= 1e-12 {
                        sweep += tau;
                    }
                    let total = sweep + tau * (turns - 1) as f64;
                    for t in 1..turns {
                        let f = tau * t as f64 / total;
                        let mut q: [f64; 6] =
                            std::array::from_fn(|i| start[i] + (end[i] - start[i]) * f);
                        q[first] = start[first];
                        q[second] = start[second];
                        moves.push(RsMove {
                            kind: "arc",
                            end: q,
                            feed_mm_min: (!per_rev).then_some(feed).flatten(),
                            dwell_s: None,
                            center: Some({
                                let mut c = center;
                                c[normal] = f64::NAN;
                                [c[0], c[1], c[2]]
                            }),
                            call: k + 1,
                            rounding_mm: 5e-5 * units + g5x_r + g92_r + tlo_r,
                        });
                    }
                }
                center[normal] = f64::NAN;
                moves.push(RsMove {
                    kind: "arc",
                    end,
                    feed_mm_min: (!per_rev).then_some(feed).flatten(),
                    dwell_s: None,
                    center: Some([center[0], center[1], center[2]]),
                    call: k + 1,
                    rounding_mm: 5e-5 * units + g5x_r + g92_r + tlo_r,
                });
            }
            "DWELL" => {
                // The machine stays where the last move left it (at machine zero before
                // any move), whatever offsets changed since.
                let last = moves.last().map_or([0.0; 6], |m: &RsMove| m.end);
                moves.push(RsMove {
                    kind: "dwell",
                    end: last,
                    feed_mm_min: None,
                    dwell_s: Some(numbers(args)[0]),
                    center: None,
                    call: k + 1,
                    rounding_mm: moves.last().map_or(0.0, |m: &RsMove| m.rounding_mm),
                });
            }
            "STRAIGHT_PROBE" => {
                // A feed move to the probe point; then rs274's world model (saicanon.cc)
                // backs the probe off 0.254 mm (0.01 in) towards the start along X Y Z and
                // goes on from there without printing a call: that back-off is a feed move
                // here, as in mtsim (docs/gcode.md, probing).
                let start = moves.last().map_or([0.0; 6], |m: &RsMove| m.end);
                let end = machine(to_mm(&numbers(args), units), &g5x, &g92, &tlo, rot_deg);
                let rounding_mm = 5e-5 * units + g5x_r + g92_r + tlo_r;
                let feed_mm_min = (!per_rev).then_some(feed).flatten();
                let probe = |end: [f64; 6]| RsMove {
                    kind: "feed",
                    end,
                    feed_mm_min,
                    dwell_s: None,
                    center: None,
                    call: k + 1,
                    rounding_mm,
                };
                moves.push(probe(end));
                let d: [f64; 3] = std::array::from_fn(|i| start[i] - end[i]);
                let distance = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                if distance > 0.0 {
                    let mut back = end;
                    for i in 0..3 {
                        back[i] += 0.254 * d[i] / distance;
                    }
                    moves.push(probe(back));
                }
            }
            "NURBS_FEED" => {
                // G5, G5.1, G5.3: rs274 prints no point (`NURBS_FEED(n, ...)`); LinuxCNC's
                // motion canon cuts the curve into biarcs. `compare_moves` matches it with
                // the run of mtsim arcs and feeds of one source line.
                moves.push(RsMove {
                    kind: "spline",
                    end: [f64::NAN; 6],
                    feed_mm_min: None,
                    dwell_s: None,
                    center: None,
                    call: k + 1,
                    rounding_mm: 0.0,
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
    scale_tool_table(mm, 1.0 / 25.4)
}

/// A LinuxCNC tool table with its lengths (X Y Z U V W D) multiplied by `factor`.
pub fn scale_tool_table(table: &str, factor: f64) -> String {
    let mm = table;
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
                        format!("{letter}{:.10}", v * factor)
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

/// Runs `cmd` for at most `timeout`: its exit code (`None` when it was killed for taking
/// too long), stdout and stderr.
pub fn run_timed(cmd: &mut Command, timeout: Duration) -> (Option<i32>, String, String) {
    let dir = std::env::temp_dir().join(format!(
        "mtsim-timed-{}-{:?}",
        std::process::id(),
        std::thread::current().id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let (out, err) = (dir.join("stdout"), dir.join("stderr"));
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out).unwrap())
        .stderr(std::fs::File::create(&err).unwrap())
        .spawn()
        .expect("the command starts");
    let started = Instant::now();
    let code = loop {
        if let Some(s) = child.try_wait().unwrap() {
            // A signal (a crash) has no code: report it as -1.
            break Some(s.code().unwrap_or(-1));
        }
        if started.elapsed() > timeout {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(2));
    };
    let read =
        |p: &Path| String::from_utf8_lossy(&std::fs::read(p).unwrap_or_default()).into_owned();
    let result = (code, read(&out), read(&err));
    let _ = std::fs::remove_dir_all(&dir);
    result
}

/// A move as `mtsim blocks --csv` prints it.
#[derive(Clone, Debug)]
pub struct Row {
    pub line: usize,
    pub kind: String,
    pub end: [f64; 6],
    pub feed: Option<f64>,
    pub dwell: Option<f64>,
}

/// Parses the output of `mtsim blocks --csv`.
pub fn parse_blocks_csv(csv: &str) -> Vec<Row> {
    let num = |s: &str| (!s.is_empty()).then(|| s.parse::<f64>().unwrap());
    csv.lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            Row {
                line: f[0].parse().unwrap(),
                kind: f[1].to_string(),
                end: std::array::from_fn(|i| f[2 + i].parse().unwrap()),
                feed: num(f[8]),
                dwell: num(f[9]),
            }
        })
        .collect()
}

/// Whether the G-code `text` has B words (outside comments), so that it needs a B axis.
pub fn uses_b_axis(text: &str) -> bool {
    text.lines().any(|l| {
        let code = l
            .split(['(', ';'])
            .next()
            .unwrap_or("")
            .to_ascii_uppercase();
        // A B followed by a number, an expression or a parameter, not inside a name.
        let b = code.as_bytes();
        (0..b.len()).any(|i| {
            b[i] == b'B'
                && (i == 0 || !b[i - 1].is_ascii_alphabetic())
                && b.get(i + 1).is_some_and(|c| {
                    c.is_ascii_digit() || matches!(c, b'-' | b'+' | b'.' | b'[' | b'#' | b' ')
                })
                && !code[i..].starts_with("BREAK")
        })
    })
}

/// End points within this, mm or deg (issue 9).
pub const END_TOLERANCE: f64 = 1e-4;

/// rs274 prints 4 decimals in program units: a feed printed in in/min is known to
/// ±0.00005 in/min = ±0.00127 mm/min.
pub const FEED_TOLERANCE_MM_MIN: f64 = 1.5e-3;

/// Compares rs274's moves with mtsim's rows: the same kinds in the same order, end points
/// within [`END_TOLERANCE`], feeds within [`FEED_TOLERANCE_MM_MIN`] and dwells within
/// 1e-4 s. Moves of length zero (within 1e-9 mm) are left out on both sides (rs274 emits
/// them for a G0/G1 block without axis words, mtsim does not; docs/rs274.md). Returns the moves compared.
///
/// `printed_resolution`: widen the end-point tolerance by [`RsMove::rounding_mm`], for
/// programs whose figures are not exact to rs274's 4 printed decimals (inch programs with
/// more decimals, computed positions). The conformance programs are exact and use 1e-4 mm.
pub fn compare_moves(
    rs: Vec<RsMove>,
    ours: Vec<Row>,
    printed_resolution: bool,
) -> Result<usize, String> {
    let moving = |kind: &str, end: &[f64; 6], prev: &mut [f64; 6]| {
        // Zero length within 1e-9 mm: a computed end point (`Z[#1 + .65]`) may differ from
        // the previous one by the rounding of the last bit only.
        let moved = end
            .iter()
            .zip(prev.iter())
            .any(|(a, b)| !((a - b).abs() <= 1e-9));
        let keep = !matches!(kind, "rapid" | "feed") || moved;
        *prev = *end;
        keep
    };
    let mut prev = [0.0; 6];
    let rs: Vec<_> = rs
        .into_iter()
        .filter(|m| moving(m.kind, &m.end, &mut prev))
        .collect();
    let mut prev = [0.0; 6];
    let ours: Vec<_> = ours
        .into_iter()
        .filter(|m| moving(&m.kind, &m.end, &mut prev))
        .collect();
    let axes = ["X", "Y", "Z", "A", "B", "C"];
    // A spline (rs274 `NURBS_FEED`, no end point printed) stands for the run of mtsim's
    // arcs and feeds from one source line; its end shows in the moves after it.
    let mut merged = Vec::with_capacity(ours.len());
    let mut j = 0;
    for r in &rs {
        if r.kind == "spline" {
            let Some(first) = ours.get(j) else { break };
            while ours
                .get(j)
                .is_some_and(|m| m.line == first.line && matches!(m.kind.as_str(), "arc" | "feed"))
            {
                j += 1;
            }
            merged.push(Row {
                line: first.line,
                kind: "spline".into(),
                end: [f64::NAN; 6],
                feed: None,
                dwell: None,
            });
        } else if let Some(m) = ours.get(j) {
            merged.push(m.clone());
            j += 1;
        }
    }
    merged.extend(ours[j.min(ours.len())..].iter().cloned());
    let ours = merged;
    for (k, (r, m)) in rs.iter().zip(&ours).enumerate() {
        let at = format!(
            "move {} (rs274 call {}, mtsim line {})",
            k + 1,
            r.call,
            m.line
        );
        if r.kind != m.kind {
            return Err(format!("{at}: rs274 {} but mtsim {}", r.kind, m.kind));
        }
        let tolerance = END_TOLERANCE
            + if printed_resolution {
                r.rounding_mm
            } else {
                0.0
            };
        for i in 0..6 {
            if r.kind == "spline" {
                break;
            }
            // Rotary axes are printed in degrees, never scaled.
            let tolerance = if i < 3 {
                tolerance
            } else {
                END_TOLERANCE + if printed_resolution { 5e-5 } else { 0.0 }
            };
            let d = (r.end[i] - m.end[i]).abs();
            if !(d <= tolerance) {
                return Err(format!(
                    "{at}: {} is {} in rs274 but {} in mtsim (difference {d:.3e})",
                    axes[i], r.end[i], m.end[i]
                ));
            }
        }
        if let (Some(a), Some(b)) = (r.feed_mm_min, m.feed) {
            if !((a - b).abs() <= FEED_TOLERANCE_MM_MIN) {
                return Err(format!("{at}: feed {a} mm/min in rs274 but {b} in mtsim"));
            }
        }
        if let (Some(a), Some(b)) = (r.dwell_s, m.dwell) {
            if !((a - b).abs() <= 1e-4) {
                return Err(format!("{at}: dwell {a} s in rs274 but {b} s in mtsim"));
            }
        }
    }
    if rs.len() != ours.len() {
        return Err(format!(
            "rs274 makes {} moves but mtsim {}",
            rs.len(),
            ours.len()
        ));
    }
    Ok(ours.len())
}
