//! The ball bar beside the cut (`tip.svg`): over the same θ axis, the bar's radial deviation
//! dL of the run that cut (raw, not centred: the tool tip's distance from the table ball less
//! L) and the cut's deviation d at the grid's lowest row, just above the tip height.
//!
//! At the tip the surface normal n lies along the bar (both are normal to the generatrix in
//! its plane), so d there is the lower envelope of dL over the cutter's reach: equal where
//! dL varies slowly against the cutter, below it in the scallops and spikes the cutter
//! cannot follow into (docs/cut.md). The bar bins dL by the commanded tip's θ, the cut sits
//! at the actual tip's: with the actual motion the bar's curve runs the servos' lag angle
//! `ω / Kv` ahead of the cut's.

use super::plot::{axis_colour, decimate_min_max, Chart, Marker, Series, CCW, CW};
use crate::error::Result;
use crate::measure::cut::CutSurface;
use crate::measure::theta::BIN_DEG;

pub const TIP_SVG: &str = "tip.svg";

/// Points per curve drawn (min-max buckets).
const BUCKETS: usize = 720;

/// The chart as SVG text: `ballbar_um` the bar's binned dL (bin centres `(i + ½) BIN_DEG`).
pub fn tip_svg(surface: &CutSurface, ballbar_um: &[f64]) -> Result<String> {
    let e = &surface.envelope;
    let z = e.rows[0].z_mm;
    let mut chart = Chart::new(
        &format!("Ball bar and cut at the tip height (z = {z:.2} mm)"),
        "θ (deg)",
        "deviation (µm)",
        1000,
        380,
    );
    chart.x_range = Some((0.0, 360.0));
    chart.x_tick = Some(30.0);
    let bar: Vec<(f64, f64)> = ballbar_um
        .iter()
        .enumerate()
        .map(|(i, &v)| ((i as f64 + 0.5) * BIN_DEG, v))
        .collect();
    let cut: Vec<(f64, f64)> = (0..e.column_count())
        .map(|j| (j as f64 * e.step_deg, e.depth_um(j, 0)))
        .map(|(t, d)| (t, if d.is_finite() { d } else { f64::NAN }))
        .collect();
    chart.series.push(Series {
        label: "ball bar dL (tool tip, radial)".to_string(),
        colour: CW,
        points: decimate_min_max(&bar, BUCKETS),
        dots: false,
    });
    chart.series.push(Series {
        label: "cut d at the tip height (along the normal)".to_string(),
        colour: CCW,
        points: decimate_min_max(&cut, BUCKETS),
        dots: false,
    });
    for (axis, angles) in surface.reversals() {
        chart.markers.extend(angles.iter().map(|&x| Marker {
            x,
            label: axis.to_string(),
            colour: axis_colour(*axis),
        }));
    }
    chart.to_svg()
}
