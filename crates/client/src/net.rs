//! The protocol client: connect and handshake, requests with their replies,
//! and the per-tick observation/action loop over a [`Policy`].

use crate::policy::Policy;
use naosoccer_proto::frame::DEFAULT_MAX_FRAME;
use naosoccer_proto::framed::{FrameReader, FrameWriter, WireError};
use naosoccer_proto::msg::{
    ActionRef, ClientMsg, CreateMatch, EndMatch, ErrorCode, ErrorMsg, Hello, Join, Joined, Leave,
    ListMatches, MatchEnd, MatchId, MatchInfo, ObservationMsg, Ping, Player, PlayerAction,
    ServerMsg, SetState, StateSet, Welcome, PROTOCOL_NAME, PROTOCOL_VERSION,
};
use naosoccer_proto::{Action, Team, Tick};
use std::collections::VecDeque;
use tokio::net::tcp::{OwnedReadHalf, OwnedWriteHalf};
use tokio::net::{TcpStream, ToSocketAddrs};

/// What can go wrong on the client side.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ClientError {
    #[error(transparent)]
    Wire(#[from] WireError),
    #[error("could not connect: {0}")]
    Connect(std::io::Error),
    #[error("the server sent a message that is not valid protocol JSON: {0}")]
    Decode(#[from] serde_json::Error),
    /// The server answered with an error.
    #[error("server error: {0}")]
    Server(ErrorMsg),
    #[error("the server closed the connection")]
    Closed,
    #[error("server speaks {protocol} {major}.x, this client {ours}")]
    Version {
        protocol: String,
        major: u32,
        ours: String,
    },
    #[error("unexpected message from the server: {0}")]
    Unexpected(String),
    #[error("policy list does not fit the joined players: {0}")]
    Policies(String),
}

impl ClientError {
    /// The server's error code, if this is a server error.
    pub fn code(&self) -> Option<ErrorCode> {
        match self {
            ClientError::Server(e) => Some(e.code),
            _ => None,
        }
    }
}

/// Something the server pushed while the client plays.
// `MatchEnd` is the largest by far, but a match ends once: boxing it would
// save nothing that matters and change every caller's pattern.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq)]
pub enum Push {
    Observation(ObservationMsg),
    MatchEnd(MatchEnd),
    /// A rejected action (the error names `"in_reply_to": "action"`), or a
    /// server notice such as `unavailable` at shutdown.
    Error(ErrorMsg),
}

/// How a match [`Client::play`] played ended.
#[derive(Debug, Clone, PartialEq)]
pub struct Played {
    pub end: MatchEnd,
    /// Each joined player's return, in join order: the sum over the match of
    /// its rewards (each observation's `reward`, then `match_end`'s
    /// `rewards` for the last tick).
    pub returns: Vec<f32>,
}

/// One connection to a match server, after a successful handshake.
#[derive(Debug)]
pub struct Client {
    reader: FrameReader<OwnedReadHalf>,
    writer: FrameWriter<OwnedWriteHalf>,
    welcome: Welcome,
    /// Pushes that arrived while a request waited for its reply.
    pushes: VecDeque<Push>,
    actions: Vec<PlayerAction>,
}

impl Client {
    /// Connects and performs the `hello`/`welcome` handshake. `name` shows up
    /// in the server's logs.
    pub async fn connect(addr: impl ToSocketAddrs, name: &str) -> Result<Client, ClientError> {
        let stream = TcpStream::connect(addr)
            .await
            .map_err(ClientError::Connect)?;
        Client::handshake(stream, &Hello::new(name)).await
    }

    /// The handshake over an open stream, with a caller-made `hello` (tests
    /// send wrong versions with it).
    pub async fn handshake(stream: TcpStream, hello: &Hello) -> Result<Client, ClientError> {
        // Observations and actions are small and latency-bound.
        stream.set_nodelay(true).map_err(ClientError::Connect)?;
        let (r, w) = stream.into_split();
        let mut reader = FrameReader::new(r, DEFAULT_MAX_FRAME);
        let mut writer = FrameWriter::new(w, DEFAULT_MAX_FRAME);
        writer.send(&ClientMsg::Hello(hello.clone())).await?;
        let welcome = match read_msg(&mut reader).await? {
            ServerMsg::Welcome(w) => w,
            ServerMsg::Error(e) => return Err(ClientError::Server(e)),
            other => return Err(ClientError::Unexpected(format!("{other:?}"))),
        };
        if welcome.protocol != PROTOCOL_NAME || welcome.version.major != PROTOCOL_VERSION.major {
            return Err(ClientError::Version {
                protocol: welcome.protocol,
                major: welcome.version.major,
                ours: PROTOCOL_VERSION.to_string(),
            });
        }
        Ok(Client {
            reader,
            writer,
            welcome,
            pushes: VecDeque::new(),
            actions: Vec::with_capacity(4),
        })
    }

    pub fn welcome(&self) -> &Welcome {
        &self.welcome
    }

    /// Sends one message without waiting for anything.
    pub async fn send(&mut self, msg: &ClientMsg) -> Result<(), ClientError> {
        self.writer.send(msg).await?;
        Ok(())
    }

    /// Sends raw bytes (tests use it for malformed input).
    pub async fn send_raw(&mut self, bytes: &[u8]) -> Result<(), ClientError> {
        self.writer.queue_raw(bytes);
        self.writer.flush().await?;
        Ok(())
    }

    /// The next message from the server, whatever it is (unknown types from
    /// newer servers are skipped).
    pub async fn recv(&mut self) -> Result<ServerMsg, ClientError> {
        loop {
            match read_msg(&mut self.reader).await? {
                ServerMsg::Unknown => continue,
                m => return Ok(m),
            }
        }
    }

    /// Sends a request and waits for its reply, keeping any pushes that come
    /// first for [`next_push`](Client::next_push). An error reply is `Err`.
    pub async fn request(&mut self, msg: &ClientMsg) -> Result<ServerMsg, ClientError> {
        self.send(msg).await?;
        loop {
            match self.recv().await? {
                ServerMsg::Observation(o) => self.pushes.push_back(Push::Observation(o)),
                ServerMsg::MatchEnd(e) => self.pushes.push_back(Push::MatchEnd(e)),
                ServerMsg::Error(e) if e.in_reply_to.as_deref() == Some("action") => {
                    self.pushes.push_back(Push::Error(e))
                }
                ServerMsg::Error(e) => return Err(ClientError::Server(e)),
                reply => return Ok(reply),
            }
        }
    }

    pub async fn create_match(&mut self, req: CreateMatch) -> Result<MatchInfo, ClientError> {
        match self.request(&ClientMsg::CreateMatch(req)).await? {
            ServerMsg::MatchCreated(c) => Ok(c.info),
            other => Err(ClientError::Unexpected(format!("{other:?}"))),
        }
    }

    /// Ends a match early (admin token; protocol 1.2): its clients get their
    /// `match_end` first. Returns the match as it ended.
    pub async fn end_match(
        &mut self,
        token: &str,
        match_id: MatchId,
    ) -> Result<MatchInfo, ClientError> {
        let req = EndMatch {
            token: token.to_owned(),
            match_id,
        };
        match self.request(&ClientMsg::EndMatch(req)).await? {
            ServerMsg::MatchEnded(e) => Ok(e.info),
            other => Err(ClientError::Unexpected(format!("{other:?}"))),
        }
    }

    /// Sets the state of a match (admin token; protocol 1.5): the ball and
    /// robots `req` names go where it says before the match's next tick.
    /// Returns that tick.
    pub async fn set_state(&mut self, req: SetState) -> Result<StateSet, ClientError> {
        match self.request(&ClientMsg::SetState(req)).await? {
            ServerMsg::StateSet(s) => Ok(s),
            other => Err(ClientError::Unexpected(format!("{other:?}"))),
        }
    }

    pub async fn list_matches(&mut self) -> Result<Vec<MatchInfo>, ClientError> {
        match self
            .request(&ClientMsg::ListMatches(ListMatches {}))
            .await?
        {
            ServerMsg::MatchList(l) => Ok(l.matches),
            other => Err(ClientError::Unexpected(format!("{other:?}"))),
        }
    }

    /// Joins `players` of `team`; observations start arriving after this.
    pub async fn join(
        &mut self,
        match_id: Option<MatchId>,
        team: Team,
        token: &str,
        players: &[Player],
    ) -> Result<Joined, ClientError> {
        let req = Join {
            match_id,
            team,
            token: token.to_owned(),
            players: players.to_vec(),
        };
        match self.request(&ClientMsg::Join(req)).await? {
            ServerMsg::Joined(j) => Ok(j),
            other => Err(ClientError::Unexpected(format!("{other:?}"))),
        }
    }

    pub async fn leave(&mut self) -> Result<MatchId, ClientError> {
        match self.request(&ClientMsg::Leave(Leave {})).await? {
            ServerMsg::Left(l) => Ok(l.match_id),
            other => Err(ClientError::Unexpected(format!("{other:?}"))),
        }
    }

    pub async fn ping(&mut self, nonce: u64) -> Result<u64, ClientError> {
        match self.request(&ClientMsg::Ping(Ping { nonce })).await? {
            ServerMsg::Pong(p) => Ok(p.nonce),
            other => Err(ClientError::Unexpected(format!("{other:?}"))),
        }
    }

    /// The next observation, match end or action error.
    pub async fn next_push(&mut self) -> Result<Push, ClientError> {
        if let Some(p) = self.pushes.pop_front() {
            return Ok(p);
        }
        match self.recv().await? {
            ServerMsg::Observation(o) => Ok(Push::Observation(o)),
            ServerMsg::MatchEnd(e) => Ok(Push::MatchEnd(e)),
            ServerMsg::Error(e) if e.fatal => Err(ClientError::Server(e)),
            ServerMsg::Error(e) => Ok(Push::Error(e)),
            other => Err(ClientError::Unexpected(format!("{other:?}"))),
        }
    }

    /// Answers tick `tick` with one action per player.
    pub async fn send_actions(
        &mut self,
        tick: Tick,
        actions: &[PlayerAction],
    ) -> Result<(), ClientError> {
        self.writer
            .send(&ActionRef {
                tick,
                team: None,
                actions,
            })
            .await?;
        Ok(())
    }

    /// Plays the joined match to its end: every observation goes to the
    /// policies, their actions go back tagged with the tick. `policies` holds
    /// either one policy per joined player (in join order; each gets its own
    /// player's observation) or one policy for all of them (`act_batch`).
    /// Returns the match end and each player's return.
    pub async fn play(
        &mut self,
        joined: &Joined,
        policies: &mut [Box<dyn Policy>],
    ) -> Result<Played, ClientError> {
        let n = joined.players.len();
        // Summed in tick order in f32, as `Match::rewards` summed in process.
        let mut returns = vec![0.0f32; n];
        if policies.len() != n && policies.len() != 1 {
            return Err(ClientError::Policies(format!(
                "{} policies for {n} players",
                policies.len()
            )));
        }
        let mut out = [Action::Stay; naosoccer_proto::PLAYERS_PER_TEAM];
        loop {
            let obs = match self.next_push().await? {
                Push::Observation(o) => o,
                Push::MatchEnd(end) => {
                    for (ret, p) in returns.iter_mut().zip(&joined.players) {
                        *ret += end.rewards.get(joined.team)[p.index()];
                    }
                    return Ok(Played { end, returns });
                }
                Push::Error(e) => {
                    tracing::warn!(error = %e, "action rejected");
                    continue;
                }
            };
            if obs.observations.len() != n {
                return Err(ClientError::Unexpected(format!(
                    "{} observations for {n} players",
                    obs.observations.len()
                )));
            }
            for (ret, o) in returns.iter_mut().zip(&obs.observations) {
                *ret += o.reward;
            }
            if policies.len() == n {
                for ((p, o), a) in policies
                    .iter_mut()
                    .zip(&obs.observations)
                    .zip(out.iter_mut())
                {
                    *a = p.act(o);
                }
            } else {
                policies[0].act_batch(&obs.observations, &mut out[..n]);
            }
            let mut actions = std::mem::take(&mut self.actions);
            actions.clear();
            actions.extend(
                joined
                    .players
                    .iter()
                    .zip(out)
                    .map(|(&player, action)| PlayerAction { player, action }),
            );
            let sent = self.send_actions(obs.tick, &actions).await;
            self.actions = actions;
            sent?;
        }
    }
}

async fn read_msg(reader: &mut FrameReader<OwnedReadHalf>) -> Result<ServerMsg, ClientError> {
    match reader.read_frame().await? {
        Some(bytes) => Ok(serde_json::from_slice(bytes)?),
        None => Err(ClientError::Closed),
    }
}
