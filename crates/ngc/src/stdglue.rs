//! LinuxCNC's standard remap glue, `stdglue.py` (`ncfiles/remap_lib/python-stdglue`), in Rust.
//!
//! A remap such as `REMAP=T prolog=prepare_prolog ngc=prepare epilog=prepare_epilog` runs a
//! Python prolog before the o-word subroutine (it checks the block and sets named parameters
//! the subroutine reads) and a Python epilog when the subroutine returns (it checks the
//! returned value and commits the result). mtsim runs no Python; these are the stdglue
//! handlers, rewritten from stdglue.py line by line, with its error messages:
//!
//! | handler | sets / commits | errors |
//! |---|---|---|
//! | `setfeed_prolog` / `_epilog` | `#<feed>` = F / feed rate = `#<feed>` | no value returned |
//! | `setspeed_prolog` / `_epilog` | `#<speed>` = S / spindle speed = `#<speed>` | no value; value < 0 |
//! | `prepare_prolog` / `_epilog` | `#<tool>` = T, `#<pocket>` (-1 for T0) / selects `#<tool>` | pocket not found; value ≤ 0: aborted |
//! | `change_prolog` / `_epilog` | `#<tool_in_spindle>` `#<selected_tool>` `#<current_pocket>` `#<selected_pocket>` / tool change | no tool prepared; compensation on; #5601 < 0 with #5600 > 0; value ≤ 0: aborted |
//! | `settool_prolog` / `_epilog` | `#<tool>` = int(Q), `#<pocket>` / tool number = `#<tool>` | no Q; Q < 0; not in table; value ≤ 0 |
//! | `cycle_prolog` / `_epilog` | every argspec word, sticky Z and R (plane's normal), `#<motion_code>` / the code stays the motion mode | other plane's words; no R; R ≤ 0; P < 0; F = 0; G93; compensation |
//!
//! An epilog reads the parameters where the subroutine left them (it may change them) and
//! does nothing when the subroutine used the built-in code itself (LinuxCNC's
//! `builtin_used`: `T#<tool>` inside the T remap), except M6 and M61, which LinuxCNC does
//! not flag and so commit again. TOLERANCE_EQUAL is LinuxCNC's 0.0001.

use crate::axis::Plane;
use crate::remap::RemapCode;

/// The handlers emulated, for messages.
pub const NAMES: &str = "prepare_, change_, settool_, setspeed_, setfeed_ and cycle_ prolog/epilog";

/// LinuxCNC's `TOLERANCE_EQUAL`.
const TOLERANCE_EQUAL: f64 = 0.0001;

/// One stdglue handler.
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

const TABLE: [(&str, Handler); 12] = [
    ("prepare_prolog", Handler::PrepareProlog),
    ("prepare_epilog", Handler::PrepareEpilog),
    ("change_prolog", Handler::ChangeProlog),
    ("change_epilog", Handler::ChangeEpilog),
    ("settool_prolog", Handler::SettoolProlog),
    ("settool_epilog", Handler::SettoolEpilog),
    ("setspeed_prolog", Handler::SetspeedProlog),
    ("setspeed_epilog", Handler::SetspeedEpilog),
    ("setfeed_prolog", Handler::SetfeedProlog),
    ("setfeed_epilog", Handler::SetfeedEpilog),
    ("cycle_prolog", Handler::CycleProlog),
    ("cycle_epilog", Handler::CycleEpilog),
];

impl Handler {
    /// The stdglue handler called `name`.
    pub fn named(name: &str) -> Option<Handler> {
        TABLE.iter().find(|(n, _)| *n == name).map(|(_, h)| *h)
    }

    pub fn name(self) -> &'static str {
        TABLE
            .iter()
            .find(|(_, h)| *h == self)
            .map_or("", |(n, _)| n)
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

/// The remapped block as a prolog sees it.
pub(crate) struct Call<'a> {
    pub code: RemapCode,
    /// The remapped word's value (T, S, F number).
    pub value: f64,
    /// The block's Q word.
    pub q: Option<f64>,
    /// The argspec words present (upper-case letter), in argspec order (`**words`).
    pub words: &'a [(char, f64)],
    /// The block has the remapped G code itself (`g_modes[1] == motion_code`), not a
    /// cycle called again by axis words.
    pub explicit: bool,
    /// The configuration's cycle_prolog compares the sticky dict with 0.0 (Python 3 error).
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

/// The sticky words of stdglue's cycle_prolog (`self.sticky_params[r.name]`), per remap.
#[derive(Debug, Default)]
pub(crate) struct Sticky(Vec<(usize, Vec<(char, f64)>)>);

impl Sticky {
    fn of(&mut self, remap: usize) -> &mut Vec<(char, f64)> {
        let k = match self.0.iter().position(|(r, _)| *r == remap) {
            Some(k) => k,
            None => {
                self.0.push((remap, Vec::new()));
                self.0.len() - 1
            }
        };
        &mut self.0[k].1
    }
}

/// Python's `int()` of a number: truncation toward zero.
fn int(v: f64) -> i64 {
    v.trunc() as i64
}

/// Runs prolog `h` for `call`: the named parameters to set in the subroutine, or the error.
/// `pocket` is `find_tool_pocket`; `param` reads a numbered parameter; `change` gives
/// change_prolog's four parameters (`None`: no tool prepared).
#[allow(clippy::too_many_arguments)]
pub(crate) fn prolog(
    h: Handler,
    call: &Call,
    remap: usize,
    view: View,
    sticky: &mut Sticky,
    pocket: &dyn Fn(u32) -> Option<f64>,
    param: &dyn Fn(usize) -> f64,
    change: Option<[(&'static str, f64); 4]>,
) -> Result<Vec<(String, f64)>, String> {
    let name = call.code.to_string();
    let set = |k: &str, v: f64| (k.to_string(), v);
    match h {
        Handler::SetspeedProlog => Ok(vec![set("speed", call.value)]),
        Handler::SetfeedProlog => Ok(vec![set("feed", call.value)]),
        Handler::PrepareProlog => {
            // cblock.t_number is an integer (the reader refuses others).
            let t = call.value;
            if t < 0.0 || t.fract() != 0.0 {
                return Err(format!(
                    "T{t}: expected a tool number (a whole number, 0 or more)"
                ));
            }
            let tool = t as u32;
            let pocket = if tool != 0 {
                pocket(tool).ok_or_else(|| format!("T{tool}: pocket not found"))?
            } else {
                -1.0 // a T0: tool unload
            };
            Ok(vec![set("tool", tool as f64), set("pocket", pocket)])
        }
        Handler::ChangeProlog => {
            toolchanger_fault(param)?;
            let Some(p) = change else {
                return Err("M6: no tool prepared".into());
            };
            if view.comp_on {
                return Err("Cannot change tools with cutter radius compensation on".into());
            }
            Ok(p.iter().map(|(k, v)| set(k, *v)).collect())
        }
        Handler::SettoolProlog => {
            let Some(q) = call.q else {
                return Err("M61 requires a Q parameter".into());
            };
            let tool = int(q);
            if (tool as f64) < -TOLERANCE_EQUAL {
                return Err("M61: Q value < 0".into());
            }
            let pocket = pocket(tool as u32)
                .ok_or_else(|| format!("M61 failed: requested tool {tool} not in table"))?;
            Ok(vec![set("tool", tool as f64), set("pocket", pocket)])
        }
        Handler::CycleProlog => {
            let (sw, incompat, plane_name) = match view.plane {
                Plane::XY => (['Z', 'R'], "UVWABC", "XY"),
                Plane::YZ => (['X', 'R'], "UVWABC", "YZ"),
                Plane::ZX => (['Y', 'R'], "UVWABC", "XZ"),
            };
            let sticky = sticky.of(remap);
            if call.explicit {
                sticky.clear();
            }
            let motion_code = match call.code {
                RemapCode::G(t) if call.explicit => t as f64,
                _ => -1.0,
            };
            let mut out = vec![set("motion_code", motion_code)];
            for &(word, value) in call.words {
                let lower = word.to_ascii_lowercase().to_string();
                out.push((lower, value));
                if sw.contains(&word) {
                    match sticky.iter_mut().find(|(w, _)| *w == word) {
                        Some(s) => s.1 = value,
                        None => sticky.push((word, value)),
                    }
                }
                if incompat.contains(word) {
                    return Err(format!(
                        "{name}: Cannot put a {word} in a canned cycle in the {plane_name} plane"
                    ));
                }
            }
            for &(word, value) in sticky.iter() {
                if !call.words.iter().any(|(w, _)| *w == word) {
                    out.push((word.to_ascii_lowercase().to_string(), value));
                }
            }
            let Some(&(_, r)) = sticky.iter().find(|(w, _)| *w == 'R') else {
                return Err(format!("{name}: cycle requires R word"));
            };
            if call.cycle_typeerror {
                return Err(format!("{name}: cycle_prolog raised TypeError: '<=' not supported between instances of 'dict' and 'float' (the configuration's stdglue.py compares the whole sticky-word dict with 0.0 where it means its R, which Python 3 refuses: LinuxCNC 2.9 stops at this block too)"));
            }
            if r <= 0.0 {
                return Err(format!("{name}: R word must be > 0 if used ({r:.4})"));
            }
            if let Some(&(_, p)) = call.words.iter().find(|(w, _)| *w == 'P') {
                if p < 0.0 {
                    return Err(format!("{name}: P word must be >= 0 if used ({p:.4})"));
                }
            }
            if view.feed_zero {
                return Err(format!("{name}: feed rate must be > 0"));
            }
            if view.inverse_time {
                return Err(format!(
                    "{name}: Cannot use inverse time feed with canned cycles"
                ));
            }
            if view.comp_on {
                return Err(format!(
                    "{name}: Cannot use canned cycles with cutter compensation on"
                ));
            }
            Ok(out)
        }
        epilog => Err(format!(
            "`{}` is an epilog, named as the prolog of {name}",
            epilog.name()
        )),
    }
}

/// iocontrol-v2's toolchanger fault: #5600 > 0 with #5601 < 0 is a hard fault.
fn toolchanger_fault(param: &dyn Fn(usize) -> f64) -> Result<(), String> {
    if param(5600) > 0.0 && param(5601) < 0.0 {
        return Err(format!("Toolchanger hard fault {}", int(param(5601))));
    }
    Ok(())
}

/// Runs epilog `h` when the subroutine `ngc` of remap `code` returned `value` (`None`: no
/// value); `local` reads the subroutine's named parameters, `builtin_used` whether it used
/// the built-in code. The commit, or the error that stops the program.
pub(crate) fn epilog(
    h: Handler,
    code: RemapCode,
    ngc: &str,
    value: Option<f64>,
    builtin_used: bool,
    local: &dyn Fn(&str) -> Option<f64>,
    param: &dyn Fn(usize) -> f64,
) -> Result<Commit, String> {
    if h == Handler::CycleEpilog {
        return Ok(Commit::KeepMotion);
    }
    let Some(v) = value else {
        return Err(format!(
            "the {code} remap procedure {ngc} did not return a value"
        ));
    };
    // A parameter the prolog did not set is a Python KeyError, caught by the epilog.
    let get = |k: &str| local(k).ok_or_else(|| format!("{code}/{}: '{k}'", h.name()));
    match h {
        Handler::SetspeedEpilog => {
            if v < -TOLERANCE_EQUAL {
                return Err(format!("S: remap procedure returned {v:.6}"));
            }
            if builtin_used {
                return Ok(Commit::None);
            }
            Ok(Commit::Speed(get("speed")?))
        }
        Handler::SetfeedEpilog => {
            if builtin_used {
                return Ok(Commit::None);
            }
            Ok(Commit::Feed(get("feed")?))
        }
        Handler::PrepareEpilog => {
            if builtin_used {
                return Ok(Commit::None);
            }
            if v > 0.0 {
                let tool = int(get("tool")?);
                let pocket = int(get("pocket")?);
                Ok(Commit::SelectTool {
                    tool: tool.max(0) as u32,
                    prepared: pocket >= 0,
                })
            } else {
                Err(format!(
                    "T{}: aborted (return code {v:.1})",
                    int(get("tool")?)
                ))
            }
        }
        Handler::ChangeEpilog => {
            toolchanger_fault(param)?;
            if builtin_used {
                return Ok(Commit::None);
            }
            if v > 0.0 {
                get("selected_pocket")?;
                Ok(Commit::ChangeTool)
            } else {
                Err(format!("M6 aborted (return code {v:.1})"))
            }
        }
        Handler::SettoolEpilog => {
            if builtin_used {
                return Ok(Commit::None);
            }
            if v > 0.0 {
                Ok(Commit::SetToolNumber(int(get("tool")?).max(0) as u32))
            } else {
                Err(format!("M61 aborted (return code {v:.1})"))
            }
        }
        prolog => Err(format!(
            "`{}` is a prolog, named as the epilog of {code}",
            prolog.name()
        )),
    }
}

#[cfg(test)]
mod tests {
    use crate::remap::parse_remap;
    use crate::{read_str_with, Axis, Dialect, Move, Options, Tool};
    use std::path::{Path, PathBuf};

    /// A scratch folder of subroutines, removed on drop.
    struct Subs(PathBuf);

    impl Subs {
        /// Each call has its own folder: tests that share a tag run in parallel, and one's
        /// drop must not remove the other's files.
        fn new(tag: &str, files: &[(&str, &str)]) -> Subs {
            static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
            let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            let dir = std::env::temp_dir()
                .join(format!("ngc-stdglue-{tag}-{}-{call}", std::process::id()));
            std::fs::create_dir_all(&dir).unwrap();
            for (name, text) in files {
                std::fs::write(dir.join(name), text).unwrap();
            }
            Subs(dir)
        }
    }

    impl Drop for Subs {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    /// The extend-builtins remaps (LinuxCNC sample configuration), tools 5 and 7 in
    /// pockets 15 and 17.
    fn options(dir: &Path, remaps: &[&str]) -> Options {
        Options {
            dialect: Dialect::Linuxcnc,
            search_path: vec![dir.to_path_buf()],
            remaps: remaps
                .iter()
                .enumerate()
                .map(|(k, r)| parse_remap(r, format!("t.ini:{}", k + 1)).unwrap())
                .collect(),
            tools: [5, 7]
                .map(|n| Tool {
                    number: n,
                    length_mm: 0.0,
                    diameter_mm: 0.0,
                })
                .to_vec(),
            pockets: vec![(5, 15), (7, 17)],
            ..Options::default()
        }
    }

    const EXTEND_BUILTINS: [&str; 5] = [
        "T prolog=prepare_prolog ngc=prepare epilog=prepare_epilog",
        "M6 modalgroup=6 prolog=change_prolog ngc=change epilog=change_epilog",
        "M61 modalgroup=6 prolog=settool_prolog ngc=settool epilog=settool_epilog",
        "S prolog=setspeed_prolog ngc=setspeed epilog=setspeed_epilog",
        "F prolog=setfeed_prolog ngc=setfeed epilog=setfeed_epilog",
    ];

    fn read(program: &str, o: &Options) -> Result<Vec<Move>, String> {
        read_str_with(Path::new("p.ngc"), program, o)
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| e.to_string())
    }

    fn xyz(m: &Move) -> [f64; 3] {
        [m.end[Axis::X], m.end[Axis::Y], m.end[Axis::Z]]
    }

    /// Subroutines that show the prologs' parameters as rapids and leave the commit to the
    /// epilogs (they use no built-in code).
    fn showing_subs() -> Subs {
        Subs::new(
            "show",
            &[
                ("prepare.ngc", "o<prepare> sub\nG0 X#<tool> Y#<pocket>\no<prepare> endsub [1]\n"),
                ("change.ngc", "o<change> sub\nG0 X#<tool_in_spindle> Y#<selected_tool> Z#<selected_pocket>\no<change> endsub [1]\n"),
                ("settool.ngc", "o<settool> sub\nG0 X#<tool> Y#<pocket>\no<settool> endsub [1]\n"),
                ("setspeed.ngc", "o<setspeed> sub\nG0 X#<speed>\no<setspeed> endsub [1]\n"),
                ("setfeed.ngc", "o<setfeed> sub\nG0 X#<feed>\no<setfeed> endsub [1]\n"),
            ],
        )
    }

    /// stdglue.py by hand: prepare_prolog sets #<tool> = 5 and #<pocket> = 15 (the tool
    /// table's pocket), prepare_epilog selects tool 5; change_prolog passes tool in spindle
    /// 0, selected tool 5, pocket 15, change_epilog makes 5 the tool; settool_prolog sets
    /// #<tool> = int(Q7) = 7, #<pocket> = 17, settool_epilog makes 7 the tool; in
    /// `S300 F50` F runs first (#<feed> = 50), then S (#<speed> = 300); the epilogs commit
    /// feed 50 mm/min and 300 rpm, which the next feed move carries.
    #[test]
    fn tool_speed_and_feed_remaps_set_and_commit_what_stdglue_does() {
        let subs = showing_subs();
        let o = options(&subs.0, &EXTEND_BUILTINS);
        let program = "G21 G90\nT5\nM6\nG0 X1\nM61 Q7.9\nG0 X2\nS300 F50\nG1 X3 Y#<_rpm>\nM2\n";
        let moves = read(program, &o).unwrap();
        let got: Vec<([f64; 3], u32)> = moves.iter().map(|m| (xyz(m), m.tool)).collect();
        assert_eq!(
            got,
            [
                ([5.0, 15.0, 0.0], 0),
                ([0.0, 5.0, 15.0], 0),
                ([1.0, 5.0, 15.0], 5),
                ([7.0, 17.0, 15.0], 5),
                ([2.0, 17.0, 15.0], 7),
                ([50.0, 17.0, 15.0], 7),
                ([300.0, 17.0, 15.0], 7),
                ([3.0, 300.0, 15.0], 7),
            ]
        );
        assert_eq!(moves[7].feed, Some(50.0));
    }

    /// An epilog commits the parameter as the subroutine left it (`#<feed> = 3·F`), and
    /// nothing when the subroutine used the built-in code (`F[2·#<feed>]`: builtin_used).
    #[test]
    fn epilogs_read_the_subroutines_parameters_unless_it_used_the_builtin() {
        let changed = Subs::new(
            "changed",
            &[(
                "setfeed.ngc",
                "o<setfeed> sub\n#<feed> = [#<feed> * 3]\no<setfeed> endsub [1]\n",
            )],
        );
        let o = options(&changed.0, &EXTEND_BUILTINS[4..]);
        let moves = read("G21\nF50\nG1 X1\n", &o).unwrap();
        assert_eq!(moves[0].feed, Some(150.0));
        let builtin = Subs::new(
            "builtin",
            &[
                (
                    "setfeed.ngc",
                    "o<setfeed> sub\nF[#<feed> * 2]\no<setfeed> endsub [1]\n",
                ),
                ("prepare.ngc", "o<prepare> sub\nT7\no<prepare> endsub [1]\n"),
            ],
        );
        let o = options(&builtin.0, &[EXTEND_BUILTINS[0], EXTEND_BUILTINS[4]]);
        // F50 gives 100 (the body's F, the epilog does not commit 50); T5's body selects 7
        // and the epilog leaves it (builtin_used), so the built-in M6 loads tool 7.
        let moves = read("G21\nF50\nT5 M6\nG1 X1\n", &o).unwrap();
        assert_eq!((moves[0].feed, moves[0].tool), (Some(100.0), 7));
    }

    /// stdglue's errors, at the remapped code.
    #[test]
    fn prologs_and_epilogs_refuse_as_stdglue_does() {
        let subs = showing_subs();
        let o = options(&subs.0, &EXTEND_BUILTINS);
        let err = |p: &str| read(p, &o).unwrap_err();
        assert!(
            err("T9\n").contains("T9: pocket not found"),
            "{}",
            err("T9\n")
        );
        assert!(err("M6\n").contains("M6: no tool prepared"));
        assert!(err("M61\n").contains("M61 requires a Q parameter"));
        assert!(err("M61 Q9\n").contains("M61 failed: requested tool 9 not in table"));
        let comp = err("T5\nG41 D5\nG1 X10 Y10 F100\nM6\n");
        assert!(
            comp.contains("Cannot change tools with cutter radius compensation on"),
            "{comp}"
        );
        let failing = Subs::new(
            "failing",
            &[
                ("prepare.ngc", "o<prepare> sub\no<prepare> endsub [0]\n"),
                ("setspeed.ngc", "o<setspeed> sub\no<setspeed> endsub\n"),
                ("change.ngc", "o<change> sub\no<change> endsub [-1]\n"),
            ],
        );
        let o = options(&failing.0, &EXTEND_BUILTINS);
        let e = read("T5\nG0 X1\n", &o).unwrap_err();
        assert!(
            e.contains("T5: aborted (return code 0.0)") && e.contains("p.ngc:1:1"),
            "{e}"
        );
        let e = read("S100\n", &o).unwrap_err();
        assert!(
            e.contains("the S remap procedure setspeed did not return a value"),
            "{e}"
        );
        let o = options(&failing.0, &EXTEND_BUILTINS[1..2]);
        let e = read("T5\nM6\n", &o).unwrap_err();
        assert!(e.contains("M6 aborted (return code -1.0)"), "{e}");
        // A handler that is not stdglue's is refused by name where the code is used.
        let mut o = options(&subs.0, &["T prolog=my_prolog ngc=prepare"]);
        let e = read("G0 X1\nT5\n", &o).unwrap_err();
        assert!(e.contains("`my_prolog`") && e.contains("p.ngc:2"), "{e}");
        o.remaps.clear();
        assert!(read("T5\nM6\nG0 X1\n", &o).is_ok());
    }

    const CYCLE: &str =
        "G84.3 argspec=xyzabcuvwqplr prolog=cycle_prolog ngc=g843 epilog=cycle_epilog modalgroup=1";

    fn cycle_subs() -> Subs {
        Subs::new(
            "cycle",
            &[(
                "g843.ngc",
                "o<g843> sub\nG0 X#<x> Y#<y> Z[#<z> + #<r>]\nG0 Z#<motion_code>\no100 if [EXISTS[#<p>]]\nG0 Z#<p>\no100 endif\no<g843> endsub [1]\n",
            )],
        )
    }

    /// cycle_prolog: the first call (G84.3 in the block) records the sticky Z and R and
    /// sets #<motion_code> = 843; cycle_epilog keeps G84.3 the motion mode, so `X4 Y5 P1`
    /// calls it again with X Y P and the sticky Z3 R2 (#<motion_code> = -1: no G code in
    /// the block); G0 ends the cycle.
    #[test]
    fn the_cycle_glue_keeps_sticky_words_and_the_motion_mode() {
        let subs = cycle_subs();
        let o = options(&subs.0, &[CYCLE]);
        let program = "G21 G90 G17 F20\nG84.3 X1 Y2 Z3 Q5 R2\nX4 Y5 P1\nG0 X0\nX7\nM2\n";
        let ends: Vec<[f64; 3]> = read(program, &o).unwrap().iter().map(xyz).collect();
        assert_eq!(
            ends,
            [
                [1.0, 2.0, 5.0],
                [1.0, 2.0, 843.0],
                [4.0, 5.0, 5.0],
                [4.0, 5.0, -1.0],
                [4.0, 5.0, 1.0],
                [0.0, 5.0, 1.0],
                [7.0, 5.0, 1.0],
            ]
        );
        let err = |p: &str| read(p, &o).unwrap_err();
        assert!(err("F20\nG84.3 X1 Z-1\n").contains("G84.3: cycle requires R word"));
        assert!(err("G84.3 X1 Z-1 R1\n").contains("G84.3: feed rate must be > 0"));
        assert!(
            err("F20\nG84.3 X1 Z-1 R0\n").contains("G84.3: R word must be > 0 if used (0.0000)")
        );
        assert!(err("F20\nG84.3 X1 Z-1 R1 P-1\n")
            .contains("G84.3: P word must be >= 0 if used (-1.0000)"));
        assert!(err("G93 F20\nG84.3 X1 Z-1 R1\n").contains("Cannot use inverse time feed"));
        // LinuxCNC 2.9's stdglue.py compares the sticky dict with 0.0: Python 3 raises.
        let mut o = o;
        o.remaps[0].cycle_prolog_typeerror = true;
        let e = read("F20\nG84.3 X1 Z-1 R1\n", &o).unwrap_err();
        assert!(e.contains("TypeError") && e.contains("p.ngc:2:1"), "{e}");
    }
}
