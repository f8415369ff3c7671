//! fit.svg: measured against fitted ball-bar traces, with the residuals, for `mtsim fit`.
//!
//! One row per (trace, direction): the measured deviation and the fitted model against θ
//! (left), the residual `measured − fitted` against θ (right); each row names its scenario
//! and trace. Everything in µm.

use std::path::PathBuf;

use plotters::prelude::*;

use crate::error::{Error, Result};

/// One (trace, direction) to plot: a label and (θ deg, measured um, fitted um) points.
#[derive(Clone, Debug)]
pub struct PlotSeries {
    pub label: String,
    pub points: Vec<(f64, f64, f64)>,
}

const ROW_PX: u32 = 260;
const WIDTH_PX: u32 = 1100;

/// Renders the plot as SVG text.
pub fn render_fit_svg(series: &[PlotSeries]) -> Result<String> {
    let mut svg = String::new();
    {
        let height = ROW_PX * series.len().max(1) as u32;
        let root = SVGBackend::with_string(&mut svg, (WIDTH_PX, height)).into_drawing_area();
        let err = |e: DrawingAreaErrorKind<_>| Error::Write {
            path: PathBuf::from("<svg>"),
            source: std::io::Error::other(e.to_string()),
        };
        root.fill(&WHITE).map_err(err)?;
        let rows = root.split_evenly((series.len().max(1), 2));
        for (k, s) in series.iter().enumerate() {
            let mut pts = s.points.clone();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            let range = |f: &dyn Fn(&(f64, f64, f64)) -> f64| {
                let (lo, hi) = pts
                    .iter()
                    .map(f)
                    .fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(v), h.max(v)));
                let pad = ((hi - lo) * 0.08).max(0.05);
                (lo - pad)..(hi + pad)
            };
            let y_trace = {
                let a = range(&|p| p.1);
                let b = range(&|p| p.2);
                a.start.min(b.start)..a.end.max(b.end)
            };
            let mut chart = ChartBuilder::on(&rows[2 * k])
                .caption(
                    format!("{}: measured and fitted (µm)", s.label),
                    ("sans-serif", 15),
                )
                .margin(8)
                .x_label_area_size(32)
                .y_label_area_size(52)
                .build_cartesian_2d(0.0..360.0, y_trace)
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc("theta (deg)")
                .y_desc("deviation (µm)")
                .draw()
                .map_err(err)?;
            chart
                .draw_series(LineSeries::new(
                    pts.iter().map(|p| (p.0, p.1)),
                    BLUE.stroke_width(1),
                ))
                .map_err(err)?
                .label("measured")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLUE));
            chart
                .draw_series(LineSeries::new(
                    pts.iter().map(|p| (p.0, p.2)),
                    RED.stroke_width(2),
                ))
                .map_err(err)?
                .label("fitted")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], RED));
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()
                .map_err(err)?;
            let mut res = ChartBuilder::on(&rows[2 * k + 1])
                .caption("residual: measured − fitted (µm)", ("sans-serif", 15))
                .margin(8)
                .x_label_area_size(32)
                .y_label_area_size(52)
                .build_cartesian_2d(0.0..360.0, range(&|p| p.1 - p.2))
                .map_err(err)?;
            res.configure_mesh()
                .x_desc("theta (deg)")
                .y_desc("residual (µm)")
                .draw()
                .map_err(err)?;
            res.draw_series(LineSeries::new(
                pts.iter().map(|p| (p.0, p.1 - p.2)),
                BLACK.stroke_width(1),
            ))
            .map_err(err)?;
        }
        root.present().map_err(err)?;
    }
    Ok(svg)
}
