//! A LinuxCNC configuration file (`.ini`) as far as the interpreter needs it: the tool
//! table, parameter file, subroutine and user-M search paths, remaps, and the machine's
//! length units.
//!
//! The format (LinuxCNC `docs/config/ini-config`): `[SECTION]` headers, `KEY = value`
//! lines, `#` and `;` comment lines, and `#INCLUDE file` lines that insert another file
//! (relative to the including file's folder) in place. A key may repeat (`REMAP`); for
//! single-valued keys the first occurrence wins, as LinuxCNC's `IniFile::Find` does.
//! Paths in values are relative to the folder of the top-level `.ini`; search paths are
//! colon-separated.

use std::path::{Path, PathBuf};

/// One `KEY = value` line.
#[derive(Clone, Debug, PartialEq)]
pub struct IniEntry {
    /// Section name without brackets, upper-case as written (`RS274NGC`).
    pub section: String,
    pub key: String,
    pub value: String,
    /// The file the line is in (an `#INCLUDE`d file or the ini itself) and its 1-based line.
    pub path: PathBuf,
    pub line: usize,
}

/// An ini file that could not be read: where and why. The message names keys and what was
/// expected, never the file's text (the file may be anything a scenario names).
#[derive(Clone, Debug, PartialEq)]
pub struct IniError {
    pub path: PathBuf,
    /// 1-based line, 0 when the file itself could not be opened.
    pub line: usize,
    pub message: String,
}

impl std::fmt::Display for IniError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.line == 0 {
            write!(f, "{}: {}", self.path.display(), self.message)
        } else {
            write!(f, "{}:{}: {}", self.path.display(), self.line, self.message)
        }
    }
}

/// A parsed LinuxCNC ini file.
#[derive(Clone, Debug, PartialEq)]
pub struct Ini {
    /// The top-level file.
    pub path: PathBuf,
    pub entries: Vec<IniEntry>,
}

/// Deepest `#INCLUDE` nesting accepted (a file including itself is an error, not a hang).
const MAX_INCLUDE_DEPTH: usize = 8;

impl Ini {
    /// Reads `path` and the files it includes.
    pub fn read(path: &Path) -> Result<Ini, IniError> {
        let mut entries = Vec::new();
        read_into(path, 0, &mut String::new(), &mut entries)?;
        Ok(Ini {
            path: path.to_path_buf(),
            entries,
        })
    }

    /// Parses `text` as the content of `path` (no `#INCLUDE` allowed to be missing: they are
    /// read from disk relative to `path`).
    pub fn parse(path: &Path, text: &str) -> Result<Ini, IniError> {
        let mut entries = Vec::new();
        parse_into(path, text, 0, &mut String::new(), &mut entries)?;
        Ok(Ini {
            path: path.to_path_buf(),
            entries,
        })
    }

    /// The folder paths in values are relative to.
    pub fn dir(&self) -> &Path {
        self.path.parent().unwrap_or(Path::new("."))
    }

    /// The first value of `[section] key` (case-insensitive names).
    pub fn get(&self, section: &str, key: &str) -> Option<&IniEntry> {
        self.entries
            .iter()
            .find(|e| e.section.eq_ignore_ascii_case(section) && e.key.eq_ignore_ascii_case(key))
    }

    /// Every value of `[section] key`, in file order.
    pub fn all<'a>(&'a self, section: &'a str, key: &'a str) -> impl Iterator<Item = &'a IniEntry> {
        self.entries.iter().filter(move |e| {
            e.section.eq_ignore_ascii_case(section) && e.key.eq_ignore_ascii_case(key)
        })
    }

    /// `value` as a path relative to the ini's folder.
    pub fn resolve(&self, value: &str) -> PathBuf {
        let p = Path::new(value.trim());
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.dir().join(p)
        }
    }

    /// A colon-separated search path (`SUBROUTINE_PATH = nc_subs:../common`), resolved.
    pub fn search_path(&self, section: &str, key: &str) -> Vec<PathBuf> {
        self.get(section, key)
            .map(|e| {
                e.value
                    .split(':')
                    .map(str::trim)
                    .filter(|s| !s.is_empty())
                    .map(|s| self.resolve(s))
                    .collect()
            })
            .unwrap_or_default()
    }

    /// `[TRAJ]LINEAR_UNITS`: true for `inch`/`in`/`imperial`, false for mm (the default)
    /// and for anything else LinuxCNC reads as millimetres.
    pub fn linear_units_inch(&self) -> Result<bool, IniError> {
        let Some(e) = self.get("TRAJ", "LINEAR_UNITS") else {
            return Ok(false);
        };
        match e.value.trim().to_ascii_lowercase().as_str() {
            "inch" | "in" | "imperial" => Ok(true),
            "mm" | "metric" | "millimeter" | "millimetre" => Ok(false),
            v => match v.parse::<f64>() {
                // LinuxCNC also accepts the number of machine units per mm.
                Ok(u) if (u - 1.0 / 25.4).abs() < 1e-6 => Ok(true),
                Ok(u) if (u - 1.0).abs() < 1e-9 => Ok(false),
                _ => Err(IniError {
                    path: e.path.clone(),
                    line: e.line,
                    message: "[TRAJ]LINEAR_UNITS: expected `mm`, `inch` or the machine units \
                              per mm"
                        .into(),
                }),
            },
        }
    }
}

/// What the interpreter takes from a configuration, paths resolved, lengths still in the
/// machine units of `[TRAJ]LINEAR_UNITS` (see [`Ini::tool_table`], [`Ini::parameters`]).
#[derive(Clone, Debug, PartialEq)]
pub struct LinuxcncConfig {
    /// `[EMCIO]TOOL_TABLE`.
    pub tool_table: Option<PathBuf>,
    /// `[RS274NGC]PARAMETER_FILE`.
    pub parameter_file: Option<PathBuf>,
    /// `[RS274NGC]SUBROUTINE_PATH`.
    pub subroutine_path: Vec<PathBuf>,
    /// `[RS274NGC]USER_M_PATH`, then `[DISPLAY]PROGRAM_PREFIX`: where M100-M199 programs are.
    pub user_m_path: Vec<PathBuf>,
    /// `[RS274NGC]REMAP` lines, in order.
    pub remaps: Vec<crate::remap::Remap>,
    /// `[TRAJ]LINEAR_UNITS` is inch: tool table and parameter file lengths are in inches.
    pub inch: bool,
}

impl Ini {
    /// The interpreter's part of the configuration.
    pub fn config(&self) -> Result<LinuxcncConfig, IniError> {
        let python = self.python_dirs();
        let mut remaps = Vec::new();
        for e in self.all("RS274NGC", "REMAP") {
            let origin = format!("{}:{}", e.path.display(), e.line);
            let mut r = crate::remap::parse_remap(&e.value, origin).map_err(|m| IniError {
                path: e.path.clone(),
                line: e.line,
                message: format!("REMAP = {}: {m}", e.value),
            })?;
            if r.ngc.is_none() {
                let f = r.python.as_deref().unwrap_or("");
                r.python_motion = crate::remap::python_motion(&python, f);
                r.python_keeps_motion = crate::remap::python_keeps_motion(&python, f);
            }
            crate::remap::check_handlers(&python, &mut r);
            remaps.push(r);
        }
        let mut user_m_path = self.search_path("RS274NGC", "USER_M_PATH");
        user_m_path.extend(self.search_path("DISPLAY", "PROGRAM_PREFIX"));
        Ok(LinuxcncConfig {
            tool_table: self
                .get("EMCIO", "TOOL_TABLE")
                .map(|e| self.resolve(&e.value)),
            parameter_file: self
                .get("RS274NGC", "PARAMETER_FILE")
                .map(|e| self.resolve(&e.value)),
            subroutine_path: self.search_path("RS274NGC", "SUBROUTINE_PATH"),
            user_m_path,
            remaps,
            inch: self.linear_units_inch()?,
        })
    }

    /// The folders of a configuration's `[PYTHON]` section: `PATH_PREPEND`, `PATH_APPEND` and
    /// the folder of `TOPLEVEL`, relative to `ini_dir`.
    pub fn python_dirs(&self) -> Vec<PathBuf> {
        let mut dirs = Vec::new();
        for key in ["PATH_PREPEND", "PATH_APPEND"] {
            for e in self.all("PYTHON", key) {
                dirs.extend(
                    e.value
                        .split(':')
                        .filter(|s| !s.trim().is_empty())
                        .map(|s| self.resolve(s)),
                );
            }
        }
        if let Some(e) = self.get("PYTHON", "TOPLEVEL") {
            dirs.push(
                self.resolve(&e.value)
                    .parent()
                    .map_or_else(|| self.dir().to_path_buf(), Path::to_path_buf),
            );
        }
        dirs
    }
}

/// Multiplies the lengths of LinuxCNC parameters by `factor` (machine inches to mm): the
/// X Y Z (and U V W) words of G28 (5161-), G30 (5181-), G92 (5211-) and the nine
/// coordinate systems (5221-5389, 20 apart); rotations and angles stay.
pub fn scale_parameter_lengths(params: &mut [(u32, f64)], factor: f64) {
    for (n, v) in params.iter_mut() {
        let base = match *n {
            5161..=5169 => 5161,
            5181..=5189 => 5181,
            5211..=5219 => 5211,
            5221..=5399 => 5221 + 20 * ((*n - 5221) / 20),
            _ => continue,
        };
        if matches!(*n - base, 0..=2 | 6..=8) {
            *v *= factor;
        }
    }
}

fn read_into(
    path: &Path,
    depth: usize,
    section: &mut String,
    entries: &mut Vec<IniEntry>,
) -> Result<(), IniError> {
    let text = crate::side_file::read_side_file(path).map_err(|e| IniError {
        path: path.to_path_buf(),
        line: 0,
        message: format!("cannot read the LinuxCNC configuration: {e}"),
    })?;
    parse_into(path, &text, depth, section, entries)
}

fn parse_into(
    path: &Path,
    text: &str,
    depth: usize,
    section: &mut String,
    entries: &mut Vec<IniEntry>,
) -> Result<(), IniError> {
    let err = |line: usize, message: String| IniError {
        path: path.to_path_buf(),
        line,
        message,
    };
    for (k, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if let Some(rest) = line.strip_prefix("#INCLUDE") {
            let file = rest.trim();
            if depth >= MAX_INCLUDE_DEPTH {
                return Err(err(k + 1, format!("`#INCLUDE {file}` nested deeper than {MAX_INCLUDE_DEPTH}: expected no file to include itself")));
            }
            let included = path.parent().unwrap_or(Path::new(".")).join(file);
            read_into(&included, depth + 1, section, entries).map_err(|e| {
                if e.line == 0 {
                    err(k + 1, format!("`#INCLUDE {file}`: {}", e.message))
                } else {
                    e
                }
            })?;
            continue;
        }
        if line.is_empty() || line.starts_with('#') || line.starts_with(';') {
            continue;
        }
        if let Some(name) = line.strip_prefix('[') {
            let Some(name) = name.strip_suffix(']') else {
                return Err(err(
                    k + 1,
                    "expected a section header `[NAME]` closed by `]`".into(),
                ));
            };
            *section = name.trim().to_string();
            continue;
        }
        let Some((key, value)) = line.split_once('=') else {
            return Err(err(
                k + 1,
                "expected `KEY = value`, a `[SECTION]` header or a comment".into(),
            ));
        };
        if section.is_empty() {
            return Err(err(
                k + 1,
                "`KEY = value` before any `[SECTION]` header: expected a header first".into(),
            ));
        }
        entries.push(IniEntry {
            section: section.clone(),
            key: key.trim().to_string(),
            value: value.trim().to_string(),
            path: path.to_path_buf(),
            line: k + 1,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const DEMO: &str = "\
# a comment
[RS274NGC]
PARAMETER_FILE = sim.var
SUBROUTINE_PATH = nc_subroutines: ../../common
REMAP= M400  modalgroup=10 argspec=Pq ngc=m400
REMAP= M410  modalgroup=10 argspec=@Pq ngc=m410
PARAMETER_FILE = second.var

[TRAJ]
LINEAR_UNITS = inch
";

    #[test]
    fn keys_sections_repeats_and_paths() {
        let ini = Ini::parse(Path::new("/cfg/demo.ini"), DEMO).unwrap();
        // The first of a repeated single-valued key wins.
        assert_eq!(
            ini.get("rs274ngc", "parameter_file").unwrap().value,
            "sim.var"
        );
        assert_eq!(ini.get("RS274NGC", "PARAMETER_FILE").unwrap().line, 3);
        let remaps: Vec<_> = ini.all("RS274NGC", "REMAP").map(|e| e.line).collect();
        assert_eq!(remaps, [5, 6]);
        assert_eq!(
            ini.search_path("RS274NGC", "SUBROUTINE_PATH"),
            [
                PathBuf::from("/cfg/nc_subroutines"),
                PathBuf::from("/cfg/../../common")
            ]
        );
        assert_eq!(ini.resolve("/abs/t.tbl"), PathBuf::from("/abs/t.tbl"));
        assert!(ini.linear_units_inch().unwrap());
        assert!(ini.get("EMCIO", "TOOL_TABLE").is_none());
    }

    #[test]
    fn errors_name_file_and_line() {
        let e = Ini::parse(Path::new("a.ini"), "[X]\nA = 1\njunk line\n").unwrap_err();
        assert_eq!((e.line, e.to_string().starts_with("a.ini:3: ")), (3, true));
        let e = Ini::parse(Path::new("a.ini"), "A = 1\n").unwrap_err();
        assert_eq!(e.line, 1);
        let e = Ini::parse(Path::new("a.ini"), "[TRAJ\n").unwrap_err();
        assert_eq!(e.line, 1);
        let e = Ini::parse(Path::new("a.ini"), "[TRAJ]\nLINEAR_UNITS = furlong\n")
            .unwrap()
            .linear_units_inch()
            .unwrap_err();
        assert_eq!(e.line, 2);
        let e = Ini::read(Path::new("/nonexistent/x.ini")).unwrap_err();
        assert_eq!(e.line, 0);
    }

    #[test]
    fn include_inserts_another_file_in_place() {
        let dir = std::env::temp_dir().join(format!("ngc-ini-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("base.inc"), "[TRAJ]\nLINEAR_UNITS = inch\n").unwrap();
        std::fs::write(
            dir.join("top.ini"),
            "[EMCIO]\nTOOL_TABLE = t.tbl\n#INCLUDE base.inc\nMAX = 2\n",
        )
        .unwrap();
        std::fs::write(dir.join("loop.ini"), "#INCLUDE loop.ini\n").unwrap();
        std::fs::write(dir.join("missing.ini"), "[A]\n#INCLUDE nothere.inc\n").unwrap();
        let ini = Ini::read(&dir.join("top.ini")).unwrap();
        assert!(ini.linear_units_inch().unwrap());
        // The section of the included file carries on after it, as in LinuxCNC.
        assert_eq!(ini.get("TRAJ", "MAX").unwrap().value, "2");
        assert!(Ini::read(&dir.join("loop.ini")).is_err());
        let e = Ini::read(&dir.join("missing.ini")).unwrap_err();
        assert_eq!((e.line, e.path.ends_with("missing.ini")), (2, true));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
