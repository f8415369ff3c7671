//! A generated property suite of hostile inputs, in process (issue 42): every bundled machine,
//! scenario and study file, one of its keys given a value no key should take, removed, or
//! joined by an unknown key; and the bundled G-code program with hostile words put in. Over
//! 1,000 cases a run. Each case must load cleanly or fail with exit code 2, naming the file
//! with its line and column, never panic, and never quote the machine file's marker.
//!
//! The binary suite beside it (`bad_inputs.rs`) writes every key out by hand; this one draws
//! the keys from the bundled files and the values at random, so that a key added to a file
//! is covered the day it is added.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use mtsim::input::machine::Machine;
use mtsim::input::scenario::Scenario;
use mtsim::study::param::Study;
use proptest::prelude::*;
use proptest::test_runner::Config;
use toml::Value;

/// The repository root.
pub(crate) fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The bundled files of one kind, sorted.
pub(crate) fn bundled(folder: &str) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(root().join(folder))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    files
}

/// A value of each kind that no key of a machine, scenario or study should take as it is,
/// or that sits at the edge of what a number can be.
pub(crate) fn hostile_values() -> Vec<Value> {
    let f = Value::Float;
    vec![
        f(f64::NAN),
        f(f64::INFINITY),
        f(f64::NEG_INFINITY),
        f(1e308),
        f(-1e308),
        f(5e-324),
        f(-1.0),
        f(0.0),
        Value::Integer(i64::MAX),
        Value::Integer(i64::MIN),
        Value::Integer(0),
        Value::Integer(-1),
        Value::String("x".into()),
        Value::String("ü".repeat(5000)),
        Value::Boolean(true),
        Value::Array(vec![]),
        Value::Array(vec![f(f64::NAN), f(0.0), f(0.0)]),
        Value::Array(vec![f(1e308); 7]),
        Value::Table(toml::Table::new()),
    ]
}

/// The dotted paths of every value below `table` (tables are walked into; an array is one
/// value, and each of its elements another).
pub(crate) fn leaves(table: &toml::Table) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let mut stack: Vec<(Vec<String>, &Value)> =
        table.iter().map(|(k, v)| (vec![k.clone()], v)).collect();
    while let Some((path, value)) = stack.pop() {
        match value {
            Value::Table(t) => {
                out.push(path.clone());
                stack.extend(t.iter().map(|(k, v)| {
                    let mut p = path.clone();
                    p.push(k.clone());
                    (p, v)
                }));
            }
            Value::Array(a) => {
                out.push(path.clone());
                for (i, v) in a.iter().enumerate() {
                    if !matches!(v, Value::Table(_)) {
                        let mut p = path.clone();
                        p.push(format!("[{i}]"));
                        out.push(p);
                    }
                }
            }
            _ => out.push(path),
        }
    }
    out.sort();
    out
}

/// What is done to the chosen key.
#[derive(Clone, Debug)]
pub(crate) enum Edit {
    Set(usize),
    Remove,
    Unknown,
}

/// Applies `edit` to the value at `path` in `table` (nothing when the path is gone).
pub(crate) fn apply(table: &mut toml::Table, path: &[String], edit: &Edit, values: &[Value]) {
    let (last, parents) = path.split_last().unwrap();
    let (walk, element) = match last.strip_prefix('[').and_then(|s| s.strip_suffix(']')) {
        // An array element: the array is the value at the parents' last part.
        Some(index) => match parents.split_last() {
            Some((_, above)) => (above, Some(index.parse::<usize>().unwrap())),
            None => return,
        },
        None => (parents, None),
    };
    let mut at = table;
    for step in walk {
        at = match at.get_mut(step) {
            Some(Value::Table(t)) => t,
            _ => return,
        };
    }
    if let Some(index) = element {
        return set_element(at, parents, index, edit, values);
    }
    match edit {
        Edit::Set(i) => {
            at.insert(last.clone(), values[*i].clone());
        }
        Edit::Remove => {
            at.remove(last);
        }
        Edit::Unknown => {
            match at.get_mut(last) {
                Some(Value::Table(t)) => t.insert("zz_not_a_key".into(), Value::Integer(1)),
                _ => at.insert(format!("{last}_not_a_key"), Value::Integer(1)),
            };
        }
    }
}

/// Element `index` of the array that `parents` ends in (inside `table`, its parent table).
fn set_element(
    table: &mut toml::Table,
    parents: &[String],
    index: usize,
    edit: &Edit,
    values: &[Value],
) {
    let Some(name) = parents.last() else { return };
    let Some(Value::Array(array)) = table.get_mut(name) else {
        return;
    };
    if index >= array.len() {
        return;
    }
    match edit {
        Edit::Set(i) => array[index] = values[*i].clone(),
        Edit::Remove => {
            array.remove(index);
        }
        Edit::Unknown => array.push(Value::Integer(1)),
    }
}

/// A relative file key (`machine`, `file`, `scenario`) of a bundled file made absolute, so
/// that the edited copy in a scratch folder still names the bundled file.
pub(crate) fn absolute_paths(table: &mut toml::Table, dir: &Path) {
    for key in ["machine", "scenario"] {
        if let Some(Value::String(p)) = table.get_mut(key) {
            *p = dir.join(&*p).display().to_string();
        }
    }
    if let Some(Value::Table(program)) = table.get_mut("program") {
        if let Some(Value::String(p)) = program.get_mut("file") {
            *p = dir.join(&*p).display().to_string();
        }
    }
}

/// A scratch folder for this process's cases.
fn scratch() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mtsim-hostile-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Whether `text` names a place: `NAME:line:column`.
pub(crate) fn names_place(text: &str, name: &str) -> bool {
    text.match_indices(name).any(|(i, _)| {
        let rest = &text[i + name.len()..];
        let mut parts = rest.splitn(3, ':');
        parts.next() == Some("")
            && parts
                .next()
                .is_some_and(|l| !l.is_empty() && l.bytes().all(|b| b.is_ascii_digit()))
            && parts
                .next()
                .is_some_and(|c| c.bytes().next().is_some_and(|b| b.is_ascii_digit()))
    })
}

/// Loads `path` with `load`: no panic, and either a clean load or exit code 2 naming
/// `name` (or the machine file a scenario names) with line and column, or, where the key
/// is not in the file to point at (removed, or a table that lacks what it needs), with the
/// key: one of the parts of `key`.
fn loads_or_names_the_place<T>(
    path: &Path,
    load: impl FnOnce(&Path) -> mtsim::error::Result<T>,
    case: &str,
    key: &[String],
) -> Result<(), TestCaseError> {
    let name = path.file_name().unwrap().to_string_lossy().into_owned();
    let outcome = catch_unwind(AssertUnwindSafe(|| load(path)));
    let Ok(result) = outcome else {
        return Err(TestCaseError::fail(format!("{case}: panicked")));
    };
    if let Err(e) = result {
        let code = e.exit_code();
        let text = format!("{e}");
        prop_assert_eq!(code, 2, "{}: exit {} for {}", case, code, text);
        // A scenario's error may be about the machine file it names (never quoted).
        let named_key = key
            .iter()
            .filter(|k| !k.starts_with('['))
            .any(|k| text.contains(k.as_str()));
        let placed = names_place(&text, &name)
            || names_place(&text, ".toml")
            || text.contains("cannot read")
            || (text.contains(&name) && named_key);
        prop_assert!(
            placed,
            "{}: the error names no file:line:column: {}",
            case,
            text
        );
    }
    Ok(())
}

/// One case: file `index` of `files`, leaf `leaf` of it edited by `edit`.
fn edited_copy(
    files: &[PathBuf],
    index: usize,
    leaf: usize,
    edit: &Edit,
    tag: &str,
) -> (PathBuf, String, Vec<String>) {
    let source = &files[index % files.len()];
    let text = std::fs::read_to_string(source).unwrap();
    let mut table: toml::Table = toml::from_str(&text).unwrap();
    absolute_paths(&mut table, source.parent().unwrap());
    let paths = leaves(&table);
    let path = &paths[leaf % paths.len()];
    apply(&mut table, path, edit, &hostile_values());
    let out = scratch().join(format!("{tag}.toml"));
    std::fs::write(&out, toml::to_string(&table).unwrap_or_default()).unwrap();
    let case = format!(
        "{} with {} {:?}",
        source.file_name().unwrap().to_string_lossy(),
        path.join("."),
        edit
    );
    (out, case, path.clone())
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        6 => (0..hostile_values().len()).prop_map(Edit::Set),
        1 => Just(Edit::Remove),
        1 => Just(Edit::Unknown),
    ]
}

/// Words a program should never be able to hang, crash or fool the reader with.
const HOSTILE_WORDS: [&str; 24] = [
    "G1 X1.2.3",
    "#1=[1/0]",
    "G1 X[",
    "G2 X10 R0",
    "F-1",
    "F0 G1 X5",
    "G1 X1e999",
    "M98 P1 L99999999",
    "G65 P9000 L99999999",
    "O100 WHILE [1 LT 2] DO1",
    "GOTO 1",
    "o1 repeat [1000000000]",
    "(unclosed comment",
    "#<_undefined>",
    "G43.4 H99",
    "G68.2 X0 Y0 Z0 I90 J90 K90",
    "G10 L2 P9 X1e308",
    "N99999999999999999999",
    "G4 P1e300",
    "T999999 M6",
    "\u{0}\u{1}\u{7f}",
    "G91 G28 Z0",
    "G7 G18 G2 X1 Z1 R0.1",
    "%",
];

proptest! {
    #![proptest_config(Config { cases: 300, failure_persistence: None, ..Config::default() })]

    /// 300 edited machine files.
    #[test]
    fn an_edited_machine_file_loads_or_names_its_place(
        index in 0usize..64, leaf in 0usize..4096, edit in edit(),
    ) {
        let files = bundled("machines");
        let (path, case, key) = edited_copy(&files, index, leaf, &edit, "m");
        loads_or_names_the_place(&path, Machine::load, &case, &key)?;
    }

    /// 300 edited scenario files.
    #[test]
    fn an_edited_scenario_loads_or_names_its_place(
        index in 0usize..64, leaf in 0usize..4096, edit in edit(),
    ) {
        let files = bundled("scenarios");
        let (path, case, key) = edited_copy(&files, index, leaf, &edit, "s");
        loads_or_names_the_place(&path, Scenario::load, &case, &key)?;
    }

    /// 300 edited study files.
    #[test]
    fn an_edited_study_loads_or_names_its_place(
        index in 0usize..64, leaf in 0usize..4096, edit in edit(),
    ) {
        let files = bundled("scenarios/studies");
        let (path, case, key) = edited_copy(&files, index, leaf, &edit, "t");
        loads_or_names_the_place(&path, |p| Study::load(p, None, None), &case, &key)?;
    }

    /// 300 programs with hostile words put in: read and analysed in process, they end
    /// cleanly or fail with exit code 2 at a place in the program, never panic.
    #[test]
    fn a_program_with_hostile_words_is_read_or_refused(
        words in proptest::collection::vec((0usize..HOSTILE_WORDS.len(), 0usize..420), 1..4),
    ) {
        let base = std::fs::read_to_string(root().join("scenarios/programs/cone-15-10-yt25.nc")).unwrap();
        let mut lines: Vec<&str> = base.lines().collect();
        for (word, at) in &words {
            let at = at % (lines.len() + 1);
            lines.insert(at, HOSTILE_WORDS[*word]);
        }
        let dir = scratch();
        std::fs::write(dir.join("p.nc"), lines.join("\n")).unwrap();
        let scenario = dir.join("p.toml");
        std::fs::write(
            &scenario,
            format!(
                "machine = \"{}\"\n[program]\nfile = \"p.nc\"\n",
                root().join("machines/trt-ac.toml").display()
            ),
        )
        .unwrap();
        let case: Vec<&str> = words.iter().map(|(w, _)| HOSTILE_WORDS[*w]).collect();
        let analyse = |path: &Path| {
            Scenario::load(path).and_then(|s| mtsim::study::analysis::analyse_program(&s))
        };
        // The error names the program, p.nc, with its line and column.
        let outcome = catch_unwind(AssertUnwindSafe(|| analyse(&scenario)));
        prop_assert!(outcome.is_ok(), "{:?}: panicked", case);
        if let Err(e) = outcome.unwrap() {
            let text = format!("{e}");
            prop_assert_eq!(e.exit_code(), 2, "{:?}: {}", case, text);
            prop_assert!(names_place(&text, "p.nc"), "{:?}: no p.nc:line:column in {}", case, text);
        }
    }
}
