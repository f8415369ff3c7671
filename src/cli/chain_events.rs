//! The poles and solution switches of a program on a kinematic chain, as `analyze`,
//! `check` and `simulate` print them (text, and the `chain_events` key of their JSON).

/// The poles and solution switches of a program on a general chain, for the terminal
/// (`analyze`, `check`, `simulate`); nothing on a named layout (`None`).
pub fn chain_events_text(events: Option<&[crate::study::chain_events::ChainEvent]>) -> String {
    match events {
        None => String::new(),
        Some([]) => "kinematic chain: no poles or solution switches\n".to_string(),
        Some(events) => {
            let mut out = "kinematic chain: poles and solution switches\n".to_string();
            for e in events {
                out.push_str(&format!("  {}\n", e.message));
            }
            out
        }
    }
}

/// `value` as pretty JSON, with a last key `chain_events` when there are
/// ([`chain_events_text`]); its own fields in their order (as without).
pub fn json_with_chain_events<T: serde::Serialize>(
    value: &T,
    events: Option<&[crate::study::chain_events::ChainEvent]>,
) -> String {
    #[derive(serde::Serialize)]
    struct With<'a, T: serde::Serialize> {
        #[serde(flatten)]
        value: &'a T,
        chain_events: Vec<serde_json::Value>,
    }
    match events {
        None => serde_json::to_string_pretty(value),
        Some(events) => serde_json::to_string_pretty(&With {
            value,
            chain_events: events.iter().map(|e| e.to_json()).collect(),
        }),
    }
    .expect("plain data serializes")
}
