//! Nuisance parameters: a location error (or placement) that the tests barely see, moving
//! the traces by less than [`MIN_VISIBILITY`] um RMS per unit (the A axis's tilt EB0A on a
//! single 15/10 cone, for example). Left out, it would leak: its small effect is fitted by
//! the parameters whose shapes resemble it, which then come out many standard errors off
//! with no warning. So it stays in the fit, its value is not reported (`identifiable:
//! false`), and its spread enters the others' standard errors through the joint fit.
//! Inputs: the solution. Outputs: which parameters are nuisances, and what each would shift.

use nalgebra::DVector;

use super::decomposition::{Decomposition, NullDirection};
use super::estimate::Solution;
use super::params::{round_sig, Param, MIN_VISIBILITY};

/// The nuisances: acting (not dropped), not a servo parameter, and below [`MIN_VISIBILITY`].
pub(super) fn mask(params: &[Param], solution: &Solution) -> Vec<bool> {
    params
        .iter()
        .enumerate()
        .map(|(j, p)| {
            !solution.dropped[j]
                && !solution.fixed[j]
                && !p.is_servo()
                && solution.visibility[j] < MIN_VISIBILITY
        })
        .collect()
}

/// One entry per nuisance: how little it is seen, and the identifiable parameter that
/// leaving it out (holding it at its prior) would shift most, per unit and against that
/// parameter's standard error: `Δx = J_k⁺ J_k`, with `J_k` the other free columns.
pub(super) fn describe(
    params: &[Param],
    solution: &Solution,
    nuisance: &[bool],
    standard_error: &DVector<f64>,
    identifiable: &[bool],
) -> Vec<NullDirection> {
    let mut out = Vec::new();
    for (k, p) in params.iter().enumerate().filter(|(k, _)| nuisance[*k]) {
        let mut without = solution.fixed.clone();
        without[k] = true;
        let d = Decomposition::new(&solution.jac, &without);
        let shift = d.solve(&solution.jac.column(k).into_owned());
        // The identifiable parameter shifted most against its standard error.
        let worst = (0..params.len())
            .filter(|&j| identifiable[j] && standard_error[j] > 0.0)
            .max_by(|&a, &b| {
                (shift[a] / standard_error[a])
                    .abs()
                    .total_cmp(&(shift[b] / standard_error[b]).abs())
            });
        let leak = match worst {
            Some(j) if shift[j] != 0.0 => format!(
                "; left out, it would shift {} by {:+} {}/{} x {} (by one standard error, {} {}, \
                 at {} {} of {})",
                params[j].name(),
                round_sig(shift[j]),
                params[j].unit(),
                p.unit(),
                p.name(),
                round_sig(standard_error[j]),
                params[j].unit(),
                round_sig((standard_error[j] / shift[j]).abs()),
                p.unit(),
                p.name()
            ),
            _ => String::new(),
        };
        let description = format!(
            "{} moves the traces by only {} um RMS per {}: these tests barely see it, so it is \
             kept in the fit as a nuisance (no value given; its spread is in the others' \
             standard errors){leak}",
            p.name(),
            round_sig(solution.visibility[k]),
            p.unit()
        );
        out.push(NullDirection {
            direction: [(p.name(), 1.0)].into_iter().collect(),
            description,
        });
    }
    out
}
