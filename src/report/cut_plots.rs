//! The cut cone's pictures: the unrolled surface map (`surface.svg`: θ against height, the
//! deviation as colour on a linear scale, each reversal's θ marked with its axis) and the
//! roundness per evaluation height as a CMM prints it (`roundness.svg`: the profile's
//! deviation from its least-squares circle, magnified about a base circle).

use plotters::prelude::*;
use plotters::style::text_anchor::HPos;

use super::plot::{axis_colour, draw_error, text, GRID, INK};
use crate::error::Result;
use crate::measure::cut::{CutFigures, CutSurface};
use crate::Axis;

pub const SURFACE_SVG: &str = "surface.svg";
pub const ROUNDNESS_SVG: &str = "roundness.svg";

/// Columns of the map: the grid's θ columns are averaged into this many bins.
const MAP_BINS: usize = 360;

/// A diverging colour for `v` in [−1, 1]: blue (overcut) through white to red (material left).
fn diverging(v: f64) -> RGBColor {
    let v = v.clamp(-1.0, 1.0);
    let fade = |c: f64| (255.0 - (255.0 - c) * v.abs()).round() as u8;
    if v >= 0.0 {
        RGBColor(fade(200.0), fade(30.0), fade(30.0))
    } else {
        RGBColor(fade(30.0), fade(80.0), fade(200.0))
    }
}

/// The largest |d| over the grid, um (the colour scale's end), at least 0.01.
fn scale_um(surface: &CutSurface) -> f64 {
    surface
        .envelope
        .values
        .iter()
        .filter(|d| d.is_finite())
        .fold(0.01, |m: f64, d| m.max(d.abs()))
}

/// The unrolled map as SVG text.
pub fn surface_svg(surface: &CutSurface, reversals: &[(Axis, Vec<f64>)]) -> Result<String> {
    let (width, height) = (1000u32, 520u32);
    let (left, right, top, bottom) = (70i32, 130i32, 50i32, 60i32);
    let e = &surface.envelope;
    let rows = e.rows.len();
    let scale = scale_um(surface);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_error)?;
        let (w, h) = (width as i32 - left - right, height as i32 - top - bottom);
        let (z0, z1) = (e.rows[0].z_mm, e.rows[rows - 1].z_mm);
        let x_of = |theta: f64| left + (theta / 360.0 * w as f64).round() as i32;
        let y_of = |z: f64| top + h - ((z - z0) / (z1 - z0).max(1e-9) * h as f64).round() as i32;
        let per_bin = (e.column_count() / MAP_BINS).max(1);
        let bins = e.column_count() / per_bin;
        for i in 0..rows {
            // Each row spans half way to its neighbours.
            let lo = if i == 0 {
                z0
            } else {
                0.5 * (e.rows[i - 1].z_mm + e.rows[i].z_mm)
            };
            let hi = if i + 1 == rows {
                z1
            } else {
                0.5 * (e.rows[i].z_mm + e.rows[i + 1].z_mm)
            };
            // A bin's colour, and neighbours of one colour drawn as one rectangle (the same
            // picture in a third of the rectangles).
            let colour_of = |b: usize| {
                let cut = || {
                    (b * per_bin..(b + 1) * per_bin)
                        .map(|j| e.depth_um(j, i))
                        .filter(|d| d.is_finite())
                };
                match cut().count() {
                    0 => RGBColor(190, 190, 190),
                    n => diverging(cut().sum::<f64>() / n as f64 / scale),
                }
            };
            let x_of_bin = |b: usize| x_of((b * per_bin) as f64 * e.step_deg);
            let draw = |run: std::ops::Range<usize>, colour: RGBColor| {
                root.draw(&Rectangle::new(
                    [
                        (x_of_bin(run.start), y_of(hi)),
                        (x_of_bin(run.end), y_of(lo)),
                    ],
                    colour.filled(),
                ))
                .map_err(draw_error)
            };
            for (run, colour) in runs_of((0..bins).map(colour_of)) {
                draw(run, colour)?;
            }
        }
        for theta in (0..=360).step_by(30) {
            let x = x_of(theta as f64);
            root.draw(&PathElement::new(vec![(x, top + h), (x, top + h + 5)], INK))
                .map_err(draw_error)?;
            root.draw(&Text::new(
                format!("{theta}"),
                (x, top + h + 8),
                text(12.0, &INK, HPos::Center),
            ))
            .map_err(draw_error)?;
        }
        for k in 0..=4 {
            let z = z0 + (z1 - z0) * k as f64 / 4.0;
            root.draw(&Text::new(
                format!("{z:.1}"),
                (left - 8, y_of(z) - 6),
                text(12.0, &INK, HPos::Right),
            ))
            .map_err(draw_error)?;
        }
        root.draw(&Text::new(
            "θ (deg)",
            (left + w / 2, top + h + 28),
            text(13.0, &INK, HPos::Center),
        ))
        .map_err(draw_error)?;
        root.draw(&Text::new(
            "z (mm)",
            (left - 8, top + h + 8),
            text(12.0, &INK, HPos::Right),
        ))
        .map_err(draw_error)?;
        root.draw(&Text::new(
            "Cut surface, unrolled: deviation d from the nominal cone (red: material left, blue: overcut)",
            (left, 12),
            text(14.0, &INK, HPos::Left),
        ))
        .map_err(draw_error)?;
        for (axis, angles) in reversals {
            for &theta in angles {
                let x = x_of(theta.rem_euclid(360.0));
                let colour = axis_colour(*axis);
                root.draw(&PathElement::new(
                    vec![(x, top), (x, top + h)],
                    colour.stroke_width(1),
                ))
                .map_err(draw_error)?;
                root.draw(&Text::new(
                    axis.to_string(),
                    (x, top - 14),
                    text(12.0, &colour, HPos::Center),
                ))
                .map_err(draw_error)?;
            }
        }
        // The colour bar, linear from −scale to +scale.
        let (bx, steps) = (width as i32 - right + 30, 40);
        for k in 0..steps {
            let v = 1.0 - 2.0 * (k as f64 + 0.5) / steps as f64;
            let y = top + h * k / steps;
            root.draw(&Rectangle::new(
                [(bx, y), (bx + 18, top + h * (k + 1) / steps)],
                diverging(v).filled(),
            ))
            .map_err(draw_error)?;
        }
        root.draw(&Rectangle::new(
            [(bx, top), (bx + 18, top + h)],
            GRID.stroke_width(1),
        ))
        .map_err(draw_error)?;
        for (label, y) in [(scale, top), (0.0, top + h / 2), (-scale, top + h)] {
            root.draw(&Text::new(
                format!("{label:+.2}"),
                (bx + 24, y - 6),
                text(12.0, &INK, HPos::Left),
            ))
            .map_err(draw_error)?;
        }
        root.draw(&Text::new(
            "d (µm)",
            (bx, top - 20),
            text(12.0, &INK, HPos::Left),
        ))
        .map_err(draw_error)?;
        root.present().map_err(draw_error)?;
    }
    Ok(svg)
}

/// The runs of equal items of `items`: each run's index range and its item, in order.
fn runs_of<T: PartialEq>(items: impl Iterator<Item = T>) -> Vec<(std::ops::Range<usize>, T)> {
    let mut runs: Vec<(std::ops::Range<usize>, T)> = Vec::new();
    for (k, item) in items.enumerate() {
        match runs.last_mut() {
            Some((range, last)) if *last == item => range.end = k + 1,
            _ => runs.push((k..k + 1, item)),
        }
    }
    runs
}

/// The roundness plots, one polar panel per evaluation height, as SVG text.
pub fn roundness_svg(surface: &CutSurface, figures: &CutFigures) -> Result<String> {
    let panels = figures.heights.len().max(1) as u32;
    let (size, height) = (340u32, 400u32);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (size * panels, height)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_error)?;
        let e = &surface.envelope;
        // One magnification for every panel: the largest residual fills 40 % of the radius.
        let residuals: Vec<Vec<(f64, f64)>> = surface
            .evaluation_rows()
            .iter()
            .zip(&figures.heights)
            .map(|(&i, h)| {
                let r0 = h.nominal_radius_mm * 1e3 + h.diameter_error_um / 2.0;
                let [a, b] = h.centre_offset_um;
                (0..e.column_count())
                    .filter_map(|j| {
                        let d = e.depth_um(j, i);
                        let theta = (j as f64 * e.step_deg).to_radians();
                        d.is_finite().then(|| {
                            let r = h.nominal_radius_mm * 1e3 + d / surface.geometry.cos_alpha();
                            (theta, r - (r0 + a * theta.cos() + b * theta.sin()))
                        })
                    })
                    .collect()
            })
            .collect();
        let worst = residuals
            .iter()
            .flatten()
            .fold(0.01f64, |m, r| m.max(r.1.abs()));
        let base = 0.28 * size as f64;
        let magnification = 0.4 * base / worst;
        for (k, (points, h)) in residuals.iter().zip(&figures.heights).enumerate() {
            let cx = (k as u32 * size + size / 2) as f64;
            let cy = (height / 2 + 20) as f64;
            let at =
                |theta: f64, r: f64| ((cx + r * theta.cos()) as i32, (cy - r * theta.sin()) as i32);
            root.draw(&Circle::new(
                (cx as i32, cy as i32),
                base as i32,
                GRID.stroke_width(1),
            ))
            .map_err(draw_error)?;
            let ring = (base - 0.4 * base, base + 0.4 * base);
            for r in [ring.0, ring.1] {
                root.draw(&Circle::new(
                    (cx as i32, cy as i32),
                    r as i32,
                    GRID.stroke_width(1),
                ))
                .map_err(draw_error)?;
            }
            let mut path: Vec<(i32, i32)> = points
                .iter()
                .map(|&(theta, res)| at(theta, base + magnification * res))
                .collect();
            if let Some(&first) = path.first() {
                path.push(first);
            }
            root.draw(&PathElement::new(
                path,
                RGBColor(20, 90, 200).stroke_width(1),
            ))
            .map_err(draw_error)?;
            let lines = [
                format!("z = {:.2} mm", h.z_mm),
                format!("roundness {:.3} µm", h.roundness_um),
                format!("Ø error {:+.3} µm", h.diameter_error_um),
                format!(
                    "centre {:+.2}, {:+.2} µm",
                    h.centre_offset_um[0], h.centre_offset_um[1]
                ),
            ];
            for (n, line) in lines.iter().enumerate() {
                root.draw(&Text::new(
                    line.clone(),
                    (cx as i32, 8 + 16 * n as i32),
                    text(12.0, &INK, HPos::Center),
                ))
                .map_err(draw_error)?;
            }
        }
        root.draw(&Text::new(
            format!(
                "deviation from the least-squares circle (ISO 12181-1), rings at ±{:.2} µm",
                0.4 * base / magnification
            ),
            (8, height as i32 - 18),
            text(12.0, &INK, HPos::Left),
        ))
        .map_err(draw_error)?;
        root.present().map_err(draw_error)?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::runs_of;

    #[test]
    fn equal_neighbours_make_one_run_and_a_repeat_after_another_a_new_one() {
        let runs = runs_of("aabaaac".chars());
        assert_eq!(
            runs,
            vec![(0..2, 'a'), (2..3, 'b'), (3..6, 'a'), (6..7, 'c')]
        );
        assert!(runs_of(std::iter::empty::<u8>()).is_empty());
        assert_eq!(runs_of([7].into_iter()), vec![(0..1, 7)]);
    }
}
