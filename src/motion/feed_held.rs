//! The feed held to the machine: a feed block the planner runs below its F word, the axis
//! limit that holds it ([`FeedLimit`]), and those summarised per axis and limit
//! ([`FeedReductions`]: memory bounded by the axes, not by the program).

use serde::{Deserialize, Serialize};

use crate::Axis;

/// Which axis limit holds a block's feed below its F word.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LimitKind {
    /// The axis's maximum velocity: `v ≤ vmax_i / |q'_i|`.
    Velocity,
    /// The axis's maximum acceleration through the path's curvature: `v² |q''_i| ≤ ½ amax_i`.
    Acceleration,
    /// The axis's maximum jerk through the path's curvature at constant speed:
    /// `v³ |q'''_i| ≤ ⅓ jmax_i`.
    Jerk,
}

/// A feed block planned below its programmed speed: the feed held to the machine.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FeedLimit {
    /// Source line and 0-based position of the block.
    pub line: usize,
    pub block_index: u64,
    /// The axis whose limit binds, and which limit.
    pub axis: Axis,
    pub limit: LimitKind,
    /// The programmed path speed and the cruise speed the block is planned at, per minute in
    /// path units (mm, deg counted as mm in mixed moves, the tool tip under TCP).
    pub programmed_per_min: f64,
    pub planned_per_min: f64,
}

/// Feed blocks held below their F word by one axis's limit.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FeedReduction {
    /// The axis whose limit binds, and which limit.
    pub axis: Axis,
    pub limit: LimitKind,
    /// How many feed blocks it held.
    pub blocks: u64,
    /// The source line of the first of them.
    pub first_line: usize,
    /// The block held the most (lowest planned/programmed ratio): its programmed and planned
    /// path speeds, per minute in path units (mm; deg counted as mm in mixed moves).
    pub programmed_per_min: f64,
    pub planned_per_min: f64,
}

impl FeedReduction {
    /// One line for a person: `X acceleration limit holds 3 feed blocks from line 7
    /// (F3000 runs at 2264 mm/min)`.
    pub fn describe(&self) -> String {
        let limit = match self.limit {
            LimitKind::Velocity => "velocity",
            LimitKind::Acceleration => "acceleration",
            LimitKind::Jerk => "jerk",
        };
        format!(
            "the {} {limit} limit holds {} feed block{} below the programmed feed, from line {} \
             (down to {:.0} of a programmed {:.0} per min)",
            self.axis,
            self.blocks,
            if self.blocks == 1 { "" } else { "s" },
            self.first_line,
            self.planned_per_min,
            self.programmed_per_min
        )
    }
}

/// The [`FeedReduction`]s of one run, noted block by block.
#[derive(Clone, Debug, Default)]
pub struct FeedReductions {
    /// Per axis index and limit kind (velocity, acceleration, jerk).
    by: [[Option<FeedReduction>; 3]; 9],
}

impl FeedReductions {
    /// Notes one block held below its F word.
    pub fn note(&mut self, f: &FeedLimit) {
        let kind = match f.limit {
            LimitKind::Velocity => 0,
            LimitKind::Acceleration => 1,
            LimitKind::Jerk => 2,
        };
        let slot = &mut self.by[f.axis.index()][kind];
        let r = slot.get_or_insert(FeedReduction {
            axis: f.axis,
            limit: f.limit,
            blocks: 0,
            first_line: f.line,
            programmed_per_min: f.programmed_per_min,
            planned_per_min: f.planned_per_min,
        });
        r.blocks += 1;
        // Compare ratios as products: planned/programmed < r.planned/r.programmed.
        if f.planned_per_min * r.programmed_per_min < r.planned_per_min * f.programmed_per_min {
            r.programmed_per_min = f.programmed_per_min;
            r.planned_per_min = f.planned_per_min;
        }
    }

    /// Every reduction, by axis then limit.
    pub fn list(&self) -> Vec<FeedReduction> {
        self.by.iter().flatten().flatten().copied().collect()
    }
}
