//! `[simulate] trace_format = "parquet"` (and `simulate --trace-format parquet`): the trace as
//! `trace.parquet`, the columns of `trace.csv` as the f64 the run computed.
//!
//! The CSV writer is the independent reference: both traces come from the same run's rows
//! through two different writers, so every Parquet value must round to the CSV's text.

use std::fs::File;
use std::path::{Path, PathBuf};

use arrow::array::{Array, Float64Array, StringArray, UInt64Array};
use mtsim::input::scenario::{Scenario, TraceFormat};
use mtsim::study::simulate::simulate;
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;

use crate::common;

use common::{mtsim_plain, scratch};

/// The bundled ISO 230-4 circle (both directions), its trace in `format`, into `out`.
fn run(out: &Path, format: TraceFormat) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/circle-iso230-4.toml");
    let mut scenario = Scenario::load(&path).unwrap();
    scenario.simulate.trace_format = format;
    simulate(&scenario, out, false, &|_| {}).unwrap();
}

/// `trace.parquet` as (column names, rows of text cells: direction, line, then floats).
fn parquet_columns(path: &Path) -> (Vec<String>, Vec<Vec<String>>, Vec<Vec<f64>>) {
    let reader = ParquetRecordBatchReaderBuilder::try_new(File::open(path).unwrap())
        .unwrap()
        .build()
        .unwrap();
    let mut names = Vec::new();
    let (mut text, mut floats): (Vec<Vec<String>>, Vec<Vec<f64>>) = (Vec::new(), Vec::new());
    for batch in reader {
        let batch = batch.unwrap();
        if names.is_empty() {
            names = batch
                .schema()
                .fields()
                .iter()
                .map(|f| f.name().clone())
                .collect();
            text = vec![Vec::new(); 2];
            floats = vec![Vec::new(); names.len() - 2];
        }
        for i in 0..batch.num_rows() {
            let direction = batch.column(0).as_any().downcast_ref::<StringArray>();
            let line = batch.column(2).as_any().downcast_ref::<UInt64Array>();
            text[0].push(direction.expect("direction is text").value(i).to_string());
            text[1].push(line.expect("line is u64").value(i).to_string());
        }
        let float_columns = (0..names.len()).filter(|&c| c != 0 && c != 2);
        for (k, c) in float_columns.enumerate() {
            let column = batch.column(c).as_any().downcast_ref::<Float64Array>();
            let column = column.unwrap_or_else(|| panic!("{} is f64", names[c]));
            assert_eq!(column.null_count(), 0, "{} has no nulls", names[c]);
            floats[k].extend(column.values().iter());
        }
    }
    (names, text, floats)
}

/// Decimals `trace.csv` prints in a column.
fn decimals(name: &str) -> i32 {
    if name.ends_with("_ferr_mm") || name.ends_with("_ferr_deg") {
        7
    } else if name.ends_with("_mm") || name.ends_with("_deg") && name != "theta_deg" {
        6
    } else {
        4
    }
}

/// Asserts that `trace.parquet` in `pq_dir` holds the rows of `trace.csv` in `csv_dir`, each
/// value within half a unit of the CSV's last decimal, and unrounded; returns the row count.
fn assert_parquet_matches_csv(csv_dir: &Path, pq_dir: &Path) -> usize {
    assert!(!pq_dir.join("trace.csv").exists());
    let (names, text, floats) = parquet_columns(&pq_dir.join("trace.parquet"));

    let mut csv = csv::Reader::from_path(csv_dir.join("trace.csv")).unwrap();
    let header: Vec<String> = csv.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(names, header, "the same columns in the same order");
    let rows: Vec<csv::StringRecord> = csv.records().map(|r| r.unwrap()).collect();
    assert_eq!(rows.len(), text[0].len(), "the same rows");

    let float_columns: Vec<usize> = (0..names.len()).filter(|&c| c != 0 && c != 2).collect();
    let mut worst = 0.0f64;
    for (i, row) in rows.iter().enumerate() {
        assert_eq!(&row[0], text[0][i].as_str(), "direction, row {i}");
        assert_eq!(&row[2], text[1][i].as_str(), "line, row {i}");
        for (k, &c) in float_columns.iter().enumerate() {
            let printed: f64 = row[c].parse().unwrap();
            let half_unit = 0.5 * 10f64.powi(-decimals(&names[c]));
            let error = (floats[k][i] - printed).abs() / half_unit;
            assert!(
                error <= 1.0 + 1e-6,
                "{} row {i}: {} printed as {}",
                names[c],
                floats[k][i],
                &row[c]
            );
            worst = worst.max(error);
        }
    }
    // Unrounded: the values do not all sit on the CSV's decimals.
    assert!(
        worst > 0.5,
        "the Parquet values are the unrounded ones (worst {worst})"
    );
    assert!(text[0].iter().all(|d| d == "cw" || d == "ccw"));
    rows.len()
}

#[test]
fn the_parquet_trace_holds_the_csv_trace_s_values_unrounded() {
    let dir = scratch("trace-parquet", "values");
    let (csv_dir, pq_dir) = (dir.join("csv"), dir.join("parquet"));
    run(&csv_dir, TraceFormat::Csv);
    run(&pq_dir, TraceFormat::Parquet);
    let rows = assert_parquet_matches_csv(&csv_dir, &pq_dir);
    assert!(rows > 10_000, "a whole trace: {rows} rows");
    let (_, text, _) = parquet_columns(&pq_dir.join("trace.parquet"));
    assert!(text[0].iter().any(|d| d == "cw") && text[0].iter().any(|d| d == "ccw"));
    // The ISO circle is centred on its pivot: its centre is tiny, the runs two.
    assert_read_back_centred_by_an_independent_fit(&csv_dir, &pq_dir, 0.0);
}

/// The least-squares centre `(a, b)` of `dL = r0 + a cos θ + b sin θ` over rows of
/// `(θ deg, dL µm)`: the normal equations, solved here (not the ball bar's code).
fn fitted_centre(rows: &[(f64, f64)]) -> (f64, f64) {
    let mut ata = nalgebra::Matrix3::<f64>::zeros();
    let mut aty = nalgebra::Vector3::<f64>::zeros();
    for &(theta, dev) in rows {
        let t = theta.to_radians();
        let a = nalgebra::Vector3::new(1.0, t.cos(), t.sin());
        ata += a * a.transpose();
        aty += a * dev;
    }
    let x = ata.try_inverse().expect("a full revolution") * aty;
    (x[1], x[2])
}

/// `read_trace` of both folders gives each row's dL less its run's centre, the centre fitted
/// here from the Parquet trace's unrounded rows of that run: within 1e-6 µm for the
/// Parquet trace, and for the CSV one within half the CSV's last decimal of dL more (and
/// 1e-5 µm for θ's: `|a| + |b|` µm times 5e-5 deg); each centre at least `least_um`.
fn assert_read_back_centred_by_an_independent_fit(csv_dir: &Path, pq_dir: &Path, least_um: f64) {
    let (names, text, floats) = parquet_columns(&pq_dir.join("trace.parquet"));
    assert!(
        !names.iter().any(|n| n == "deviation_centred_um"),
        "{names:?}"
    );
    let float = |name: &str| {
        let c = names.iter().position(|n| n == name).unwrap();
        // `floats` leaves out direction (0) and line (2).
        &floats[c - 1 - usize::from(c > 2)]
    };
    let (theta, dev) = (float("theta_deg"), float("deviation_um"));
    // The rows' runs: stretches of one direction.
    let mut runs: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for (i, d) in text[0].iter().enumerate() {
        if runs.last().is_none_or(|r| &r.0 != d) {
            runs.push((d.clone(), Vec::new()));
        }
        runs.last_mut().unwrap().1.push((theta[i], dev[i]));
    }
    for (dir, tolerance) in [(pq_dir, 1e-6), (csv_dir, 0.5e-4 + 1e-5)] {
        let read = mtsim::report::trace::read_trace(dir).unwrap().unwrap();
        assert_eq!(read.runs.len(), runs.len(), "{}", dir.display());
        for (got, (direction, rows)) in read.runs.iter().zip(&runs) {
            assert_eq!(&got.direction, direction);
            let (a, b) = fitted_centre(rows);
            assert!(a.abs() + b.abs() >= least_um, "a centre to remove: {a} {b}");
            assert_eq!(got.deviation_centred_um.len(), rows.len());
            for (&c, &(theta, dev)) in got.deviation_centred_um.iter().zip(rows) {
                let t = theta.to_radians();
                let want = dev - (a * t.cos() + b * t.sin());
                assert!(
                    (c - want).abs() <= tolerance,
                    "{}: θ {theta} centred {c}, fitted {want}",
                    dir.display()
                );
            }
        }
    }
}

/// A long trace (eleven revolutions of the bundled cone file in one run, about 400,000 rows,
/// 80 MB of CSV) is written as it goes in both formats, the same rows in each, and read back
/// centred by an independently fitted centre.
#[test]
fn a_long_trace_comes_out_the_same_in_both_formats() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = scratch("trace-parquet", "spill");
    let program =
        std::fs::read_to_string(root.join("scenarios/programs/cone-15-10-yt25.nc")).unwrap();
    let mut text = String::new();
    let moves: Vec<&str> = program.lines().filter(|l| l.starts_with("G01")).collect();
    for l in program.lines().take_while(|l| !l.starts_with("G01")) {
        text += &format!("{l}\n");
    }
    for revolution in 0..11 {
        for m in &moves {
            // C a full turn further each revolution, so that the table keeps turning.
            let words: Vec<String> = m
                .split_whitespace()
                .map(|w| match w.strip_prefix('C') {
                    Some(v) => format!(
                        "C{:.4}",
                        v.parse::<f64>().unwrap() - 360.0 * revolution as f64
                    ),
                    None => w.to_string(),
                })
                .collect();
            text += &format!("{}\n", words.join(" "));
        }
    }
    text += "M30\n";
    std::fs::write(dir.join("long.nc"), text).unwrap();
    let scenario = format!(
        "machine = {:?}\n[program]\nfile = \"long.nc\"\n[program.cone]\nhalf_apex_deg = 15.0\n\
         inclination_deg = 10.0\ncenter_mm = [0.0, -25.0, 200.0]\nballbar_length_mm = 100.0\n",
        root.join("machines/trt-ac.toml").display().to_string()
    );
    std::fs::write(dir.join("long.toml"), scenario).unwrap();
    let mut scenario = Scenario::load(&dir.join("long.toml")).unwrap();
    let (csv_dir, pq_dir) = (dir.join("csv"), dir.join("parquet"));
    simulate(&scenario, &csv_dir, false, &|_| {}).unwrap();
    scenario.simulate.trace_format = TraceFormat::Parquet;
    simulate(&scenario, &pq_dir, false, &|_| {}).unwrap();
    let rows = assert_parquet_matches_csv(&csv_dir, &pq_dir);
    assert!(rows > 350_000, "{rows} rows");
    assert_read_back_centred_by_an_independent_fit(&csv_dir, &pq_dir, 1.0);
    assert!(std::fs::read_dir(&pq_dir).unwrap().all(|e| !e
        .unwrap()
        .file_name()
        .to_string_lossy()
        .ends_with(".tmp")));
}

#[test]
fn the_same_run_writes_the_same_parquet_bytes() {
    let dir = scratch("trace-parquet", "bytes");
    let (a, b) = (dir.join("a"), dir.join("b"));
    run(&a, TraceFormat::Parquet);
    run(&b, TraceFormat::Parquet);
    let read = |d: &PathBuf| std::fs::read(d.join("trace.parquet")).unwrap();
    assert!(
        read(&a) == read(&b),
        "trace.parquet differs between two runs"
    );
}

#[test]
fn a_run_in_one_format_removes_the_other_format_s_trace() {
    let dir = scratch("trace-parquet", "switch").join("out");
    run(&dir, TraceFormat::Csv);
    assert!(dir.join("trace.csv").exists());
    run(&dir, TraceFormat::Parquet);
    assert!(dir.join("trace.parquet").exists() && !dir.join("trace.csv").exists());
    run(&dir, TraceFormat::Csv);
    assert!(dir.join("trace.csv").exists() && !dir.join("trace.parquet").exists());
}

#[test]
fn the_report_reads_a_parquet_trace_as_it_reads_the_csv_one() {
    use mtsim::report::trace::read_trace;
    let dir = scratch("trace-parquet", "report");
    let (csv_dir, pq_dir) = (dir.join("csv"), dir.join("parquet"));
    run(&csv_dir, TraceFormat::Csv);
    run(&pq_dir, TraceFormat::Parquet);
    let from_csv = read_trace(&csv_dir).unwrap().unwrap();
    let from_pq = read_trace(&pq_dir).unwrap().unwrap();
    assert_eq!(from_csv.axes, from_pq.axes);
    assert_eq!(from_csv.runs.len(), 2, "ccw and cw");
    assert_eq!(from_csv.runs.len(), from_pq.runs.len());
    for (c, p) in from_csv.runs.iter().zip(&from_pq.runs) {
        assert_eq!(c.direction, p.direction);
        assert_eq!(c.theta_deg.len(), p.theta_deg.len());
        let close = |a: &[f64], b: &[f64], half_unit: f64| {
            a.iter()
                .zip(b)
                .all(|(x, y)| (x - y).abs() <= half_unit * (1.0 + 1e-6))
        };
        assert!(close(&c.theta_deg, &p.theta_deg, 0.5e-4));
        assert!(close(
            &c.deviation_centred_um,
            &p.deviation_centred_um,
            0.5e-4
        ));
        for k in 0..c.actual.len() {
            assert!(close(&c.actual[k], &p.actual[k], 0.5e-6));
            assert!(close(&c.following_error[k], &p.following_error[k], 0.5e-7));
        }
    }
    // And `mtsim report` makes the page from the Parquet folder alone.
    let out = mtsim_plain(&pq_dir, &["report", "."]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let page = std::fs::read_to_string(pq_dir.join("report.html")).unwrap();
    let csv_page = {
        let out = mtsim_plain(&csv_dir, &["report", "."]);
        assert!(out.status.success());
        std::fs::read_to_string(csv_dir.join("report.html")).unwrap()
    };
    assert_eq!(
        page.matches("<svg").count(),
        csv_page.matches("<svg").count()
    );
}

#[test]
fn an_unknown_trace_format_names_the_key_and_the_choices() {
    let dir = scratch("trace-parquet", "bad");
    let scenario = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/circle-iso230-4.toml"),
    )
    .unwrap()
    .replace(
        "../machines/",
        &format!("{}/machines/", env!("CARGO_MANIFEST_DIR")),
    );
    let path = dir.join("bad.toml");
    std::fs::write(
        &path,
        format!("{scenario}\n[simulate]\ntrace_format = \"xml\"\n"),
    )
    .unwrap();
    let out = mtsim_plain(&dir, &["simulate", "bad.toml", "-o", "out"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.toml:") && err.contains("`xml`"), "{err}");
    assert!(err.contains("csv") && err.contains("parquet"), "{err}");
    assert!(!dir.join("out").join("trace.csv").exists());
}

/// The file's layout, as docs/simulation.md gives it: row groups of 4,096 rows of one run
/// each (a run's last holds the rest), uncompressed, min/max statistics on `time_s` (the
/// first and last time of the group) and `line` only, the direction dictionary-encoded.
#[test]
fn the_parquet_trace_has_the_documented_layout() {
    use parquet::basic::{Compression, Encoding};
    use parquet::file::reader::{FileReader, SerializedFileReader};
    use parquet::file::statistics::Statistics;

    let dir = scratch("trace-parquet", "layout");
    run(&dir, TraceFormat::Parquet);
    let (names, text, floats) = parquet_columns(&dir.join("trace.parquet"));
    let time = &floats[0];
    let direction = &text[0];
    let file = File::open(dir.join("trace.parquet")).unwrap();
    let meta = SerializedFileReader::new(file).unwrap().metadata().clone();
    let groups = meta.row_groups();
    // docs/simulation.md: row groups of 4,096 rows.
    let full = 4_096;
    assert!(
        groups.len() >= 4,
        "{} rows fill more than one group per run",
        time.len()
    );
    let mut first_row = 0;
    for (k, g) in groups.iter().enumerate() {
        let rows = g.num_rows() as usize;
        // A group holds rows of one run, and is full unless the run ends with it.
        let run = &direction[first_row..first_row + rows];
        assert!(run.iter().all(|d| *d == run[0]), "group {k} holds one run");
        let run_ends = direction.get(first_row + rows).is_none_or(|d| *d != run[0]);
        assert!(
            rows == full || (rows < full && run_ends),
            "group {k}: {rows} rows"
        );
        for (c, column) in g.columns().iter().enumerate() {
            assert_eq!(column.compression(), Compression::UNCOMPRESSED);
            let stats = column.statistics();
            match names[c].as_str() {
                "time_s" => match stats {
                    Some(Statistics::Double(s)) => {
                        assert_eq!(*s.min_opt().unwrap(), time[first_row]);
                        assert_eq!(*s.max_opt().unwrap(), time[first_row + rows - 1]);
                    }
                    other => panic!("time_s statistics: {other:?}"),
                },
                "line" => assert!(stats.is_some(), "line has statistics"),
                name => assert!(stats.is_none(), "{name} has no statistics"),
            }
            if c == 0 {
                assert!(column.encodings().any(|e| e == Encoding::RLE_DICTIONARY));
            }
        }
        first_row += rows;
    }
}
