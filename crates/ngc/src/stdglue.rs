//! The standard remap glue: the prolog and epilog handlers LinuxCNC ships for remapping T,
//! M6, M61, S, F and canned-cycle G codes to o-word subroutines, emulated without Python.
//!
//! A remap such as `REMAP=T prolog=prepare_prolog ngc=prepare epilog=prepare_epilog` runs
//! the prolog before the subroutine (it checks the block and sets named parameters the
//! subroutine reads) and the epilog when the subroutine returns (it checks the returned
//! value and commits the result to the interpreter). Behaviour as the LinuxCNC manual's
//! "Remap: Extending G-code" chapter describes the standard glue, one row of [`RULES`] per
//! handler:
//!
//! | handler | prolog sets | epilog commits | refused when |
//! |---|---|---|---|
//! | `setfeed_` | `#<feed>` = F | feed rate `#<feed>` | no value returned |
//! | `setspeed_` | `#<speed>` = S | spindle speed `#<speed>` | no value returned; value < −0.0001 |
//! | `prepare_` | `#<tool>` = T, `#<pocket>` (−1 for T0) | selects `#<tool>` | tool not in the table; value ≤ 0 |
//! | `change_` | tool in spindle, selected tool, their pockets | the tool change | no tool selected; compensation on; tool changer fault (#5601 < 0 while #5600 > 0); value ≤ 0 |
//! | `settool_` | `#<tool>` = int(Q), `#<pocket>` | tool number `#<tool>` | no Q; Q < 0; tool not in the table; value ≤ 0 |
//! | `cycle_` | each argspec word, the plane normal's axis and R kept from the last call, `#<motion_code>` | the code stays the motion mode | U V W A B C words; no R; R ≤ 0; P < 0; no feed; G93; compensation on |
//!
//! An epilog reads the parameters where the subroutine left them (it may change them). When
//! the subroutine ran the built-in code itself (`T#<tool>` inside the T remap) there is
//! nothing left to commit, except for M6 and M61, whose epilogs commit in any case.
//!
//! This module depends on no other part of the interpreter: the remapped code comes in as
//! its name (`impl Display`, e.g. `G84.3`), the interpreter state as a [`View`], and the
//! lookups as closures.

use std::fmt::Display;

use crate::axis::Plane;

/// The handlers emulated, for messages.
pub const NAMES: &str = "prepare_, change_, settool_, setspeed_, setfeed_ and cycle_ prolog/epilog";

/// One standard glue handler.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Handler {
    PrepareProlog,
    PrepareEpilog,
    ChangeProlog,
    ChangeEpilog,
    SettoolProlog,
    SettoolEpilog,
    SetspeedProlog,
    SetspeedEpilog,
    SetfeedProlog,
    SetfeedEpilog,
    CycleProlog,
    CycleEpilog,
}

/// How far below zero a speed subroutine's return value may round before it counts as an
/// abort.
const SPEED_TOLERANCE: f64 = 1e-4;

/// What an epilog commits from the value `v` of the parameter it reads.
type Commits = fn(f64) -> Commit;

/// An epilog's rule: the parameter it reads (none: it commits without one), what it commits,
/// the lowest return value that is not an abort, and whether it commits after the subroutine
/// used the built-in code.
#[derive(Clone, Copy)]
struct EpilogRule {
    reads: Option<&'static str>,
    commits: Commits,
    /// The return value must be at least this (`inclusive`) or above it.
    least: f64,
    inclusive: bool,
    even_after_builtin: bool,
}

/// One handler: its configuration name, and for an epilog its rule.
struct Rule {
    name: &'static str,
    handler: Handler,
    epilog: Option<EpilogRule>,
}

const fn epilog_rule(
    reads: Option<&'static str>,
    commits: Commits,
    least: f64,
    inclusive: bool,
    even_after_builtin: bool,
) -> Option<EpilogRule> {
    Some(EpilogRule {
        reads,
        commits,
        least,
        inclusive,
        even_after_builtin,
    })
}

/// Every handler: names as a configuration's `prolog=` and `epilog=` give them.
const RULES: [Rule; 12] = [
    Rule {
        name: "prepare_prolog",
        handler: Handler::PrepareProlog,
        epilog: None,
    },
    Rule {
        name: "prepare_epilog",
        handler: Handler::PrepareEpilog,
        epilog: epilog_rule(
            Some("tool"),
            |t| Commit::SelectTool {
                tool: whole(t),
                prepared: true,
            },
            0.0,
            false,
            false,
        ),
    },
    Rule {
        name: "change_prolog",
        handler: Handler::ChangeProlog,
        epilog: None,
    },
    Rule {
        name: "change_epilog",
        handler: Handler::ChangeEpilog,
        epilog: epilog_rule(None, |_| Commit::ChangeTool, 0.0, false, true),
    },
    Rule {
        name: "settool_prolog",
        handler: Handler::SettoolProlog,
        epilog: None,
    },
    Rule {
        name: "settool_epilog",
        handler: Handler::SettoolEpilog,
        epilog: epilog_rule(
            Some("tool"),
            |t| Commit::SetToolNumber(whole(t)),
            0.0,
            false,
            true,
        ),
    },
    Rule {
        name: "setspeed_prolog",
        handler: Handler::SetspeedProlog,
        epilog: None,
    },
    Rule {
        name: "setspeed_epilog",
        handler: Handler::SetspeedEpilog,
        epilog: epilog_rule(Some("speed"), Commit::Speed, -SPEED_TOLERANCE, true, false),
    },
    Rule {
        name: "setfeed_prolog",
        handler: Handler::SetfeedProlog,
        epilog: None,
    },
    Rule {
        name: "setfeed_epilog",
        handler: Handler::SetfeedEpilog,
        epilog: epilog_rule(Some("feed"), Commit::Feed, f64::NEG_INFINITY, true, false),
    },
    Rule {
        name: "cycle_prolog",
        handler: Handler::CycleProlog,
        epilog: None,
    },
    Rule {
        name: "cycle_epilog",
        handler: Handler::CycleEpilog,
        epilog: None,
    },
];

impl Handler {
    /// The handler a configuration calls `name`.
    pub fn named(name: &str) -> Option<Handler> {
        RULES.iter().find(|r| r.name == name).map(|r| r.handler)
    }

    /// The handler's configuration name.
    pub fn name(self) -> &'static str {
        self.rule().name
    }

    fn rule(self) -> &'static Rule {
        RULES
            .iter()
            .find(|r| r.handler == self)
            .expect("every handler has a rule")
    }
}

/// The interpreter state the handlers read.
#[derive(Clone, Copy, Debug)]
pub(crate) struct View {
    pub plane: Plane,
    /// The feed rate is 0 (no F yet, or F0).
    pub feed_zero: bool,
    pub inverse_time: bool,
    pub comp_on: bool,
}

/// The remapped block as a prolog sees it; `C` names the remapped code (`T`, `M6`, `G84.3`).
pub(crate) struct Call<'a, C> {
    pub code: C,
    /// The remapped word's value (T, S, F number).
    pub value: f64,
    /// The block's Q word.
    pub q: Option<f64>,
    /// The argspec words present (upper-case letter), in argspec order.
    pub words: &'a [(char, f64)],
    /// The block has the remapped G code itself, not a cycle called again by axis words.
    pub explicit: bool,
    /// The configuration's cycle_prolog is the LinuxCNC 2.9 one that fails under Python 3
    /// (it compares its whole table of kept words with 0.0 where it means R).
    pub cycle_typeerror: bool,
}

/// What an epilog commits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Commit {
    None,
    /// `SELECT_TOOL`: the tool for the next M6; not prepared when its pocket is -1 (T0).
    SelectTool {
        tool: u32,
        prepared: bool,
    },
    /// `CHANGE_TOOL` of the prepared tool.
    ChangeTool,
    /// `CHANGE_TOOL_NUMBER` (M61).
    SetToolNumber(u32),
    /// Spindle speed, rpm.
    Speed(f64),
    /// Feed rate in program units (per minute, or inverse time).
    Feed(f64),
    /// The remapped code stays the motion mode.
    KeepMotion,
}

/// The words a cycle remap keeps from one call to the next, per remap (by index).
#[derive(Debug, Default)]
pub(crate) struct Sticky(Vec<(usize, Vec<(char, f64)>)>);

impl Sticky {
    fn of(&mut self, remap: usize) -> &mut Vec<(char, f64)> {
        if let Some(k) = self.0.iter().position(|(r, _)| *r == remap) {
            return &mut self.0[k].1;
        }
        self.0.push((remap, Vec::new()));
        &mut self.0.last_mut().expect("just pushed").1
    }
}

/// A tool number from a parameter: the whole part (toward zero), negative ones as 0.
fn whole(v: f64) -> u32 {
    v.trunc().max(0.0) as u32
}

/// The G number of a code name in tenths (`G84.3` → 843), `None` for other codes.
fn g_tenths(code: &str) -> Option<u32> {
    let number = code.strip_prefix('G')?;
    let (int, frac) = number.split_once('.').unwrap_or((number, "0"));
    Some(int.parse::<u32>().ok()? * 10 + frac.parse::<u32>().ok()?)
}

/// Named parameter `name` = `v`.
fn set(name: &str, v: f64) -> (String, f64) {
    (name.to_string(), v)
}

/// Runs prolog `h` for `call`: the named parameters to set in the subroutine, or why the
/// block is refused. `pocket` finds a tool's pocket in the tool table; `param` reads a
/// numbered parameter; `change` gives the four tool-change parameters (`None`: no tool has
/// been selected).
#[allow(clippy::too_many_arguments)]
pub(crate) fn prolog<C: Display>(
    h: Handler,
    call: &Call<C>,
    remap: usize,
    view: View,
    sticky: &mut Sticky,
    pocket: &dyn Fn(u32) -> Option<f64>,
    param: &dyn Fn(usize) -> f64,
    change: Option<[(&'static str, f64); 4]>,
) -> Result<Vec<(String, f64)>, String> {
    match h {
        Handler::SetspeedProlog => Ok(vec![set("speed", call.value)]),
        Handler::SetfeedProlog => Ok(vec![set("feed", call.value)]),
        Handler::PrepareProlog => {
            let tool = whole(call.value);
            Ok(vec![
                set("tool", tool as f64),
                set("pocket", tool_pocket(tool, pocket)?),
            ])
        }
        Handler::SettoolProlog => {
            let q = call.q.ok_or("no Q word: expected `M61 Q<tool number>`")?;
            if q < 0.0 {
                return Err(format!("Q{q} is negative: expected a tool number ≥ 0"));
            }
            let tool = whole(q);
            Ok(vec![
                set("tool", tool as f64),
                set("pocket", tool_pocket(tool, pocket)?),
            ])
        }
        Handler::ChangeProlog => {
            let change =
                change.ok_or("no tool selected for the change: expected a T word before M6")?;
            if view.comp_on {
                return Err(
                    "tool change with cutter radius compensation on: expected G40 first".into(),
                );
            }
            if param(5601) < 0.0 && param(5600) > 0.0 {
                return Err(format!(
                    "the tool changer reports a fault (#5600 = {}, #5601 = {}): clear it before the change",
                    param(5600),
                    param(5601)
                ));
            }
            Ok(change.iter().map(|&(k, v)| set(k, v)).collect())
        }
        Handler::CycleProlog => cycle_prolog(call, remap, view, sticky),
        epilog => Err(format!(
            "`{}` is an epilog, named as a prolog",
            epilog.name()
        )),
    }
}

/// The pocket of `tool` (−1 for T0, no tool), or why there is none.
fn tool_pocket(tool: u32, pocket: &dyn Fn(u32) -> Option<f64>) -> Result<f64, String> {
    if tool == 0 {
        return Ok(-1.0);
    }
    pocket(tool).ok_or_else(|| {
        format!("tool {tool} is not in the tool table: add it, or call a tool that is")
    })
}

/// The cycle prolog: the block's argspec words as parameters, the plane normal's axis word
/// and R kept from the last call of the same remap (a new G code in the block starts them
/// afresh), and `#<motion_code>`: the code in tenths when the block names it, else −1.
fn cycle_prolog<C: Display>(
    call: &Call<C>,
    remap: usize,
    view: View,
    sticky: &mut Sticky,
) -> Result<Vec<(String, f64)>, String> {
    // The words kept across calls: the cycle axis (the plane's normal) and R.
    let (kept, plane) = match view.plane {
        Plane::XY => (['Z', 'R'], "XY"),
        Plane::YZ => (['X', 'R'], "YZ"),
        Plane::ZX => (['Y', 'R'], "XZ"),
    };
    if let Some((w, _)) = call.words.iter().find(|(w, _)| "UVWABC".contains(*w)) {
        return Err(format!(
            "`{w}` word in a canned cycle in the {plane} plane: a cycle takes X Y Z R Q P L only"
        ));
    }
    let kept_words = sticky.of(remap);
    if call.explicit {
        kept_words.clear();
    }
    let mut words: Vec<(char, f64)> = call.words.to_vec();
    for letter in kept {
        match words.iter().find(|(w, _)| *w == letter) {
            Some(&(_, v)) => match kept_words.iter_mut().find(|(w, _)| *w == letter) {
                Some(k) => k.1 = v,
                None => kept_words.push((letter, v)),
            },
            None => {
                if let Some(&k) = kept_words.iter().find(|(w, _)| *w == letter) {
                    words.push(k);
                }
            }
        }
    }
    let value = |letter: char| words.iter().find(|(w, _)| *w == letter).map(|w| w.1);
    let Some(r) = value('R') else {
        return Err("no R word: a canned cycle needs its retract plane R (in this block or an earlier call)".into());
    };
    if call.cycle_typeerror {
        return Err("the configuration's cycle_prolog (LinuxCNC 2.9's stdglue.py) fails here under Python 3 with a TypeError (it compares its table of kept words with 0.0 where it means R), and LinuxCNC stops at this block too".into());
    }
    if r <= 0.0 {
        return Err(format!("R{r:.4} is not positive: expected R > 0"));
    }
    if let Some(p) = value('P').filter(|&p| p < 0.0) {
        return Err(format!("P{p:.4} is negative: expected a dwell P ≥ 0"));
    }
    if view.feed_zero {
        return Err(
            "no feed rate for the cycle: expected a positive F in this or an earlier block".into(),
        );
    }
    if view.inverse_time {
        return Err("canned cycle in inverse-time feed mode (G93): expected G94 first".into());
    }
    if view.comp_on {
        return Err("canned cycle with cutter radius compensation on: expected G40 first".into());
    }
    let name = call.code.to_string();
    let motion_code = match g_tenths(&name) {
        Some(t) if call.explicit => t as f64,
        _ => -1.0,
    };
    let mut out: Vec<(String, f64)> = words
        .iter()
        .map(|&(w, v)| (w.to_ascii_lowercase().to_string(), v))
        .collect();
    out.push(set("motion_code", motion_code));
    Ok(out)
}

/// Runs epilog `h` after the subroutine `ngc` of the remap of `code` returned `value`:
/// what to commit, or why the program stops. `local` reads the subroutine's named
/// parameters; `builtin_used` says the subroutine ran the built-in code itself.
#[allow(clippy::too_many_arguments)]
pub(crate) fn epilog(
    h: Handler,
    code: impl Display,
    ngc: &str,
    value: Option<f64>,
    builtin_used: bool,
    local: &dyn Fn(&str) -> Option<f64>,
    _param: &dyn Fn(usize) -> f64,
) -> Result<Commit, String> {
    if h == Handler::CycleEpilog {
        return Ok(Commit::KeepMotion);
    }
    let Some(rule) = h.rule().epilog else {
        return Err(format!(
            "`{}` is a prolog, named as the epilog of {code}",
            h.name()
        ));
    };
    let Some(v) = value else {
        return Err(format!(
            "the subroutine `{ngc}` of the {code} remap returned no value: expected `endsub [1]` (or a value ≤ 0 to abort)"
        ));
    };
    let aborted = if rule.inclusive {
        v < rule.least
    } else {
        v <= rule.least
    };
    if aborted {
        return Err(format!(
            "{code} aborted: its subroutine `{ngc}` returned {v:.1}"
        ));
    }
    if builtin_used && !rule.even_after_builtin {
        return Ok(Commit::None);
    }
    let Some(name) = rule.reads else {
        return Ok((rule.commits)(0.0));
    };
    let read = local(name).ok_or_else(|| {
        format!(
            "the {code} remap's subroutine `{ngc}` has no parameter #<{name}> for {} to read",
            h.name()
        )
    })?;
    let commit = (rule.commits)(read);
    Ok(match (h, commit) {
        // T0 selects no tool: its pocket is negative (-1).
        (Handler::PrepareEpilog, Commit::SelectTool { tool, .. }) => Commit::SelectTool {
            tool,
            prepared: local("pocket").is_none_or(|p| p >= 0.0),
        },
        _ => commit,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_handler_is_found_by_its_name() {
        for r in &RULES {
            assert_eq!(Handler::named(r.name), Some(r.handler));
            assert_eq!(r.handler.name(), r.name);
        }
        assert_eq!(Handler::named("my_prolog"), None);
    }

    #[test]
    fn a_g_code_name_gives_its_number_in_tenths() {
        assert_eq!(g_tenths("G84.3"), Some(843));
        assert_eq!(g_tenths("G81"), Some(810));
        assert_eq!(g_tenths("M6"), None);
        assert_eq!(g_tenths("T"), None);
    }

    #[test]
    fn epilogs_commit_abort_or_leave_by_their_rule() {
        let params = |k: &str| match k {
            "speed" => Some(1200.0),
            "feed" => Some(300.0),
            "tool" => Some(7.9),
            "pocket" => Some(-1.0),
            _ => None,
        };
        let run = |h, v: Option<f64>, builtin| epilog(h, "X", "sub", v, builtin, &params, &|_| 0.0);
        assert_eq!(
            run(Handler::SetspeedEpilog, Some(-0.00005), false),
            Ok(Commit::Speed(1200.0))
        );
        assert!(run(Handler::SetspeedEpilog, Some(-0.001), false)
            .unwrap_err()
            .contains("aborted"));
        assert_eq!(
            run(Handler::SetfeedEpilog, Some(-5.0), false),
            Ok(Commit::Feed(300.0))
        );
        assert_eq!(
            run(Handler::SetfeedEpilog, Some(1.0), true),
            Ok(Commit::None)
        );
        // M6 and M61 commit even after the subroutine used the built-in code.
        assert_eq!(
            run(Handler::ChangeEpilog, Some(1.0), true),
            Ok(Commit::ChangeTool)
        );
        assert_eq!(
            run(Handler::SettoolEpilog, Some(1.0), true),
            Ok(Commit::SetToolNumber(7))
        );
        // A negative pocket (T0) selects without preparing.
        assert_eq!(
            run(Handler::PrepareEpilog, Some(1.0), false),
            Ok(Commit::SelectTool {
                tool: 7,
                prepared: false
            })
        );
        assert!(run(Handler::PrepareEpilog, Some(0.0), false)
            .unwrap_err()
            .contains("aborted"));
        assert!(run(Handler::PrepareEpilog, None, false)
            .unwrap_err()
            .contains("returned no value"));
        assert!(run(Handler::PrepareProlog, Some(1.0), false)
            .unwrap_err()
            .contains("is a prolog"));
        assert_eq!(
            run(Handler::CycleEpilog, None, false),
            Ok(Commit::KeepMotion)
        );
    }
}
