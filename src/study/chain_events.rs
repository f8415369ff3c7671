//! Poles and solution switches of a scenario's program on a general chain: the block ends
//! as machine axes (a TCP block's through the chain), watched by
//! [`PoleWatch`](crate::kinematics::chain_events::PoleWatch).

use serde_json::{json, Value};

use crate::error::Result;
use crate::input::program::Direction;
use crate::input::scenario::Scenario;
use crate::kinematics::chain_events::{describe, PoleWatch};
use crate::kinematics::chain_inverse::PathEvent;
use crate::program::Motion;

/// One event with its message.
#[derive(Clone, Debug, PartialEq)]
pub struct ChainEvent {
    pub event: PathEvent,
    /// "line 42: pole of B (tool along C): C swings 180.000 deg in one block".
    pub message: String,
}

impl ChainEvent {
    /// `{"line", "kind": "pole"|"switch", "axis", "swing_deg" | "from", "to", "message"}`,
    /// and `last_line` for a pole passage over more than one block end.
    pub fn to_json(&self) -> Value {
        match &self.event {
            PathEvent::Pole {
                line,
                last_line,
                axis,
                swing_deg,
            } => {
                let mut v = json!({"line": line, "kind": "pole", "axis": axis.to_string(),
                        "swing_deg": swing_deg, "message": self.message});
                if last_line != line {
                    v["last_line"] = json!(last_line);
                }
                v
            }
            PathEvent::Switch { line, from, to } => json!({"line": line, "kind": "switch",
                        "from": from, "to": to, "message": self.message}),
        }
    }
}

/// The poles and switches of the scenario's program (its counter-clockwise run, lead
/// included); `None` when the machine is no general chain with two rotaries (the named
/// layouts report none, so their outputs keep their shape).
pub fn chain_events(scenario: &Scenario) -> Result<Option<Vec<ChainEvent>>> {
    let kin = scenario.machine.kinematics;
    let Some(&chain) = kin.own_chain() else {
        return Ok(None);
    };
    let Some(mut watch) = PoleWatch::new(&chain, kin.pole_tolerance_deg) else {
        return Ok(None);
    };
    let run = crate::program::scenario_run(scenario, Direction::Ccw, scenario.simulate.lead_deg)?;
    for m in run.moves {
        let m = m?;
        if matches!(m.motion, Motion::Dwell { .. }) {
            continue;
        }
        let q = if m.tcp {
            kin.tcp_axes(&m.end, m.tool_length_mm)
        } else {
            m.end
        };
        watch.push(m.line, &q);
    }
    Ok(Some(
        watch
            .finish()
            .into_iter()
            .map(|event| ChainEvent {
                message: describe(&event, &chain),
                event,
            })
            .collect(),
    ))
}
