//! The standard remap glue (crates/ngc/src/stdglue.rs) through the reader: remaps of T, M6,
//! M61, S, F and a canned cycle with the glue's prologs and epilogs around subroutines
//! written for the test, each expectation worked out by hand from the handler table in the
//! module doc.

use ngc::{parse_remap, read_str_with, Axis, Dialect, Move, Options, Tool};
use std::path::{Path, PathBuf};

/// A scratch folder of subroutines, removed on drop.
struct Subs(PathBuf);

impl Subs {
    /// Each call has its own folder: tests that share a tag run in parallel, and one's
    /// drop must not remove the other's files.
    fn new(tag: &str, files: &[(&str, &str)]) -> Subs {
        static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let dir =
            std::env::temp_dir().join(format!("ngc-stdglue-{tag}-{}-{call}", std::process::id()));
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

/// The handlers by the table in the module doc: prepare_prolog sets #<tool> = 5 and #<pocket> = 15 (the tool
/// table's pocket), prepare_epilog selects tool 5; change_prolog passes tool in spindle
/// 0, selected tool 5, pocket 15, change_epilog makes 5 the tool; settool_prolog sets
/// #<tool> = int(Q7) = 7, #<pocket> = 17, settool_epilog makes 7 the tool; in
/// `S300 F50` F runs first (#<feed> = 50), then S (#<speed> = 300); the epilogs commit
/// feed 50 mm/min and 300 rpm, which the next feed move carries.
#[test]
fn tool_speed_and_feed_remaps_set_and_commit_the_parameters() {
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
    assert_eq!(moves[7].feed, ngc::Feed::PerMinute(50.0));
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
    assert_eq!(moves[0].feed, ngc::Feed::PerMinute(150.0));
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
    assert_eq!(
        (moves[0].feed, moves[0].tool),
        (ngc::Feed::PerMinute(100.0), 7)
    );
}

/// The glue's refusals, at the remapped code (the point of each check is its message).
#[test]
fn prologs_and_epilogs_refuse_what_the_glue_refuses() {
    let subs = showing_subs();
    let o = options(&subs.0, &EXTEND_BUILTINS);
    let err = |p: &str| read(p, &o).unwrap_err();
    assert!(
        err("T9\n").contains("tool 9 is not in the tool table"),
        "{}",
        err("T9\n")
    );
    assert!(err("M6\n").contains("no tool selected for the change"));
    assert!(err("M61\n").contains("no Q word"));
    assert!(err("M61 Q9\n").contains("tool 9 is not in the tool table"));
    let comp = err("T5\nG41 D5\nG1 X10 Y10 F100\nM6\n");
    assert!(
        comp.contains("tool change with cutter radius compensation on"),
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
        e.contains("T aborted: its subroutine `prepare` returned 0.0") && e.contains("p.ngc:1:1"),
        "{e}"
    );
    let e = read("S100\n", &o).unwrap_err();
    assert!(
        e.contains("the subroutine `setspeed` of the S remap returned no value"),
        "{e}"
    );
    let o = options(&failing.0, &EXTEND_BUILTINS[1..2]);
    let e = read("T5\nM6\n", &o).unwrap_err();
    assert!(
        e.contains("M6 aborted: its subroutine `change` returned -1.0"),
        "{e}"
    );
    // A handler that is not one of the glue handlers is refused by name where the code is used.
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
    assert!(err("F20\nG84.3 X1 Z-1\n").contains("no R word"));
    assert!(err("G84.3 X1 Z-1 R1\n").contains("no feed rate for the cycle"));
    assert!(err("F20\nG84.3 X1 Z-1 R0\n").contains("R0.0000 is not positive"));
    assert!(err("F20\nG84.3 X1 Z-1 R1 P-1\n").contains("P-1.0000 is negative"));
    assert!(err("G93 F20\nG84.3 X1 Z-1 R1\n").contains("inverse-time feed mode (G93)"));
    // The configuration flagged as carrying the cycle_prolog that fails under Python 3.
    let mut o = o;
    o.remaps[0].cycle_prolog_typeerror = true;
    let e = read("F20\nG84.3 X1 Z-1 R1\n", &o).unwrap_err();
    assert!(e.contains("TypeError") && e.contains("p.ngc:2:1"), "{e}");
}
