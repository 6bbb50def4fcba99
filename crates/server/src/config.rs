//! The server's configuration: one TOML file, every field optional.

use naosoccer_proto::frame::DEFAULT_MAX_FRAME;
use naosoccer_proto::msg::{Fill, MatchId, Mode};
use naosoccer_proto::Team;
use naosoccer_referee::MatchConfig;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Server settings. The match itself (pitch, rules, length) comes from a
/// match configuration file (`match_config`), with `minutes` as a shortcut.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ServerConfig {
    /// Address to listen on; loopback unless you mean to expose the server.
    pub bind: String,
    pub port: u16,
    /// Default mode of new matches.
    pub mode: Mode,
    /// Who plays slots no client joined.
    pub fill: Fill,
    /// Matches created at start (ids 1..=N), so clients can play without
    /// anyone calling `create_match`.
    pub matches: u32,
    /// Seed of match 1; match i gets `seed + i - 1` unless `create_match`
    /// names one.
    pub seed: u64,
    /// Robots that must be joined before a match's first tick (0..=8);
    /// 8 means every slot is a client.
    pub start_players: u8,
    /// Lockstep: how long a tick waits for actions (milliseconds).
    pub deadline_ms: u64,
    /// Overrides the match length of `match_config`.
    pub minutes: Option<f32>,
    /// Match configuration TOML; relative paths are relative to this file.
    /// Absent: the built-in default (assets/match.toml).
    pub match_config: Option<PathBuf>,
    /// Connections served at once; further ones are refused with `resource_exhausted`.
    pub max_connections: usize,
    /// Unfinished matches at once.
    pub max_matches: usize,
    /// Largest accepted frame payload in bytes.
    pub max_frame: usize,
    /// Per-connection limits and deadlines (`[limits]` table).
    pub limits: Limits,
    pub tokens: TokenConfig,
    /// Directory every match is recorded to (MCAP, one file per match;
    /// docs/RECORDINGS.md). Absent: matches are not recorded. Relative
    /// paths are relative to the working directory.
    pub record_dir: Option<PathBuf>,
    /// The resolved match configuration (from `match_config` and `minutes`).
    #[serde(skip)]
    pub match_cfg: MatchConfig,
    /// Fault injection for the server's own tests, set in code only (not in
    /// the file, not on the wire): the match with this id panics when it
    /// reaches this tick.
    #[doc(hidden)]
    #[serde(skip)]
    pub panic_at: BTreeMap<MatchId, u64>,
}

/// Per-connection limits and deadlines: what one peer may cost the server.
/// Every limit answers with `resource_exhausted` and every deadline with
/// `deadline_exceeded` (see docs/PROTOCOL.md, "Limits"); the server TOML
/// sets them in a `[limits]` table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Limits {
    /// Connections served at once from one IP address.
    pub max_connections_per_addr: usize,
    /// Successful joins over a connection's life (reconnecting is a new connection).
    pub max_joins_per_connection: u32,
    /// Sustained messages per second a connection may send (token bucket)...
    pub messages_per_second: u32,
    /// ...and the burst above that rate. Messages beyond it are refused with a
    /// non-fatal error; a peer that keeps sending another burst's worth while
    /// refused is disconnected.
    pub message_burst: u32,
    /// A connection that has not said hello by then is closed.
    pub hello_timeout_ms: u64,
    /// A frame whose first bytes arrived must be complete within this
    /// (checked every `frame_timeout_ms`, so a stalled frame goes within twice it).
    pub frame_timeout_ms: u64,
    /// A connection outside a match that sends no complete frame for this
    /// long is closed (clients waiting in the lobby send `ping`).
    pub idle_timeout_ms: u64,
    /// A write to a peer that does not read for this long closes the connection.
    pub write_timeout_ms: u64,
    /// Messages a match may queue for one connection; a connection that
    /// falls this far behind is dropped from the match (its robots stand).
    pub max_outbound: usize,
    /// TCP keepalive idle time in seconds (0: off), so dead peers whose
    /// machine vanished are noticed by the kernel.
    pub keepalive_s: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_connections_per_addr: 64,
            max_joins_per_connection: 256,
            // Lockstep training runs thousands of ticks a second on one
            // connection, so the rate is generous; it bounds floods, not play.
            messages_per_second: 20_000,
            message_burst: 20_000,
            hello_timeout_ms: 10_000,
            frame_timeout_ms: 10_000,
            idle_timeout_ms: 600_000,
            write_timeout_ms: 10_000,
            max_outbound: 64,
            keepalive_s: 60,
        }
    }
}

impl Limits {
    fn validate(&self) -> Result<(), ConfigError> {
        let positive = [
            (
                "max_connections_per_addr",
                self.max_connections_per_addr as u64,
            ),
            (
                "max_joins_per_connection",
                u64::from(self.max_joins_per_connection),
            ),
            ("messages_per_second", u64::from(self.messages_per_second)),
            ("message_burst", u64::from(self.message_burst)),
            ("hello_timeout_ms", self.hello_timeout_ms),
            ("frame_timeout_ms", self.frame_timeout_ms),
            ("idle_timeout_ms", self.idle_timeout_ms),
            ("write_timeout_ms", self.write_timeout_ms),
            ("max_outbound", self.max_outbound as u64),
        ];
        for (name, v) in positive {
            if v == 0 {
                return Err(ConfigError::Invalid(format!("{name} must be at least 1")));
            }
        }
        Ok(())
    }
}

/// Access tokens. Missing ones are generated at random at start. None is
/// ever logged; `naosoccer server` prints all three on standard output at
/// start, configured ones too (docs/PROTOCOL.md section 4).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(default, deny_unknown_fields)]
pub struct TokenConfig {
    pub blue: Option<String>,
    pub red: Option<String>,
    pub admin: Option<String>,
}

/// Tokens after start-up: all set.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Tokens {
    pub blue: String,
    pub red: String,
    pub admin: String,
}

impl Tokens {
    pub fn team(&self, team: Team) -> &str {
        match team {
            Team::Blue => &self.blue,
            Team::Red => &self.red,
        }
    }
}

/// Token comparison whose time does not depend on the tokens' contents
/// (`subtle`'s constant-time equality; only a length difference shows).
pub(crate) fn token_eq(given: &str, expected: &str) -> bool {
    use subtle::ConstantTimeEq;
    given.as_bytes().ct_eq(expected.as_bytes()).into()
}

impl Default for ServerConfig {
    fn default() -> Self {
        ServerConfig {
            bind: "127.0.0.1".into(),
            port: 7878,
            mode: Mode::Lockstep,
            fill: Fill::Scripted,
            matches: 1,
            seed: 1,
            start_players: 8,
            deadline_ms: 1000,
            minutes: None,
            match_config: None,
            max_connections: 256,
            max_matches: 64,
            max_frame: DEFAULT_MAX_FRAME,
            limits: Limits::default(),
            tokens: TokenConfig::default(),
            record_dir: None,
            match_cfg: MatchConfig::default(),
            panic_at: BTreeMap::new(),
        }
    }
}

/// A configuration that cannot be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ConfigError {
    #[error("cannot read {path}: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {source}")]
    Parse {
        path: PathBuf,
        source: toml::de::Error,
    },
    #[error("match configuration: {0}")]
    Match(#[from] naosoccer_referee::ConfigError),
    #[error("invalid server configuration: {0}")]
    Invalid(String),
}

impl ServerConfig {
    /// Reads a server configuration file and the match configuration it names.
    pub fn from_file(path: &Path) -> Result<ServerConfig, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Read {
            path: path.to_owned(),
            source,
        })?;
        let mut cfg: ServerConfig = toml::from_str(&text).map_err(|source| ConfigError::Parse {
            path: path.to_owned(),
            source,
        })?;
        if let Some(m) = &cfg.match_config {
            if m.is_relative() {
                let base = path.parent().unwrap_or(Path::new("."));
                cfg.match_config = Some(base.join(m));
            }
        }
        cfg.resolve_match_config()?;
        Ok(cfg)
    }

    /// Loads `match_config` (if set) into `match_cfg` and applies `minutes`.
    pub fn resolve_match_config(&mut self) -> Result<(), ConfigError> {
        if let Some(path) = &self.match_config {
            self.match_cfg = MatchConfig::from_file(path)?;
        }
        if let Some(min) = self.minutes {
            self.match_cfg.minutes = min;
        }
        self.validate()
    }

    pub fn validate(&self) -> Result<(), ConfigError> {
        self.match_cfg.validate()?;
        if self.start_players as usize > naosoccer_proto::ROBOTS {
            return Err(ConfigError::Invalid(format!(
                "start_players {} exceeds 8",
                self.start_players
            )));
        }
        if self.deadline_ms == 0 || self.deadline_ms > 600_000 {
            return Err(ConfigError::Invalid(format!(
                "deadline_ms {} not in 1..=600000",
                self.deadline_ms
            )));
        }
        if self.max_frame < 1024 {
            return Err(ConfigError::Invalid(format!(
                "max_frame {} is below 1024 bytes",
                self.max_frame
            )));
        }
        if self.max_connections == 0 || self.max_matches == 0 {
            return Err(ConfigError::Invalid(
                "max_connections and max_matches must be at least 1".into(),
            ));
        }
        self.limits.validate()?;
        if self.matches as usize > self.max_matches {
            return Err(ConfigError::Invalid(format!(
                "matches {} exceeds max_matches {}",
                self.matches, self.max_matches
            )));
        }
        Ok(())
    }

    /// The configured tokens, with random ones for those not set.
    pub fn resolve_tokens(&mut self) -> Tokens {
        let t = &mut self.tokens;
        Tokens {
            blue: t.blue.get_or_insert_with(random_token).clone(),
            red: t.red.get_or_insert_with(random_token).clone(),
            admin: t.admin.get_or_insert_with(random_token).clone(),
        }
    }
}

fn random_token() -> String {
    use rand::Rng;
    let bytes: [u8; 12] = rand::rng().random();
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn token_eq_compares_whole_tokens() {
        assert!(token_eq("blue-secret", "blue-secret"));
        assert!(!token_eq("blue-secreT", "blue-secret"));
        assert!(!token_eq("blue-secret", "blue-secret-2"));
        assert!(!token_eq("", "blue-secret"));
    }

    #[test]
    fn partial_file_and_tokens() {
        let cfg: ServerConfig =
            toml::from_str("mode = \"realtime\"\n[tokens]\nblue = \"b\"\n").unwrap();
        assert_eq!(cfg.mode, Mode::Realtime);
        assert_eq!(cfg.port, 7878);
        let mut cfg = cfg;
        let t = cfg.resolve_tokens();
        assert_eq!(t.blue, "b");
        assert_eq!(t.red.len(), 24);
        assert_ne!(t.red, t.admin);
        assert_eq!(cfg.resolve_tokens(), t, "resolving twice keeps the tokens");
        assert!(toml::from_str::<ServerConfig>("colour = 1").is_err());
    }
}
