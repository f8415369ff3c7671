//! What the Klartext and post tests share: the options (tool 1, 10 mm, no length), a body
//! wrapped into a program, reading to moves or to the refusal's (line, message), and
//! positions compared to 1e-9 mm.

use std::path::Path;

use ngc::{read_str_with, Axis, Dialect, Error, Move, Options, Tool};

/// The Heidenhain dialect with tool 1 in the table: 10 mm diameter, no length.
pub fn klartext_options() -> Options {
    Options {
        dialect: Dialect::Heidenhain,
        tools: vec![Tool {
            number: 1,
            length_mm: 0.0,
            diameter_mm: 10.0,
        }],
        ..Options::default()
    }
}

/// `body` between `BEGIN PGM` and `END PGM`, after `TOOL CALL 1` (file lines 1 and 2).
pub fn in_program(body: &str) -> String {
    format!("0 BEGIN PGM T MM\n1 TOOL CALL 1 Z S1000\n{body}\n99 END PGM T MM\n")
}

/// The moves of `text` (read as the file `name`), or its refusal's line and message.
pub fn read_named(name: &str, text: &str, o: &Options) -> Result<Vec<Move>, (usize, String)> {
    read_str_with(Path::new(name), text, o)
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| match e {
            Error::Syntax(s) => (s.line, s.message),
            other => panic!("{other}"),
        })
}

/// A move's end X Y Z.
pub fn xyz(m: &Move) -> [f64; 3] {
    [m.end[Axis::X], m.end[Axis::Y], m.end[Axis::Z]]
}

/// Two points within 1e-9 mm on every axis.
pub fn near(a: [f64; 3], b: [f64; 3]) -> bool {
    a.iter().zip(b).all(|(a, b)| (a - b).abs() < 1e-9)
}
