//! Reading a recording back, also one cut short.

use std::collections::BTreeMap;
use std::path::Path;

use mcap::read::Options;
use naosoccer_proto::Event;
use serde::de::DeserializeOwned;

use crate::messages::{
    FinalRecord, MatchMeta, SetStateRecord, StateRecord, TickActions, OLDEST_READABLE_FORMAT,
    RECORDING_FORMAT,
};
use crate::{topics, RecordError};

/// A recording's naosoccer channels, in order.
#[derive(Debug, Clone)]
pub struct Recording {
    pub meta: MatchMeta,
    pub actions: Vec<TickActions>,
    pub states: Vec<StateRecord>,
    pub events: Vec<Event>,
    /// The state changes an admin made (`set_state`), in order.
    pub set_states: Vec<SetStateRecord>,
    /// Absent when the writer did not finish (killed, or stopped before the end).
    pub stats: Option<FinalRecord>,
    /// Messages per topic, Foxglove channels included.
    pub counts: BTreeMap<String, u64>,
    /// Why reading stopped early, when the file is cut short: everything up
    /// to the last completed chunk is here.
    pub truncated: Option<String>,
}

fn parse<T: DeserializeOwned>(topic: &str, data: &[u8]) -> Result<T, RecordError> {
    serde_json::from_slice(data).map_err(|source| RecordError::Json {
        topic: topic.to_string(),
        source,
    })
}

impl Recording {
    pub fn read_file(path: &Path) -> Result<Recording, RecordError> {
        let bytes = std::fs::read(path)?;
        Recording::read(&bytes)
    }

    /// Streams through every message. A file that ends early (no summary, a
    /// half-written chunk) yields what its completed chunks hold.
    pub fn read(bytes: &[u8]) -> Result<Recording, RecordError> {
        if bytes.len() < 8 || &bytes[..8] != mcap::MAGIC {
            return Err(RecordError::NotARecording(
                "the file does not start with the MCAP magic".into(),
            ));
        }
        let stream = mcap::MessageStream::new_with_options(bytes, Options::IgnoreEndMagic.into())?;
        let mut meta = None;
        let mut actions = Vec::new();
        let mut states = Vec::new();
        let mut events = Vec::new();
        let mut set_states = Vec::new();
        let mut stats = None;
        let mut counts = BTreeMap::new();
        let mut truncated = None;
        for msg in stream {
            let msg = match msg {
                Ok(m) => m,
                Err(e) => {
                    truncated = Some(e.to_string());
                    break;
                }
            };
            let topic = msg.channel.topic.as_str();
            *counts.entry(topic.to_string()).or_insert(0) += 1;
            match topic {
                topics::META => meta = Some(parse::<MatchMeta>(topic, &msg.data)?),
                topics::ACTIONS => actions.push(parse(topic, &msg.data)?),
                topics::STATE => states.push(parse(topic, &msg.data)?),
                topics::EVENTS => events.push(parse(topic, &msg.data)?),
                topics::STATS => stats = Some(parse(topic, &msg.data)?),
                topics::SET_STATE => set_states.push(parse(topic, &msg.data)?),
                _ => {}
            }
        }
        if truncated.is_none() && mcap::read::footer(bytes).is_err() {
            truncated = Some("the file ends before its summary and footer".into());
        }
        let meta =
            meta.ok_or_else(|| RecordError::NotARecording(format!("no {} message", topics::META)))?;
        if !(OLDEST_READABLE_FORMAT..=RECORDING_FORMAT).contains(&meta.format) {
            return Err(RecordError::UnsupportedFormat {
                found: meta.format,
                oldest: OLDEST_READABLE_FORMAT,
                newest: RECORDING_FORMAT,
            });
        }
        Ok(Recording {
            meta,
            actions,
            states,
            events,
            set_states,
            stats,
            counts,
            truncated,
        })
    }

    /// Whether the writer finished the file (final statistics, summary, footer).
    pub fn is_complete(&self) -> bool {
        self.truncated.is_none() && self.stats.is_some()
    }
}
