//! The Siemens Sinumerik front end: each part of `tests/program/siemens_parts/NN-name/`
//! written by hand in LinuxCNC RS274/NGC (`linuxcnc.ngc`) and in Sinumerik
//! (`siemens.mpf`) gives the same canonical moves (same kinds, positions and arc centres
//! within 1e-6 mm); and constructs whose results are worked out by hand here.

use std::path::{Path, PathBuf};

use ngc::{read_file_with, read_str_with, AxisVec, Dialect, Error, Motion, Move, Options, UserM};

fn parts_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/program/siemens_parts")
}

/// The options both dialects of a part read with: the part's tool table (`tools.tbl`) if
/// it has one, work offsets G55 (100 50 0), G56 (-20 30 -5), G57 (0 0 10), and M428/M429
/// mapped to TCP on/off (LinuxCNC has no TCP code of its own).
fn options(dialect: Dialect, dir: &Path) -> Options {
    let mut o = Options {
        dialect,
        search_path: vec![dir.to_path_buf()],
        ..Options::default()
    };
    if let Ok(text) = std::fs::read_to_string(dir.join("tools.tbl")) {
        o.tools = ngc::parse_tool_table(&text).expect("tools.tbl");
    }
    o.set_work_offset(2, AxisVec::xyzabc([100.0, 50.0, 0.0, 0.0, 0.0, 0.0]));
    o.set_work_offset(3, AxisVec::xyzabc([-20.0, 30.0, -5.0, 0.0, 0.0, 0.0]));
    o.set_work_offset(4, AxisVec::xyzabc([0.0, 0.0, 10.0, 0.0, 0.0, 0.0]));
    o.user_m.insert(428, UserM::TcpOn);
    o.user_m.insert(429, UserM::TcpOff);
    o
}

fn read(path: &Path, o: &Options) -> Vec<Move> {
    read_file_with(path, o)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .collect::<Result<Vec<_>, _>>()
        .unwrap_or_else(|e| panic!("{e}"))
}

fn moves(text: &str) -> Vec<Move> {
    read_str_with(Path::new("t.mpf"), text, &options(Dialect::Siemens, Path::new(".")))
        .collect::<Result<Vec<_>, _>>()
        .unwrap_or_else(|e| panic!("expected the program to read, got: {e}"))
}

fn error(text: &str) -> (usize, usize, String) {
    let err = read_str_with(Path::new("t.mpf"), text, &options(Dialect::Siemens, Path::new(".")))
        .find_map(|m| m.err())
        .unwrap_or_else(|| panic!("expected an error in {text:?}"));
    match err {
        Error::Syntax(s) => (s.line, s.column, s.message),
        other => panic!("expected a syntax error, got {other:?}"),
    }
}

fn centre(m: &Move) -> Option<[f64; 3]> {
    match m.motion {
        Motion::Arc { center_mm, .. } => Some(center_mm),
        _ => None,
    }
}

/// The first difference between two move lists, if any.
fn difference(a: &[Move], b: &[Move]) -> Option<String> {
    if a.len() != b.len() {
        return Some(format!("{} moves against {}", a.len(), b.len()));
    }
    for (k, (x, y)) in a.iter().zip(b).enumerate() {
        let close = |p: [f64; 9], q: [f64; 9]| p.iter().zip(&q).all(|(u, v)| (u - v).abs() <= 1e-6);
        let same_arc = match (x.motion, y.motion) {
            (Motion::Arc { clockwise: c1, plane: p1, .. }, Motion::Arc { clockwise: c2, plane: p2, .. }) => {
                c1 == c2 && p1 == p2 && centre(x).zip(centre(y)).is_some_and(|(u, v)| u.iter().zip(&v).all(|(s, t)| (s - t).abs() <= 1e-6))
            }
            (Motion::Dwell { seconds: s }, Motion::Dwell { seconds: t }) => (s - t).abs() < 1e-9,
            _ => true,
        };
        if x.kind() != y.kind() || !close(x.start.0, y.start.0) || !close(x.end.0, y.end.0) || !same_arc || x.tcp != y.tcp || x.feed.zip(y.feed).is_some_and(|(f, g)| (f - g).abs() > 1e-9) {
            return Some(format!("move {k}:\n linuxcnc line {} {:?} {:?}->{:?} tcp {} {:?} F{:?}\n siemens  line {} {:?} {:?}->{:?} tcp {} {:?} F{:?}", x.line, x.motion, x.start.to_xyzabc(), x.end.to_xyzabc(), x.tcp, x.path, x.feed, y.line, y.motion, y.start.to_xyzabc(), y.end.to_xyzabc(), y.tcp, y.path, y.feed));
        }
    }
    None
}

#[test]
fn every_part_gives_the_same_moves_in_linuxcnc_and_siemens() {
    let mut parts: Vec<PathBuf> = std::fs::read_dir(parts_dir())
        .expect("tests/program/siemens_parts")
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .collect();
    parts.sort();
    let mut failures = Vec::new();
    for part in &parts {
        let lcnc = read(&part.join("linuxcnc.ngc"), &options(Dialect::Linuxcnc, part));
        let sie = read(&part.join("siemens.mpf"), &options(Dialect::Siemens, part));
        assert!(lcnc.len() >= 3, "{}: too few moves to compare", part.display());
        if let Some(d) = difference(&lcnc, &sie) {
            failures.push(format!("{}: {d}", part.display()));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(parts.len() >= 10, "expected at least 10 parts, found {}", parts.len());
    eprintln!("siemens parts: {} of {} identical", parts.len() - failures.len(), parts.len());
}

/// The corpus folder (`shared/corpus` above the checkout), when present.
fn corpus() -> Option<PathBuf> {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .ancestors()
        .map(|d| d.join("shared/corpus"))
        .find(|d| d.join("manifest.tsv").is_file())
}

#[test]
#[ignore]
fn corpus_scan() {
    let dir = corpus().unwrap();
    let manifest = std::fs::read_to_string(dir.join("manifest.tsv")).unwrap();
    for line in manifest.lines().skip(1) {
        let f: Vec<&str> = line.split('\t').collect();
        if f.get(1) != Some(&"siemens") {
            continue;
        }
        let path = dir.join("programs").join(f[0]);
        let o = options(Dialect::Siemens, path.parent().unwrap());
        let mut n = 0;
        let mut err = None;
        for m in read_file_with(&path, &o).unwrap() {
            match m {
                Ok(_) => n += 1,
                Err(e) => err = Some(e.to_string()),
            }
        }
        eprintln!("{} moves={n} {}", f[0], err.unwrap_or_default());
    }
}
