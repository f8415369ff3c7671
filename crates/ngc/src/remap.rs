//! LinuxCNC remapped codes (`[RS274NGC]REMAP`, LinuxCNC manual "Remap: extending G code").
//!
//! `REMAP = M400 modalgroup=10 argspec=Pq ngc=m400` makes `M400 P1 Q2` call the o-word
//! subroutine `o<m400>` (file `m400.ngc` on the subroutine path) with the block's argspec
//! words as named local parameters: `#<p> = 1`, `#<q> = 2`. Argspec letters: upper case
//! required, lower case optional (passed only when present, so `EXISTS[#<q>]` tells),
//! `@` passes them positionally instead (`#1`, `#2` ... in argspec order, 0 when absent),
//! `>` and `^` (feed, speed > 0) are not checked. The motion mode after an `ngc=` remap is
//! whatever its subroutine left, as rs274 does (a remapped G code is not re-invoked by later
//! blocks with axis words alone).
//!
//! mtsim runs no Python: a remap with only `python=`/`py=` is accepted (with a notice) when
//! the function's source shows no effect on motion, otherwise refused, naming it.
//! `prolog=`/`epilog=` Python handlers around an `ngc=` subroutine are emulated when they are
//! those of LinuxCNC's standard glue `stdglue.py` (crate::stdglue); others are refused where
//! the code is used, naming them.

use std::path::PathBuf;

/// The code a remap replaces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RemapCode {
    /// G code, in tenths (G84.2 → 842).
    G(u32),
    M(u32),
    /// `REMAP=T`, `REMAP=S`, `REMAP=F`: the tool-prepare, spindle-speed and feed words.
    T,
    S,
    F,
}

impl RemapCode {
    /// When the code runs in a block, in LinuxCNC's order of execution (feed mode 2, F 3,
    /// S 4, T 5, M6/M61 6, other M codes 10, motion 20, stops 30): the block's remapped
    /// codes are called lowest first, one after the other's return.
    pub(crate) fn step(self) -> u8 {
        match self {
            RemapCode::F => 3,
            RemapCode::S => 4,
            RemapCode::T => 5,
            RemapCode::M(6 | 61) => 6,
            RemapCode::M(0 | 1 | 2 | 30 | 60) => 30,
            RemapCode::M(_) => 10,
            RemapCode::G(_) => 20,
        }
    }
}

impl std::fmt::Display for RemapCode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RemapCode::G(t) if t % 10 == 0 => write!(f, "G{}", t / 10),
            RemapCode::G(t) => write!(f, "G{}.{}", t / 10, t % 10),
            RemapCode::M(n) => write!(f, "M{n}"),
            RemapCode::T => f.write_str("T"),
            RemapCode::S => f.write_str("S"),
            RemapCode::F => f.write_str("F"),
        }
    }
}

/// One `REMAP` line.
#[derive(Clone, Debug, PartialEq)]
pub struct Remap {
    pub code: RemapCode,
    /// LinuxCNC modal group: 1 (motion) for G codes, 5-10 for M codes (10 by default).
    pub modal_group: u8,
    /// Word letters passed to the handler (see the module doc).
    pub argspec: String,
    /// The o-word subroutine called.
    pub ngc: Option<String>,
    /// The Python function called (`python=` or `py=`), when there is no `ngc=`.
    pub python: Option<String>,
    /// Python prolog/epilog handlers (emulated when they are stdglue's, crate::stdglue).
    pub prolog: Option<String>,
    pub epilog: Option<String>,
    /// Why the prolog/epilog cannot be emulated (defined in another file on the `[PYTHON]`
    /// path, see [`check_handlers`]); `None` when there are none or they are emulated. A
    /// handler name that is not one of stdglue's is refused where the code is read.
    pub handlers_refused: Option<String>,
    /// The configuration's stdglue `cycle_prolog` compares the sticky-word dict with 0.0
    /// (LinuxCNC 2.9's stdglue.py), a TypeError in Python 3 once an R word is recorded.
    pub cycle_prolog_typeerror: bool,
    /// A Python-only remap whose function keeps its code as the motion mode
    /// (`self.motion_mode = ...motion_code`): later blocks with axis words call it again.
    pub python_keeps_motion: bool,
    /// Where the remap is defined, `file:line`, for messages.
    pub origin: String,
    /// For a Python-only remap: why it cannot be simulated (it moves the machine, or its
    /// source was not found); `None` when it has no effect on motion.
    pub python_motion: Option<String>,
}

impl Remap {
    /// Argspec letters (upper case) the handler takes, required first flag.
    pub fn letters(&self) -> impl Iterator<Item = (char, bool)> + '_ {
        self.argspec
            .chars()
            .filter(|c| c.is_ascii_alphabetic())
            .map(|c| (c.to_ascii_uppercase(), c.is_ascii_uppercase()))
    }

    /// `@` in the argspec: positional arguments.
    pub fn positional(&self) -> bool {
        self.argspec.contains('@')
    }
}

/// Parses the value of a `REMAP` line (`M400 modalgroup=10 argspec=Pq ngc=m400`).
pub fn parse_remap(value: &str, origin: String) -> Result<Remap, String> {
    let mut parts = value.split_whitespace();
    let code_text = parts
        .next()
        .ok_or("empty REMAP: expected a code such as `M400`")?;
    let upper = code_text.to_ascii_uppercase();
    let number = |s: &str| s.parse::<f64>().ok().filter(|v| v.is_finite() && *v >= 0.0);
    let code = match (upper.chars().next(), number(&upper[1..])) {
        (Some('T'), None) if upper == "T" => RemapCode::T,
        (Some('S'), None) if upper == "S" => RemapCode::S,
        (Some('F'), None) if upper == "F" => RemapCode::F,
        (Some('G'), Some(v)) if (v * 10.0).fract().abs() < 1e-9 => {
            RemapCode::G((v * 10.0).round() as u32)
        }
        (Some('M'), Some(v)) if v.fract() == 0.0 => RemapCode::M(v as u32),
        _ => {
            return Err(format!(
                "`{code_text}`: expected a G or M code (such as `G84.2` or `M400`), or T, S or F"
            ))
        }
    };
    let mut r = Remap {
        code,
        modal_group: if matches!(code, RemapCode::G(_)) {
            1
        } else {
            10
        },
        argspec: String::new(),
        ngc: None,
        python: None,
        prolog: None,
        epilog: None,
        handlers_refused: None,
        cycle_prolog_typeerror: false,
        python_keeps_motion: false,
        origin,
        python_motion: None,
    };
    for part in parts {
        let Some((key, v)) = part.split_once('=') else {
            return Err(format!(
                "`{part}`: expected `key=value` (modalgroup argspec ngc python prolog epilog)"
            ));
        };
        match key.to_ascii_lowercase().as_str() {
            "modalgroup" => {
                r.modal_group = v
                    .parse()
                    .map_err(|_| format!("`{part}`: expected a modal group number"))?
            }
            "argspec" => {
                if let Some(c) = v
                    .chars()
                    .find(|c| !(c.is_ascii_alphabetic() || "@^>-".contains(*c)))
                {
                    return Err(format!(
                        "`{part}`: unexpected `{c}`: expected word letters, `@`, `^` or `>`"
                    ));
                }
                r.argspec = v.to_string();
            }
            "ngc" => r.ngc = Some(v.to_string()),
            "python" | "py" => r.python = Some(v.to_string()),
            "prolog" => r.prolog = Some(v.to_string()),
            "epilog" => r.epilog = Some(v.to_string()),
            _ => {
                return Err(format!(
                    "`{part}`: unknown key: expected modalgroup argspec ngc python prolog epilog"
                ))
            }
        }
    }
    let allowed: &[u8] = match code {
        RemapCode::G(_) => &[1],
        // The stops (group 4) can be remapped too (LinuxCNC 2.6 on: extend M0 M1 M60).
        RemapCode::M(0 | 1 | 60) => &[4, 5, 6, 7, 8, 9, 10],
        RemapCode::M(_) => &[5, 6, 7, 8, 9, 10],
        RemapCode::T | RemapCode::S | RemapCode::F => &[r.modal_group],
    };
    if !allowed.contains(&r.modal_group) {
        return Err(format!(
            "modalgroup={} for {code}: LinuxCNC remaps G codes in group 1 and M codes in groups 5-10 (M0, M1, M60 also in 4)",
            r.modal_group
        ));
    }
    if r.ngc.is_none() && r.python.is_none() {
        return Err(format!(
            "{code} has neither `ngc=` nor `python=`: expected the handler"
        ));
    }
    Ok(r)
}

/// Calls in a Python remap body that move the machine or change where it goes.
const MOTION_CALLS: &[&str] = &[
    "execute(",
    "STRAIGHT_TRAVERSE",
    "STRAIGHT_FEED",
    "ARC_FEED",
    "STRAIGHT_PROBE",
    "RIGID_TAP",
    "CHANGE_TOOL",
    "USE_TOOL_LENGTH_OFFSET",
    "SET_G5X_OFFSET",
    "SET_G92_OFFSET",
    "SET_XY_ROTATION",
    "USE_LENGTH_UNITS",
];

/// Whether Python function `name` (found as `def name(` in a `.py` file of `dirs`) has an
/// effect on motion: `None` when its body calls none of [`MOTION_CALLS`], otherwise why not.
pub fn python_motion(dirs: &[PathBuf], name: &str) -> Option<String> {
    match python_def(dirs, name) {
        Some((file, body)) => MOTION_CALLS.iter().find(|c| body.contains(*c)).map(|c| {
            format!(
                "it moves the machine (`{}` in {})",
                c.trim_end_matches('('),
                file.display()
            )
        }),
        None => Some(format!(
            "its source (`def {name}(`) was not found on the [PYTHON] path"
        )),
    }
}

/// Whether Python function `name` keeps its remapped code as the motion mode
/// (`self.motion_mode = c.executing_remap.motion_code`, as the cycle example's g842).
pub fn python_keeps_motion(dirs: &[PathBuf], name: &str) -> bool {
    python_def(dirs, name).is_some_and(|(_, body)| {
        body.lines()
            .any(|l| l.contains("self.motion_mode") && l.contains("motion_code"))
    })
}

/// Checks a remap's prolog/epilog against the `[PYTHON]` path: they must be the functions
/// of LinuxCNC's `stdglue.py` (a configuration may define its own under the same name).
/// Sets `handlers_refused` otherwise, and `cycle_prolog_typeerror` for the stdglue.py of
/// LinuxCNC 2.9, whose cycle_prolog compares the sticky-word dict with 0.0.
pub fn check_handlers(dirs: &[PathBuf], r: &mut Remap) {
    if r.handlers_refused.is_some() {
        return;
    }
    for name in [&r.prolog, &r.epilog].into_iter().flatten() {
        match python_def(dirs, name) {
            None => {
                r.handlers_refused = Some(format!(
                    "the source of `{name}` (`def {name}(`) was not found on the [PYTHON] path"
                ));
                return;
            }
            Some((file, body)) => {
                if file.file_name().is_none_or(|f| f != "stdglue.py") {
                    r.handlers_refused = Some(format!(
                        "`{name}` is defined in {}, not in LinuxCNC's stdglue.py, whose handlers mtsim emulates",
                        file.display()
                    ));
                    return;
                }
                if name == "cycle_prolog" && body.contains("self.sticky_params[r.name] <= 0.0") {
                    r.cycle_prolog_typeerror = true;
                }
            }
        }
    }
}

/// The file defining Python function `name` on `dirs` (first in path order, files sorted),
/// and its body.
fn python_def(dirs: &[PathBuf], name: &str) -> Option<(PathBuf, String)> {
    for dir in dirs {
        let Ok(entries) = std::fs::read_dir(dir) else {
            continue;
        };
        let mut files: Vec<PathBuf> = entries
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|e| e == "py"))
            .collect();
        files.sort();
        for file in files {
            let Ok(text) = std::fs::read_to_string(&file) else {
                continue;
            };
            if let Some(body) = function_body(&text, name) {
                return Some((file, body.to_string()));
            }
        }
    }
    None
}

/// The indented body of `def name(` in Python source `text`.
fn function_body<'t>(text: &'t str, name: &str) -> Option<&'t str> {
    let head = format!("def {name}(");
    let mut offset = 0;
    let mut start = None;
    let mut indent = 0;
    for line in text.split_inclusive('\n') {
        let trimmed = line.trim_start();
        let this_indent = line.len() - trimmed.len();
        match start {
            None if trimmed.starts_with(&head) => {
                start = Some(offset + line.len());
                indent = this_indent;
            }
            Some(s)
                if !trimmed.trim().is_empty()
                    && !trimmed.starts_with('#')
                    && this_indent <= indent =>
            {
                return Some(&text[s..offset]);
            }
            _ => {}
        }
        offset += line.len();
    }
    start.map(|s| &text[s..])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_manual_examples() {
        let r = parse_remap(
            "M400  modalgroup=10 argspec=Pq ngc=m400",
            "demo.ini:66".into(),
        )
        .unwrap();
        assert_eq!(r.code, RemapCode::M(400));
        assert_eq!(r.modal_group, 10);
        assert_eq!(r.letters().collect::<Vec<_>>(), [('P', true), ('Q', false)]);
        assert!(!r.positional());
        assert_eq!(r.ngc.as_deref(), Some("m400"));
        let r = parse_remap(
            "G84.3 argspec=xyzq prolog=cycle_prolog ngc=g843 epilog=cycle_epilog modalgroup=1",
            String::new(),
        )
        .unwrap();
        assert_eq!(
            (r.code, r.code.to_string()),
            (RemapCode::G(843), "G84.3".into())
        );
        assert_eq!(r.prolog.as_deref(), Some("cycle_prolog"));
        let r = parse_remap("G70 modalgroup=1 py=queuebuster", String::new()).unwrap();
        assert_eq!(
            (r.code.to_string(), r.python.as_deref()),
            ("G70".into(), Some("queuebuster"))
        );
        assert!(parse_remap("M410 argspec=@Pq ngc=m410", String::new())
            .unwrap()
            .positional());
        let t = parse_remap("T prolog=p ngc=prepare", String::new()).unwrap();
        assert_eq!(t.code, RemapCode::T);
        assert!(parse_remap("M0 modalgroup=4 ngc=extend_m0", String::new()).is_ok());
        assert!(parse_remap("M400 modalgroup=4 ngc=m400", String::new()).is_err());
        assert!(parse_remap("M400 modalgroup=1 ngc=m400", String::new()).is_err());
        assert!(parse_remap("M400 argspec=P", String::new()).is_err());
        assert!(parse_remap("M400 colour=red ngc=x", String::new()).is_err());
    }

    /// Prolog/epilog handlers must be stdglue.py's: a configuration's own function of the
    /// same name is refused, naming its file; LinuxCNC 2.9's cycle_prolog is marked for its
    /// Python 3 TypeError; a Python cycle that sets `self.motion_mode` stays modal.
    #[test]
    fn handlers_are_taken_from_stdglue_only() {
        let dir = std::env::temp_dir().join(format!("ngc-glue-py-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join("stdglue.py"),
            "def cycle_prolog(self, **words):\n    if self.sticky_params[r.name] <= 0.0:\n        return 'x'\n\ndef cycle_epilog(self, **words):\n    return INTERP_OK\n\ndef change_epilog(self, **words):\n    pass\n",
        )
        .unwrap();
        std::fs::write(
            dir.join("custom.py"),
            "def change_epilog(self, **words):\n    pass\n\ndef g842(self, **words):\n    MESSAGE('x')\n    self.motion_mode = c.executing_remap.motion_code\n    return INTERP_OK\n",
        )
        .unwrap();
        let dirs = [dir.clone()];
        let mut cycle = parse_remap(
            "G84.3 argspec=xyzr prolog=cycle_prolog ngc=g843 epilog=cycle_epilog",
            String::new(),
        )
        .unwrap();
        check_handlers(&dirs, &mut cycle);
        assert_eq!(cycle.handlers_refused, None);
        assert!(cycle.cycle_prolog_typeerror);
        let mut change = parse_remap(
            "M6 modalgroup=6 prolog=change_prolog ngc=change epilog=change_epilog",
            String::new(),
        )
        .unwrap();
        check_handlers(&dirs, &mut change);
        // change_prolog is nowhere; once found, change_epilog is custom.py's (sorted first).
        assert!(change.handlers_refused.unwrap().contains("`change_prolog`"));
        change.prolog = None;
        change.handlers_refused = None;
        check_handlers(&dirs, &mut change);
        assert!(change.handlers_refused.unwrap().contains("custom.py"));
        assert!(python_keeps_motion(&dirs, "g842"));
        assert!(!python_keeps_motion(&dirs, "change_epilog"));
        assert_eq!(python_motion(&dirs, "g842"), None);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn python_bodies_are_read_to_their_end() {
        let src = "import x\n\ndef queuebuster(self, **words):\n    yield INTERP_EXECUTE_FINISH\n\n\ndef involute(self, **words):\n    # comment\n    self.execute(\"G1 X1\")\n    return INTERP_OK\n";
        assert_eq!(
            function_body(src, "queuebuster").unwrap().trim(),
            "yield INTERP_EXECUTE_FINISH"
        );
        assert!(function_body(src, "involute").unwrap().contains("execute("));
        assert!(function_body(src, "missing").is_none());
    }
}

/// How a block with a remapped code runs: the words before the call, the call, the words
/// after it. Indices are into the block's words.
#[derive(Debug)]
pub(crate) struct Split {
    /// Index into the remaps.
    pub remap: usize,
    /// Argspec words present, upper-case letter and value, in argspec order.
    pub args: Vec<(char, f64)>,
    /// Words executed before the handler (LinuxCNC's order of execution: F S T, spindle,
    /// coolant, tool change come before user M codes; motion and stops after).
    pub before: Vec<usize>,
    pub after: Vec<usize>,
    /// The remapped code's word (for a cycle called again by axis words, the first word).
    pub span: std::ops::Range<usize>,
    /// The block has the remapped code itself (not a modal cycle called again).
    pub explicit: bool,
    /// The remapped word's value (T, S, F number) and the block's Q (M61), for the prologs.
    pub value: f64,
    pub q: Option<f64>,
}

/// The remappable code of word `w`, if any.
fn code_of(w: &crate::lex::Word) -> Option<RemapCode> {
    let tenths = w.value * 10.0;
    let exact = (tenths - tenths.round()).abs() < 1e-6 && w.value >= 0.0;
    match w.letter {
        'G' if exact => Some(RemapCode::G(tenths.round() as u32)),
        'M' if exact && w.value.fract() == 0.0 => Some(RemapCode::M(w.value as u32)),
        'T' => Some(RemapCode::T),
        'S' => Some(RemapCode::S),
        'F' => Some(RemapCode::F),
        _ => None,
    }
}

/// Whether the block sets the motion mode (a group-1 G code: G0-G3, G5.x, G33, G38.x,
/// G73-G89 ...), which ends a remapped cycle's modal call.
pub(crate) fn sets_motion(words: &[crate::lex::Word]) -> bool {
    words.iter().any(|w| {
        matches!(code_of(w), Some(RemapCode::G(t)) if matches!(t, 0 | 10 | 20 | 30 | 50..=53 | 330 | 331 | 382..=385 | 700..=739 | 760 | 800..=899))
    })
}

/// Whether the block uses the built-in T, S or F of a remap being executed (LinuxCNC's
/// `builtin_used`, which stdglue's epilogs read: the subroutine did the work).
pub(crate) fn uses_builtin(remaps: &[Remap], words: &[crate::lex::Word], busy: &[usize]) -> bool {
    words.iter().any(|w| {
        let code = code_of(w);
        matches!(code, Some(RemapCode::T | RemapCode::S | RemapCode::F))
            && busy.iter().any(|&r| Some(remaps[r].code) == code)
    })
}

/// The remapped code of a block, if any: the first in LinuxCNC's order of execution.
/// Remaps in `busy` (being executed) run built in. `modal` is a remapped cycle that is the
/// motion mode (stdglue `cycle_epilog`): a block with axis words and no code of its own
/// calls it again.
pub(crate) fn split(
    remaps: &[Remap],
    words: &[crate::lex::Word],
    line: &str,
    busy: &[usize],
    modal: Option<usize>,
) -> crate::lex::LineResult<Option<Split>> {
    use crate::lex::LineError;
    let mut found: Option<(usize, usize)> = None;
    for (k, w) in words.iter().enumerate() {
        let Some(code) = code_of(w) else { continue };
        let Some(r) = (0..remaps.len()).find(|&r| remaps[r].code == code && !busy.contains(&r))
        else {
            continue;
        };
        if found.is_none_or(|(_, f)| code.step() < remaps[f].code.step()) {
            found = Some((k, r));
        }
    }
    let (k, r) = match (found, modal) {
        (Some((k, r)), _) => (Some(k), r),
        (None, Some(r))
            if !busy.contains(&r) && words.iter().any(|w| "XYZABC".contains(w.letter)) =>
        {
            (None, r)
        }
        _ => return Ok(None),
    };
    let remap = &remaps[r];
    let span = match k {
        Some(k) => words[k].span(),
        None => words
            .iter()
            .find(|w| "XYZABC".contains(w.letter))
            .map_or(0..0, |w| w.span()),
    };
    let mut used = vec![false; words.len()];
    if let Some(k) = k {
        used[k] = true;
    }
    let mut args = Vec::new();
    for (letter, required) in remap.letters() {
        match words
            .iter()
            .position(|w| w.letter == letter && !matches!(letter, 'G' | 'M'))
        {
            Some(k) => {
                used[k] = true;
                args.push((letter, words[k].value));
            }
            None if required => {
                return Err(LineError::new(
                    span.clone(),
                    format!(
                        "`{}` needs a `{letter}` word: its remap ({}, argspec={}) requires it",
                        &line[span.clone()],
                        remap.origin,
                        remap.argspec
                    ),
                    format!("no {letter}"),
                ))
            }
            None => {}
        }
    }
    // stdglue's settool_prolog reads the block's Q itself.
    let q_at = words.iter().position(|w| w.letter == 'Q');
    let q = q_at.map(|k| words[k].value);
    if remap.code == RemapCode::M(61) && remap.prolog.as_deref() == Some("settool_prolog") {
        if let Some(k) = q_at {
            used[k] = true;
        }
    }
    let is_stop =
        |w: &crate::lex::Word| w.letter == 'M' && matches!(w.value as u32, 0 | 1 | 2 | 30 | 60);
    let group1 = matches!(remap.code, RemapCode::G(_));
    let step = remap.code.step();
    let (mut before, mut after) = (Vec::new(), Vec::new());
    for (k, w) in words.iter().enumerate() {
        if used[k] {
            continue;
        }
        if group1 && "XYZABCUVW".contains(w.letter) {
            // The handler reads the block's axis words itself (LinuxCNC: `blocks[..].x_number`),
            // argspec or not; they never move the machine as a G0/G1 would.
            continue;
        }
        let early = if step < 6 {
            // T, S, F remaps: only what LinuxCNC executes before them.
            let word_step = match w.letter {
                'N' => 0,
                'G' if matches!(code_of(w), Some(RemapCode::G(930 | 940 | 950))) => 2,
                'F' => 3,
                'S' => 4,
                'T' => 5,
                _ => u8::MAX,
            };
            word_step < step
        } else if step == 30 {
            // A remapped stop (M0 M1 M60) comes last: the block's motion first.
            true
        } else {
            match w.letter {
                'F' | 'S' | 'T' | '$' | 'N' => true,
                'M' => !is_stop(w),
                'G' => matches!(code_of(w), Some(RemapCode::G(930 | 940 | 950))),
                _ => false,
            }
        };
        if is_stop(w) || !(early || group1) {
            after.push(k);
        } else {
            before.push(k);
        }
    }
    Ok(Some(Split {
        remap: r,
        args,
        before,
        after,
        span,
        explicit: k.is_some(),
        value: k.map_or(0.0, |k| words[k].value),
        q,
    }))
}

#[cfg(test)]
mod calls {
    use crate::{read_str_with, Axis, Dialect, Options};
    use std::path::Path;

    /// `M401 P10 Q5` with `argspec=Pq` gives the subroutine `#<p> = 10` and `#<q> = 5`;
    /// with `@Pq` they arrive as `#1`, `#2`; the block's own move runs after the call.
    #[test]
    fn arguments_reach_the_subroutine_as_named_or_positional_parameters() {
        let dir = std::env::temp_dir().join(format!("ngc-remap-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("m401.ngc"), "o<m401> sub\nG1 X[#<p> * 2] F100\no1 if [EXISTS[#<q>]]\nG1 Y#<q>\no1 endif\no<m401> endsub\n").unwrap();
        std::fs::write(
            dir.join("m402.ngc"),
            "o<m402> sub\nG0 X#1 Y#2\no<m402> endsub\n",
        )
        .unwrap();
        let o = Options {
            dialect: Dialect::Linuxcnc,
            search_path: vec![dir.clone()],
            remaps: vec![
                super::parse_remap("M401 argspec=Pq ngc=m401", "t.ini:1".into()).unwrap(),
                super::parse_remap("M402 argspec=@Pq ngc=m402", "t.ini:2".into()).unwrap(),
            ],
            ..Options::default()
        };
        let program = "G21 G90\nM401 P10\nM401 P3 Q5\nG0 Z3 M402 P1.5\nM2\n";
        let moves: Vec<_> = read_str_with(Path::new("p.ngc"), program, &o)
            .collect::<Result<_, _>>()
            .unwrap();
        let ends: Vec<[f64; 3]> = moves
            .iter()
            .map(|m| [m.end[Axis::X], m.end[Axis::Y], m.end[Axis::Z]])
            .collect();
        // X = 2·P; Y = Q only when Q is given; Q absent under @ is 0; then the block's G0 Z3.
        assert_eq!(
            ends,
            [
                [20.0, 0.0, 0.0],
                [6.0, 0.0, 0.0],
                [6.0, 5.0, 0.0],
                [1.5, 0.0, 0.0],
                [1.5, 0.0, 3.0]
            ]
        );
        let missing = read_str_with(Path::new("p.ngc"), "M401 Q1\n", &o)
            .find_map(|r| r.err())
            .unwrap();
        assert!(
            missing.to_string().contains("needs a `P` word"),
            "{missing}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

#[cfg(test)]
mod modal {
    use crate::{read_str_with, Axis, Dialect, Options};
    use std::path::Path;

    /// A Python cycle that keeps its code as the motion mode (the cycle example's g842) is
    /// called again, without moving, by blocks with axis words, until a G0 ends it.
    #[test]
    fn a_python_cycle_that_keeps_the_motion_mode_takes_later_axis_blocks() {
        let mut g842 = super::parse_remap(
            "G84.2 argspec=xyzqplr python=g842 modalgroup=1",
            "cycle.ini:37".into(),
        )
        .unwrap();
        g842.python_keeps_motion = true;
        let o = Options {
            dialect: Dialect::Linuxcnc,
            remaps: vec![g842],
            ..Options::default()
        };
        let program =
            "G21 F20\nG1 X1\nG84.2 X1 Y2 Z3 Q5 R1\nX321 Y452 P12\nZ23 X10 Q3\nG0 X5\nY6\n";
        let mut moves = read_str_with(Path::new("p.ngc"), program, &o);
        let ends: Vec<[f64; 2]> = moves
            .by_ref()
            .map(|m| m.map(|m| [m.end[Axis::X], m.end[Axis::Y]]))
            .collect::<Result<_, _>>()
            .unwrap();
        assert_eq!(ends, [[1.0, 0.0], [5.0, 0.0], [5.0, 6.0]]);
        assert!(moves.notices()[0].message.contains("`g842`"));
    }
}

#[cfg(test)]
mod stops {
    use crate::{read_str_with, Axis, Dialect, Options};
    use std::path::Path;

    /// A remapped M0 (group 4, the extend-builtins example) runs after the block's motion,
    /// as the built-in stop would; inside its subroutine `M0` is the built-in stop.
    #[test]
    fn a_remapped_stop_runs_after_the_blocks_motion() {
        let dir = std::env::temp_dir().join(format!("ngc-remap-m0-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join("extend_m0.ngc"),
            "o<extend_m0> sub\nG0 Z9\nM0\no<extend_m0> endsub\n",
        )
        .unwrap();
        let o = Options {
            dialect: Dialect::Linuxcnc,
            search_path: vec![dir.clone()],
            remaps: vec![
                super::parse_remap("M0 modalgroup=4 ngc=extend_m0", String::new()).unwrap(),
            ],
            ..Options::default()
        };
        let ends: Vec<[f64; 2]> = read_str_with(Path::new("p.ngc"), "G0 X1 M0\nG0 X2\n", &o)
            .map(|m| m.map(|m| [m.end[Axis::X], m.end[Axis::Z]]))
            .collect::<Result<_, _>>()
            .unwrap();
        assert_eq!(ends, [[1.0, 0.0], [1.0, 9.0], [2.0, 9.0]]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
