//! A seeded campaign of hostile inputs through the binary, across its commands and the five
//! dialects (issue 42): programs of each dialect with words put in, lines lost, repeated or
//! cut, and bytes changed; machine, scenario and study files with a key given a value no key
//! should take; program paths that name files which are not programs; and measured traces
//! that are not traces. Each case runs as a user runs it, as its own process, under 30 s of
//! wall time and 1 GB of address space, and must end with a code scripts can trust (0, 1, 2
//! or 3, never a panic, an abort or a kill), write at most 64 MB, never quote a file it was
//! not given as that kind of file, and refuse what no control accepts.
//!
//! 320 cases a run; `MTSIM_LONG_FAULTS=1` runs 1,200 (docs/performance.md has the figures).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use crate::hostile::{absolute_paths, apply, bundled, hostile_values, leaves, root, Edit};

/// Wall time a case may take, s, and its address space, KiB.
const TIME_LIMIT_S: u32 = 30;
const MEMORY_LIMIT_KIB: u64 = 1 << 20;
/// Bytes a case may write (its output folder and standard output).
const OUTPUT_LIMIT: u64 = 64 << 20;

/// xorshift64*: the campaign's cases from its seed alone, the same on every machine.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }

    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// A dialect's seed program (valid, short, using its flow constructs), its file name, and
/// words that dialect should never hang, crash or be fooled by.
struct Dialect {
    name: &'static str,
    file: &'static str,
    seed: &'static str,
    words: &'static [&'static str],
    /// Words that are wrong in this dialect: a program holding one must be refused.
    refused: &'static [&'static str],
}

const DIALECTS: [Dialect; 5] = [
    Dialect {
        name: "linuxcnc",
        file: "p.ngc",
        seed: "G21 G90 G17\n#1 = 10\no100 sub\nG1 X[#1] Y0 F500\no100 endsub\nG0 X0 Y0 Z5\n\
               G1 Z0 F300\no100 call\no200 repeat [3]\nG91 G1 X1 F400\nG90\no200 endrepeat\n\
               G2 X0 Y10 R10\nM2\n",
        words: &[
            "o1 repeat [1000000000]",
            "o1 while [1]",
            "o9 call",
            "#<_undefined>",
            "G43.4 H99",
            "o100 sub",
            "o200 endrepeat",
            "G68.2 X0 Y0 Z0 I90 J90 K90",
        ],
        refused: &["G1 X1.2.3", "#1=[1/0]", "G1 X[", "G2 X10 R0"],
    },
    Dialect {
        name: "fanuc",
        file: "p.nc",
        seed: "O0001\nG21 G90 G17 G54\n#100=3\nG0 X0 Y0 Z5\nG1 Z0 F300\nWHILE [#100 GT 0] DO1\n\
               #100=#100-1\nG1 X#100 F500\nEND1\nG2 X0 Y10 R10\nM30\n",
        words: &[
            "M98 P1 L99999999",
            "G65 P9000 L99999999",
            "WHILE [1 LT 2] DO1",
            "GOTO 1",
            "#3000=1(STOP)",
            "G10 L2 P9 X1e308",
            "END1",
            "N99999999999999999999",
        ],
        refused: &["G1 X1.2.3", "#1=[1/0]", "G1 X[", "G2 X10 R0"],
    },
    Dialect {
        name: "haas",
        file: "p.nc",
        seed: "%\nO00001\nG21 G90 G17\nG0 X0 Y0 Z5\nG1 Z0 F300\nM97 P100 L2\nG2 X0 Y10 R10\n\
               M30\nN100 G91 G1 X1 F400\nG90\nM99\n%\n",
        words: &[
            "M97 P100 L99999999",
            "M97 P9999",
            "M98 P1 L99999999",
            "G65 P9000 L99999999",
            "GOTO 100",
            "M99",
            "G187 P1",
            "G91 G28 Z0",
        ],
        refused: &["G1 X1.2.3", "#1=[1/0]", "G1 X[", "G2 X10 R0"],
    },
    Dialect {
        name: "heidenhain",
        file: "p.h",
        seed:
            "0 BEGIN PGM CAMP MM\n1 BLK FORM 0.1 Z X+0 Y+0 Z-20\n2 BLK FORM 0.2 X+100 Y+100 Z+0\n\
               3 TOOL CALL 1 Z S1000\n4 L Z+5 R0 FMAX\n5 L X+0 Y+0 R0 FMAX\n6 Q1 = 10\n\
               7 L X+Q1 Y+0 R0 F500\n8 LBL 1\n9 L IX+1 R0 F400\n10 LBL 0\n11 CALL LBL 1 REP 2\n\
               12 END PGM CAMP MM\n",
        words: &[
            "CALL LBL 1 REP 99999999",
            "LBL 1",
            "CALL LBL 99",
            "FN 9: IF +1 EQU +1 GOTO LBL 99",
            "CYCL DEF 99",
            "CALL PGM NOSUCH",
            "L X+1e999 R0 F100",
            "M140 MB MAX",
        ],
        refused: &[
            "L X+1.2.3 R0 F100",
            "Q1 = 1 / 0",
            "L X+ R0 F100",
            "LBL 1 REP",
        ],
    },
    Dialect {
        name: "siemens",
        file: "p.mpf",
        seed: "DEF INT CNT=0\nG17 G90 G71\nG0 X0 Y0 Z5\nG1 Z0 F300\nWHILE CNT<3\nCNT=CNT+1\n\
               G1 X=CNT F500\nENDWHILE\nR1=10\nG1 Y=R1\nM30\n",
        words: &[
            "REPEAT LAB1 P=99999999",
            "WHILE 1",
            "LAB1:",
            "GOTOB LAB1",
            "IF 1 GOTOF NOWHERE",
            "TRAORI",
            "G1 X=1e999",
            "ENDWHILE",
        ],
        refused: &["G1 X1.2.3", "R1=1/0", "G1 X=(", "DEF REAL"],
    },
];

/// Words no dialect reads as a program.
const GARBAGE: [&str; 5] = [
    "\u{0}\u{1}\u{7f}",
    "%",
    "(unclosed comment",
    "ü€𝄞",
    "[[[[[[[[",
];

/// One case: what it runs, and what is demanded of it.
struct Case {
    label: String,
    args: Vec<String>,
    /// Must be refused (exit 2).
    must_refuse: bool,
    /// Text the messages must not hold (the content of a file that is not a program).
    never_quoted: Option<String>,
}

/// How a case ended.
#[derive(Debug, Default)]
struct Tally {
    cases: usize,
    by_code: std::collections::BTreeMap<i32, usize>,
    bad: Vec<String>,
}

/// A scenario on the three-axis machine reading `program` in `dialect`.
fn program_scenario(dir: &Path, program: &str, dialect: &str) -> PathBuf {
    let path = dir.join("s.toml");
    let text = format!(
        "machine = {:?}\n[program]\nfile = {program:?}\n[reader]\ndialect = \"{dialect}\"\n\
         tools = [{{ number = 1, length_mm = 50.0, diameter_mm = 6.0 }}]\n",
        root().join("machines/vmc-3axis.toml").display().to_string()
    );
    std::fs::write(&path, text).unwrap();
    path
}

/// The program of dialect `d` changed by one of the campaign's mutations; whether it must
/// now be refused.
fn mutated(rng: &mut Rng, d: &Dialect) -> (Vec<u8>, String, bool) {
    let mut lines: Vec<String> = d.seed.lines().map(String::from).collect();
    let at = rng.below(lines.len() + 1);
    let (what, refuse) = match rng.below(9) {
        0 | 1 => {
            let w = rng.pick(d.words).to_string();
            lines.insert(at, w.clone());
            (format!("word {w:?} at {at}"), false)
        }
        2 => {
            // A wrong word where the program runs: after its first line (before it, a
            // Heidenhain program lacks its BEGIN PGM, a refusal too) and before its end
            // (after M30 a control reads only the blocks a call jumps to).
            let w = rng.pick(d.refused).to_string();
            let end = lines
                .iter()
                .position(|l| l == "M30" || l == "M2" || l.contains("END PGM"))
                .unwrap_or(lines.len() - 1);
            let at = 1 + at % end;
            lines.insert(at, w.clone());
            (format!("wrong word {w:?} at {at}"), true)
        }
        3 => {
            let w = rng.pick(&GARBAGE).to_string();
            lines.insert(at, w.clone());
            (format!("garbage {w:?} at {at}"), false)
        }
        4 => {
            let i = rng.below(lines.len());
            let n = 2 + rng.below(200);
            let line = lines[i].clone();
            for _ in 0..n {
                lines.insert(i, line.clone());
            }
            (format!("line {i} {n} times"), false)
        }
        5 => {
            let i = rng.below(lines.len());
            lines.remove(i);
            (format!("line {i} removed"), false)
        }
        6 => {
            let long = "X1".repeat(50_000 + rng.below(50_000));
            lines.insert(at, format!("G1 {long}"));
            (format!("a line of {} bytes at {at}", long.len() + 3), false)
        }
        _ => {
            let mut bytes = lines.join("\n").into_bytes();
            if rng.below(2) == 0 {
                let cut = rng.below(bytes.len());
                bytes.truncate(cut);
                return (bytes, format!("cut at byte {cut}"), false);
            }
            let i = rng.below(bytes.len());
            let b = rng.next() as u8;
            bytes[i] = b;
            return (bytes, format!("byte {i} = {b:#04x}"), false);
        }
    };
    (lines.join("\n").into_bytes(), what, refuse)
}

/// A program case: a mutated program of one dialect, read by one command.
fn program_case(rng: &mut Rng, dir: &Path) -> Case {
    let d = rng.pick(&DIALECTS);
    let (bytes, what, must_refuse) = mutated(rng, d);
    std::fs::write(dir.join(d.file), bytes).unwrap();
    let scenario = program_scenario(dir, d.file, d.name);
    let command = *rng.pick(&["analyze", "blocks", "check", "simulate"]);
    let mut args = vec![command.to_string(), scenario.display().to_string()];
    match command {
        "blocks" => args.push("--csv".into()),
        "simulate" => args.extend(["-o".into(), dir.join("out").display().to_string()]),
        _ => {}
    }
    Case {
        label: format!("{command} {} program, {what}", d.name),
        args,
        must_refuse,
        never_quoted: None,
    }
}

/// A bundled file of `folder` with one key edited; its copy's path and what was done.
fn edited(rng: &mut Rng, folder: &str, dir: &Path, name: &str) -> (PathBuf, String) {
    let files = bundled(folder);
    let source = rng.pick(&files);
    let text = std::fs::read_to_string(source).unwrap();
    let mut table: toml::Table = toml::from_str(&text).unwrap();
    absolute_paths(&mut table, source.parent().unwrap());
    let paths = leaves(&table);
    let path = rng.pick(&paths).clone();
    let values = hostile_values();
    let edit = match rng.below(8) {
        0 => Edit::Remove,
        1 => Edit::Unknown,
        _ => Edit::Set(rng.below(values.len())),
    };
    apply(&mut table, &path, &edit, &values);
    let out = dir.join(name);
    std::fs::write(&out, toml::to_string(&table).unwrap_or_default()).unwrap();
    let what = format!(
        "{} with {} {edit:?}",
        source.file_name().unwrap().to_string_lossy(),
        path.join(".")
    );
    (out, what)
}

/// A file case: an edited machine (under a bundled scenario), scenario or study file, run
/// by a command that reads it.
fn file_case(rng: &mut Rng, dir: &Path) -> Case {
    let out = dir.join("out").display().to_string();
    let (command, file, what) = match rng.below(3) {
        0 => {
            let (machine, what) = edited(rng, "machines", dir, "m.toml");
            let scenario = dir.join("s.toml");
            let body = std::fs::read_to_string(root().join("scenarios/circle-iso230-4.toml"))
                .unwrap()
                .lines()
                .filter(|l| !l.starts_with("machine"))
                .collect::<Vec<_>>()
                .join("\n");
            let text = format!("machine = {:?}\n{body}\n", machine.display().to_string());
            std::fs::write(&scenario, text).unwrap();
            let command = *rng.pick(&["check", "simulate", "analyze", "cone"]);
            (command, scenario, what)
        }
        1 => {
            let (scenario, what) = edited(rng, "scenarios", dir, "s.toml");
            let command = *rng.pick(&["check", "simulate", "analyze", "cone", "cut"]);
            (command, scenario, what)
        }
        _ => {
            let (study, what) = edited(rng, "scenarios/studies", dir, "t.toml");
            ("study", study, what)
        }
    };
    let mut args = vec![command.to_string(), file.display().to_string()];
    match command {
        "simulate" => args.extend(["-o".into(), out, "--no-budget".into()]),
        "cut" => args.extend(["-o".into(), out]),
        "study" => args.extend(["-o".into(), out]),
        "cone" => args.extend(["-o".into(), dir.join("cone.nc").display().to_string()]),
        _ => {}
    }
    if command == "study" && what.starts_with("tolerance") {
        // A random study: a trial run of its first points.
        args.extend(["--samples".into(), "3".into()]);
    }
    Case {
        label: format!("{command} {what}"),
        args,
        must_refuse: false,
        never_quoted: None,
    }
}

/// A path case: a program path that names a file which is not a program (a machine file,
/// bytes, an image, a folder, nothing), or a measured trace that is not a trace.
fn path_case(rng: &mut Rng, dir: &Path) -> Case {
    const MARKER: &str = "SECRET-CONTENT-7f3a";
    let kind = rng.below(6);
    let (name, bytes): (&str, Vec<u8>) = match kind {
        0 => (
            "p.toml",
            format!("# {MARKER}\n[axes.X]\nmin = 0\n").into_bytes(),
        ),
        1 => ("p.nc", {
            let mut b = vec![0u8, 159, 146, 150];
            b.extend(MARKER.bytes());
            b
        }),
        2 => ("p.png", {
            let mut b = b"\x89PNG\r\n\x1a\n".to_vec();
            b.extend(MARKER.bytes());
            b
        }),
        3 => ("p.csv", format!("time_s,{MARKER}\n1,2\n").into_bytes()),
        4 => ("p.nc", Vec::new()),
        _ => ("missing.nc", Vec::new()),
    };
    if kind != 5 {
        std::fs::write(dir.join(name), &bytes).unwrap();
    }
    let scenario = program_scenario(dir, name, "fanuc");
    let (args, refuse) = if kind == 3 && rng.below(2) == 0 {
        // A measured trace that is not one, for `fit`.
        let fit_scenario = root().join("scenarios/circle-iso230-4.toml");
        (
            vec![
                "fit".into(),
                fit_scenario.display().to_string(),
                "--measured".into(),
                dir.join(name).display().to_string(),
                "-o".into(),
                dir.join("out").display().to_string(),
            ],
            true,
        )
    } else {
        let command = *rng.pick(&["analyze", "check", "blocks", "simulate"]);
        let mut args = vec![command.to_string(), scenario.display().to_string()];
        if command == "simulate" {
            args.extend(["-o".into(), dir.join("out").display().to_string()]);
        }
        // An empty program is a program with nothing in it; the others are refused.
        (args, kind != 4)
    };
    Case {
        label: format!("{} on a {name} that is not a program ({kind})", args[0]),
        args,
        must_refuse: refuse,
        never_quoted: Some(MARKER.into()),
    }
}

/// Bytes below `path` (a file, or a folder's files).
fn bytes_below(path: &Path) -> u64 {
    let Ok(meta) = std::fs::symlink_metadata(path) else {
        return 0;
    };
    if !meta.is_dir() {
        return meta.len();
    }
    std::fs::read_dir(path)
        .map(|entries| entries.flatten().map(|e| bytes_below(&e.path())).sum())
        .unwrap_or(0)
}

/// Runs one case in `dir` under the campaign's limits and records how it ended.
fn run(case: &Case, dir: &Path, tally: &mut Tally) {
    let stdout_path = dir.join("stdout");
    let stdout = std::fs::File::create(&stdout_path).unwrap();
    let script = format!("ulimit -v {MEMORY_LIMIT_KIB}; exec \"$0\" -q \"$@\"");
    let output = Command::new("timeout")
        .args(["-k", "5", &TIME_LIMIT_S.to_string(), "sh", "-c", &script])
        .arg(env!("CARGO_BIN_EXE_mtsim"))
        .args(&case.args)
        .current_dir(dir)
        .env("NO_COLOR", "1")
        .stdin(Stdio::null())
        .stdout(stdout)
        .output()
        .expect("timeout and sh run");
    let code = output.status.code().unwrap_or(-1);
    let stderr = String::from_utf8_lossy(&output.stderr);
    tally.cases += 1;
    *tally.by_code.entry(code).or_default() += 1;
    let written = bytes_below(&dir.join("out")) + bytes_below(&stdout_path);
    let mut bad = |why: String| tally.bad.push(format!("{}: {why}", case.label));
    match code {
        0..=3 => {}
        124 | 137 => bad(format!("did not end within {TIME_LIMIT_S} s")),
        _ => bad(format!(
            "exit {code}: {}",
            stderr.chars().take(300).collect::<String>()
        )),
    }
    if stderr.contains("panicked") || stderr.contains("memory allocation") {
        bad(format!(
            "crashed: {}",
            stderr.chars().take(300).collect::<String>()
        ));
    }
    if case.must_refuse && code != 2 {
        bad(format!("accepted (exit {code}); it must be refused"));
    }
    if code == 2 && stderr.trim().is_empty() {
        bad("refused without a message".into());
    }
    if let Some(marker) = &case.never_quoted {
        if stderr.contains(marker.as_str()) {
            bad(format!("quoted the file's content: {stderr}"));
        }
    }
    if written > OUTPUT_LIMIT {
        bad(format!("wrote {written} bytes"));
    }
}

/// The whole campaign: `n` cases from `seed`, in fresh folders; the tally.
fn campaign(seed: u64, n: usize) -> Tally {
    let mut rng = Rng(seed);
    let mut tally = Tally::default();
    let base = std::env::temp_dir().join(format!("mtsim-campaign-{}", std::process::id()));
    for i in 0..n {
        let dir = base.join(format!("{i}"));
        std::fs::create_dir_all(&dir).unwrap();
        let case = match i % 8 {
            0..=4 => program_case(&mut rng, &dir),
            5 | 6 => file_case(&mut rng, &dir),
            _ => path_case(&mut rng, &dir),
        };
        run(&case, &dir, &mut tally);
        let _ = std::fs::remove_dir_all(&dir);
    }
    let _ = std::fs::remove_dir_all(&base);
    tally
}

/// Every dialect's seed reads cleanly: a mutation's refusal is the mutation's.
#[test]
fn each_dialect_s_seed_program_reads_cleanly() {
    for d in &DIALECTS {
        let dir = crate::common::scratch("campaign-seed", d.name);
        std::fs::write(dir.join(d.file), d.seed).unwrap();
        let scenario = program_scenario(&dir, d.file, d.name);
        let o = crate::common::mtsim(&["analyze", scenario.to_str().unwrap()]);
        assert_eq!(
            o.status.code(),
            Some(0),
            "{}: {}",
            d.name,
            String::from_utf8_lossy(&o.stderr)
        );
    }
}

#[test]
fn a_seeded_campaign_of_hostile_inputs_ends_cleanly_every_time() {
    if Command::new("timeout").arg("--version").output().is_err() {
        assert!(
            std::env::var_os("CI").is_none(),
            "`timeout` (coreutils) is missing"
        );
        eprintln!("skipped: `timeout` (coreutils) is not installed");
        return;
    }
    let n = if std::env::var_os("MTSIM_LONG_FAULTS").is_some() {
        1200
    } else {
        320
    };
    let tally = campaign(0x5EED_0042, n);
    eprintln!(
        "campaign: {} cases, exit codes {:?}, {} bad",
        tally.cases,
        tally.by_code,
        tally.bad.len()
    );
    assert!(tally.bad.is_empty(), "{:#?}", tally.bad);
}
