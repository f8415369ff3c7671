//! The boring cycles that stop the spindle at the depth, as the steps of a drilling cycle
//! (SINUMERIK 840D sl Programming Manual Cycles, "Boring 2 (CYCLE86)", "Boring 3
//! (CYCLE87)", "Boring 4 (CYCLE88)"):
//!
//! * `CYCLE86(RTP, RFP, SDIS, DP, DPR, DTB, SDIR, RPA, RPO, RPAP, POSS)`: G0 to RFP + SDIS,
//!   G1 to the depth at the programmed F, dwell DTB, oriented spindle stop at POSS (M19),
//!   the lift-off with G0 by RPA and RPO in the plane's first and second axes and RPAP on
//!   the tool axis (incremental, with sign), G0 out to RFP + SDIS still lifted off, G0 to
//!   RTP back over the drilling position, the spindle on again in SDIR (M3/M4).
//! * `CYCLE87(RTP, RFP, SDIS, DP, DPR, SDIR)` and `CYCLE88(.., DTB, SDIR)`: G0 to
//!   RFP + SDIS, G1 to the depth at F, dwell DTB (CYCLE88), spindle stop M5 and program
//!   stop M0; after NC start, G0 to RTP, the spindle on again in SDIR. mtsim runs on at M0
//!   as the control does after NC start (a notice says so): whatever the operator does
//!   by hand in the stop is not simulated.
//!
//! SDIR must be 3 or 4 (the cycle's alarm 61102 "no spindle direction programmed"); our
//! reading: the spindle turns again in SDIR after the retraction, which the next hole of
//! an `MCALL` needs.

use super::deep_hole::Planes;
use super::state::{CycleFeed, CycleStep};

/// The steps of `CYCLE86`, `CYCLE87` or `CYCLE88` (`name`) from its values `a`.
pub(super) fn boring_steps(
    name: &str,
    a: &[Option<f64>],
    p: Planes,
) -> Result<Vec<CycleStep>, String> {
    let zero = |k: usize| a.get(k).copied().flatten().unwrap_or(0.0);
    let (dwell, sdir) = match name {
        "CYCLE87" => (0.0, zero(5)),
        _ => (zero(5), zero(6)),
    };
    if dwell < 0.0 {
        return Err(format!("{name} DTB {dwell}: a dwell in spindle revolutions is not read by mtsim; give it in seconds (a positive value)"));
    }
    let spindle = match sdir {
        3.0 => 3,
        4.0 => 4,
        _ => return Err(format!("{name} SDIR {sdir}: expected the spindle's direction 3 (M3) or 4 (M4), the {} value (the cycle's alarm 61102, no spindle direction programmed)", if name == "CYCLE87" { "6th" } else { "7th" })),
    };
    let at = |level: f64, aside: [f64; 2], feed: Option<CycleFeed>| CycleStep::Move {
        level,
        aside,
        feed,
    };
    let mut steps = vec![
        at(p.approach, [0.0; 2], None),
        at(p.depth, [0.0; 2], Some(CycleFeed::Programmed)),
    ];
    if dwell > 0.0 {
        steps.push(CycleStep::Dwell(dwell));
    }
    if name == "CYCLE86" {
        let aside = [zero(7), zero(8)];
        steps.extend([
            CycleStep::M(19),
            at(p.depth + zero(9), aside, None),
            at(p.approach, aside, None),
        ]);
    } else {
        steps.extend([CycleStep::M(5), CycleStep::M(0)]);
    }
    steps.extend([at(p.retract, [0.0; 2], None), CycleStep::M(spindle)]);
    Ok(steps)
}
