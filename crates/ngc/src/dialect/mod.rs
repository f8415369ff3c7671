//! Dialects as front ends: what each control does, as data the interpreter's phases ask.
//!
//! Input: the dialect a scenario names ([`Dialect`]); output: its [`Table`] (start-up modal
//! state, code table, parameter and subprogram syntax). The reader and the phases of crate
//! `interp` read the table; no phase branches on which control it is.
//!
//! ```text
//!  program text                         front end                        shared
//!  ───────────                          ─────────                        ──────
//!  RS274/NGC (LinuxCNC) ─┐
//!  Fanuc (0i/30i, macro B)├─ lex + reader (o-words / O-M98-M99 / #<name> / IF-WHILE)
//!  Haas (NGC)           ─┘        │  the dialect's Table
//!                                 ▼
//!                          typed block (crate `block`) ─► interp phases ─► canonical Move
//!                                 ▲        words of the same G codes (G1, G2 I J, G52, G68.2 …)
//!  Heidenhain Klartext ──── own front end, crate module `heidenhain`: BEGIN PGM, L/C/CC/CT/RND, Q, LBL,
//!                           CYCL DEF, PLANE (read whatever the dialect when BEGIN PGM opens it)
//!  Siemens Sinumerik ────── own front end, crate module `siemens`: R params, DEF, IF/WHILE/FOR,
//!                           frames, CYCLE81/82, MCALL; ISO blocks in Fanuc's codes
//! ```
//!
//! The three G-code dialects share one line syntax, so they differ only in this table. The
//! Heidenhain conversational and Siemens Sinumerik languages have their own line syntax: they
//! plug in as whole front ends beside `lex`/`reader`, each turning its program text into the
//! words of a typed [`Block`](crate::block::Block) the same interpreter runs, with a
//! [`Table`] of its own for the modal state it starts in. Whatever the front end, every move
//! leaves as the same canonical [`Move`](crate::Move). The Siemens front end hands the
//! interpreter ISO blocks in Fanuc's codes, so its table is Fanuc's.

mod fanuc;
mod haas;
mod heidenhain;
mod linuxcnc;
mod table;

use crate::code::{GCode, MotionMode};
use crate::lex::{LineError, LineResult, Word};
use crate::options::Dialect;
use table::common_refusal;
pub(crate) use table::{ArcRadiusRule, DwellUnit, Table};

impl Dialect {
    /// The dialect's table.
    pub(crate) fn table(self) -> &'static Table {
        match self {
            Dialect::Linuxcnc => &linuxcnc::TABLE,
            Dialect::Fanuc => &fanuc::TABLE,
            Dialect::Haas => &haas::TABLE,
            Dialect::Heidenhain => &heidenhain::TABLE,
            // The Siemens front end hands the interpreter ISO blocks in Fanuc's codes.
            Dialect::Siemens => &fanuc::TABLE,
        }
    }
}

/// The lathe cycles left out of mtsim (code ×10): their name and what they do.
pub(crate) fn dropped_lathe_cycle(code: u32) -> Option<(&'static str, &'static str)> {
    Some(match code {
        700 => ("G70", "lathe finishing cycle"),
        710 => ("G71", "lathe roughing cycle"),
        711 => ("G71.1", "lathe roughing cycle"),
        712 => ("G71.2", "lathe roughing cycle"),
        720 => ("G72", "lathe facing cycle"),
        721 => ("G72.1", "lathe facing cycle"),
        722 => ("G72.2", "lathe facing cycle"),
        760 => ("G76", "lathe threading cycle"),
        _ => return None,
    })
}

/// The meaning of G word `word` (of `line`) in `table`'s dialect: the code ×10 looked up in
/// the dialect's codes, else refused with the dialect's reason, else as a lathe cycle left
/// out, else as unsupported. Inlined into the block reader (docs/performance.md).
#[inline(always)]
pub(crate) fn parse_g_code(word: &Word, line: &str, table: &Table) -> LineResult<GCode> {
    // The codes of nearly every block, as written in most programs.
    match word.number {
        "1" | "01" => return Ok(GCode::Motion(Some(MotionMode::Linear))),
        "0" | "00" => return Ok(GCode::Motion(Some(MotionMode::Rapid))),
        _ => {}
    }
    let tenths = word.value * 10.0;
    // `round` without the call to libm: the same code for every value accepted below.
    let code = if tenths >= 0.0 {
        (tenths + 0.5) as i64 as f64
    } else {
        tenths.round()
    };
    let unsupported = |why: &str, help: &str| {
        let text = &line[word.span()];
        LineError::new(
            word.span(),
            format!("unsupported code `{text}`{why}"),
            "unsupported G code",
        )
        .help(if help.is_empty() {
            "docs/gcode.md lists every supported G code"
        } else {
            help
        })
    };
    if word.number.starts_with(['+', '-'])
        || word.value < 0.0
        || (tenths - code).abs() > 1e-6
        || code > 99999.0
    {
        return Err(unsupported("", ""));
    }
    let code = code as u32;
    if let Some(c) = (table.g_code)(code) {
        return Ok(c);
    }
    if let Some((why, help)) = (table.refusal)(code).or_else(|| common_refusal(code)) {
        return Err(unsupported(why, help));
    }
    if let Some((name, what)) = dropped_lathe_cycle(code) {
        return Err(LineError::new(
            word.span(),
            format!("{name} ({what}) is not supported by mtsim: it simulates milling machines and leaves out the lathe cycles G70-G72 and G76"),
            "lathe cycle not supported",
        )
        .help("post the cycle as G00/G01 moves (a thread as G33 passes)"));
    }
    Err(unsupported("", ""))
}
