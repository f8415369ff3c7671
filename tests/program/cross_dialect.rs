//! One toolpath, every dialect: each part of `tests/program/dialects/` is written by hand in
//! every dialect that can say it (LinuxCNC, Fanuc, Haas, Heidenhain, Siemens), and every version must give the canonical moves of the
//! reference (`linuxcnc.ngc`, else `fanuc.nc`): same kinds, positions, arc centres, feeds and
//! dwell times within 1e-6 (mm, deg, mm/min, s). The parts and their toolpaths are listed
//! in `tests/program/dialects/README.md`.

use std::path::{Path, PathBuf};

use ngc::{Axis, AxisVec, Dialect, Motion, Move, Options, RotaryTable, TcpAxes, Tool, UserM};

const TOLERANCE: f64 = 1e-6;

fn parts_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/program/dialects")
}

/// The files of a part and their dialects, reference first.
const FILES: [(&str, Dialect); 5] = [
    ("linuxcnc.ngc", Dialect::Linuxcnc),
    ("fanuc.nc", Dialect::Fanuc),
    ("haas.nc", Dialect::Haas),
    ("heidenhain.h", Dialect::Heidenhain),
    ("siemens.mpf", Dialect::Siemens),
];

/// The machine every part runs on: X Y Z A B C, T1 Ø10 mm of length 0, the G28 position
/// at machine Z450; the five-axis parts (16, 17, 22, 24) on a table-table AC machine with
/// its pivot at the origin, LinuxCNC's TCP as the user M codes M428/M429.
fn options(part: &str, dialect: Dialect) -> Options {
    let mut o = Options {
        dialect,
        tools: vec![Tool {
            number: 1,
            length_mm: 0.0,
            diameter_mm: 10.0,
        }],
        ..Options::default()
    };
    if ["16-", "17-", "22-", "24-"]
        .iter()
        .any(|p| part.starts_with(p))
    {
        let table = RotaryTable {
            tilt: Axis::A,
            pivot_mm: [0.0; 3],
        };
        o.table = Some(table);
        o.tcp_axes = Some(tcp_axes(table));
        o.user_m.insert(428, UserM::TcpOn);
        o.user_m.insert(429, UserM::TcpOff);
    }
    // Part 23: the G28 position, machine Z450.
    o.set_reference(false, AxisVec::xyzabc([0.0, 0.0, 450.0, 0.0, 0.0, 0.0]));
    o
}

/// The table-table machine's axes at a TCP position (for a TCP cancel, part 22):
/// `m = R(q) (x, y, z − L) + (0, 0, L)`, pivot at the origin.
fn tcp_axes(table: RotaryTable) -> TcpAxes {
    TcpAxes(std::sync::Arc::new(move |q: &AxisVec, l: f64| {
        let r = table.rotation(q);
        let tip = [q[Axis::X], q[Axis::Y], q[Axis::Z] - l];
        let mut out = *q;
        for (k, a) in [Axis::X, Axis::Y, Axis::Z].into_iter().enumerate() {
            out[a] = (0..3).map(|j| r[k][j] * tip[j]).sum::<f64>();
        }
        out[Axis::Z] += l;
        out
    }))
}

fn moves(path: &Path, o: &Options) -> Vec<Move> {
    ngc::read_file_with(path, o)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .collect::<Result<Vec<_>, _>>()
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Where two move lists differ, or None.
fn difference(reference: &[Move], other: &[Move]) -> Option<String> {
    if reference.len() != other.len() {
        return Some(format!(
            "{} moves, the reference has {}",
            other.len(),
            reference.len()
        ));
    }
    let close = |a: f64, b: f64| (a - b).abs() <= TOLERANCE;
    for (k, (r, m)) in reference.iter().zip(other).enumerate() {
        let same_points = Axis::ALL
            .iter()
            .all(|&a| close(r.start[a], m.start[a]) && close(r.end[a], m.end[a]));
        let same_motion = match (r.motion, m.motion) {
            (
                Motion::Arc {
                    clockwise: c1,
                    center_mm: a,
                    ..
                },
                Motion::Arc {
                    clockwise: c2,
                    center_mm: b,
                    ..
                },
            ) => c1 == c2 && (0..3).all(|i| close(a[i], b[i])),
            (Motion::Dwell { seconds: a }, Motion::Dwell { seconds: b }) => close(a, b),
            (a, b) => a == b,
        };
        let same_feed = match (r.feed.rate(), m.feed.rate()) {
            (Some(a), Some(b)) => close(a, b),
            (a, b) => r.kind() == ngc::MoveKind::Rapid || a == b,
        };
        if r.kind() != m.kind() || !same_points || !same_motion || !same_feed {
            return Some(format!(
                "move {k}: {:?} {:?} → {:?} F{:?}, the reference (line {}) {:?} {:?} → {:?} F{:?}",
                m.motion,
                &m.start.0[..6],
                &m.end.0[..6],
                m.feed,
                r.line,
                r.motion,
                &r.start.0[..6],
                &r.end.0[..6],
                r.feed
            ));
        }
    }
    None
}

#[test]
fn every_dialect_of_every_part_gives_the_reference_moves() {
    let mut parts: Vec<_> = std::fs::read_dir(parts_dir())
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.path().is_dir())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    parts.sort();
    assert!(parts.len() >= 20, "{} parts", parts.len());
    let mut failures = Vec::new();
    let mut compared = 0;
    let mut heidenhain = 0;
    let mut siemens = 0;
    for part in &parts {
        let dir = parts_dir().join(part);
        let present: Vec<_> = FILES
            .iter()
            .filter(|(f, _)| dir.join(f).is_file())
            .collect();
        let (ref_file, ref_dialect) = present[0];
        let reference = moves(&dir.join(ref_file), &options(part, *ref_dialect));
        assert!(
            reference.len() >= 4,
            "{part}: {} moves in {ref_file}",
            reference.len()
        );
        for (file, dialect) in &present[1..] {
            let got = moves(&dir.join(file), &options(part, *dialect));
            compared += 1;
            heidenhain += usize::from(*dialect == Dialect::Heidenhain);
            siemens += usize::from(*dialect == Dialect::Siemens);
            if let Some(d) = difference(&reference, &got) {
                failures.push(format!("{part}/{file} against {ref_file}: {d}"));
            }
        }
    }
    eprintln!(
        "cross-dialect: {} parts, {compared} programs compared with their reference ({heidenhain} Heidenhain, {siemens} Siemens)",
        parts.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert_eq!(
        heidenhain,
        parts.len(),
        "every part has a Heidenhain version"
    );
    assert_eq!(siemens, parts.len(), "every part has a Siemens version");
}
