//! Analysis of NC programs from their blocks, checked against the exact-path analysis:
//! the generated cone programs (mixed-unit F, G93 and G43.4) are read back through the
//! G-code reader and must tell the same story as the geometry they came from.

use std::path::Path;

use mtsim::input::machine::Machine;
use mtsim::input::{ConeTest, NcOptions};
use mtsim::measure::CircleFrame;
use mtsim::program::cone::{write_program, ConePath};
use mtsim::program::file::read_str;
use mtsim::study::reversals::{analyse_cone, analyse_moves, angular_distance_deg, Analysis};
use mtsim::Axis;

use crate::common;

fn machine() -> Machine {
    common::load_trt_ac()
}

fn cone_yt25() -> ConeTest {
    common::cone(15.0, 10.0, -25.0, 100.0)
}

fn options(inverse_time: bool, tcp: bool) -> NcOptions {
    NcOptions {
        segments: 360,
        feed_mm_min: 1000.0,
        inverse_time,
        tcp,
        lead_deg: 0.0,
        clockwise: false,
    }
}

/// Generates the program, reads it back and analyses its blocks.
fn file_analysis(m: &Machine, opts: &NcOptions) -> (Analysis, usize) {
    let path = ConePath::new(cone_yt25(), m);
    let (text, measured) = write_program(&path, &m.name, opts);
    let blocks = read_str(Path::new("generated.nc"), &text);
    (
        analyse_moves(blocks, m, Some(&CircleFrame::of_cone(&cone_yt25()))).unwrap(),
        measured.first,
    )
}

#[test]
fn turning_points_sit_at_the_analytic_reversals_to_the_resolution_of_the_blocks() {
    let m = machine();
    let exact = analyse_cone(&ConePath::new(cone_yt25(), &m), 1000.0);
    for (inverse_time, tcp) in [(false, false), (true, false), (false, true)] {
        let (file, first_line) = file_analysis(&m, &options(inverse_time, tcp));
        for axis in [Axis::X, Axis::Y, Axis::Z] {
            let got = file.axis(axis).unwrap();
            let want = &exact.axis(axis).unwrap().reversals_deg;
            assert_eq!(
                got.reversals_deg.len(),
                want.len(),
                "{axis}: {:?} vs {want:?}",
                got.reversals_deg
            );
            let lines = got.reversal_lines.as_ref().unwrap();
            for ((theta, line), w) in got.reversals_deg.iter().zip(lines).zip(want) {
                let block = *line as f64 - first_line as f64 + 1.0; // block k ends at θ = k deg
                if tcp {
                    // Under G43.4 the axes curve inside a block, and the tip's direction jumps by
                    // up to 1 deg at a junction: the turn is found (at 1/32 of a block) inside
                    // or at the end of a block within 1 deg of the analytic angle.
                    assert!((theta - w).abs() < 1.0, "{axis} TCP: {theta} vs {w}");
                    // The line named is the block that holds the turn.
                    assert_eq!(
                        block,
                        (theta - 1e-3).ceil(),
                        "{axis} TCP line {line} at {theta}"
                    );
                } else {
                    // Straight blocks: the turning point is the block end at the whole degree
                    // that rounds the analytic angle.
                    assert!(
                        angular_distance_deg(*theta, w.round()) < 1e-3,
                        "{axis}: {theta} vs {w}"
                    );
                    assert_eq!(block, w.round(), "{axis} line {line}");
                }
            }
        }
    }
}

#[test]
fn ranges_and_speeds_from_the_blocks_agree_with_the_exact_path() {
    let m = machine();
    let exact = analyse_cone(&ConePath::new(cone_yt25(), &m), 1000.0);
    for (inverse_time, tcp) in [(false, false), (true, false), (false, true)] {
        let (file, _) = file_analysis(&m, &options(inverse_time, tcp));
        for axis in [Axis::X, Axis::Y, Axis::Z, Axis::A, Axis::C] {
            let (f, e) = (file.axis(axis).unwrap(), exact.axis(axis).unwrap());
            // 1-deg chords miss an extreme by at most r (1 - cos 0.5 deg) ~ 4 um, plus 0.05 um rounding.
            assert!(
                (f.min - e.min).abs() < 0.005 && (f.max - e.max).abs() < 0.005,
                "{axis} {tcp}: {f:?} vs {e:?}"
            );
            // Chord-average speeds: within 0.2 % of the exact peak. Under G43.4 the tip runs on
            // 1-deg chords whose direction differs from the tangent by up to 0.5 deg, which
            // moves a linear axis's speed by up to F sin(0.5 deg) = 8.7 mm/min: allow twice that.
            let err = (f.peak_speed_per_min - e.peak_speed_per_min).abs();
            let bound = if tcp && !axis.is_rotary() {
                2.0 * 1000.0 * 0.5f64.to_radians().sin()
            } else {
                2e-3 * e.peak_speed_per_min
            };
            assert!(
                err < bound,
                "{axis} G93={inverse_time} TCP={tcp}: {} vs {}",
                f.peak_speed_per_min,
                e.peak_speed_per_min
            );
        }
    }
}

#[test]
fn mixed_unit_f_and_inverse_time_imply_the_same_block_times() {
    // Both are written from dt = chord / F: the F words differ, the speeds must not, but for
    // the 4-decimal rounding of the coordinates (0.05 um in ~0.6 mm steps, ~1e-4).
    let m = machine();
    let (g94, _) = file_analysis(&m, &options(false, false));
    let (g93, _) = file_analysis(&m, &options(true, false));
    for axis in [Axis::X, Axis::Y, Axis::Z, Axis::A, Axis::C] {
        let (a, b) = (
            g94.axis(axis).unwrap().peak_speed_per_min,
            g93.axis(axis).unwrap().peak_speed_per_min,
        );
        assert!((a - b).abs() / b < 2e-4, "{axis}: {a} vs {b}");
    }
}

#[test]
fn the_mixed_unit_f_word_is_the_five_axis_length_over_the_chord_time() {
    let m = machine();
    let path = ConePath::new(cone_yt25(), &m);
    let (text, _) = write_program(&path, &m.name, &options(false, false));
    let first = text.lines().find(|l| l.starts_with("G01")).unwrap();
    let f: f64 = first
        .split_whitespace()
        .find_map(|w| w.strip_prefix('F'))
        .unwrap()
        .parse()
        .unwrap();
    let q0 = path.start();
    let q1 = path.axes_near(1f64.to_radians(), q0[Axis::C]);
    let chord = 2.0 * cone_yt25().radius_mm() * (0.5f64.to_radians()).sin();
    let want = (q1 - q0).mixed_norm() / (chord / 1000.0);
    assert!((f - want).abs() < 2e-3, "F{f} vs {want}");
}

#[test]
fn a_file_scenario_reports_reversal_lines_in_json() {
    let v = common::stdout_json(&common::mtsim(&[
        "analyze",
        "scenarios/file-cone-15-10-yt25.toml",
        "--json",
    ]));
    let lines = v["axes"]["X"]["reversal_lines"].as_array().unwrap();
    assert_eq!(lines.len(), 2);
    let deg = v["axes"]["X"]["reversals_deg"].as_array().unwrap();
    assert_eq!(deg.len(), 2);
}
