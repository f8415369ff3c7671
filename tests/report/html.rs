//! The HTML report: one self-contained page per run, and that page in a real browser.
//!
//! The browser test renders every bundled scenario's report in headless Chromium. It skips,
//! saying why, when Chromium is missing, and fails instead when the env var `CI` is set.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::{mtsim, scratch};

/// Runs `simulate --html --no-timing` on `scenario` into `dir` and returns the summary.
fn simulate_with_report(scenario: &str, dir: &Path) -> serde_json::Value {
    let out = mtsim(&[
        "simulate",
        scenario,
        "-o",
        dir.to_str().unwrap(),
        "--no-timing",
        "--html",
    ]);
    assert!(
        out.status.code() == Some(0) || out.status.code() == Some(1),
        "{scenario}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap()
}

/// The figures the page must show as text: (data-figure name, value with 2 decimals).
fn figures(summary: &serde_json::Value) -> Vec<(String, String)> {
    let b = &summary["ballbar"];
    let mut out = vec![
        ("G".to_string(), b["circular_deviation_um"].clone()),
        ("F-max".to_string(), b["radial_max_um"].clone()),
        ("F-min".to_string(), b["radial_min_um"].clone()),
        ("H".to_string(), b["hysteresis_um"].clone()),
    ];
    for r in b["runs"].as_array().unwrap() {
        let dir = r["direction"].as_str().unwrap().to_uppercase();
        out.push((format!("G-{dir}"), r["circular_deviation_um"].clone()));
    }
    out.into_iter()
        .filter_map(|(k, v)| v.as_f64().map(|x| (k, format!("{x:.2}"))))
        .collect()
}

/// The text of the element with `data-figure="name"` in `html`.
fn figure_text<'a>(html: &'a str, name: &str) -> Option<&'a str> {
    let key = format!("data-figure=\"{name}\">");
    let i = html.find(&key)? + key.len();
    let j = html[i..].find('<')? + i;
    Some(&html[i..j])
}

/// Every plot the page must hold for a run whose trace has `axes`.
fn expected_plots(axes: &[&str]) -> Vec<String> {
    let mut plots = vec!["polar".to_string(), "deviation".to_string()];
    for a in axes {
        for q in ["position", "velocity", "following-error"] {
            plots.push(format!("{a}-{q}"));
        }
    }
    plots
}

/// The axes of a trace, from its header (`X_act_mm`, `A_act_deg`, ...).
fn trace_axes(dir: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join("trace.csv")).unwrap();
    text.lines()
        .next()
        .unwrap()
        .split(',')
        .filter_map(|c| c.split_once("_act_").map(|(a, _)| a.to_string()))
        .collect()
}

#[test]
fn the_report_is_one_self_contained_page_with_every_section_and_figure() {
    let dir = scratch("report", "circle");
    let summary = simulate_with_report("scenarios/circle-iso230-4.toml", &dir);
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();

    // Self-contained: no script, no external resource.
    assert!(!html.contains("<script"), "no JavaScript");
    for external in ["src=\"http", "href=\"http", "@import", "url("] {
        assert!(!html.contains(external), "no network: {external}");
    }
    // ISO 230-4 test parameters.
    for key in [
        "Machine",
        "Test",
        "Radius",
        "Feed",
        "Direction",
        "Plane",
        "Position (centre)",
        "Start arc / overshoot arc",
        "Compensation",
        "Sample period",
        "Date",
        "mtsim version",
        "Scenario hash (XXH64)",
    ] {
        assert!(html.contains(&format!("<th>{key}</th>")), "parameter {key}");
    }
    // The scenario's own numbers, as the scenario file states them.
    let scenario = std::fs::read_to_string("scenarios/circle-iso230-4.toml").unwrap();
    assert!(scenario.contains("radius_mm = 50.0"), "{scenario}");
    assert!(html.contains("<td>50.000 mm</td>"), "radius row");
    assert!(html.contains("1 ms (trace: every 1 sample)"));
    // Every figure, as the summary states it, to 2 decimals; both directions.
    let figs = figures(&summary);
    assert!(figs.iter().any(|(k, _)| k == "H"), "two directions: H");
    for (name, value) in &figs {
        assert_eq!(
            figure_text(&html, name).map(str::trim),
            Some(value.as_str()),
            "{name}"
        );
    }
    // Every plot, with µm (never "um") on its deviation axis.
    let axes = trace_axes(&dir);
    let axes: Vec<&str> = axes.iter().map(String::as_str).collect();
    assert_eq!(axes, ["X", "Y", "Z"]);
    for plot in expected_plots(&axes) {
        assert!(
            html.contains(&format!("data-plot=\"{plot}\"")),
            "plot {plot}"
        );
    }
    assert!(html.contains("deviation (µm)") && !html.contains("(um)"));
    for section in ["Marks", "Diagnoses", "Limits and collisions", "Files"] {
        assert!(
            html.contains(&format!("\">{section}</h2>")),
            "section {section}"
        );
    }
    for file in [
        "trace.csv",
        "summary.json",
        "ballbar.svg",
        "check.json",
        "test.json",
    ] {
        assert!(
            html.contains(&format!("<a href=\"{file}\">")),
            "link {file}"
        );
    }

    // Determinism: the same run gives the same page; `report` on the folder rewrites it.
    let again = scratch("report", "circle-again");
    simulate_with_report("scenarios/circle-iso230-4.toml", &again);
    let html_again = std::fs::read_to_string(again.join("report.html")).unwrap();
    assert_eq!(
        html.replace(again.to_str().unwrap(), ""),
        html_again.replace(again.to_str().unwrap(), ""),
        "byte-identical reports"
    );
    let out = mtsim(&["report", dir.to_str().unwrap(), "--date", "2026-01-31"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let dated = std::fs::read_to_string(dir.join("report.html")).unwrap();
    assert!(dated.contains("<th>Date</th><td>2026-01-31</td>"));
    assert!(!dir.join("report.html.tmp").exists());
}

#[test]
fn report_refuses_a_folder_without_a_run_and_a_bad_date() {
    let dir = scratch("report", "empty");
    let out = mtsim(&["report", dir.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("summary.json"));
    let out = mtsim(&["report", dir.to_str().unwrap(), "--date", "23.11.2026"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("YYYY-MM-DD"));
}

#[test]
fn check_html_writes_the_limits_page() {
    let dir = scratch("report", "check-html");
    let page = dir.join("check.html");
    let out = mtsim(&[
        "check",
        "scenarios/cone-15-10.toml",
        "--html",
        page.to_str().unwrap(),
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(html.contains("Limits and collisions") && html.contains("<td>X</td>"));
    assert!(
        html.contains("Expected, not a collision"),
        "cutting explained"
    );
}

/// `check.json` reads back into the `CheckReport` that wrote it: each axis's usage takes
/// its axis from its key, and writing it again gives the same JSON.
#[test]
fn check_json_reads_back_into_the_check_report() {
    let dir = scratch("report", "check-json");
    let out = mtsim(&["check", "scenarios/cone-15-10.toml", "--json"]);
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8(out.stdout).unwrap();
    let report: mtsim::check::CheckReport = serde_json::from_str(&text).unwrap();
    assert_eq!(report.axes.len(), 5);
    for (name, usage) in &report.axes {
        assert_eq!(&usage.axis.to_string(), name);
    }
    assert!(!report.engagement.is_empty(), "the cone is cut");
    let again = serde_json::to_string_pretty(&report).unwrap();
    assert_eq!(format!("{again}\n"), text);
    let _ = std::fs::remove_dir_all(dir);
}

/// The velocity the report plots is the central difference of the actual position: exact
/// for a parabola inside the run, one-sided at its ends.
#[test]
fn the_plotted_velocity_is_the_central_difference_of_the_position() {
    use mtsim::report::trace::TraceRun;
    // p = t² mm at uneven times: (p(t+) - p(t-)) / (t+ - t-) = t+ + t-.
    let time_s = vec![0.0, 0.1, 0.3, 0.4, 0.7];
    let run = TraceRun {
        actual: vec![time_s.iter().map(|t| t * t).collect()],
        time_s: time_s.clone(),
        ..TraceRun::default()
    };
    let v = run.velocity_per_min(0);
    let want = [0.1, 0.3, 0.5, 1.0, 1.1].map(|x: f64| 60.0 * x);
    for (got, want) in v.iter().zip(want) {
        assert!((got - want).abs() < 1e-9, "{v:?}");
    }
}

// ---- the browser test --------------------------------------------------------------

/// The Chromium binary, if installed.
fn chromium() -> Option<PathBuf> {
    ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .flat_map(|name| {
            std::env::var_os("PATH")
                .map(|p| std::env::split_paths(&p).collect::<Vec<_>>())
                .unwrap_or_default()
                .into_iter()
                .map(move |d| d.join(name))
        })
        .find(|p| p.is_file())
}

/// Decodes an 8-bit RGB or RGBA PNG to RGBA pixels (width, height, pixels).
fn decode_png(bytes: &[u8]) -> (usize, usize, Vec<[u8; 4]>) {
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "a PNG file");
    let (mut i, mut idat) = (8, Vec::new());
    let (mut width, mut height, mut channels) = (0, 0, 0);
    while i + 8 <= bytes.len() {
        let len = u32::from_be_bytes(bytes[i..i + 4].try_into().unwrap()) as usize;
        let kind = &bytes[i + 4..i + 8];
        let data = &bytes[i + 8..i + 8 + len];
        match kind {
            b"IHDR" => {
                width = u32::from_be_bytes(data[0..4].try_into().unwrap()) as usize;
                height = u32::from_be_bytes(data[4..8].try_into().unwrap()) as usize;
                assert_eq!(data[8], 8, "8-bit");
                channels = match data[9] {
                    2 => 3,
                    6 => 4,
                    c => panic!("colour type {c}"),
                };
                assert_eq!(data[12], 0, "not interlaced");
            }
            b"IDAT" => idat.extend_from_slice(data),
            _ => {}
        }
        i += 12 + len;
    }
    let raw = miniz_oxide::inflate::decompress_to_vec_zlib(&idat).expect("zlib data");
    let stride = width * channels;
    let mut img = vec![0u8; stride * height];
    for y in 0..height {
        let line = &raw[y * (stride + 1)..(y + 1) * (stride + 1)];
        let (filter, src) = (line[0], &line[1..]);
        for x in 0..stride {
            let a = if x >= channels {
                img[y * stride + x - channels]
            } else {
                0
            } as i16;
            let b = if y > 0 { img[(y - 1) * stride + x] } else { 0 } as i16;
            let c = if x >= channels && y > 0 {
                img[(y - 1) * stride + x - channels]
            } else {
                0
            } as i16;
            let predictor = match filter {
                0 => 0,
                1 => a,
                2 => b,
                3 => (a + b) / 2,
                4 => {
                    let p = a + b - c;
                    let (pa, pb, pc) = ((p - a).abs(), (p - b).abs(), (p - c).abs());
                    if pa <= pb && pa <= pc {
                        a
                    } else if pb <= pc {
                        b
                    } else {
                        c
                    }
                }
                f => panic!("filter {f}"),
            };
            img[y * stride + x] = (src[x] as i16 + predictor) as u8;
        }
    }
    let pixels = img
        .chunks(channels)
        .map(|p| [p[0], p[1], p[2], if channels == 4 { p[3] } else { 255 }])
        .collect();
    (width, height, pixels)
}

/// Measures every plot after layout and writes the sizes into the DOM, for `--dump-dom`.
/// (Only the test copy of the page has it: the report itself needs no script.)
const PROBE: &str = "<script>var out=[];document.querySelectorAll('svg.plot').forEach(function(s){\
var r=s.getBoundingClientRect();out.push(s.getAttribute('data-plot')+' '+Math.round(r.width)+' '+Math.round(r.height));});\
var p=document.createElement('pre');p.id='mtsim-sizes';p.textContent=out.join('\\n');document.body.appendChild(p);</script>";

/// The browser, or None after saying that `test` is skipped; with the env var `CI` set a
/// missing browser fails the test instead.
pub(crate) fn chromium_or_skip(test: &str) -> Option<PathBuf> {
    let browser = chromium();
    if browser.is_none() {
        if std::env::var_os("CI").is_some() {
            panic!("chromium is missing and CI is set: install it (apt-get install chromium)");
        }
        eprintln!("SKIPPED {test}: chromium not found on PATH");
    }
    browser
}

/// Renders `page` headless: (DOM after load, screenshot PNG bytes).
pub(crate) fn render(browser: &Path, page: &Path, work: &Path) -> (String, Vec<u8>) {
    let shot = work.join("shot.png");
    let mut child = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-extensions",
            "--no-first-run",
            "--hide-scrollbars",
            "--window-size=1280,2400",
        ])
        .arg(format!(
            "--user-data-dir={}",
            work.join("profile").display()
        ))
        .arg(format!("--screenshot={}", shot.display()))
        .arg("--dump-dom")
        .arg(format!("file://{}", page.display()))
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("chromium starts");
    let mut stdout = child.stdout.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        std::io::Read::read_to_string(&mut stdout, &mut s).unwrap();
        s
    });
    let started = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        if started.elapsed() > Duration::from_secs(90) {
            let _ = child.kill();
            panic!(
                "chromium did not finish rendering {} in 90 s",
                page.display()
            );
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let dom = reader.join().unwrap();
    let png =
        std::fs::read(&shot).unwrap_or_else(|e| panic!("no screenshot of {}: {e}", page.display()));
    (dom, png)
}

/// Asserts that the screenshot `png` of `what` has ink on more than 1 % of its pixels;
/// returns (width, height, pixels) for further checks.
fn assert_inked(png: &[u8], what: &str) -> (usize, usize, Vec<[u8; 4]>) {
    let (w, h, pixels) = decode_png(png);
    let inked = pixels
        .iter()
        .filter(|p| p[0] < 200 || p[1] < 200 || p[2] < 200)
        .count();
    assert!(
        inked as f64 > 0.01 * (w * h) as f64,
        "{what}: a blank page ({inked} inked pixels)"
    );
    (w, h, pixels)
}

/// The laid-out size, px, of the plot `plot` as the probe wrote it into `dom`; None when
/// the page has no such plot.
fn plot_size(dom: &str, plot: &str) -> Option<[f64; 2]> {
    let start = dom.find("<pre id=\"mtsim-sizes\">").expect("the probe ran") + 22;
    let sizes = &dom[start..start + dom[start..].find("</pre>").unwrap()];
    let line = sizes.lines().find(|l| l.split(' ').next() == Some(plot))?;
    let dims: Vec<f64> = line
        .split(' ')
        .skip(1)
        .map(|v| v.parse().unwrap())
        .collect();
    Some([dims[0], dims[1]])
}

#[test]
fn every_bundled_scenario_report_renders_in_headless_chromium() {
    let Some(browser) =
        chromium_or_skip("every_bundled_scenario_report_renders_in_headless_chromium")
    else {
        return;
    };
    let mut scenarios: Vec<PathBuf> = std::fs::read_dir("scenarios")
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    scenarios.sort();
    assert!(scenarios.len() >= 6, "{scenarios:?}");
    for scenario in &scenarios {
        let name = scenario.file_stem().unwrap().to_string_lossy().into_owned();
        let dir = scratch("report-browser", &name);
        let summary = simulate_with_report(scenario.to_str().unwrap(), &dir.join("run"));
        let html = std::fs::read_to_string(dir.join("run/report.html")).unwrap();
        let page = dir.join("run/probe.html");
        std::fs::write(&page, html.replace("</body>", &format!("{PROBE}</body>"))).unwrap();
        let (dom, png) = render(&browser, &page, &dir);

        // A screenshot with something on it: many colours, and far from all white.
        let (w, h, pixels) = assert_inked(&png, &name);
        assert!(w >= 1000 && h >= 1000, "{name}: {w} x {h}");
        let mut colours: Vec<[u8; 4]> = pixels;
        colours.sort_unstable();
        colours.dedup();
        assert!(colours.len() > 16, "{name}: {} colours", colours.len());

        // Every plot laid out with a non-zero size.
        let axes = trace_axes(&dir.join("run"));
        let axes: Vec<&str> = axes.iter().map(String::as_str).collect();
        assert!(axes.len() >= 3, "{name}: axes {axes:?}");
        for plot in expected_plots(&axes) {
            let dims = plot_size(&dom, &plot)
                .unwrap_or_else(|| panic!("{name}: plot {plot} not in the page"));
            assert!(
                dims[0] > 100.0 && dims[1] > 50.0,
                "{name}: {plot} is {dims:?} px"
            );
        }
        // The summary first: G, B of each axis and the ranked shares, as summary.json has them.
        let g = summary["ballbar"]["circular_deviation_um"]
            .as_f64()
            .unwrap();
        assert!(
            dom.find("id=\"summary\"") < dom.find("id=\"test\""),
            "{name}"
        );
        assert_eq!(
            figure_text(&dom, "G").map(str::trim),
            text_after(&dom, "data-summary=\"G\""),
            "{name}: {g}"
        );
        for r in summary["reversal_b"].as_array().unwrap() {
            let axis = r["axis"].as_str().unwrap();
            let shown = text_after(&dom, &format!("data-b=\"{axis}\""))
                .unwrap_or_else(|| panic!("{name}: no B of {axis}"));
            match r["b_um"].as_f64() {
                Some(b) => assert_eq!(shown, format!("{b:.2}"), "{name}: B of {axis}"),
                None => assert!(shown.starts_with('–'), "{name}: B of {axis}: {shown}"),
            }
        }
        // The error budget: its sentence, then every row ranked by share, then the interplay.
        let rows = budget_rows(&dom);
        let budget = summary["error_budget"]["rows"].as_array().unwrap();
        assert_eq!(rows.len(), budget.len() + 1, "{name}: {rows:?}");
        assert!(!budget.is_empty(), "{name}: no budget");
        let (ranked, interplay) = rows.split_at(rows.len() - 1);
        assert!(
            ranked.windows(2).all(|w| w[0].1 >= w[1].1),
            "{name}: ranked: {rows:?}"
        );
        assert!(
            interplay[0].0.starts_with("interaction:"),
            "{name}: {rows:?}"
        );
        assert!(
            text_after(&dom, "data-summary=\"headline\"").is_some_and(|t| t.contains("% of G")),
            "{name}: no sentence on top"
        );
        // Every figure as text, as the summary states it.
        for (figure, value) in figures(&summary) {
            assert_eq!(
                figure_text(&dom, &figure).map(str::trim),
                Some(value.as_str()),
                "{name}: figure {figure}"
            );
        }
    }
}

// ---- the plots of the studies -------------------------------------------------------

/// (x, y, text) of every `<text>` element of an SVG plotters wrote.
fn svg_texts(svg: &str) -> Vec<(f64, f64, String)> {
    let mut out = Vec::new();
    let mut rest = svg;
    while let Some(i) = rest.find("<text ") {
        rest = &rest[i..];
        let head_end = rest.find('>').unwrap();
        let head = &rest[..head_end];
        let attr = |name: &str| -> f64 {
            let key = format!(" {name}=\"");
            let a = head.find(&key).unwrap() + key.len();
            head[a..a + head[a..].find('"').unwrap()].parse().unwrap()
        };
        let end = rest.find("</text>").unwrap();
        out.push((
            attr("x"),
            attr("y"),
            rest[head_end + 1..end].trim().to_string(),
        ));
        rest = &rest[end..];
    }
    out
}

#[test]
fn the_sweep_plot_names_its_axis_in_words_and_keeps_the_legend_off_the_points() {
    let dir = scratch("report", "sweep");
    let out = mtsim(&[
        "sweep",
        "scenarios/cone-15-10.toml",
        "--vary",
        "center_y",
        "--from",
        "-40",
        "--to",
        "0",
        "--step",
        "2",
        "-o",
        dir.to_str().unwrap(),
        "--html",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let svg = std::fs::read_to_string(dir.join("sweep-center_y.svg")).unwrap();
    // `--html`: the study page holds the plot inline and links the files.
    let page = std::fs::read_to_string(dir.join("report.html")).unwrap();
    assert!(page.contains("data-plot=\"sweep-center_y\"") && !page.contains("<script"));
    assert!(page.contains("<a href=\"sweep-center_y.csv\">"));
    let texts = svg_texts(&svg);
    let has = |t: &str| texts.iter().any(|(_, _, s)| s == t);
    assert!(has("cone centre Y, table frame (mm)"), "x axis in words");
    assert!(has("reversal angle θ (deg)"));
    assert!(!texts.iter().any(|(_, _, s)| s == "center_y (mm)"));
    // The legend entries sit in the strip above the plot; every point lies below it.
    let legend_y: Vec<f64> = texts
        .iter()
        .filter(|(_, _, s)| s.ends_with(" reversal") || s.contains("coincide at"))
        .map(|t| t.1)
        .collect();
    assert_eq!(legend_y.len(), 4, "X, Y, Z and the coincidence: {texts:?}");
    let strip = legend_y.iter().fold(0.0f64, |m, y| m.max(*y)) + 8.0;
    let mut points = 0;
    for c in svg.split("<circle ").skip(1) {
        let cy: f64 = c
            .split("cy=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        assert!(
            cy > strip,
            "a point at y {cy} under the legend (strip to {strip})"
        );
        points += 1;
    }
    assert!(points > 40, "{points} points");
}

#[test]
fn the_placement_map_scales_margins_linearly_and_refuses_a_cone_base_off_the_table() {
    let dir = scratch("report", "placement");
    let out = mtsim(&[
        "sweep",
        "scenarios/cone-15-10.toml",
        "--feasibility",
        "--vary",
        "center_x,center_y",
        "--from",
        "-100",
        "--to",
        "100",
        "--step",
        "50",
        "-o",
        dir.to_str().unwrap(),
    ]);
    assert!(out.status.code() == Some(0) || out.status.code() == Some(1));
    let svg = std::fs::read_to_string(dir.join("placement.svg")).unwrap();
    let csv = std::fs::read_to_string(dir.join("placement.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let (m, f) = (
        header.iter().position(|h| h.starts_with("margin")).unwrap(),
        header.iter().position(|h| *h == "fits").unwrap(),
    );
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let l = header.iter().position(|h| *h == "limiting").unwrap();
    // The cone base (the frustum's, radius (L − R)/cos α with L 100 mm, α 15°, the cutter
    // radius R 10 mm, tilted by β 10°) must stay on the table top (radius 200 mm): a cell
    // whose base reaches past the edge does not fit, and says so; the margin of a cell that
    // fits is at most its distance to the edge.
    let rho = (100.0 - 10.0) / 15f64.to_radians().cos();
    let beta = 10f64.to_radians();
    let mut overhanging = 0;
    for c in &rows {
        let (x, y): (f64, f64) = (c[0].parse().unwrap(), c[1].parse().unwrap());
        let farthest = (0..3600)
            .map(|k| {
                let phi = (k as f64 * 0.1).to_radians();
                (x + rho * beta.cos() * phi.cos()).hypot(y + rho * phi.sin())
            })
            .fold(0.0, f64::max);
        let margin: f64 = c[m].parse().unwrap();
        if farthest > 200.0 + 0.01 {
            overhanging += 1;
            assert_eq!(
                c[f],
                "false",
                "({x}, {y}) overhangs by {}",
                farthest - 200.0
            );
            assert!(c[l].contains("over the table edge"), "{c:?}");
        } else {
            assert!(margin <= 200.0 - farthest + 0.002, "{c:?}: {farthest}");
        }
    }
    assert!(overhanging >= 4, "{overhanging}");
    let at = |x: &str, y: &str| rows.iter().find(|c| c[0] == x && c[1] == y).unwrap();
    assert_eq!(at("0", "-100")[f], "true");
    assert!((at("0", "-100")[m].parse::<f64>().unwrap() - (200.0 - 100.0 - rho)).abs() < 0.002);
    assert_eq!(at("-50", "-100")[f], "false");
    // A linear colour scale in mm: the legend's five values are equally spaced from the
    // smallest to the largest margin of the cells that fit.
    let fit: Vec<f64> = rows
        .iter()
        .filter(|c| c[f] == "true")
        .map(|c| c[m].parse().unwrap())
        .collect();
    let (lo, hi) = fit
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(*v), b.max(*v))
        });
    assert!(hi > lo, "{fit:?}");
    let legend: Vec<f64> = svg_texts(&svg)
        .into_iter()
        .filter(|t| t.0 > 760.0)
        .filter_map(|t| t.2.parse().ok())
        .collect();
    assert_eq!(legend.len(), 5, "{legend:?}");
    for (k, v) in legend.iter().enumerate() {
        let want = hi - (hi - lo) * k as f64 / 4.0;
        assert!((v - want).abs() < 0.006, "{legend:?} against {lo}..{hi}");
    }
    assert!(svg.contains("(linear scale)"));
    assert!(svg.contains("table edge (radius 200 mm)"));
    let texts = svg_texts(&svg);
    assert!(
        texts.iter().any(|t| t.2 == "scenario"),
        "the scenario's position"
    );
    assert!(texts
        .iter()
        .any(|t| t.2 == "cone centre X, table frame (mm)"));
    // The table edge: a polyline of many points (a circle of the table radius).
    assert!(
        svg.split("<polyline").any(|p| p
            .split("points=\"")
            .nth(1)
            .is_some_and(|pts| pts.split(' ').count() > 60)),
        "no table outline"
    );
}

/// `fit` writes fit.html beside fit.svg: one self-contained page with the traces, the plot
/// (each panel naming its scenario, in µm), the parameters with their uncertainty, what
/// cannot be separated and the next test; it renders in headless Chromium.
#[test]
fn the_fit_page_renders_in_headless_chromium() {
    let dir = scratch("report-browser", "fit");
    let mut args = vec!["fit".to_string()];
    for name in ["cone-15-10", "cone-45-30"] {
        let run = dir.join(name);
        let sim = mtsim(&[
            "simulate",
            &format!("scenarios/{name}.toml"),
            "-o",
            run.to_str().unwrap(),
            "--no-timing",
        ]);
        assert!(sim.status.code() == Some(0) || sim.status.code() == Some(1));
        args.extend([
            format!("scenarios/{name}.toml"),
            "--measured".into(),
            run.join("trace.csv").display().to_string(),
        ]);
    }
    let out_dir = dir.join("fit");
    args.extend(["-o".into(), out_dir.display().to_string()]);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let out = mtsim(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let html = std::fs::read_to_string(out_dir.join("fit.html")).unwrap();
    let svg = std::fs::read_to_string(out_dir.join("fit.svg")).unwrap();
    for name in ["cone-15-10.toml", "cone-45-30.toml", "µm"] {
        assert!(svg.contains(name), "fit.svg lacks {name}");
    }
    for section in [
        "id=\"traces\"",
        "id=\"plots\"",
        "id=\"parameters\"",
        "id=\"inseparable\"",
        "id=\"next\"",
        "data-plot=\"fit\"",
        "EY0A",
        "standard error",
    ] {
        assert!(html.contains(section), "fit.html lacks {section}");
    }
    assert!(
        !html.contains("<script") && !html.contains("src=\"http") && !html.contains("href=\"http"),
        "not self-contained"
    );

    let Some(browser) =
        chromium_or_skip("the_fit_page_renders_in_headless_chromium (browser part)")
    else {
        return;
    };
    let page = out_dir.join("probe.html");
    std::fs::write(&page, html.replace("</body>", &format!("{PROBE}</body>"))).unwrap();
    let (dom, png) = render(&browser, &page, &dir);
    assert_inked(&png, "fit.html");
    let dims = plot_size(&dom, "fit").expect("the fit plot in the page");
    assert!(dims[0] > 500.0 && dims[1] > 300.0, "fit plot {dims:?} px");
    assert!(dom.contains("What these tests cannot separate"));
}

// ---- the summary a metrologist reads first ------------------------------------------

/// The three-axis machine with a 10 µm backlash on X only and no Coulomb friction (so no
/// axis has an elastic lost motion): the circle scenario on it, run into `dir/run`.
fn backlash_on_x_only(dir: &Path) -> serde_json::Value {
    let machine = std::fs::read_to_string(common::machine("vmc-3axis"))
        .unwrap()
        .replace("coulomb_n = 150.0", "coulomb_n = 0.0")
        .replacen(
            "[axes.X.friction]",
            "[axes.X.drive]\nbacklash_mm = 0.010\n\n[axes.X.friction]",
            1,
        );
    std::fs::write(dir.join("machine.toml"), machine).unwrap();
    let scenario = std::fs::read_to_string("scenarios/circle-iso230-4.toml")
        .unwrap()
        .replace("../machines/vmc-3axis.toml", "machine.toml");
    std::fs::write(dir.join("scenario.toml"), scenario).unwrap();
    simulate_with_report(
        dir.join("scenario.toml").to_str().unwrap(),
        &dir.join("run"),
    )
}

/// The text of the first element after `key` (an attribute such as `data-b="X"`).
fn text_after<'a>(html: &'a str, key: &str) -> Option<&'a str> {
    let i = html.find(key)?;
    let start = html[i..].find('>')? + i + 1;
    let end = html[start..].find('<')? + start;
    Some(html[start..end].trim())
}

/// Every `data-budget` row of the page: (mechanism:axis, share %), in page order.
fn budget_rows(html: &str) -> Vec<(String, f64)> {
    html.split("<tr data-budget=\"")
        .skip(1)
        .map(|row| {
            let key = row[..row.find('"').unwrap()].to_string();
            let share = text_after(row, "class=\"share\"").unwrap().parse().unwrap();
            (key, share)
        })
        .collect()
}

/// The numbers among the `<text>` elements of the plot `name` in `html`.
fn plot_numbers(html: &str, name: &str) -> Vec<String> {
    let i = html
        .find(&format!("data-plot=\"{name}\""))
        .unwrap_or_else(|| panic!("no plot {name}"));
    let svg = &html[i..i + html[i..].find("</svg>").unwrap()];
    svg.split("<text")
        .skip(1)
        .filter_map(|t| {
            let s = &t[t.find('>')? + 1..];
            let s = s[..s.find('<')?].trim();
            s.parse::<f64>().ok().map(|_| s.to_string())
        })
        .collect()
}

/// Backlash on X only: B of X is the gap (the closed-form step of a semi-closed loop at
/// its reversal, where the bar lies along X), B of Y is 0; only X gets backlash advice
/// and a backlash share; the marks are listed by their peak; the flat Z position shows one
/// value.
#[test]
fn backlash_on_x_only_gives_b_and_advice_for_x_only() {
    let dir = scratch("report", "backlash-x");
    let summary = backlash_on_x_only(&dir);
    let b = |axis: &str| {
        summary["reversal_b"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["axis"] == axis)
            .unwrap()["b_um"]
            .as_f64()
    };
    let (bx, by) = (b("X").unwrap(), b("Y").unwrap());
    assert!((bx - 10.0).abs() < 0.5, "B of X {bx} µm, gap 10 µm");
    assert!(by.abs() < 0.2, "B of Y {by} µm, no lost motion");
    assert_eq!(b("Z"), None, "the bar does not see Z on an XY circle");
    let budget = &summary["error_budget"];
    let rows = budget["rows"].as_array().unwrap();
    let row = |mechanism: &str, axis: &str| {
        rows.iter()
            .find(|c| c["axis"] == axis && c["mechanism"] == mechanism)
            .map(|c| (c["pv_um"].as_f64().unwrap(), c["share"].as_f64().unwrap()))
    };
    // X's backlash row: the gap's step, and most of G.
    let (pv, share) = row("backlash", "X").unwrap();
    assert!((pv - 10.0).abs() < 0.5, "{budget}");
    assert!(share > 0.5, "{budget}");
    // No lost motion on Y, no friction anywhere: no such rows.
    assert_eq!(row("backlash", "Y"), None, "{budget}");
    assert!(
        !rows.iter().any(|c| c["mechanism"] == "friction"),
        "{budget}"
    );
    // Equal loops: what each servo does differently from the other is small against the step.
    for axis in ["X", "Y"] {
        assert!(row("servo", axis).unwrap().0 < 1.0, "{budget}");
    }
    let sum: f64 = rows
        .iter()
        .map(|c| c["share"].as_f64().unwrap())
        .sum::<f64>()
        + budget["interaction_share"].as_f64().unwrap();
    assert!((sum - 1.0).abs() < 1e-9, "{sum}");

    let html = std::fs::read_to_string(dir.join("run/report.html")).unwrap();
    let diagnoses = &html[html.find("<ul class=\"diagnoses\">").unwrap()..];
    let diagnoses = &diagnoses[..diagnoses.find("</ul>").unwrap()];
    let advice: Vec<&str> = diagnoses
        .lines()
        .filter(|l| l.contains("backlash compensation on"))
        .collect();
    assert_eq!(advice.len(), 1, "{diagnoses}");
    assert!(advice[0].contains("Steps at X reversals"), "{}", advice[0]);
    assert!(!diagnoses.contains("compensation on Y"), "{diagnoses}");
    // One line per axis and mechanism: the four X steps are one line.
    assert_eq!(diagnoses.matches("Steps at X reversals").count(), 1);

    // Marks by their peak angle, as summary.json holds it.
    for (i, e) in summary["ballbar"]["spikes"]
        .as_array()
        .unwrap()
        .iter()
        .enumerate()
    {
        let row = format!("<tr data-mark=\"{}\">", i + 1);
        let row = &html[html.find(&row).unwrap()..];
        let peak: f64 = text_after(row, "class=\"peak\"").unwrap().parse().unwrap();
        assert!((peak - e["peak_deg"].as_f64().unwrap()).abs() < 0.006);
    }
    // The Z position stays within 10 nm: one labelled value besides the θ ticks.
    let x_ticks = ["0", "100", "200", "300"];
    let z = plot_numbers(&html, "Z-position");
    assert_eq!(z.len() - x_ticks.len(), 1, "{z:?}");
    // X's position is not flat: its ticks are many.
    assert!(plot_numbers(&html, "X-position").len() > x_ticks.len() + 3);
}

/// The same page in headless Chromium: the DOM holds the summary, B of each axis and the
/// ranked shares, with X's B at the gap and no backlash share for Y.
#[test]
fn the_summary_b_and_ranked_shares_render_in_headless_chromium() {
    let Some(browser) =
        chromium_or_skip("the_summary_b_and_ranked_shares_render_in_headless_chromium")
    else {
        return;
    };
    let dir = scratch("report-browser", "backlash-x");
    let summary = backlash_on_x_only(&dir);
    let (dom, _) = render(&browser, &dir.join("run/report.html"), &dir);
    let g = summary["ballbar"]["circular_deviation_um"]
        .as_f64()
        .unwrap();
    assert_eq!(
        text_after(&dom, "data-summary=\"G\""),
        Some(format!("{g:.2}").as_str())
    );
    let bx: f64 = text_after(&dom, "data-b=\"X\"").unwrap().parse().unwrap();
    let by: f64 = text_after(&dom, "data-b=\"Y\"").unwrap().parse().unwrap();
    assert!((bx - 10.0).abs() < 0.5, "B of X {bx}");
    assert!(by.abs() < 0.2, "B of Y {by}");
    assert!(text_after(&dom, "data-b=\"Z\"").unwrap().starts_with('–'));
    let rows = budget_rows(&dom);
    assert_eq!(rows[0].0, "backlash:X", "{rows:?}");
    assert!(rows[0].1 > 50.0, "{rows:?}");
    let ranked = &rows[..rows.len() - 1];
    assert!(
        ranked.windows(2).all(|w| w[0].1 >= w[1].1),
        "ranked: {rows:?}"
    );
    assert!(!rows.iter().any(|r| r.0 == "backlash:Y"), "{rows:?}");
}

/// The Done-when of a study: its page renders in headless Chromium with its plot laid out,
/// its title and one row per point, each row's G the figure rows.csv holds.
#[test]
fn a_study_page_renders_in_headless_chromium_with_its_plot_and_rows() {
    let Some(browser) =
        chromium_or_skip("a_study_page_renders_in_headless_chromium_with_its_plot_and_rows")
    else {
        return;
    };
    let dir = scratch("study-browser", "backlash-x");
    let out = dir.join("study");
    let run = mtsim(&[
        "study",
        "scenarios/studies/backlash-x-circle.toml",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let html = std::fs::read_to_string(out.join("study.html")).unwrap();
    let page = out.join("probe.html");
    std::fs::write(&page, html.replace("</body>", &format!("{PROBE}</body>"))).unwrap();
    let (dom, png) = render(&browser, &page, &dir);

    assert_inked(&png, "study.html");
    assert!(dom.contains("mtsim study: grid 5 points"), "title missing");
    let dims = plot_size(&dom, "study-response").expect("the response plot in the page");
    assert!(
        dims[0] > 100.0 && dims[1] > 50.0,
        "response plot {dims:?} px"
    );
    // One row per point: each point's G from rows.csv, as the page prints it (4 decimals).
    let csv = std::fs::read_to_string(out.join("rows.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let g_col = header.iter().position(|c| *c == "G_um").unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 5);
    for row in rows {
        let g: f64 = row.split(',').nth(g_col).unwrap().parse().unwrap();
        let shown = format!("{g:.4}");
        assert!(
            dom.contains(&shown),
            "G {shown} um of a row is not in the page"
        );
    }
}

/// test.json names the machine file a scenario's `[machine_overrides]` change, not the
/// scenario (which it names beside it), and its hash changes with the machine file.
#[test]
fn test_json_names_the_machine_file_under_machine_overrides() {
    let dir = scratch("report", "overrides");
    let machine = Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/trt-ac.toml");
    std::fs::copy(&machine, dir.join("m.toml")).unwrap();
    std::fs::write(
        dir.join("s.toml"),
        format!(
            "machine = \"m.toml\"\n{}\n[machine_overrides.axes.X.drive]\nbacklash_mm = 0.003\n",
            common::CONE_15_10
        ),
    )
    .unwrap();
    let hash = |dir: &Path| -> (String, String) {
        simulate_with_report(dir.join("s.toml").to_str().unwrap(), &dir.join("out"));
        let t: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.join("out/test.json")).unwrap()).unwrap();
        (
            t["machine_file"].as_str().unwrap().to_string(),
            t["scenario_hash"].as_str().unwrap().to_string(),
        )
    };
    let (file, before) = hash(&dir);
    assert!(file.ends_with("m.toml"), "{file}");
    let mut text = std::fs::read_to_string(dir.join("m.toml")).unwrap();
    text.push_str("\n# an edit of the machine file\n");
    std::fs::write(dir.join("m.toml"), text).unwrap();
    let (_, after) = hash(&dir);
    assert_ne!(before, after, "the scenario hash reads the machine file");
}

/// Beside the machine's name the page gives its chain's geometry: each axis's line as the
/// machine file writes it (here the head-table machine's nutating B at 45° through
/// (0, 0, 150) mm and its C table), and the gauge point.
#[test]
fn the_report_shows_the_chain_s_axis_lines_and_gauge_point() {
    let dir = scratch("report", "chain-geometry");
    let scenario = common::write_scenario(
        &dir,
        &common::machine("head-table-b45-c"),
        "[program.circle]\nplane = \"XY\"\nradius_mm = 50.0\nfeed_mm_min = 1000.0\n\
         center_mm = [0.0, 0.0, 100.0]\n[check]\ncollisions = false\n",
    );
    let out = dir.join("out");
    simulate_with_report(scenario.to_str().unwrap(), &out);
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    // From the machine file: B along (0, 0.7071068, 0.7071068) through (0, 0, 150), C along Z
    // through the origin, gauge point at the origin with the tool along +Z.
    // The machine file's seven digits, not 1/√2.
    #[allow(clippy::approx_constant)]
    let b = (0.7071068f64 / (2.0f64 * 0.7071068 * 0.7071068).sqrt() * 1e4).round() / 1e4;
    for want in [
        format!("B on the head: turns about (0, {b}, {b}) through (0, 0, 150) mm"),
        "C on the table: turns about (0, 0, 1) through (0, 0, 0) mm".to_string(),
        "gauge point (0, 0, 0) mm, tool along (0, 0, 1)".to_string(),
    ] {
        assert!(html.contains(&want), "the page lacks {want:?}");
    }
    let test: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("test.json")).unwrap()).unwrap();
    assert!(
        test["chain_geometry"].as_array().unwrap().len() >= 6,
        "{test}"
    );
}
