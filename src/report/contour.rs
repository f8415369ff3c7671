//! `contour.csv` and `contour.svg`: the contour error of a program without a measured circle.
//!
//! `contour.csv` has one row per traced sample of a feed move (the trace's stride):
//! `direction,time_s,line,contour_um,tool_axis_error_urad` (`measure::contour` defines both
//! figures). It is written as the run goes, into a temporary file that becomes `contour.csv`
//! only when complete. `contour.svg` plots the largest contour error along the program's
//! machine time, with the worst lines marked.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use plotters::prelude::*;

use super::files::temporary_path;
use super::trace_rows::write_error;
use crate::error::{Error, Result};
use crate::input::program::Direction;
use crate::measure::contour::{ContourFigures, ContourProfile, ContourReading};
use crate::numeric::push_fixed_bytes_const;

/// The contour error's file names.
pub const CONTOUR_FILE: &str = "contour.csv";
pub const CONTOUR_PLOT_FILE: &str = "contour.svg";

/// `contour.csv` being written.
pub struct ContourFile {
    path: PathBuf,
    tmp: PathBuf,
    out: Option<BufWriter<File>>,
    line: Vec<u8>,
}

impl ContourFile {
    /// Creates the temporary file of `path` with its header.
    pub fn create(path: &Path) -> Result<ContourFile> {
        let tmp = temporary_path(path);
        let file = File::create(&tmp).map_err(write_error(&tmp))?;
        let mut out = BufWriter::with_capacity(1 << 16, file);
        writeln!(out, "direction,time_s,line,contour_um,tool_axis_error_urad")
            .map_err(write_error(&tmp))?;
        Ok(ContourFile {
            path: path.to_path_buf(),
            tmp,
            out: Some(out),
            line: Vec::with_capacity(96),
        })
    }

    /// Appends the row of a sample at `time_s` on program line `line`.
    pub fn push(
        &mut self,
        direction: Direction,
        time_s: f64,
        line: usize,
        r: &ContourReading,
    ) -> Result<()> {
        let Some(out) = self.out.as_mut() else {
            return Ok(());
        };
        let row = &mut self.line;
        row.clear();
        row.extend_from_slice(if direction == Direction::Cw {
            b"cw"
        } else {
            b"ccw"
        });
        row.push(b',');
        push_fixed_bytes_const::<4>(row, time_s);
        row.push(b',');
        row.extend_from_slice(line.to_string().as_bytes());
        row.push(b',');
        push_fixed_bytes_const::<4>(row, r.contour_um);
        row.push(b',');
        push_fixed_bytes_const::<3>(row, r.tool_axis_error_urad);
        row.push(b'\n');
        out.write_all(row).map_err(write_error(&self.tmp))
    }

    /// Flushes the file and puts it in place.
    pub fn finish(mut self) -> Result<()> {
        let mut out = self.out.take().expect("open until finished");
        out.flush().map_err(write_error(&self.tmp))?;
        drop(out);
        std::fs::rename(&self.tmp, &self.path).map_err(write_error(&self.path))
    }
}

impl Drop for ContourFile {
    fn drop(&mut self) {
        // Not finished: the run failed, and a partial file is not kept.
        if self.out.take().is_some() {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// Renders the contour error along the program: the largest value in each span of machine
/// time, the worst lines marked and named.
pub fn render_contour_svg(
    profile: &ContourProfile,
    figures: &ContourFigures,
    title: &str,
) -> Result<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1000, 420)).into_drawing_area();
        let err = |e: DrawingAreaErrorKind<_>| Error::Write {
            path: PathBuf::from(CONTOUR_PLOT_FILE),
            source: std::io::Error::other(e.to_string()),
        };
        root.fill(&WHITE).map_err(err)?;
        let t0 = profile.start_s;
        let t1 = t0 + profile.bin_s * profile.max_um.len().max(1) as f64;
        let top = (figures.max_um * 1.15).max(0.01);
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!("{title}: contour error along the program (µm)"),
                ("sans-serif", 16),
            )
            .margin(10)
            .x_label_area_size(36)
            .y_label_area_size(56)
            .build_cartesian_2d(t0..t1, 0.0..top)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("machine time (s)")
            .y_desc("largest contour error (µm)")
            .draw()
            .map_err(err)?;
        let points = profile
            .max_um
            .iter()
            .enumerate()
            .filter(|(_, v)| v.is_finite())
            .map(|(k, &v)| (t0 + (k as f64 + 0.5) * profile.bin_s, v));
        chart
            .draw_series(LineSeries::new(points, BLUE.stroke_width(1)))
            .map_err(err)?
            .label("largest in each span")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLUE));
        chart
            .draw_series(figures.worst.iter().map(|w| {
                EmptyElement::at((w.time_s, w.contour_um))
                    + Circle::new((0, 0), 4, RED.filled())
                    + Text::new(format!("N{}", w.line), (6, -12), ("sans-serif", 12))
            }))
            .map_err(err)?
            .label("worst lines")
            .legend(|(x, y)| Circle::new((x + 9, y), 4, RED.filled()));
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(err)?;
        root.present().map_err(err)?;
    }
    Ok(svg)
}
