//! LinuxCNC `G2`/`G3 ... P<n>`: an arc (or helix) of `n` turns, emitted as `n - 1` full
//! turns and the programmed arc.
//!
//! With the single arc's sweep θ₁ ∈ (0, 2π] (from start to end about the centre), the
//! whole move sweeps θ = θ₁ + 2π(n − 1). Axes other than the two in-plane ones move in
//! proportion to the angle, so after turn k (k = 1 … n − 1) they are at
//! `start + (end − start)·2πk/θ`, and the in-plane axes are back at the start.

use crate::axis::AxisVec;
use crate::canon::{Motion, Move};

/// The end points of the full turns before the last arc, for `turns` ≥ 1 (none for 1).
pub(crate) fn full_turn_ends(
    motion: Motion,
    start: AxisVec,
    end: AxisVec,
    turns: u32,
) -> Vec<AxisVec> {
    let Motion::Arc { plane, .. } = motion else {
        return Vec::new();
    };
    let one = Move {
        motion,
        start,
        end,
        ..Move::default()
    };
    let Some(sweep) = one.arc_sweep_rad() else {
        return Vec::new();
    };
    let tau = std::f64::consts::TAU;
    let total = sweep.abs() + tau * f64::from(turns.saturating_sub(1));
    let (u, v, _) = plane.axes();
    (1..turns)
        .map(|k| {
            let f = tau * f64::from(k) / total;
            let mut p = start + (end - start) * f;
            p[u] = start[u];
            p[v] = start[v];
            p
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use crate::{read_str_with, Axis, Dialect, Motion, Options};
    use std::path::Path;

    /// `G2 X10 Y0 I5 Z-3 P2` from (0, 0, 0): a half turn (θ₁ = π) plus one full turn,
    /// θ = 3π; the full turn ends back at (0, 0) with Z = −3·2π/3π = −2.
    #[test]
    fn two_turns_of_a_helix() {
        let o = Options {
            dialect: Dialect::Linuxcnc,
            ..Options::default()
        };
        let moves: Vec<_> = read_str_with(
            Path::new("t.ngc"),
            "G21 G90 G17\nG1 F100 X0 Y0 Z0\nG2 X10 Y0 I5 Z-3 P2\nM2\n",
            &o,
        )
        .collect::<Result<_, _>>()
        .unwrap();
        // The G1 to where the machine already is may or may not be emitted.
        let arcs: Vec<_> = moves
            .iter()
            .filter(|m| matches!(m.motion, Motion::Arc { .. }))
            .collect();
        assert_eq!(arcs.len(), 2);
        let e = |k: usize| {
            [
                arcs[k].end[Axis::X],
                arcs[k].end[Axis::Y],
                arcs[k].end[Axis::Z],
            ]
        };
        assert!((e(0)[0]).abs() < 1e-12 && (e(0)[1]).abs() < 1e-12);
        assert!((e(0)[2] + 2.0).abs() < 1e-12, "{:?}", e(0));
        assert_eq!(e(1), [10.0, 0.0, -3.0]);
        assert_eq!(arcs[0].arc_sweep_rad().unwrap(), -std::f64::consts::TAU);
    }
}
