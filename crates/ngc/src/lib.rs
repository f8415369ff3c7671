//! `ngc`: a G-code (RS274/NGC, Fanuc-family) reader that keeps every number exact and every
//! bit of modal state, and emits canonical moves.
//!
//! ```text
//! program text ─► front end: tokenizer and reader (words, comments, o-words, macros,
//!                 file:line:column), with the dialect's table (dialect/)
//!              ─► typed block (block.rs: G codes by modal group, M codes, words)
//!              ─► modal interpreter, phase by phase (interp/: units, feed, tool, plane,
//!                 compensation, offsets, motion, flow)
//!              ─► canonical moves (absolute axis positions, mm and deg)
//! ```
//!
//! The crate depends on nothing of the simulator that uses it: a canonical [`Move`] is the
//! narrow interface between reading a program and moving a machine, as LinuxCNC's
//! canonical machining calls are. Reading streams one line at a time, so memory does not
//! grow with the program.
//!
//! Every input-driven depth and size is bounded, and exceeding a bound is an error with its
//! place, never a crash: expressions nest at most [`MAX_NESTING`] levels, subroutine calls
//! at most [`MAX_CALL_DEPTH`], `#INCLUDE`s in a LinuxCNC INI at most 8; program and
//! subroutine files (streamed) have lines of at most [`MAX_LINE_BYTES`]; side files (INI)
//! are read only when regular and at most [`MAX_SIDE_FILE_BYTES`] ([`read_side_file`]).
//!
//! ```
//! use std::path::Path;
//! use ngc::{read_str, AxisVec, Axis, Motion};
//!
//! let program = "G21 G90 G94\nG01 X10 Y-2.5 F600\nM30\n";
//! let moves: Vec<_> = read_str(Path::new("demo.nc"), program, AxisVec::ZERO)
//!     .collect::<Result<_, _>>()
//!     .unwrap();
//! assert_eq!(moves.len(), 1);
//! assert_eq!(moves[0].motion, Motion::Linear);
//! assert_eq!(moves[0].end[Axis::Y], -2.5);
//! assert_eq!(moves[0].feed, ngc::Feed::PerMinute(600.0));
//! ```

mod axis;
mod block;
mod budget;
mod byte_words;
mod canon;
mod code;
mod comp;
mod corner;
mod corner_arc;
mod decimal_point;
mod dialect;
mod error;
mod expr;
mod fanuc_polar;
mod frame;
mod front_end;
mod heidenhain;
mod ini;
mod interp;
mod lex;
mod mirror_scale;
mod notice;
mod options;
mod polar;
mod probe;
mod reader;
mod remap;
mod side_file;
mod siemens;
mod source;
mod spline;
mod stdglue;
mod surface_speed;
mod turns;
mod units;

pub use axis::{Axis, AxisVec, Plane};
pub use canon::{Feed, FeedMode, Motion, Move, MoveKind, PathControl, FULL_CIRCLE_TOLERANCE_MM};
pub use decimal_point::WholeNumbers;
pub use error::{line_column, Error, Result, Syntax};
pub use expr::MAX_NESTING;
pub use frame::{RotaryTable, ToolAligner};
pub use ini::{scale_parameter_lengths, Ini, IniEntry, IniError, LinuxcncConfig};
pub use notice::Notice;
pub use options::{
    parse_tool_orientations, parse_tool_table, parse_var_file, tool_pockets, work_offset_parameter,
    ControlParameters, Dialect, Distance, Options, StartFeed, StartState, TcpAxes, Tool, Units,
    UserM, G28_PARAMETER, G30_PARAMETER, MAX_BLOCKS, MAX_CALL_DEPTH, PECK_CLEARANCE_MM,
};
pub use reader::{read_file, read_file_with, read_str, read_str_with, Moves};
pub use remap::{parse_remap, Remap, RemapCode};
pub use side_file::{read_side_bytes, read_side_file, MAX_SIDE_FILE_BYTES};
pub use source::MAX_LINE_BYTES;
pub use units::{ARC_RADIUS_TOLERANCE_MM, FANUC_ARC_RADIUS_TOLERANCE_MM, MM_PER_INCH};
