//! `CYCLE83` deep-hole drilling, chip breaking (VARI 0) and chip removal (VARI 1), as the
//! steps of a drilling cycle (SINUMERIK 840D sl Programming Manual Cycles, "Deep-hole
//! drilling (CYCLE83)").
//!
//! `CYCLE83(RTP, RFP, SDIS, DP, DPR, FDEP, FDPR, DAM, DTB, DTS, FRF, VARI, _AXN, _MDEP,
//! _VRT, _DTD, _DIS1)`, along the tool axis, depths measured down from RFP:
//!
//! * the final depth is `RFP - |DPR|` when DPR ≠ 0, else DP; the first depth `RFP - |FDPR|`
//!   when FDPR ≠ 0, else FDEP (FDPR acts as DPR does). A first depth past the final one is
//!   the final one (the final depth is never passed); one at or above RFP is the cycle's
//!   alarm 61107 "first drilling depth defined incorrectly", refused.
//! * the strokes (DAM > 0, the degression as an amount): the first stroke to the first depth;
//!   the second the first minus DAM when that is more than DAM, else DAM; then DAM while
//!   more than twice DAM is left; what is left then (more than DAM) in two equal strokes,
//!   each more than half of DAM. Our reading where the manual says nothing: a rest no more
//!   than the stroke due is drilled in one stroke. DAM = 0: every stroke as the first, the
//!   last the rest. DAM < 0 (a factor, with the minimum `_MDEP`) is refused.
//! * the sequence: G0 to RFP + SDIS; G1 to the first depth at F × FRF; dwell DTB; then per
//!   stroke, VARI 1: G0 out to RFP + SDIS, dwell DTS, G0 back to the depth reached less the
//!   anticipation distance (`_DIS1` > 0, else 0.6 mm up to a depth of 30 mm and depth/50,
//!   at most 7 mm, beyond), G1 to the next depth at F; VARI 0: G1 back by `_VRT` (0: 1 mm)
//!   at F, G1 to the next depth at F; a dwell DTB at each depth, `_DTD` (0: DTB) at the
//!   final one; G0 to RTP.
//!
//! A dwell given in spindle revolutions (negative), a drilling axis `_AXN` other than the
//! plane's normal, and (cycles.rs) the later Operate arguments `_GMODE`, `_AMODE` are refused.

use super::state::{CycleFeed, CycleStep};

/// The most strokes one call may drill (a runaway first depth of 1 µm in a deep hole).
const MAX_STROKES: usize = 10_000;

/// The three planes every drilling cycle has, on the tool axis (program units).
#[derive(Clone, Copy, Debug)]
pub(super) struct Planes {
    pub retract: f64,
    pub reference: f64,
    /// RFP + SDIS.
    pub approach: f64,
    /// The final drilling depth.
    pub depth: f64,
}

/// CYCLE83's steps from its values `a` (`None` where left out), with the active plane's
/// normal `normal` (0 X, 1 Y, 2 Z) for `_AXN`.
pub(super) fn deep_hole_steps(
    a: &[Option<f64>],
    p: Planes,
    normal: usize,
) -> Result<Vec<CycleStep>, String> {
    let get = |k: usize| a.get(k).copied().flatten();
    let zero = |k: usize| get(k).unwrap_or(0.0);
    let total = p.reference - p.depth;
    if total <= 0.0 {
        return Err(format!("CYCLE83 final depth {} is not below the reference plane RFP {}: expected a depth under RFP", p.depth, p.reference));
    }
    let first = match (get(6).filter(|v| *v != 0.0), get(5)) {
        (Some(fdpr), _) => p.reference - fdpr.abs(),
        (None, Some(fdep)) => fdep,
        (None, None) => {
            return Err("CYCLE83 without a first drilling depth: expected FDEP (absolute, the 6th value) or FDPR (relative to RFP, the 7th)".into())
        }
    };
    let first_stroke = p.reference - first;
    if first_stroke <= 0.0 {
        return Err(format!("CYCLE83 first drilling depth {first} is not below the reference plane RFP {} (the cycle's alarm 61107, first drilling depth defined incorrectly)", p.reference));
    }
    let dam = zero(7);
    if dam < 0.0 {
        return Err(format!("CYCLE83 DAM {dam}: a degression factor (with the minimum drilling depth _MDEP) is not read by mtsim; give the degression as an amount (DAM > 0) or 0"));
    }
    let vari = zero(11);
    if vari != 0.0 && vari != 1.0 {
        return Err(format!(
            "CYCLE83 VARI {vari}: expected 0 (chip breaking) or 1 (chip removal)"
        ));
    }
    let axn = zero(12);
    let axn_ok = axn == 0.0 || (normal == 2 && axn == 3.0);
    if !axn_ok {
        return Err(format!("CYCLE83 _AXN {axn}: mtsim drills along the active plane's normal (_AXN 0, or 3 under G17); select the plane (G17/G18/G19) instead"));
    }
    let [dtb, dts, dtd] = [zero(8), zero(9), zero(15)];
    if let Some((name, v)) = [("DTB", dtb), ("DTS", dts), ("_DTD", dtd)]
        .into_iter()
        .find(|(_, v)| *v < 0.0)
    {
        return Err(format!("CYCLE83 {name} {v}: a dwell in spindle revolutions is not read by mtsim; give it in seconds (a positive value)"));
    }
    let frf = zero(10);
    if !(0.0..=1.0).contains(&frf) {
        return Err(format!(
            "CYCLE83 FRF {frf}: expected a feed factor from 0.001 to 1"
        ));
    }
    let strokes = strokes(total, first_stroke, dam)?;
    let first_feed = if frf == 0.0 || frf == 1.0 {
        CycleFeed::Programmed
    } else {
        CycleFeed::Factor(frf)
    };
    let back_off = if zero(14) > 0.0 { zero(14) } else { 1.0 };
    let final_dwell = if dtd > 0.0 { dtd } else { dtb };
    let feed = |level: f64, f: CycleFeed| CycleStep::Move {
        level,
        aside: [0.0; 2],
        feed: Some(f),
    };
    let rapid = |level: f64| CycleStep::Move {
        level,
        aside: [0.0; 2],
        feed: None,
    };
    let mut steps = vec![rapid(p.approach)];
    let mut reached = p.reference;
    for (k, stroke) in strokes.iter().enumerate() {
        if k > 0 {
            if vari == 1.0 {
                steps.push(rapid(p.approach));
                if dts > 0.0 {
                    steps.push(CycleStep::Dwell(dts));
                }
                let depth_reached = p.reference - reached;
                steps.push(rapid(reached + anticipation(zero(16), depth_reached)));
            } else {
                steps.push(feed(reached + back_off, CycleFeed::Programmed));
            }
        }
        reached -= stroke;
        let last = k + 1 == strokes.len();
        if last {
            reached = p.depth;
        }
        let f = if k == 0 {
            first_feed
        } else {
            CycleFeed::Programmed
        };
        steps.push(feed(reached, f));
        let dwell = if last { final_dwell } else { dtb };
        if dwell > 0.0 {
            steps.push(CycleStep::Dwell(dwell));
        }
    }
    steps.push(rapid(p.retract));
    Ok(steps)
}

/// The anticipation distance of the re-approach after a chip removal at `depth` below RFP:
/// `_DIS1` when given (> 0), else 0.6 mm up to 30 mm and depth/50 beyond, at most 7 mm.
fn anticipation(dis1: f64, depth: f64) -> f64 {
    if dis1 > 0.0 {
        dis1
    } else if depth <= 30.0 {
        0.6
    } else {
        (depth / 50.0).min(7.0)
    }
}

/// The drilling strokes of a hole `total` deep: the first `first`, then by the degression
/// amount `dam` (module doc).
fn strokes(total: f64, first: f64, dam: f64) -> Result<Vec<f64>, String> {
    let mut out = vec![first.min(total)];
    let mut left = total - out[0];
    let mut due = if dam == 0.0 {
        first
    } else if first - dam > dam {
        first - dam
    } else {
        dam
    };
    while left > 1e-9 {
        if out.len() >= MAX_STROKES {
            return Err(format!("CYCLE83 would drill more than {MAX_STROKES} strokes: expected a first drilling depth and degression that fit the hole's depth {total}"));
        }
        // The second stroke is `due`; from the third, DAM while more than twice DAM is
        // left, then the rest in two equal strokes (each over DAM/2) or in one.
        let stroke = if dam > 0.0 && out.len() >= 2 {
            if left > 2.0 * dam {
                dam
            } else if left > dam {
                left / 2.0
            } else {
                left
            }
        } else {
            due.min(left)
        };
        out.push(stroke);
        left -= stroke;
        due = if dam == 0.0 { first } else { dam };
    }
    Ok(out)
}
