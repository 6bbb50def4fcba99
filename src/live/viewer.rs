//! A minimal Foxglove viewer: it speaks the SDK's WebSocket protocol
//! (`foxglove.sdk.v1`: JSON control messages, binary message data) well
//! enough to subscribe to a match's channels and read what they carry
//! (JSON, and the Foxglove SDK's protobuf messages, decoded with its types).
//! `bench server --viewer` watches its match with it, and the live tests
//! use it as their viewer.

use std::collections::{BTreeMap, BTreeSet, VecDeque};

use anyhow::Context as _;
use foxglove::messages::{FrameTransforms, Log, SceneUpdate};
use foxglove::Decode;
use futures_util::{SinkExt, StreamExt};
use serde_json::{json, Value};
use tokio::net::TcpStream;
use tokio_tungstenite::tungstenite::client::IntoClientRequest;
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::WebSocketStream;

/// The SDK's WebSocket subprotocol.
pub const SUBPROTOCOL: &str = "foxglove.sdk.v1";

/// The topics each match gets (`/match/{id}/{topic}`), the log created last.
pub const TOPICS: [&str; 7] = ["scene", "tf", "state", "score", "events", "stats", "log"];

/// One viewer connection.
pub struct Viewer {
    ws: WebSocketStream<TcpStream>,
    /// Each subscription's message encoding and schema name.
    subs: BTreeMap<u32, (String, String)>,
    /// Message data that arrived while [`Viewer::subscribe`] waited for the
    /// server's answer, handed out first by [`Viewer::next_raw`].
    early: VecDeque<(u32, Vec<u8>)>,
}

/// The id of the request [`Viewer::subscribe`] sends to learn that the
/// server has taken its subscriptions.
const PROBE_ID: &str = "naosoccer-viewer-probe";

/// How often [`Viewer::subscribe`] asks again for a channel the server
/// does not know yet before it gives up.
const SUBSCRIBE_ATTEMPTS: usize = 1000;

impl Viewer {
    /// Connects to a live server at `addr` (`HOST:PORT`) with the SDK's
    /// subprotocol; fails if the server does not speak it.
    pub async fn connect(addr: &str) -> anyhow::Result<Viewer> {
        let mut req = format!("ws://{addr}").into_client_request()?;
        req.headers_mut()
            .insert("sec-websocket-protocol", SUBPROTOCOL.parse()?);
        let tcp = TcpStream::connect(addr)
            .await
            .with_context(|| format!("connecting to the live server {addr}"))?;
        let (ws, resp) = tokio_tungstenite::client_async(req, tcp)
            .await
            .context("the WebSocket handshake")?;
        let proto = resp.headers().get("sec-websocket-protocol");
        anyhow::ensure!(
            proto.is_some_and(|p| p == SUBPROTOCOL),
            "the live server answered with subprotocol {proto:?}, not {SUBPROTOCOL}"
        );
        Ok(Viewer {
            ws,
            subs: BTreeMap::new(),
            early: VecDeque::new(),
        })
    }

    /// Reads control messages until all of match `id`'s channels are
    /// advertised; returns every channel advertised so far, by topic.
    ///
    /// A match's channels are created one after the other, and the SDK may
    /// advertise one a moment before it takes subscriptions for it: this
    /// waits for the whole set (the log channel is created last).
    pub async fn advertised(&mut self, id: u64) -> anyhow::Result<BTreeMap<String, Value>> {
        let all = TOPICS.map(|t| format!("/match/{id}/{t}"));
        let mut channels = BTreeMap::new();
        while !all.iter().all(|t| channels.contains_key(t)) {
            let msg = self
                .ws
                .next()
                .await
                .context("the live server closed before advertising the match")??;
            if let Message::Text(t) = msg {
                let v: Value = serde_json::from_str(&t)?;
                if v["op"] == "advertise" {
                    for c in v["channels"].as_array().into_iter().flatten() {
                        if let Some(topic) = c["topic"].as_str() {
                            channels.insert(topic.to_string(), c.clone());
                        }
                    }
                }
            }
        }
        Ok(channels)
    }

    /// Subscribes to `channels` (advertised channels, as
    /// [`Viewer::advertised`] returns them), each under its subscription id,
    /// one after the other in the order given, each taken by the server
    /// before the next is asked for. A caller can so rely on the order: under
    /// `--wait-viewer` the scene's subscription releases kick-off, and a
    /// viewer that subscribes to the scene last has every other channel from
    /// the first tick on.
    ///
    /// The SDK sends a channel's advertisement a moment before it takes
    /// subscriptions for the channel, and answers one that comes in between
    /// with "Unknown channel ID". So after each subscription this asks the
    /// server something it always answers (a parameter request) and reads
    /// up to the answer: a subscription the server refused in between is
    /// sent again. Message data that arrives meanwhile is kept for
    /// [`Viewer::next_raw`].
    pub async fn subscribe(&mut self, channels: &[(u32, &Value)]) -> anyhow::Result<()> {
        for (sub, c) in channels {
            let field = |k: &str| c[k].as_str().unwrap_or_default().to_string();
            self.subs
                .insert(*sub, (field("encoding"), field("schemaName")));
            let channel = c["id"]
                .as_u64()
                .context("an advertised channel without an id")?;
            let msg =
                json!({"op": "subscribe", "subscriptions": [{"id": sub, "channelId": channel}]});
            let mut attempts = 0;
            loop {
                self.ws.send(Message::Text(msg.to_string().into())).await?;
                if !self.refused_channels().await?.contains(&channel) {
                    break;
                }
                attempts += 1;
                anyhow::ensure!(
                    attempts < SUBSCRIBE_ATTEMPTS,
                    "the live server does not know channel {} ({})",
                    channel,
                    field("topic")
                );
            }
        }
        Ok(())
    }

    /// Asks the server a question it always answers (the parameters, which
    /// it answers with their values, or with an error where it has none) and
    /// reads up to the answer. The server takes a client's messages in
    /// order, so every subscription sent before has been taken or refused
    /// by then. Returns the channels it refused as unknown; message data
    /// read meanwhile is kept for [`Viewer::next_raw`].
    async fn refused_channels(&mut self) -> anyhow::Result<BTreeSet<u64>> {
        let probe = json!({"op": "getParameters", "parameterNames": [], "id": PROBE_ID});
        self.ws
            .send(Message::Text(probe.to_string().into()))
            .await?;
        let mut refused = BTreeSet::new();
        loop {
            let msg = self
                .ws
                .next()
                .await
                .context("the live server closed while taking subscriptions")??;
            match msg {
                Message::Binary(b) if b.len() >= 13 && b[0] == 1 => {
                    let sub = u32::from_le_bytes([b[1], b[2], b[3], b[4]]);
                    self.early.push_back((sub, b[13..].to_vec()));
                }
                Message::Text(t) => {
                    let v: Value = serde_json::from_str(&t)?;
                    let text = v["message"].as_str().unwrap_or_default();
                    match v["op"].as_str() {
                        Some("parameterValues") if v["id"] == PROBE_ID => return Ok(refused),
                        Some("status") if text.contains("parameters") => return Ok(refused),
                        Some("status") => {
                            if let Some(id) = text
                                .strip_prefix("Unknown channel ID: ")
                                .and_then(|n| n.trim().parse().ok())
                            {
                                refused.insert(id);
                            }
                        }
                        _ => {}
                    }
                }
                _ => {}
            }
        }
    }

    /// The next message data frame as (subscription id, payload bytes), or
    /// `None` once the connection is closed or broken. Control messages are
    /// skipped.
    pub async fn next_raw(&mut self) -> Option<(u32, Vec<u8>)> {
        if let Some(early) = self.early.pop_front() {
            return Some(early);
        }
        loop {
            match self.ws.next().await? {
                // Opcode 1 (message data): subscription id, log time, payload.
                Ok(Message::Binary(b)) if b.len() >= 13 && b[0] == 1 => {
                    let sub = u32::from_le_bytes([b[1], b[2], b[3], b[4]]);
                    return Some((sub, b[13..].to_vec()));
                }
                Ok(_) => continue,
                Err(_) => return None,
            }
        }
    }

    /// The next message data frame as (subscription id, payload as JSON):
    /// a JSON channel's message as it is, a Foxglove channel's protobuf
    /// message decoded with the SDK's type and shown as JSON (field names
    /// as in the schema). Frames that do not decode are skipped.
    pub async fn next_data(&mut self) -> Option<(u32, Value)> {
        loop {
            let (sub, b) = self.next_raw().await?;
            if let Some(v) = self.decode(sub, &b) {
                return Some((sub, v));
            }
        }
    }

    fn decode(&self, sub: u32, b: &[u8]) -> Option<Value> {
        fn pb<T: Decode + serde::Serialize>(b: &[u8]) -> Option<Value> {
            serde_json::to_value(T::decode(b).ok()?).ok()
        }
        match self.subs.get(&sub) {
            Some((encoding, schema)) if encoding == "protobuf" => match schema.as_str() {
                "foxglove.SceneUpdate" => pb::<SceneUpdate>(b),
                "foxglove.FrameTransforms" => pb::<FrameTransforms>(b),
                "foxglove.Log" => pb::<Log>(b),
                _ => None,
            },
            _ => serde_json::from_slice(b).ok(),
        }
    }

    /// Closes the connection politely.
    pub async fn close(mut self) {
        let _ = self.ws.close(None).await;
    }
}

/// The robots (`robot_*` entities) in a scene update, and whether it holds
/// the ball, the pitch and the scoreboard.
pub fn scene_contents(scene: &Value) -> SceneContents {
    let ids: Vec<&str> = scene["entities"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|e| e["id"].as_str())
        .collect();
    SceneContents {
        robots: ids.iter().filter(|i| i.starts_with("robot_")).count(),
        ball: ids.contains(&"ball"),
        pitch: ids.contains(&"pitch"),
        scoreboard: ids.contains(&"scoreboard"),
    }
}

/// What [`scene_contents`] found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SceneContents {
    pub robots: usize,
    pub ball: bool,
    pub pitch: bool,
    pub scoreboard: bool,
}
