//! Live viewing: matches streamed to Foxglove over the Foxglove
//! SDK's WebSocket server (docs/RECORDINGS.md, "Watching live").
//!
//! Each match gets its own topics, `/match/{id}/...`: the recording's 3D
//! scene (`foxglove.SceneUpdate`, built by `naosoccer_record`'s scene code)
//! with a scoreboard text above the pitch, the robots' and ball's
//! transforms (`foxglove.FrameTransforms`), the state, the score and clock,
//! the referee events (also as `foxglove.Log`) and the statistics. The
//! Foxglove channels carry the SDK's own message types, protobuf-encoded
//! under the SDK's schemas; the naosoccer channels are JSON.
//!
//! Watching changes nothing: a stream only reads the match after a tick, on
//! the match's own thread, and hands the bytes to the SDK, whose per-viewer
//! queue is bounded ([`BACKLOG`] messages, the oldest dropped when a viewer
//! does not keep up); nothing waits for a viewer. With no viewer subscribed
//! the messages are not even built.

use std::net::SocketAddr;
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use anyhow::Context as _;
use foxglove::messages::{log, FrameTransforms, Log, SceneEntity, SceneUpdate, TextPrimitive};
use foxglove::websocket::{ChannelView, Client, ServerListener};
use foxglove::{Context, Encode, PartialMetadata, RawChannel, Schema, WebSocketServerHandle};
use naosoccer_proto::{Event, MatchStats, Team, Tick};
use naosoccer_record::foxglove as scene;
use naosoccer_record::StateRecord;
use naosoccer_referee::Match;
use serde_json::json;

pub mod viewer;

/// Where `--live` listens when no address is given.
pub const DEFAULT_ADDR: &str = "127.0.0.1:8765";

/// Messages queued per viewer before the oldest are dropped.
pub const BACKLOG: usize = 256;

/// The pitch is re-sent in the scene once every this many ticks (1 s at
/// 10 Hz), so a viewer that connects mid-match sees it; the robots, the
/// ball and the scoreboard go out every tick.
const PITCH_EVERY: u64 = 10;

/// Counts subscriptions, so a runner can wait for its first viewer.
#[derive(Default)]
struct Viewers {
    subscribed: Mutex<u64>,
    changed: Condvar,
}

impl ServerListener for Viewers {
    fn on_subscribe(&self, _client: Client, channel: ChannelView) {
        if channel.topic().ends_with("/scene") {
            *self.subscribed.lock().unwrap() += 1;
            self.changed.notify_all();
        }
    }
}

/// The WebSocket server and its channels' context.
pub struct LiveServer {
    ctx: Arc<Context>,
    handle: Option<WebSocketServerHandle>,
    viewers: Arc<Viewers>,
    addr: SocketAddr,
}

impl LiveServer {
    /// Starts the server on `addr` (`HOST:PORT`; port 0 picks a free one)
    /// and prints `live: ws://HOST:PORT` on stderr.
    pub fn start(addr: &str) -> anyhow::Result<LiveServer> {
        let sock: SocketAddr = addr
            .parse()
            .with_context(|| format!("--live {addr}: expected HOST:PORT, e.g. {DEFAULT_ADDR}"))?;
        let ctx = Context::new();
        let viewers = Arc::new(Viewers::default());
        let handle = ctx
            .websocket_server()
            .name(format!("naosoccer {}", env!("CARGO_PKG_VERSION")))
            .bind(sock.ip().to_string(), sock.port())
            .message_backlog_size(BACKLOG)
            .listener(viewers.clone())
            .start_blocking()
            .with_context(|| format!("starting the live server on {addr}"))?;
        let addr = SocketAddr::new(sock.ip(), handle.port());
        eprintln!("live: ws://{addr} (in Foxglove: Open connection, Foxglove WebSocket)");
        Ok(LiveServer {
            ctx,
            handle: Some(handle),
            viewers,
            addr,
        })
    }

    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// Blocks until a viewer has subscribed to a scene channel (or `timeout`
    /// passed); true if one did.
    pub fn wait_for_viewer(&self, timeout: Duration) -> bool {
        let guard = self.viewers.subscribed.lock().unwrap();
        let (guard, _) = self
            .viewers
            .changed
            .wait_timeout_while(guard, timeout, |n| *n == 0)
            .unwrap();
        *guard > 0
    }

    /// The channels of match `id`.
    pub fn stream(&self, id: u64) -> anyhow::Result<MatchStream> {
        MatchStream::new(&self.ctx, id)
    }
}

impl LiveServer {
    /// After the last tick: waits while viewers are still connected (at most
    /// `linger`), so that they receive what is queued for them, then stops.
    pub fn finish(mut self, linger: Duration) {
        self.linger(linger);
        if let Some(h) = self.handle.take() {
            drop(h.stop());
        }
    }

    /// Waits while viewers are still connected, at most `linger`, so that
    /// they receive what is queued for them (the server's last ticks).
    pub fn linger(&self, linger: Duration) {
        let end = Instant::now() + linger;
        if let Some(h) = &self.handle {
            while h.client_count() > 0 && Instant::now() < end {
                std::thread::sleep(Duration::from_millis(20));
            }
        }
    }
}

/// How long `--live` keeps serving connected viewers after the match ends.
pub const LINGER: Duration = Duration::from_secs(5);

impl Drop for LiveServer {
    fn drop(&mut self) {
        if let Some(h) = self.handle.take() {
            // Shut down in the background: the caller is done with it.
            drop(h.stop());
        }
    }
}

fn wall_ns() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_nanos() as u64)
        .unwrap_or(0)
}

/// One match's channels.
pub struct MatchStream {
    id: u64,
    scene: Arc<RawChannel>,
    tf: Arc<RawChannel>,
    state: Arc<RawChannel>,
    score: Arc<RawChannel>,
    events: Arc<RawChannel>,
    stats: Arc<RawChannel>,
    /// The events again as `foxglove.Log`, for Foxglove's Log panel.
    log: Arc<RawChannel>,
    /// The recording's scene entities, encoded once at kick-off, each part
    /// a whole `SceneUpdate` (protobuf messages concatenate into one whose
    /// entities are all of theirs): the pitch, and the robots and ball
    /// (frame-locked: the transforms move them).
    pitch: Vec<u8>,
    bodies: Vec<u8>,
    /// Where the scoreboard floats: above the far touch line.
    board_y: f32,
    /// The scenario the match started from (docs/SCENARIOS.md): its name
    /// and the colour of its own team, shown on the scoreboard and sent
    /// with the score.
    scenario: Option<(String, Team)>,
    buf: Vec<u8>,
}

fn channel(
    ctx: &Arc<Context>,
    topic: String,
    encoding: &str,
    schema: Schema,
) -> anyhow::Result<Arc<RawChannel>> {
    ctx.channel_builder(topic.clone())
        .message_encoding(encoding)
        .schema(schema)
        .build_raw()
        .with_context(|| format!("creating the live channel {topic}"))
}

/// A naosoccer channel: JSON objects.
fn json_channel(
    ctx: &Arc<Context>,
    topic: String,
    schema: &str,
) -> anyhow::Result<Arc<RawChannel>> {
    let any_object = b"{\"type\":\"object\"}".to_vec();
    channel(
        ctx,
        topic,
        "json",
        Schema::new(schema, "jsonschema", any_object),
    )
}

/// A Foxglove channel: the SDK's type `T`, protobuf.
fn foxglove_channel<T: Encode>(
    ctx: &Arc<Context>,
    topic: String,
) -> anyhow::Result<Arc<RawChannel>> {
    channel(ctx, topic, scene::ENCODING, scene::schema::<T>())
}

impl MatchStream {
    fn new(ctx: &Arc<Context>, id: u64) -> anyhow::Result<MatchStream> {
        let t = |name: &str| format!("/match/{id}/{name}");
        Ok(MatchStream {
            id,
            scene: foxglove_channel::<SceneUpdate>(ctx, t("scene"))?,
            tf: foxglove_channel::<FrameTransforms>(ctx, t("tf"))?,
            state: json_channel(ctx, t("state"), "naosoccer.State")?,
            score: json_channel(ctx, t("score"), "naosoccer.Score")?,
            events: json_channel(ctx, t("events"), "naosoccer.Event")?,
            stats: json_channel(ctx, t("stats"), "naosoccer.Stats")?,
            log: foxglove_channel::<Log>(ctx, t("log"))?,
            pitch: Vec::new(),
            bodies: Vec::new(),
            board_y: 0.0,
            scenario: None,
            buf: Vec::with_capacity(4096),
        })
    }

    pub fn id(&self) -> u64 {
        self.id
    }

    /// Whether any viewer is subscribed to any of this match's channels.
    pub fn watched(&self) -> bool {
        [
            &self.scene,
            &self.tf,
            &self.state,
            &self.score,
            &self.events,
            &self.stats,
            &self.log,
        ]
        .iter()
        .any(|c| c.has_sinks())
    }

    /// Takes the scene (pitch, robot bodies, ball) and the scenario, if
    /// any, from `m` at kick-off.
    pub fn begin(&mut self, m: &Match) {
        self.scenario = m.scenario().map(|(name, _, own)| (name.to_string(), own));
        let update = |entities| SceneUpdate {
            deletions: Vec::new(),
            entities,
        };
        self.pitch = scene::encode(&update(vec![scene::pitch(m)]));
        self.bodies = scene::encode(&update(scene::bodies(m)));
        self.board_y = m.field().half_width + 0.9;
    }

    /// Only the events of a tick (`server --live` between two sent ticks).
    pub fn events_only(&mut self, events: &[Event]) {
        self.publish_events(events, wall_ns());
    }

    fn publish_events(&mut self, events: &[Event], now: u64) {
        let meta = PartialMetadata::with_log_time(now);
        for e in events {
            if self.events.has_sinks() {
                if let Ok(b) = serde_json::to_vec(e) {
                    self.events.log_with_meta(&b, meta);
                }
            }
            if self.log.has_sinks() {
                let msg = Log {
                    timestamp: Some(scene::timestamp(now)),
                    level: log::Level::Info as i32,
                    message: serde_json::to_string(e).unwrap_or_default(),
                    name: format!("match {}", self.id),
                    file: String::new(),
                    line: 0,
                };
                self.log.log_with_meta(&scene::encode(&msg), meta);
            }
        }
    }

    /// Publishes one tick: `state` after it, the events it produced, and
    /// (when known) the statistics so far.
    pub fn tick(&mut self, state: &StateRecord, events: &[Event], stats: Option<&MatchStats>) {
        let now = wall_ns();
        let meta = PartialMetadata::with_log_time(now);
        self.publish_events(events, now);
        let secs = state.time.max(0.0) as u64;
        let clock = format!("{:02}:{:02}", secs / 60, secs % 60);
        let mut text = format!(
            "blue {} - {} red   {clock}",
            state.score.blue, state.score.red
        );
        if let Some((name, own)) = &self.scenario {
            text = format!("{name} ({own}): {text}");
        }
        if self.scene.has_sinks() {
            // One SceneUpdate with the entities [pitch?, bodies, scoreboard]:
            // the encoded updates one after the other (the static parts
            // encoded once), as protobuf merges repeated fields by appending.
            let board = SceneUpdate {
                deletions: Vec::new(),
                entities: vec![scoreboard(self.board_y, &text)],
            };
            let b = &mut self.buf;
            b.clear();
            if state.tick.get().is_multiple_of(PITCH_EVERY) {
                b.extend_from_slice(&self.pitch);
            }
            b.extend_from_slice(&self.bodies);
            board
                .encode(&mut *b)
                .expect("encoding into a Vec cannot fail");
            self.scene.log_with_meta(b, meta);
        }
        if self.tf.has_sinks() {
            scene::write_transforms(&mut self.buf, now, state);
            self.tf.log_with_meta(&self.buf, meta);
        }
        if self.state.has_sinks() {
            if let Ok(b) = serde_json::to_vec(state) {
                self.state.log_with_meta(&b, meta);
            }
        }
        if self.score.has_sinks() {
            let mut msg = json!({"tick": state.tick, "time": state.time, "clock": clock,
                "blue": state.score.blue, "red": state.score.red, "text": text});
            if let Some((name, own)) = &self.scenario {
                msg["scenario"] = json!({"name": name, "team": own});
            }
            if let Ok(b) = serde_json::to_vec(&msg) {
                self.score.log_with_meta(&b, meta);
            }
        }
        if let Some(s) = stats {
            self.publish_stats(s, meta);
        }
    }

    /// [`MatchStream::tick`] for the in-process match `m` as it stands,
    /// with its statistics when `with_stats`.
    pub fn tick_of(&mut self, m: &Match, events: &[Event], with_stats: bool) {
        let stats = with_stats.then(|| m.stats());
        self.tick(&StateRecord::of(m), events, stats.as_ref());
    }

    fn publish_stats(&self, stats: &MatchStats, meta: PartialMetadata) {
        if self.stats.has_sinks() {
            if let Ok(b) = serde_json::to_vec(stats) {
                self.stats.log_with_meta(&b, meta);
            }
        }
    }
}

/// The scoreboard: a text that always faces the camera, above `y`.
fn scoreboard(y: f32, text: &str) -> SceneEntity {
    let mut e = scene::entity(scene::WORLD_FRAME, "scoreboard", false);
    e.texts = vec![TextPrimitive {
        pose: scene::pose(0.0, y, 0.6),
        billboard: true,
        font_size: 28.0,
        scale_invariant: true,
        color: scene::rgba(1.0, 1.0, 1.0, 1.0),
        text: text.to_string(),
    }];
    e
}

impl Drop for MatchStream {
    /// A match's topics go away with it (a server runs many in turn).
    fn drop(&mut self) {
        for c in [
            &self.scene,
            &self.tf,
            &self.state,
            &self.score,
            &self.events,
            &self.stats,
            &self.log,
        ] {
            c.close();
        }
    }
}

/// Real-time pacing: tick `t` is due `t / (control_hz × speed)` seconds
/// after the start. Only wall-clock waiting; the match never reads it.
pub struct Pace {
    start: Instant,
    tick_secs: f64,
}

impl Pace {
    pub fn new(control_hz: f32, speed: f64) -> Pace {
        Pace {
            start: Instant::now(),
            tick_secs: 1.0 / (f64::from(control_hz) * speed),
        }
    }

    /// Sleeps until tick `tick` is due.
    pub fn wait(&self, tick: u64) {
        let due = self.start + Duration::from_secs_f64(tick as f64 * self.tick_secs);
        let now = Instant::now();
        if due > now {
            std::thread::sleep(due - now);
        }
    }
}

/// `server --live` sends a match's scene, transforms, state and score at
/// most this often (wall clock): a lockstep match can play thousands of
/// ticks a second, more than a viewer can draw. Events, their log lines and
/// the statistics are never skipped.
pub const SERVER_MAX_HZ: f64 = 30.0;

/// `server --live`: each server match's stream, fed by the match task.
pub struct LiveObserver {
    stream: MatchStream,
    last_sent: Option<Instant>,
    last_stats_tick: Tick,
}

impl LiveObserver {
    /// The observer of server match `id`, its channels advertised from now.
    pub fn new(server: &LiveServer, id: u64) -> anyhow::Result<LiveObserver> {
        Ok(LiveObserver {
            stream: server.stream(id)?,
            last_sent: None,
            last_stats_tick: Tick::ZERO,
        })
    }
}

impl naosoccer_server::MatchObserver for LiveObserver {
    fn on_start(&mut self, _info: &naosoccer_proto::msg::MatchInfo, game: &Match) {
        self.stream.begin(game);
        if self.stream.watched() {
            self.stream.tick_of(game, &[], true);
        }
    }

    fn on_tick(&mut self, r: &naosoccer_server::TickRecord<'_>) {
        if !self.stream.watched() {
            return;
        }
        let m = r.game;
        let now = Instant::now();
        let due = self
            .last_sent
            .is_none_or(|t| now.duration_since(t).as_secs_f64() >= 1.0 / SERVER_MAX_HZ);
        if due || m.is_finished() {
            self.last_sent = Some(now);
            // Statistics at least 10 ticks apart, and at the end.
            let with_stats = m.tick() >= self.last_stats_tick + PITCH_EVERY || m.is_finished();
            if with_stats {
                self.last_stats_tick = m.tick();
            }
            self.stream.tick_of(m, r.events, with_stats);
        } else {
            self.stream.events_only(r.events);
        }
    }

    fn on_end(&mut self, end: &naosoccer_proto::msg::MatchEnd, _game: &Match) {
        self.stream
            .publish_stats(&end.stats, PartialMetadata::with_log_time(wall_ns()));
    }
}
