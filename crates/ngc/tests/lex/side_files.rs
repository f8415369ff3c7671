//! Files beside the program: subroutine files are streamed like the program, and only
//! regular files are read; side files (LinuxCNC INI) only up to `MAX_SIDE_FILE_BYTES`;
//! a line longer than `MAX_LINE_BYTES` is a read error; messages about a tool table,
//! parameter file or INI name the line and column, never the file's text (issue 26,
//! items 3 and 7).

use std::path::{Path, PathBuf};

use ngc::{
    parse_tool_orientations, parse_tool_table, parse_var_file, read_file, read_file_with,
    read_side_file, Axis, AxisVec, Dialect, Error, Ini, Options, MAX_LINE_BYTES,
    MAX_SIDE_FILE_BYTES,
};

/// A fresh temporary folder for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ngc-side-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The moves' X ends, or the error's text.
fn run(path: &Path, options: &Options) -> Result<Vec<f64>, String> {
    let mut xs = Vec::new();
    for m in read_file_with(path, options).map_err(|e| e.to_string())? {
        match m {
            Ok(m) => xs.push(m.end[Axis::X]),
            Err(Error::Syntax(s)) => return Err(format!("{}:{}: {}", s.line, s.column, s.message)),
            Err(e) => return Err(format!("{e}: {}", std::error::Error::source(&e).unwrap())),
        }
    }
    Ok(xs)
}

/// LinuxCNC options with subroutine files searched in `dir`.
fn searching(dir: &Path) -> Options {
    Options {
        search_path: vec![dir.to_path_buf()],
        dialect: Dialect::Linuxcnc,
        ..Options::default()
    }
}

/// Runs `dir/p.ngc` calling `o<label>` on its line 2; the error's text.
fn calling(dir: &Path, label: &str) -> String {
    let main = dir.join("p.ngc");
    std::fs::write(&main, format!("G21\no<{label}> call\nM2\n")).unwrap();
    run(&main, &searching(dir)).unwrap_err()
}

const SECRET: &str = "root:$6$secretsecret:19000:0:99999:7:::\n";

#[test]
fn a_subroutine_file_is_streamed_and_called_more_than_once() {
    let dir = scratch("sub");
    std::fs::write(
        dir.join("two.ngc"),
        "o<two> sub\nG1 X[#1 * 2] F100\no<two> endsub\n",
    )
    .unwrap();
    let main = dir.join("p.ngc");
    std::fs::write(&main, "G21 G90\no<two> call [1]\no<two> call [3.5]\nM2\n").unwrap();
    assert_eq!(run(&main, &searching(&dir)), Ok(vec![2.0, 7.0]));
}

#[cfg(unix)]
#[test]
fn a_subroutine_file_that_is_not_regular_is_refused_with_its_name() {
    let dir = scratch("zero");
    std::os::unix::fs::symlink("/dev/zero", dir.join("zero.ngc")).unwrap();
    std::fs::create_dir(dir.join("folder.ngc")).unwrap();
    for label in ["zero", "folder"] {
        let e = calling(&dir, label);
        assert!(e.starts_with("2:1: subroutine file "), "{e}");
        assert!(e.contains(&format!("{label}.ngc")), "{e}");
        assert!(e.contains("not a regular file"), "{e}");
    }
}

#[cfg(unix)]
#[test]
fn the_program_as_dev_zero_is_refused() {
    let e = read_file(Path::new("/dev/zero"), AxisVec::ZERO)
        .err()
        .expect("refused before reading");
    let source = std::error::Error::source(&e).unwrap().to_string();
    assert!(source.contains("not a regular file"), "{source}");
}

#[test]
fn a_line_longer_than_the_limit_is_a_read_error_naming_the_line() {
    let dir = scratch("long");
    let main = dir.join("p.ngc");
    // 100 MB without a newline on line 2.
    let mut text = String::from("G21\n(");
    text.push_str(&"x".repeat(100_000_000));
    std::fs::write(&main, text).unwrap();
    let e = run(&main, &Options::default()).unwrap_err();
    assert!(e.contains("p.ngc"), "{e}");
    assert!(
        e.contains(&format!(
            "line 2: a line longer than {MAX_LINE_BYTES} bytes"
        )),
        "{e}"
    );
    // A subroutine file with such a line: an error at the call, naming the file.
    std::fs::rename(&main, dir.join("long.ngc")).unwrap();
    let e = calling(&dir, "long");
    assert!(e.starts_with("2:1: subroutine file "), "{e}");
    assert!(e.contains("long.ngc: line 2: a line longer than"), "{e}");
}

#[test]
fn a_line_at_the_limit_is_read() {
    let dir = scratch("limit");
    let main = dir.join("p.ngc");
    // `G1 X1 F100` and a comment that fills the line to exactly MAX_LINE_BYTES bytes.
    let head = "G1 X1 F100 (";
    let line = format!("{head}{})", "c".repeat(MAX_LINE_BYTES - head.len() - 1));
    assert_eq!(line.len(), MAX_LINE_BYTES);
    std::fs::write(&main, format!("G21 G90\n{line}\nM2\n")).unwrap();
    assert_eq!(run(&main, &Options::default()), Ok(vec![1.0]));
}

#[cfg(unix)]
#[test]
fn side_files_must_be_regular_and_at_most_the_limit() {
    let dir = scratch("side");
    std::os::unix::fs::symlink("/dev/zero", dir.join("zero.ini")).unwrap();
    for path in [dir.join("zero.ini"), dir.clone()] {
        let e = read_side_file(&path).unwrap_err().to_string();
        assert!(e.contains("not a regular file"), "{e}");
        let e = Ini::read(&path).unwrap_err();
        assert_eq!(e.line, 0);
        assert!(e.to_string().contains("not a regular file"), "{e}");
    }
    let big = dir.join("big.tbl");
    let f = std::fs::File::create(&big).unwrap();
    f.set_len(MAX_SIDE_FILE_BYTES + 1).unwrap();
    let e = read_side_file(&big).unwrap_err().to_string();
    assert_eq!(e, "larger than 64 MiB");
    f.set_len(MAX_SIDE_FILE_BYTES).unwrap();
    assert_eq!(
        read_side_file(&big).unwrap().len() as u64,
        MAX_SIDE_FILE_BYTES
    );
}

#[test]
fn tool_table_messages_give_line_and_column_not_the_text() {
    let text = format!("T1 P1 Z+10 D6\n{SECRET}");
    let (line, m) = parse_tool_table(&text).unwrap_err();
    assert_eq!(line, 2);
    assert!(m.starts_with("column 1: expected a word"), "{m}");
    assert!(!m.contains("secret") && !m.contains("root"), "{m}");
    let (line, m) = parse_tool_table("T1 P1\nP2 Zsecret\n").unwrap_err();
    assert_eq!((line, m.starts_with("column 4: ")), (2, true), "{m}");
    assert!(!m.contains("secret"), "{m}");
    let (line, m) = parse_tool_table("  P2 Z1 ; no tool\n").unwrap_err();
    assert_eq!(line, 1);
    assert_eq!(m, "column 3: expected a tool number `T<n>`");
    let (line, m) = parse_tool_orientations("T1 Q12 Z1\n").unwrap_err();
    assert_eq!(line, 1);
    assert_eq!(m, "column 4: expected a lathe tool orientation Q0 to Q9");
}

#[test]
fn parameter_file_messages_give_line_and_column_not_the_text() {
    let (line, m) = parse_var_file(&format!("5220 1\n{SECRET}")).unwrap_err();
    assert_eq!(line, 2);
    assert_eq!(m, "column 1: expected a parameter number 1-5601");
    let (line, m) = parse_var_file("5220 1\n  5221 secret\n").unwrap_err();
    assert_eq!(line, 2);
    assert_eq!(
        m,
        "column 8: expected a finite value after the parameter number"
    );
    let (line, m) = parse_var_file("5221\n").unwrap_err();
    assert_eq!((line, m.starts_with("column 5: ")), (1, true), "{m}");
}

#[test]
fn ini_messages_give_the_line_not_the_text() {
    for (text, line) in [
        (SECRET.to_string(), 1),
        (format!("[X]\nA = 1\n{SECRET}"), 3),
        ("secret = 1\n".to_string(), 1),
        ("[secret\n".to_string(), 1),
    ] {
        let e = Ini::parse(Path::new("a.ini"), &text).unwrap_err();
        assert_eq!(e.line, line);
        let shown = e.to_string();
        assert!(shown.starts_with(&format!("a.ini:{line}: ")), "{shown}");
        assert!(!shown.contains("secret"), "{shown}");
    }
    let e = Ini::parse(Path::new("a.ini"), "[TRAJ]\nLINEAR_UNITS = secret\n")
        .unwrap()
        .linear_units_inch()
        .unwrap_err();
    assert_eq!(e.line, 2);
    assert!(!e.to_string().contains("secret"), "{e}");
}
