//! The docs match the binary: every `mtsim ...` command README.md and docs/*.md show (in
//! code blocks, tables, headings and prose) is listed in [`SHOWN`] with what the test does
//! with it: run a concrete instance on the bundled scenarios in a scratch folder and check
//! its exit code, check that a command named in prose exists with the options it names, or
//! say why it cannot run here. Beside that, the names the docs list are compared with real
//! output: `blocks` columns and JSON fields, `check --json` keys, the placement and batch
//! columns, the README's example output, the scale-out example's hashes and the man pages.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::common;

use common::scratch;

const SC: &str = "scenarios/cone-15-10.toml";
const FILE_SC: &str = "scenarios/file-cone-15-10-yt25.toml";
const CIRCLE: &str = "scenarios/circle-iso230-4.toml";

/// What the test does with one command the docs show.
enum Shown {
    /// Runs these argument lists, in order, in the shared scratch folder; each must exit
    /// with its code.
    Run(&'static [(&'static [&'static str], i32)]),
    /// A command named in prose: its subcommand must exist and its `--help` must list
    /// every `--option` the text names.
    Names,
    /// A line of the worked example of docs/scale-out.md: run as the whole block by
    /// `the_scale_out_example_gives_its_hashes`.
    Example,
    /// Cannot run in a test, and why.
    Skip(&'static str),
}

use Shown::{Example, Names, Run, Skip};

/// Every command the docs show (after `\|` in tables is read as `|` and runs of white
/// space as one space), with what is done with it. The runs are in order: later ones use
/// earlier outputs (`out/`, `shards/`).
const SHOWN: &[(&str, Shown)] = &[
    ("mtsim --help", Run(&[(&["--help"], 0)])),
    ("mtsim COMMAND --help", Names),
    (
        "mtsim cone SCENARIO -o cone.nc [--g93] [--tcp]",
        Run(&[
            (&["cone", SC, "-o", "cone.nc"], 0),
            (&["cone", SC, "-o", "cone-g93.nc", "--g93"], 0),
            (&["cone", SC, "-o", "cone-tcp.nc", "--tcp"], 0),
        ]),
    ),
    ("mtsim cone SCENARIO [-o FILE] [--g93] [--tcp]", Run(&[(&["cone", SC], 0)])),
    ("mtsim cut SCENARIO -o DIR", Names),
    (
        "mtsim cut SCENARIO [-o DIR] [--commanded] [--theta-step-deg D] [--heights-mm Z,..] [--no-budget] [--json]",
        Run(&[(&["cut", SC, "-o", "cut-h", "--heights-mm", "30,40,50", "--json"], 0)]),
    ),
    ("mtsim cut scenarios/cone-15-10.toml -o cut", Run(&[(&["cut", SC, "-o", "cut"], 0)])),
    (
        "mtsim cut scenarios/cone-15-10.toml -o cut0 --commanded",
        Run(&[(&["cut", SC, "-o", "cut0", "--commanded"], 0)]),
    ),
    (
        "mtsim cut scenarios/file-cone-15-10-yt25.toml -o cutf",
        Run(&[(&["cut", FILE_SC, "-o", "cutf"], 0)]),
    ),
    (
        "mtsim analyze SCENARIO [--json]",
        Run(&[(&["analyze", SC], 0), (&["analyze", FILE_SC, "--json"], 0)]),
    ),
    ("mtsim analyze scenarios/cone-15-10.toml", Run(&[(&["analyze", SC], 0)])),
    (
        "mtsim sweep SCENARIO --vary center_y --from -160 --to 0 --step 0.5 [-o DIR] [--json]",
        Run(&[(
            &["sweep", SC, "--vary", "center_y", "--from", "-160", "--to", "0", "--step", "0.5", "-o", "sweep", "--json"],
            0,
        )]),
    ),
    (
        "mtsim sweep SCENARIO --vary P --from A --to B --step S [--json] [-o DIR]",
        Run(&[(
            &["sweep", SC, "--vary", "half_apex", "--from", "10", "--to", "20", "--step", "5", "--json", "-o", "sweep-half"],
            0,
        )]),
    ),
    (
        "mtsim sweep ... -o DIR --html",
        Run(&[(
            &["sweep", SC, "--vary", "center_y", "--from", "-30", "--to", "-15", "--step", "5", "-o", "sweep-html", "--html"],
            0,
        )]),
    ),
    ("mtsim simulate SCENARIO -o out/", Run(&[(&["simulate", SC, "-o", "out/"], 0)])),
    (
        "mtsim simulate SCENARIO [-o DIR] [--json] [--no-timing] [--html]",
        Run(&[(&["simulate", CIRCLE, "-o", "circle", "--json", "--no-timing", "--html"], 0)]),
    ),
    ("mtsim report out/", Run(&[(&["report", "out/"], 0)])),
    ("mtsim report RUN_DIR", Run(&[(&["report", "out/"], 0)])),
    (
        "mtsim report RUN_DIR... [--date YYYY-MM-DD]",
        Run(&[(&["report", "out/", "circle", "--date", "2026-01-31"], 0)]),
    ),
    (
        "mtsim report --date YYYY-MM-DD",
        Run(&[(&["report", "out/", "--date", "2026-01-31"], 0)]),
    ),
    (
        "mtsim check SCENARIO [--dynamics | --programmed]",
        Run(&[
            (&["check", SC], 0),
            (&["check", SC, "--dynamics"], 0),
            (&["check", SC, "--programmed"], 0),
        ]),
    ),
    (
        "mtsim check SCENARIO [--json] [--dynamics | --programmed] [--near-miss MM]",
        Run(&[(&["check", SC, "--json", "--near-miss", "5"], 0)]),
    ),
    (
        "mtsim check SCENARIO [--json] [--dynamics | --programmed] [--near-miss MM] [--html FILE]",
        Run(&[(&["check", FILE_SC, "--programmed", "--html", "check.html"], 0)]),
    ),
    (
        "mtsim fit A.toml --measured a.csv [B.toml --measured b.csv ...] -o fit/",
        Run(&[(&["fit", SC, "--measured", "out/trace.csv", "-o", "fit/"], 0)]),
    ),
    (
        "mtsim fit SCENARIO --measured TRACE.csv [SCENARIO --measured TRACE.csv ...] [-o DIR] [--placement-known] [--backlash] [--servo-gain] [--json]",
        Run(&[(
            &["fit", SC, "--measured", "out/trace.csv", "-o", "fit-known", "--placement-known", "--json"],
            0,
        )]),
    ),
    (
        "mtsim blocks SCENARIO [--csv | --json]",
        Run(&[
            (&["blocks", FILE_SC], 0),
            (&["blocks", FILE_SC, "--csv"], 0),
            (&["blocks", SC, "--json"], 0),
        ]),
    ),
    (
        "mtsim sweep SCENARIO --feasibility --vary center_x,center_y --from -200,-250 --to 200,150 --step 20,20 -o map/",
        Run(&[(
            &["sweep", SC, "--feasibility", "--vary", "center_x,center_y", "--from", "-200,-250", "--to", "200,150", "--step", "20,20", "-o", "map/"],
            0,
        )]),
    ),
    (
        "mtsim sweep SCENARIO --feasibility --vary center_x,center_y --from X0,Y0 --to X1,Y1 --step DX,DY [-o DIR] [--json]",
        Run(&[(
            &["sweep", SC, "--feasibility", "--vary", "center_x,center_y", "--from", "-200,-250", "--to", "200,150", "--step", "100,100", "-o", "map-coarse", "--json"],
            0,
        )]),
    ),
    (
        "mtsim sweep SCENARIO --feasibility --vary center_x,center_y --from X0,Y0 --to X1,Y1 --step DX,DY -o DIR",
        Run(&[(
            &["sweep", SC, "--feasibility", "--vary", "center_x,center_y", "--from", "-200,-250", "--to", "200,150", "--step", "200,200", "-o", "map-3x3"],
            0,
        )]),
    ),
    (
        "mtsim batch SCENARIO... [--list FILE] -o DIR [--simulate] [--json]",
        Run(&[(&["batch", SC, CIRCLE, "-o", "batch", "--json"], 0)]),
    ),
    (
        "mtsim batch [SCENARIO...] [--list FILE] -o DIR [--simulate] [--shard K/N] [--json]",
        Run(&[(&["batch", "--list", "list.txt", "-o", "batch-list", "--simulate"], 0)]),
    ),
    (
        "mtsim sweep ... --shard K/N -o DIR",
        Run(&[
            (&["sweep", SC, "--vary", "center_y", "--from", "-30", "--to", "-15", "--step", "5", "--shard", "1/2", "-o", "shards"], 0),
            (&["sweep", SC, "--vary", "center_y", "--from", "-30", "--to", "-15", "--step", "5", "--shard", "2/2", "-o", "shards"], 0),
        ]),
    ),
    (
        "mtsim merge DIR/*.json -o OUT [--json]",
        Run(&[(
            &["merge", "shards/sweep-center_y.shard-1-of-2.json", "shards/sweep-center_y.shard-2-of-2.json", "-o", "merged", "--json"],
            0,
        )]),
    ),
    (
        "mtsim merge SHARDS... -o DIR [--json]",
        Run(&[(
            &["merge", "shards/sweep-center_y.shard-2-of-2.json", "shards/sweep-center_y.shard-1-of-2.json", "-o", "merged-2"],
            0,
        )]),
    ),
    (
        "mtsim ... --shard K/N",
        Skip("the Kubernetes/Ray pattern of docs/scale-out.md (needs a cluster); `--shard` runs in the `sweep ... --shard K/N` entry"),
    ),
    (
        "mtsim completions SHELL",
        Run(&[
            (&["completions", "bash"], 0),
            (&["completions", "elvish"], 0),
            (&["completions", "fish"], 0),
            (&["completions", "powershell"], 0),
            (&["completions", "zsh"], 0),
        ]),
    ),
    (
        "mtsim completions bash > ~/.local/share/bash-completion/completions/mtsim",
        Run(&[(&["completions", "bash"], 0)]),
    ),
    ("mtsim man > mtsim.1", Run(&[(&["man"], 0)])),
    ("mtsim man [-o DIR]", Run(&[(&["man"], 0), (&["man", "-o", "man"], 0)])),
    ("mtsim man -o DIR", Run(&[(&["man", "-o", "man"], 0)])),
    ("mtsim $STUDY -o single > single.txt", Example),
    ("mtsim $STUDY --shard $k/8 -o shards", Example),
    ("mtsim merge shards/*.json -o merged > merged.txt", Example),
    (
        "python3 examples/dask/run_study.py --shards 8 --out study -- sweep scenarios/cone-15-10.toml --vary center_y --from -30 --to -15 --step 0.5",
        Skip("needs Python with the mtsim package and dask.distributed; tests/cli/dask_example.rs runs this example on a LocalCluster"),
    ),
    (
        "python3 examples/dask/run_study.py --scheduler tcp://SCHEDULER:8786 --shards 64 --out study -- batch --list plant-programs.txt",
        Skip("needs a running Dask cluster (tcp://SCHEDULER:8786) and a plant's program list"),
    ),
    (
        "mtsim study STUDY.toml -o DIR",
        Run(&[(&["study", "scenarios/studies/kv-x-circle.toml", "-o", "study-kv"], 0)]),
    ),
    (
        "mtsim study STUDY -o DIR [--g-limit-um UM] [--samples N] [--shard K/N] [--json]",
        Run(&[(
            &["study", "scenarios/studies/tolerance-cone-15-10.toml", "-o", "study-trial", "--g-limit-um", "30", "--samples", "3", "--json"],
            0,
        )]),
    ),
    (
        "mtsim study scenarios/studies/backlash-x-circle.toml -o backlash",
        Run(&[(&["study", "scenarios/studies/backlash-x-circle.toml", "-o", "backlash"], 0)]),
    ),
    (
        "mtsim study scenarios/studies/tolerance-cone-15-10.toml -o tolerance",
        // The 1,000 points take half a minute of CPU: the test runs 4 of them
        // (tests/study/param_study.rs runs 20).
        Run(&[(&["study", "scenarios/studies/tolerance-cone-15-10.toml", "-o", "tolerance", "--samples", "4"], 0)]),
    ),
    (
        "mtsim study scenarios/studies/tolerance-cone-15-10.toml --shard $k/4 -o shards",
        Run(&[
            (&["study", "scenarios/studies/tolerance-cone-15-10.toml", "--samples", "4", "--shard", "1/2", "-o", "shards-study"], 0),
            (&["study", "scenarios/studies/tolerance-cone-15-10.toml", "--samples", "4", "--shard", "2/2", "-o", "shards-study"], 0),
        ]),
    ),
    (
        "mtsim merge shards/study.shard-*.json -o tolerance",
        Run(&[(
            &["merge", "shards-study/study.shard-1-of-2.json", "shards-study/study.shard-2-of-2.json", "-o", "tolerance-merged"],
            0,
        )]),
    ),
    (
        "python3 examples/dask/run_study.py --shards 8 --out tolerance -- study scenarios/studies/tolerance-cone-15-10.toml",
        Skip("needs Python with dask.distributed; the sweep's run of the same script is tested in tests/cli/dask_example.rs"),
    ),
    ("mtsim study", Names),
    ("mtsim study --samples 128", Names),
    ("mtsim study -q", Names),
    ("mtsim study scenarios/studies/tolerance-cone-15-10.toml -q", Names),
    ("mtsim <version>", Skip("the Parquet files' `created_by` text, not a command")),
    ("mtsim analyze", Names),
    ("mtsim batch", Names),
    ("mtsim blocks", Names),
    ("mtsim blocks --csv", Names),
    ("mtsim blocks --csv > file", Names),
    ("mtsim check", Names),
    ("mtsim check --json", Names),
    ("mtsim cone", Names),
    ("mtsim cut", Names),
    ("mtsim fit", Names),
    ("mtsim merge", Names),
    ("mtsim report", Names),
    ("mtsim simulate", Names),
    ("mtsim simulate --no-timing", Names),
    ("mtsim simulate --no-budget -q --no-timing", Names),
];

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// README.md and docs/*.md, as (path relative to the repository, text).
fn docs() -> Vec<(String, String)> {
    let mut names: Vec<String> = std::fs::read_dir(repo().join("docs"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".md"))
        .map(|n| format!("docs/{n}"))
        .collect();
    names.sort();
    names.insert(0, "README.md".into());
    names
        .into_iter()
        .map(|n| {
            let text = std::fs::read_to_string(repo().join(&n)).unwrap();
            (n, text)
        })
        .collect()
}

/// One space for each run of white space, `|` for the tables' `\|`, no shell comment.
fn normalise(command: &str) -> String {
    let command = command.split(" #").next().unwrap().replace("\\|", "|");
    command.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The `mtsim ...` commands of one Markdown text with their (last) line: lines of code
/// blocks that run mtsim (`mtsim ...`, `$ mtsim ...`, `do mtsim ...;`, and the examples'
/// scripts `python3 examples/...` that run it) and inline code spans that start with
/// `mtsim ` (a span may wrap over lines of its paragraph).
fn commands_in(text: &str) -> Vec<(String, usize)> {
    let mut found = Vec::new();
    let mut in_block = false;
    let mut paragraph = String::new();
    let mut paragraph_line = 0;
    let mut continued = String::new();
    let flush = |paragraph: &mut String, line: usize, found: &mut Vec<(String, usize)>| {
        for (i, span) in paragraph.split('`').enumerate() {
            if i % 2 == 1 && span.starts_with("mtsim ") {
                found.push((normalise(span), line));
            }
        }
        paragraph.clear();
    };
    for (i, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            flush(&mut paragraph, paragraph_line, &mut found);
            in_block = !in_block;
        } else if in_block {
            // A line ending in `\` goes on in the next one.
            if !continued.is_empty() || line.trim_end().ends_with('\\') {
                continued.push_str(line.trim_end().trim_end_matches('\\'));
                continued.push(' ');
                if line.trim_end().ends_with('\\') {
                    continue;
                }
            }
            let joined = std::mem::take(&mut continued);
            let t = if joined.is_empty() { line } else { &joined };
            let t = t.trim().trim_start_matches("$ ");
            let start = t
                .find("do mtsim ")
                .map(|k| k + 3)
                .or((t.starts_with("mtsim ") || t.starts_with("python3 examples/")).then_some(0));
            if let Some(start) = start {
                let command = t[start..].split(';').next().unwrap();
                found.push((normalise(command), i + 1));
            }
        } else if line.trim().is_empty() {
            flush(&mut paragraph, paragraph_line, &mut found);
        } else {
            if paragraph.is_empty() {
                paragraph_line = i + 1;
            }
            paragraph.push_str(line);
            paragraph.push('\n');
        }
    }
    flush(&mut paragraph, paragraph_line, &mut found);
    found
}

/// Every command the docs show, with the first `file:line` that shows it.
fn shown_commands() -> BTreeMap<String, String> {
    let mut shown = BTreeMap::new();
    for (name, text) in docs() {
        for (command, line) in commands_in(&text) {
            shown.entry(command).or_insert(format!("{name}:{line}"));
        }
    }
    shown
}

/// A scratch folder that holds the bundled scenarios and machines (as links) and a
/// `list.txt` for `batch --list`.
fn workspace(name: &str) -> PathBuf {
    let dir = scratch("docs", name);
    for sub in ["scenarios", "machines"] {
        std::os::unix::fs::symlink(repo().join(sub), dir.join(sub)).unwrap();
    }
    std::fs::write(
        dir.join("list.txt"),
        "# two cones\nscenarios/cone-15-10.toml\nscenarios/cone-45-30.toml\n",
    )
    .unwrap();
    dir
}

fn run_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mtsim"))
        .args(args)
        .current_dir(dir)
        .env("NO_COLOR", "1")
        .output()
        .expect("the binary runs")
}

fn help(sub: Option<&str>) -> String {
    let args: Vec<&str> = sub.into_iter().chain(["--help"]).collect();
    let out = run_in(repo(), &args);
    assert!(
        out.status.success(),
        "mtsim {args:?} exits {:?}",
        out.status.code()
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The subcommands `mtsim --help` lists.
fn subcommands() -> Vec<String> {
    let text = help(None);
    let list = text
        .split("Commands:")
        .nth(1)
        .expect("--help lists the commands");
    list.lines()
        .skip(1)
        .take_while(|l| !l.trim().is_empty())
        .filter_map(|l| l.split_whitespace().next())
        .filter(|n| *n != "help")
        .map(String::from)
        .collect()
}

#[test]
fn every_command_the_docs_show_is_listed_once() {
    let shown = shown_commands();
    let listed: BTreeSet<&str> = SHOWN.iter().map(|(c, _)| *c).collect();
    assert_eq!(
        listed.len(),
        SHOWN.len(),
        "a command is listed twice in SHOWN"
    );
    let unlisted: Vec<String> = shown
        .iter()
        .filter(|(c, _)| !listed.contains(c.as_str()))
        .map(|(c, at)| format!("{at}: `{c}`"))
        .collect();
    assert!(
        unlisted.is_empty(),
        "commands the docs show that the test does not know; add them to SHOWN:\n{}",
        unlisted.join("\n")
    );
    let stale: Vec<&&str> = listed.iter().filter(|c| !shown.contains_key(**c)).collect();
    assert!(
        stale.is_empty(),
        "SHOWN lists commands no doc shows any more: {stale:?}"
    );
    let counts = SHOWN.iter().fold([0; 4], |mut n, (_, s)| {
        n[match s {
            Run(_) => 0,
            Names => 1,
            Example => 2,
            Skip(_) => 3,
        }] += 1;
        n
    });
    for (command, shown) in SHOWN {
        if let Skip(reason) = shown {
            assert!(
                !reason.is_empty(),
                "`{command}` is skipped without a reason"
            );
            println!("not run: `{command}`: {reason}");
        }
    }
    println!(
        "{} commands shown: {} run, {} named in prose, {} in the scale-out example, {} skipped",
        shown.len(),
        counts[0],
        counts[1],
        counts[2],
        counts[3]
    );
}

#[test]
fn every_command_the_docs_show_runs_with_the_exit_code_they_imply() {
    let dir = workspace("run");
    let subs = subcommands();
    let mut runs = 0;
    for (command, shown) in SHOWN {
        match shown {
            Run(list) => {
                for (args, code) in *list {
                    let out = run_in(&dir, args);
                    assert_eq!(
                        out.status.code(),
                        Some(*code),
                        "`{command}` as `mtsim {}`: stderr {}",
                        args.join(" "),
                        String::from_utf8_lossy(&out.stderr)
                    );
                    runs += 1;
                }
            }
            Names => {
                let words: Vec<&str> = command.split_whitespace().skip(1).collect();
                let subs_named: Vec<&str> = match words[0] {
                    "COMMAND" => subs.iter().map(String::as_str).collect(),
                    sub => vec![sub],
                };
                for sub in subs_named {
                    assert!(
                        subs.iter().any(|s| s == sub),
                        "`{command}`: no subcommand {sub}"
                    );
                    let text = help(Some(sub));
                    for option in words.iter().filter(|w| w.starts_with("--")) {
                        assert!(
                            text.contains(option),
                            "`{command}`: `mtsim {sub} --help` lacks {option}"
                        );
                    }
                }
            }
            Example | Skip(_) => {}
        }
    }
    println!("{runs} runs of documented commands, all with their documented exit codes");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The fenced block of `lang` that follows the first line of `text` containing `after`.
fn block_after<'a>(text: &'a str, after: &str, lang: &str) -> &'a str {
    let rest = &text[text.find(after).unwrap_or_else(|| panic!("no `{after}`"))..];
    let fence = format!("```{lang}\n");
    let start = rest.find(&fence).unwrap() + fence.len();
    &rest[start..start + rest[start..].find("```").unwrap()]
}

fn doc(name: &str) -> String {
    std::fs::read_to_string(repo().join(name)).unwrap()
}

#[test]
fn the_readme_example_prints_what_the_binary_prints() {
    let readme = doc("README.md");
    let block = block_after(&readme, "## Example", "text");
    let (command, printed) = block.split_once('\n').unwrap();
    let args: Vec<&str> = command
        .trim_start_matches("$ mtsim ")
        .split_whitespace()
        .collect();
    let out = run_in(repo(), &args);
    assert!(out.status.success());
    assert_eq!(
        String::from_utf8_lossy(&out.stdout),
        printed,
        "README's example output is stale"
    );
}

#[test]
fn the_scale_out_example_gives_its_hashes() {
    // The worked example's shell block, run as written with the binary on PATH; its
    // standard output (sha256sum of the single and merged files) is the text block after it.
    let text = doc("docs/scale-out.md");
    let script = block_after(&text, "## Worked example", "sh");
    let expected = block_after(&text, "gives (mtsim", "text");
    let dir = workspace("scale-out");
    let bin = Path::new(env!("CARGO_BIN_EXE_mtsim")).parent().unwrap();
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let out = Command::new("sh")
        .args(["-e", "-c", script])
        .current_dir(&dir)
        .env("PATH", path)
        .output()
        .expect("sh runs");
    assert!(
        out.status.success(),
        "the example fails: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        String::from_utf8_lossy(&out.stdout),
        expected,
        "docs/scale-out.md's hashes are stale"
    );
    let single = std::fs::read_to_string(dir.join("single.txt")).unwrap();
    let last = text
        .split("ending in\n`")
        .nth(1)
        .unwrap()
        .split('`')
        .next()
        .unwrap();
    assert_eq!(single.lines().last(), Some(last));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The backticked names of the first column of the Markdown table that follows `after`.
fn first_column(text: &str, after: &str) -> Vec<String> {
    let rest = &text[text.find(after).unwrap()..];
    rest.lines()
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'))
        .skip(2)
        .flat_map(|l| {
            let cell = l.split('|').nth(1).unwrap();
            cell.split('`')
                .skip(1)
                .step_by(2)
                .flat_map(|s| s.split([' ', ',']))
                .filter(|s| !s.is_empty())
                .map(String::from)
                .collect::<Vec<_>>()
        })
        .collect()
}

#[test]
fn the_blocks_columns_and_fields_are_the_documented_ones() {
    let cli = doc("docs/cli.md");
    let section = &cli[cli.find("## `mtsim blocks").unwrap()..];
    let documented = first_column(section, "Columns:");
    let csv = run_in(repo(), &["blocks", FILE_SC, "--csv"]);
    let header = String::from_utf8_lossy(&csv.stdout)
        .lines()
        .next()
        .unwrap()
        .to_string();
    let columns: Vec<&str> = header.split(',').collect();
    // u_mm v_mm w_mm only on a machine with U V W (trt-ac has none).
    let without_uvw: Vec<&str> = documented
        .iter()
        .map(String::as_str)
        .filter(|c| !["u_mm", "v_mm", "w_mm"].contains(c))
        .collect();
    assert_eq!(columns, without_uvw, "docs/cli.md's blocks columns");
    let json = run_in(repo(), &["blocks", FILE_SC, "--json"]);
    let rows: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
    let keys: Vec<&String> = rows[0].as_object().unwrap().keys().collect();
    let sentence = section
        .split("`--json` prints")
        .nth(1)
        .unwrap()
        .split("\n\n")
        .next()
        .unwrap();
    let named: BTreeSet<&str> = sentence
        .split('`')
        .skip(1)
        .step_by(2)
        .flat_map(|s| s.split(' '))
        .collect();
    for key in &keys {
        assert!(
            named.contains(key.as_str()),
            "blocks --json field {key} is not in docs/cli.md ({named:?})"
        );
    }
    assert_eq!(keys.len(), columns.len(), "one JSON field per CSV column");
}

/// Every quoted name in a JSON sketch of the docs.
fn quoted(sketch: &str) -> BTreeSet<String> {
    sketch
        .split('"')
        .skip(1)
        .step_by(2)
        .map(String::from)
        .collect()
}

fn keys_of(value: &serde_json::Value, into: &mut BTreeSet<String>) {
    match value {
        serde_json::Value::Object(map) => {
            for (k, v) in map {
                // `axes` is keyed by axis name; its values are what the sketch lists.
                if k.len() > 1 {
                    into.insert(k.clone());
                }
                keys_of(v, into);
            }
        }
        serde_json::Value::Array(items) => items.iter().for_each(|v| keys_of(v, into)),
        _ => {}
    }
}

#[test]
fn the_check_json_keys_and_placement_columns_are_the_documented_ones() {
    let text = doc("docs/check.md");
    let sketch = quoted(block_after(&text, "## Output", "json"));
    // A clean run and one with a travel violation and held feeds (exit 1): the cone's
    // centre 300 mm off in Y, at F20000.
    let dir = workspace("check");
    let body = "[program.cone]\nhalf_apex_deg = 15.0\ninclination_deg = 10.0\ncenter_mm = [0.0, -300.0, 200.0]\nballbar_length_mm = 100.0\nfeed_mm_min = 20000.0\n";
    let bad = common::write_scenario(&dir, &common::trt_ac(), body);
    let mut keys = BTreeSet::new();
    for (scenario, code) in [(SC, 0), (bad.to_str().unwrap(), 1)] {
        let out = run_in(&dir, &["check", scenario, "--json"]);
        assert_eq!(
            out.status.code(),
            Some(code),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        keys_of(&serde_json::from_slice(&out.stdout).unwrap(), &mut keys);
    }
    assert!(keys.contains("feed_reductions") && keys.contains("theta_start_deg"));
    let missing: Vec<&String> = keys.difference(&sketch).collect();
    assert!(
        missing.is_empty(),
        "check --json keys docs/check.md does not list: {missing:?}"
    );

    let out = run_in(
        &dir,
        &[
            "sweep",
            SC,
            "--feasibility",
            "--vary",
            "center_x,center_y",
            "--from",
            "-200,-250",
            "--to",
            "200,150",
            "--step",
            "200,200",
            "-o",
            "map",
        ],
    );
    assert!(out.status.success());
    let csv = std::fs::read_to_string(dir.join("map/placement.csv")).unwrap();
    let documented = text
        .split("placement.csv` (`")
        .nth(1)
        .unwrap()
        .split('`')
        .next()
        .unwrap();
    assert_eq!(
        csv.lines().next().unwrap(),
        documented.replace(", ", ","),
        "docs/check.md's placement columns"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_batch_columns_are_the_documented_ones() {
    let documented = first_column(&doc("docs/scale-out.md"), "### `mtsim batch`");
    let dir = workspace("batch");
    let out = run_in(&dir, &["batch", CIRCLE, "-o", "b"]);
    assert!(out.status.success());
    let csv = std::fs::read_to_string(dir.join("b/batch.csv")).unwrap();
    assert_eq!(
        csv.lines().next().unwrap(),
        documented.join(","),
        "docs/scale-out.md's batch columns"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn man_writes_a_page_for_every_subcommand_its_page_names() {
    let dir = workspace("man");
    let out = run_in(&dir, &["man", "-o", "pages"]);
    assert!(out.status.success());
    let main = std::fs::read_to_string(dir.join("pages/mtsim.1")).unwrap();
    assert_eq!(
        main.as_bytes(),
        run_in(&dir, &["man"]).stdout,
        "-o writes what stdout prints"
    );
    // Each `mtsim\-NAME(1)` the page names (roff escapes the hyphen).
    let named: Vec<&str> = main
        .split("mtsim\\-")
        .skip(1)
        .filter_map(|s| s.split_once("(1)"))
        .map(|(n, _)| n)
        .collect();
    let mut subs = subcommands();
    subs.sort();
    let mut sorted = named.clone();
    sorted.sort();
    assert_eq!(sorted, subs, "the page names every subcommand and no other");
    for name in named {
        let page = std::fs::read_to_string(dir.join(format!("pages/mtsim-{name}.1")))
            .unwrap_or_else(|_| panic!("no page mtsim-{name}.1"));
        assert!(
            page.contains(&format!(".TH mtsim-{name} 1")),
            "mtsim-{name}.1's title"
        );
        assert!(
            page.contains(&format!("\\fBmtsim {name}\\fR")),
            "mtsim-{name}.1's synopsis"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_analyze_and_sweep_json_keys_are_the_documented_ones() {
    // Every key of the real output is quoted in docs/cli.md's sketch of that command.
    let cli = doc("docs/cli.md");
    let cases: [(&str, &[&str]); 2] = [
        ("## `mtsim analyze", &["analyze", FILE_SC, "--json"]),
        (
            "## `mtsim sweep SCENARIO --vary",
            &[
                "sweep", SC, "--vary", "center_y", "--from", "-30", "--to", "-15", "--step", "5",
                "--json",
            ],
        ),
    ];
    for (section, args) in cases {
        let text = &cli[cli.find(section).unwrap()..];
        let text = &text[..text[3..].find("\n## ").map_or(text.len(), |k| k + 3)];
        let mut sketch = BTreeSet::new();
        for block in text.split("```json\n").skip(1) {
            sketch.extend(quoted(block.split("```").next().unwrap()));
        }
        let out = run_in(repo(), args);
        assert!(out.status.success());
        let mut keys = BTreeSet::new();
        keys_of(&serde_json::from_slice(&out.stdout).unwrap(), &mut keys);
        let missing: Vec<&String> = keys.difference(&sketch).collect();
        assert!(
            missing.is_empty(),
            "`mtsim {}` keys docs/cli.md does not list: {missing:?}",
            args[0]
        );
    }
}
