//! Dotted key paths into a scenario and its machine, and values set through them.
//!
//! A path names one value of the scenario's TOML tree: `program.cone.center_mm[1]`,
//! `simulate.lead_deg`; a path under `machine.` names a key of the machine file
//! (`machine.axes.X.drive.backlash_mm`), set through the scenario's `[machine_overrides]`.
//! Values are set on the tree before the scenario is validated, so every key is reachable
//! and every value meets the checks a value written in the file meets.

use std::fmt;
use std::path::Path;
use std::str::FromStr;

use crate::error::{Error, Result};
use crate::input::machine::MachineBase;
use crate::input::scenario::Scenario;
use crate::input::toml_text;

/// One step of a key path: a table key or an array index.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Step {
    Key(String),
    Index(usize),
}

/// The most parts a key path may have: the deepest key of a scenario with its machine
/// (`machine.axes.B.location_errors.x_mm`, say) has 6, so 32 leaves room and keeps every
/// walk over a path, and the tables it makes, shallow whatever the input.
pub const MAX_KEY_PARTS: usize = 32;

/// A dotted key path: `machine.axes.X.servo.kv_per_s`, `program.cone.center_mm[1]`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct KeyPath {
    pub steps: Vec<Step>,
}

impl FromStr for KeyPath {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<KeyPath, String> {
        let bad = |why: &str| {
            format!("key path {s:?}: {why}; expected e.g. machine.axes.X.drive.backlash_mm or program.cone.center_mm[1]")
        };
        let mut steps = Vec::new();
        if s.split('.').count() > MAX_KEY_PARTS {
            return Err(bad(&format!(
                "more than {MAX_KEY_PARTS} parts (no scenario or machine key is that deep)"
            )));
        }
        for part in s.split('.') {
            let (name, mut rest) = part.split_at(part.find('[').unwrap_or(part.len()));
            let key_char = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '-';
            if name.is_empty() || !name.chars().all(key_char) {
                return Err(bad("each part is a key of letters, digits, `_` or `-`"));
            }
            steps.push(Step::Key(name.to_string()));
            while !rest.is_empty() {
                let inner = rest
                    .strip_prefix('[')
                    .and_then(|r| r.split_once(']'))
                    .ok_or_else(|| bad("an index is written [n]"))?;
                let index = inner
                    .0
                    .parse()
                    .map_err(|_| bad("an index is a whole number"))?;
                steps.push(Step::Index(index));
                if steps.len() > 2 * MAX_KEY_PARTS {
                    return Err(bad("too many indexes"));
                }
                rest = inner.1;
            }
        }
        Ok(KeyPath { steps })
    }
}

impl fmt::Display for KeyPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, step) in self.steps.iter().enumerate() {
            match step {
                Step::Key(k) if i == 0 => write!(f, "{k}")?,
                Step::Key(k) => write!(f, ".{k}")?,
                Step::Index(n) => write!(f, "[{n}]")?,
            }
        }
        Ok(())
    }
}

/// The table of a scenario file that holds a machine file's keys.
const OVERRIDES: &str = "machine_overrides";

/// Sets `value` at `path` in the scenario tree `scenario`; a `machine.` path lands under
/// `[machine_overrides]`. Missing tables are made (a drive table a machine file leaves out);
/// an index must name an element that exists. An integer key keeps an integer value when
/// `value` is whole. `current` is the value the path has before (in the scenario, or in the
/// machine tree `machine` for a `machine.` path), for the integer rule.
pub fn set(
    scenario: &mut toml::Table,
    machine: &toml::Table,
    path: &KeyPath,
    value: f64,
) -> std::result::Result<(), String> {
    let (root, steps) = match path.steps.split_first() {
        Some((Step::Key(k), rest)) if k == "machine" && !rest.is_empty() => {
            let overrides = scenario
                .entry(OVERRIDES)
                .or_insert_with(|| toml::Value::Table(toml::Table::new()));
            let integer = matches!(get(machine, rest), Some(toml::Value::Integer(_)));
            copy_indexed_array(overrides, machine, rest);
            return set_in(overrides, rest, value, integer, path);
        }
        _ => (scenario, &path.steps[..]),
    };
    let integer = matches!(get(root, steps), Some(toml::Value::Integer(_)));
    let mut table = toml::Value::Table(std::mem::take(root));
    let result = set_in(&mut table, steps, value, integer, path);
    if let toml::Value::Table(t) = table {
        *root = t;
    }
    result
}

/// An index below `machine.` names an element of an array the machine file holds, while an
/// override replaces an array whole: the overrides take a copy of the array at the first
/// index's place (unless they hold one already), and the element is then set in the copy,
/// so the other elements keep the machine file's values.
fn copy_indexed_array(overrides: &mut toml::Value, machine: &toml::Table, steps: &[Step]) {
    let Some(first) = steps.iter().position(|s| matches!(s, Step::Index(_))) else {
        return;
    };
    let prefix = &steps[..first];
    let toml::Value::Table(table) = overrides else {
        return;
    };
    let mut at: &mut toml::Table = table;
    if get(at, prefix).is_some() {
        return;
    }
    let Some(array) = get(machine, prefix).cloned() else {
        return;
    };
    // The prefix is keys only: `first` is its first index.
    let Some((Step::Key(last), tables)) = prefix.split_last() else {
        return;
    };
    for step in tables {
        let Step::Key(key) = step else { return };
        at = match at
            .entry(key.clone())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()))
        {
            toml::Value::Table(t) => t,
            _ => return,
        };
    }
    at.insert(last.clone(), array);
}

/// The value at `steps` below `table`, if there is one.
pub fn get<'a>(table: &'a toml::Table, steps: &[Step]) -> Option<&'a toml::Value> {
    let (Step::Key(first), rest) = steps.split_first()? else {
        return None;
    };
    let mut at = table.get(first)?;
    for step in rest {
        at = match (step, at) {
            (Step::Key(k), toml::Value::Table(t)) => t.get(k)?,
            (Step::Index(i), toml::Value::Array(a)) => a.get(*i)?,
            _ => return None,
        };
    }
    Some(at)
}

fn set_in(
    mut at: &mut toml::Value,
    steps: &[Step],
    value: f64,
    integer: bool,
    path: &KeyPath,
) -> std::result::Result<(), String> {
    for step in steps {
        at = match (step, at) {
            (Step::Key(k), toml::Value::Table(t)) => t
                .entry(k.clone())
                .or_insert_with(|| toml::Value::Table(toml::Table::new())),
            (Step::Index(i), toml::Value::Array(a)) => {
                let n = a.len();
                a.get_mut(*i).ok_or_else(|| {
                    format!("`{path}`: index {i} is past the end of an array of {n}")
                })?
            }
            (Step::Index(_), _) => {
                return Err(format!("`{path}`: indexes a value that is not an array"))
            }
            (Step::Key(k), _) => {
                return Err(format!(
                    "`{path}`: `{k}` is below a value that is not a table"
                ))
            }
        };
    }
    *at = if integer && value.fract() == 0.0 && value.abs() < 9.0e15 {
        toml::Value::Integer(value as i64)
    } else {
        toml::Value::Float(value)
    };
    Ok(())
}

/// A scenario file read once, to be loaded again and again with values set on its tree.
#[derive(Clone, Debug)]
pub struct ScenarioTree {
    pub path: std::path::PathBuf,
    pub tree: toml::Table,
    /// The machine file's tree with the scenario's own `[machine_overrides]` over it.
    pub machine: toml::Table,
    /// The scenario as its file gives it.
    pub base: Scenario,
    /// The machine file it names, read once.
    machine_file: MachineBase,
}

impl ScenarioTree {
    /// Reads the scenario at `path` and its machine file's tree.
    pub fn read(path: &Path) -> Result<ScenarioTree> {
        let text = toml_text::read_text(path)?;
        let (base, machine_file) = Scenario::with_machine(path, &text, None)?;
        let tree: toml::Table = toml_text::parse(path, &text)?;
        let mut machine = machine_file.tree().clone();
        if let Some(toml::Value::Table(o)) = tree.get(OVERRIDES) {
            crate::input::machine::deep_merge(&mut machine, o);
        }
        Ok(ScenarioTree {
            path: path.to_path_buf(),
            tree,
            machine,
            base,
            machine_file,
        })
    }

    /// The scenario with `values` set at `keys`, validated as a scenario file is (built
    /// from the tree, [`Scenario::from_tree`]). A path that names no key is an error that
    /// names the nearest keys there are.
    pub fn load_with(&self, keys: &[KeyPath], values: &[f64]) -> Result<Scenario> {
        let mut tree = self.tree.clone();
        for (key, &value) in keys.iter().zip(values) {
            set(&mut tree, &self.machine, key, value).map_err(|m| Error::invalid(&self.path, m))?;
        }
        Scenario::from_tree(&self.path, &tree, &self.machine_file)
            .map_err(|e| self.name_the_key(e, keys))
    }

    /// An "unknown field" error of a set key, restated as the study's key path with the
    /// nearest keys the scenario or machine takes at that place.
    fn name_the_key(&self, e: Error, keys: &[KeyPath]) -> Error {
        let message = e.to_string();
        let Some(unknown) = message
            .split_once("unknown field `")
            .and_then(|(_, rest)| rest.split('`').next())
        else {
            return e;
        };
        // The step is looked for below the `machine.` prefix, which names the tree, not a key.
        let found = keys.iter().find_map(|k| {
            let offset = tree_offset(k);
            let depth = k.steps[offset..]
                .iter()
                .position(|s| *s == Step::Key(unknown.to_string()))?;
            Some((k, depth + offset))
        });
        let Some((key, depth)) = found else {
            return e;
        };
        // Serde's list of the fields the table takes, then the keys the file has there.
        let mut names: Vec<String> = message
            .split_once("expected one of")
            .or_else(|| message.split_once("expected `"))
            .map(|(_, list)| {
                list.split('`')
                    .skip(1)
                    .step_by(2)
                    .map(str::to_string)
                    .collect()
            })
            .unwrap_or_default();
        let (tree, offset) = match key.steps.first() {
            Some(Step::Key(k)) if k == "machine" => (&self.machine, 1),
            _ => (&self.tree, 0),
        };
        let present = match depth - offset {
            0 => Some(tree),
            d => match get(tree, &key.steps[offset..offset + d]) {
                Some(toml::Value::Table(t)) => Some(t),
                _ => None,
            },
        };
        for name in present.into_iter().flat_map(|t| t.keys()) {
            if !names.contains(name) {
                names.push(name.clone());
            }
        }
        names.sort_by_key(|n| (edit_distance(n, unknown), n.clone()));
        Error::usage(format!(
            "study key `{key}` names no key of the scenario {} or its machine: `{unknown}` is not a key there; nearest: {}",
            self.path.display(),
            nearest_keys(key, depth, &names)
        ))
    }
}

/// 1 for a `machine.` key (its first step names the machine's tree), else 0.
fn tree_offset(key: &KeyPath) -> usize {
    match key.steps.first() {
        Some(Step::Key(k)) if k == "machine" => 1,
        _ => 0,
    }
}

impl ScenarioTree {
    /// Where `key` leaves the scenario's (or, for `machine.`, the machine's) tree: the
    /// depth of its first step that is not there and the nearest keys present beside it;
    /// None when the whole path is present.
    pub fn absent(&self, key: &KeyPath) -> Option<(usize, Vec<String>)> {
        let (tree, offset) = match key.steps.first() {
            Some(Step::Key(k)) if k == "machine" => (&self.machine, 1),
            _ => (&self.tree, 0),
        };
        let steps = &key.steps[offset..];
        let depth = (0..steps.len()).find(|&d| get(tree, &steps[..=d]).is_none())?;
        let mut present: Vec<String> = match depth {
            0 => tree.keys().cloned().collect(),
            d => match get(tree, &steps[..d]) {
                Some(toml::Value::Table(t)) => t.keys().cloned().collect(),
                _ => Vec::new(),
            },
        };
        if let Step::Key(bad) = &steps[depth] {
            present.sort_by_key(|n| (edit_distance(n, bad), n.clone()));
        }
        Some((depth + offset, present))
    }
}

/// The first three of `names` (nearest first) as full paths beside step `depth` of `key`:
/// "`machine.axes.X.drive.backlash_mm`, ...".
pub fn nearest_keys(key: &KeyPath, depth: usize, names: &[String]) -> String {
    let prefix = KeyPath {
        steps: key.steps[..depth].to_vec(),
    };
    let full: Vec<String> = names
        .iter()
        .take(3)
        .map(|n| match depth {
            0 => format!("`{n}`"),
            _ => format!("`{prefix}.{n}`"),
        })
        .collect();
    full.join(", ")
}

/// Levenshtein distance of two keys, in characters.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for j in 0..b.len() {
            let next = (diagonal + usize::from(ca != b[j]))
                .min(row[j] + 1)
                .min(row[j + 1] + 1);
            diagonal = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_parse_and_print_back() {
        for s in [
            "machine.axes.X.drive.backlash_mm",
            "program.cone.center_mm[1]",
        ] {
            assert_eq!(s.parse::<KeyPath>().unwrap().to_string(), s);
        }
        assert!("a..b".parse::<KeyPath>().is_err());
        assert!("a[x]".parse::<KeyPath>().is_err());
    }

    #[test]
    fn edit_distance_counts_edits() {
        assert_eq!(edit_distance("backlash_mm", "bakclash_mm"), 2);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(edit_distance("kv", "kv"), 0);
    }
}
