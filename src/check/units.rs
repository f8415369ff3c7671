//! The other unit: when a program leaves the machine's travel, would it fit read in the
//! other unit? A program in inches read as mm is 25.4 times too small, one in mm read as
//! inches 25.4 times too large; `check` names the unit that fits beside its travel
//! violations, as the reader's units warning names the unit it assumed.

use crate::check::limits::AxisUsage;
use crate::input::scenario::Scenario;
use crate::program::{file, test_of};

/// A note for the travel violations of `scenario`'s program file (`usage`: its axes'
/// travel limits): when the program read in the other start unit keeps every linear axis's
/// move end points within the travel, what that unit is and the ranges it gives. `None` for
/// a generated program, when the program states its units itself (both readings agree),
/// when it still leaves the travel, or when it does not read in the other unit.
pub fn other_unit_note(scenario: &Scenario, usage: &[AxisUsage]) -> Option<String> {
    let test = test_of(scenario);
    let path = test.file()?;
    let mut options = scenario.reader.clone();
    let (read, other, factor) = match options.start_state.units {
        ngc::Units::Mm => ("mm", ngc::Units::Inch, "×25.4"),
        ngc::Units::Inch => ("inches", ngc::Units::Mm, "÷25.4"),
    };
    let linear: Vec<&AxisUsage> = usage.iter().filter(|u| !u.axis.is_rotary()).collect();
    let as_read = end_ranges(path, &options, &linear)?;
    options.start_state.units = other;
    let range = end_ranges(path, &options, &linear)?;
    let fits = range
        .iter()
        .zip(&linear)
        .all(|(r, u)| r.0 > r.1 || (r.0 >= u.limit_min && r.1 <= u.limit_max));
    if !fits || range == as_read {
        return None;
    }
    let ranges: Vec<String> = range
        .iter()
        .zip(&linear)
        .filter(|(r, _)| r.0 <= r.1)
        .map(|(r, u)| format!("{} {:.3} .. {:.3} mm", u.axis, r.0, r.1))
        .collect();
    let other_name = if other == ngc::Units::Inch {
        "inch"
    } else {
        "mm"
    };
    Some(format!(
        "the program reads in {read}; at {other_name} scale ({factor}) its move end points would \
         stay within the travel ({}): check the units it is written in (G20/G21) and the one \
         the control starts in ([reader] start_units, the machine file's [start] units)",
        ranges.join(", ")
    ))
}

/// The smallest and largest end point of `path`'s moves read with `options`, per axis of
/// `axes` (min > max for an axis no move gives); `None` when the program does not read.
fn end_ranges(
    path: &std::path::Path,
    options: &ngc::Options,
    axes: &[&AxisUsage],
) -> Option<Vec<(f64, f64)>> {
    let mut range = vec![(f64::INFINITY, f64::NEG_INFINITY); axes.len()];
    for m in file::read_file(path, options).ok()? {
        let end = m.ok()?.end;
        for (r, u) in range.iter_mut().zip(axes) {
            r.0 = r.0.min(end[u.axis]);
            r.1 = r.1.max(end[u.axis]);
        }
    }
    Some(range)
}
