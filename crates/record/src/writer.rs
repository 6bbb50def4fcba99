//! Writing a match to MCAP while it is played.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{Cursor, Seek, SeekFrom, Write};
use std::path::Path;

use ::foxglove::messages::{FrameTransforms, SceneUpdate};
use mcap::records::MessageHeader;
use mcap::{Compression, WriteOptions, Writer};
use naosoccer_proto::{Action, Event, StateChange, Tick, ROBOTS};
use naosoccer_referee::Match;
use serde::Serialize;

use crate::foxglove;
use crate::messages::{
    hash_hex, FinalRecord, MatchMeta, ScoreRecord, SetStateRecord, StateRecord, TickActions,
};
use crate::{topics, RecordError};

/// How a recording is written.
#[derive(Debug, Clone)]
pub struct RecorderOptions {
    /// Uncompressed bytes after which a chunk is compressed and written out.
    pub chunk_size: u64,
    /// A chunk is also closed every this many control ticks, so a writer
    /// killed mid-match loses at most this much play (100 ticks = 10 s at
    /// 10 Hz). Tick-based, not time-based, so the bytes stay repeatable.
    pub flush_every_ticks: u64,
    /// zstd level (1 is fast; the JSON compresses well at any level).
    pub compression_level: u32,
    /// Write the Foxglove scene and transform channels.
    pub foxglove: bool,
}

impl Default for RecorderOptions {
    fn default() -> Self {
        RecorderOptions {
            chunk_size: 1 << 20,
            flush_every_ticks: 100,
            compression_level: 1,
            foxglove: true,
        }
    }
}

/// Messages written per channel, by topic.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct RecordingSummary {
    pub messages: BTreeMap<String, u64>,
}

#[derive(Clone, Copy)]
enum Ch {
    Meta,
    Actions,
    State,
    Events,
    Stats,
    Scene,
    Tf,
}

/// Where a recording goes: a file, or a buffer in memory.
///
/// A concrete type rather than a type parameter, so that the recorder's
/// code (JSON encoding, the MCAP writer) is compiled once, optimised, in
/// this crate, whatever crate records: a generic recorder was compiled
/// again in every caller, at the caller's optimisation level.
#[derive(Debug)]
pub enum Sink {
    File(File),
    Memory(Cursor<Vec<u8>>),
}

impl Sink {
    /// The bytes of a recording made in memory; `None` for a file.
    pub fn into_bytes(self) -> Option<Vec<u8>> {
        match self {
            Sink::File(_) => None,
            Sink::Memory(c) => Some(c.into_inner()),
        }
    }
}

impl Write for Sink {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match self {
            Sink::File(f) => f.write(buf),
            Sink::Memory(c) => c.write(buf),
        }
    }

    fn write_all(&mut self, buf: &[u8]) -> std::io::Result<()> {
        match self {
            Sink::File(f) => f.write_all(buf),
            Sink::Memory(c) => c.write_all(buf),
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        match self {
            Sink::File(f) => f.flush(),
            Sink::Memory(c) => c.flush(),
        }
    }
}

impl Seek for Sink {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        match self {
            Sink::File(f) => f.seek(pos),
            Sink::Memory(c) => c.seek(pos),
        }
    }
}

/// Writes one match. Call [`Recorder::tick`] after every `Match::step` and
/// [`Recorder::finish`] at the end; dropping a recorder without `finish`
/// leaves a file whose completed chunks are still readable.
pub struct Recorder {
    writer: Writer<Sink>,
    channel_ids: [u16; 7],
    sequences: [u32; 7],
    tick_ns: u64,
    opts: RecorderOptions,
    buf: Vec<u8>,
    state: Option<StateRecord>,
    /// `/match/set_state`'s channel and its next sequence number, once the
    /// first state change made it.
    set_state: Option<(u16, u32)>,
}

impl Recorder {
    /// Creates (or truncates) `path` and writes the match's start.
    pub fn create(
        path: &Path,
        meta: &MatchMeta,
        m: &Match,
        opts: RecorderOptions,
    ) -> Result<Self, RecordError> {
        if let Some(dir) = path.parent() {
            if !dir.as_os_str().is_empty() {
                std::fs::create_dir_all(dir)?;
            }
        }
        // Unbuffered on purpose: the MCAP writer already gathers a whole
        // chunk before writing, and a chunk must reach the file as soon as
        // it is complete for a killed server to leave it readable.
        Recorder::new(Sink::File(File::create(path)?), meta, m, opts)
    }

    /// Records into memory; [`Recorder::finish`] hands back the bytes
    /// ([`Sink::into_bytes`]).
    pub fn in_memory(
        meta: &MatchMeta,
        m: &Match,
        opts: RecorderOptions,
    ) -> Result<Self, RecordError> {
        Recorder::new(
            Sink::Memory(Cursor::new(Vec::with_capacity(8 << 20))),
            meta,
            m,
            opts,
        )
    }

    /// Writes the match's start to `w`.
    pub fn new(
        w: Sink,
        meta: &MatchMeta,
        m: &Match,
        opts: RecorderOptions,
    ) -> Result<Self, RecordError> {
        let options = WriteOptions::new()
            .compression(Some(Compression::Zstd))
            .compression_level(opts.compression_level)
            // Multithreaded zstd would make the bytes depend on scheduling.
            .compression_threads(0)
            .chunk_size(Some(opts.chunk_size))
            .profile("")
            .library(format!("naosoccer {}", env!("CARGO_PKG_VERSION")));
        let mut writer = options.create(w)?;
        let json_schema =
            |w: &mut Writer<Sink>, name: &str, data: &[u8]| w.add_schema(name, "jsonschema", data);
        let meta_s = json_schema(&mut writer, "naosoccer.MatchMeta", b"{\"type\":\"object\"}")?;
        let act_s = json_schema(
            &mut writer,
            "naosoccer.TickActions",
            b"{\"type\":\"object\"}",
        )?;
        let state_s = json_schema(&mut writer, "naosoccer.State", b"{\"type\":\"object\"}")?;
        let event_s = json_schema(&mut writer, "naosoccer.Event", b"{\"type\":\"object\"}")?;
        let stats_s = json_schema(
            &mut writer,
            "naosoccer.FinalStats",
            b"{\"type\":\"object\"}",
        )?;
        // The Foxglove channels: the SDK's schemas (protobuf descriptors,
        // constants of the SDK build) and its protobuf messages.
        let sdk_schema = |w: &mut Writer<Sink>, s: ::foxglove::Schema| {
            w.add_schema(&s.name, &s.encoding, &s.data)
        };
        let scene_s = sdk_schema(&mut writer, foxglove::schema::<SceneUpdate>())?;
        let tf_s = sdk_schema(&mut writer, foxglove::schema::<FrameTransforms>())?;
        let schemas = [meta_s, act_s, state_s, event_s, stats_s, scene_s, tf_s];
        let mut channel_ids = [0u16; 7];
        let json = "json";
        let encodings = [
            json,
            json,
            json,
            json,
            json,
            foxglove::ENCODING,
            foxglove::ENCODING,
        ];
        for (i, topic) in topics::ALL.iter().enumerate() {
            channel_ids[i] =
                writer.add_channel(schemas[i], topic, encodings[i], &BTreeMap::new())?;
        }
        let tick_ns = (1e9 / f64::from(meta.control_hz)).round() as u64;
        let mut rec = Recorder {
            writer,
            channel_ids,
            sequences: [0; 7],
            tick_ns,
            opts,
            buf: Vec::with_capacity(4096),
            state: None,
            set_state: None,
        };
        rec.write_json(Ch::Meta, 0, meta)?;
        if rec.opts.foxglove {
            let scene = foxglove::encode(&foxglove::scene_update(m));
            rec.write_raw(Ch::Scene, 0, &scene)?;
        }
        rec.write_state(m)?;
        Ok(rec)
    }

    fn write_raw(&mut self, ch: Ch, log_time: u64, data: &[u8]) -> Result<(), RecordError> {
        let i = ch as usize;
        let header = MessageHeader {
            channel_id: self.channel_ids[i],
            sequence: self.sequences[i],
            log_time,
            publish_time: log_time,
        };
        self.sequences[i] += 1;
        self.writer.write_to_known_channel(&header, data)?;
        Ok(())
    }

    fn write_json<T: Serialize>(
        &mut self,
        ch: Ch,
        log_time: u64,
        v: &T,
    ) -> Result<(), RecordError> {
        let mut buf = std::mem::take(&mut self.buf);
        buf.clear();
        let r = serde_json::to_writer(&mut buf, v)
            .map_err(|source| RecordError::Json {
                topic: topics::ALL[ch as usize].to_string(),
                source,
            })
            .and_then(|()| self.write_raw(ch, log_time, &buf));
        self.buf = buf;
        r
    }

    fn write_state(&mut self, m: &Match) -> Result<(), RecordError> {
        let ns = m.tick().get() * self.tick_ns;
        let state = StateRecord::of(m);
        self.write_json(Ch::State, ns, &state)?;
        if self.opts.foxglove {
            let mut buf = std::mem::take(&mut self.buf);
            foxglove::write_transforms(&mut buf, ns, &state);
            let r = self.write_raw(Ch::Tf, ns, &buf);
            self.buf = buf;
            r?;
        }
        self.state = Some(state);
        Ok(())
    }

    /// Records one control tick: the actions that were applied to go from
    /// `m.tick() - 1` to `m.tick()`, the events that step returned, and the
    /// state after it.
    pub fn tick(
        &mut self,
        m: &Match,
        actions: &[Action; ROBOTS],
        events: &[Event],
    ) -> Result<(), RecordError> {
        let tick = m.tick().prev().unwrap_or(Tick::ZERO);
        let ns = tick.get() * self.tick_ns;
        self.write_json(
            Ch::Actions,
            ns,
            &TickActions {
                tick,
                actions: *actions,
            },
        )?;
        for e in events {
            // A match's own events always have a tick (never `Unknown`).
            let at = e.tick().unwrap_or(tick);
            self.write_json(Ch::Events, at.get() * self.tick_ns, e)?;
        }
        self.write_state(m)?;
        if self.opts.flush_every_ticks > 0
            && m.tick().get().is_multiple_of(self.opts.flush_every_ticks)
        {
            self.writer.flush()?;
        }
        Ok(())
    }

    /// Records a state change (protocol 1.5's `set_state`) made before tick
    /// `tick` was played: call it after the change, before that tick's
    /// [`Recorder::tick`]. The first one creates the `/match/set_state`
    /// channel.
    pub fn set_state(&mut self, tick: Tick, change: &StateChange) -> Result<(), RecordError> {
        let (channel, sequence) = match self.set_state {
            Some(c) => c,
            None => {
                let schema = self.writer.add_schema(
                    "naosoccer.SetState",
                    "jsonschema",
                    b"{\"type\":\"object\"}",
                )?;
                let channel =
                    self.writer
                        .add_channel(schema, topics::SET_STATE, "json", &BTreeMap::new())?;
                (channel, 0)
            }
        };
        self.set_state = Some((channel, sequence + 1));
        let record = SetStateRecord::new(tick, change);
        let data = serde_json::to_vec(&record).map_err(|source| RecordError::Json {
            topic: topics::SET_STATE.to_string(),
            source,
        })?;
        let log_time = tick.get() * self.tick_ns;
        let header = MessageHeader {
            channel_id: channel,
            sequence,
            log_time,
            publish_time: log_time,
        };
        self.writer.write_to_known_channel(&header, &data)?;
        Ok(())
    }

    /// Writes the final statistics, the summary and the index, and returns
    /// the number of messages per channel and the underlying writer.
    pub fn finish(mut self, m: &Match) -> Result<(RecordingSummary, Sink), RecordError> {
        let naosoccer_proto::PerTeam { blue, red } = m.score();
        let fin = FinalRecord {
            ticks: m.tick().get(),
            score: ScoreRecord { blue, red },
            stats: m.stats(),
            state_hash: hash_hex(m.state_hash()),
            completed: m.is_finished(),
        };
        self.write_json(Ch::Stats, m.tick().get() * self.tick_ns, &fin)?;
        self.writer.finish()?;
        let mut messages: BTreeMap<String, u64> = topics::ALL
            .iter()
            .zip(self.sequences)
            .map(|(t, n)| (t.to_string(), u64::from(n)))
            .collect();
        if let Some((_, n)) = self.set_state {
            messages.insert(topics::SET_STATE.to_string(), u64::from(n));
        }
        Ok((RecordingSummary { messages }, self.writer.into_inner()))
    }

    /// The last state written.
    pub fn last_state(&self) -> Option<&StateRecord> {
        self.state.as_ref()
    }
}
