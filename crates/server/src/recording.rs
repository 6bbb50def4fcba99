//! Every server match to MCAP: an observer that feeds `naosoccer_record`'s
//! recorder from the match task, one file per match in `record_dir`.
//!
//! Recording never stops a match: a recorder that fails (disk full, say) is
//! logged once and dropped, and the match plays on.

use std::path::{Path, PathBuf};

use naosoccer_proto::msg::{EndReason, MatchEnd, MatchInfo, Mode};
use naosoccer_proto::{StateChange, Tick};
use naosoccer_record::{MatchMeta, Recorder, RecorderOptions};
use naosoccer_referee::Match;

use crate::observer::{MatchObserver, TickRecord};
use crate::ServerConfig;

/// Writes one match to `<dir>/match-<id>-seed-<seed>.mcap`.
pub struct McapObserver {
    dir: PathBuf,
    path: PathBuf,
    rec: Option<Recorder>,
}

impl McapObserver {
    pub fn new(dir: &Path, info: &MatchInfo) -> McapObserver {
        let path = dir.join(format!("match-{}-seed-{}.mcap", info.match_id.0, info.seed));
        McapObserver {
            dir: dir.to_owned(),
            path,
            rec: None,
        }
    }

    /// Where this match is recorded.
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn fail(&mut self, what: &str, e: impl std::fmt::Display) {
        tracing::error!(path = %self.path.display(), error = %e, "recording {what} failed; the match goes on unrecorded");
        self.rec = None;
    }
}

impl MatchObserver for McapObserver {
    fn on_start(&mut self, info: &MatchInfo, game: &Match) {
        let fill = info.fill_team.clone().unwrap_or(info.fill.to_string());
        let players = format!("clients, empty slots {fill}");
        let mut meta = MatchMeta::of(game, &players, &players, "server");
        meta.match_id = Some(info.match_id.0);
        meta.mode = Some(
            match info.mode {
                Mode::Lockstep => "lockstep",
                Mode::Realtime => "realtime",
            }
            .into(),
        );
        if let Err(e) = std::fs::create_dir_all(&self.dir) {
            return self.fail("start", e);
        }
        match Recorder::create(&self.path, &meta, game, RecorderOptions::default()) {
            Ok(r) => {
                tracing::info!(path = %self.path.display(), "recording");
                self.rec = Some(r);
            }
            Err(e) => self.fail("start", e),
        }
    }

    fn on_tick(&mut self, t: &TickRecord<'_>) {
        if let Some(r) = &mut self.rec {
            if let Err(e) = r.tick(t.game, t.actions, t.events) {
                self.fail("a tick", e);
            }
        }
    }

    fn on_state_set(&mut self, tick: Tick, change: &StateChange, _game: &Match) {
        if let Some(r) = &mut self.rec {
            if let Err(e) = r.set_state(tick, change) {
                self.fail("a state change", e);
            }
        }
    }

    fn on_end(&mut self, end: &MatchEnd, game: &Match) {
        if let Some(r) = self.rec.take() {
            match r.finish(game) {
                Ok(_) => tracing::info!(
                    path = %self.path.display(),
                    complete = matches!(end.reason, EndReason::Finished),
                    "recording written"
                ),
                Err(e) => self.fail("the end", e),
            }
        }
    }
}

/// Several observers of one match, called in order.
pub struct Fanout(pub Vec<Box<dyn MatchObserver>>);

impl MatchObserver for Fanout {
    fn on_start(&mut self, info: &MatchInfo, game: &Match) {
        for o in &mut self.0 {
            o.on_start(info, game);
        }
    }
    fn on_tick(&mut self, record: &TickRecord<'_>) {
        for o in &mut self.0 {
            o.on_tick(record);
        }
    }
    fn on_state_set(&mut self, tick: Tick, change: &StateChange, game: &Match) {
        for o in &mut self.0 {
            o.on_state_set(tick, change, game);
        }
    }
    fn on_end(&mut self, end: &MatchEnd, game: &Match) {
        for o in &mut self.0 {
            o.on_end(end, game);
        }
    }
}

/// The observer of a new match: the recorder when `record_dir` is set, plus
/// whatever the hooks provide.
pub(crate) fn observer_for(
    config: &ServerConfig,
    hook: Option<Box<dyn MatchObserver>>,
    info: &MatchInfo,
) -> Option<Box<dyn MatchObserver>> {
    let rec = config
        .record_dir
        .as_deref()
        .map(|dir| Box::new(McapObserver::new(dir, info)) as Box<dyn MatchObserver>);
    match (rec, hook) {
        (None, h) => h,
        (Some(r), None) => Some(r),
        (Some(r), Some(h)) => Some(Box::new(Fanout(vec![r, h]))),
    }
}
