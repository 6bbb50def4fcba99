//! What the registry sees of a match (`list_matches`, `join` without a
//! match id): its `MatchInfo`, first and as joins and leaves change it.

use super::{MatchParams, MatchTask, Slot};
use naosoccer_proto::msg::{Fill, MatchInfo, MatchState, PerTeam, ScenarioInfo};
use naosoccer_proto::{RobotId, PLAYERS_PER_TEAM};
use naosoccer_referee::Match;

impl MatchTask {
    /// The first `MatchInfo` of a match (before its task runs).
    /// A level of the scripted ladder is reported as `fill: "scripted"`
    /// and `fill_team: "scripted:N"` (values every client knows).
    pub(crate) fn initial_info(params: &MatchParams, game: &Match) -> MatchInfo {
        let (fill, level) = match params.fill {
            Fill::ScriptedLevel(n) => (Fill::Scripted, Some(format!("scripted:{n}"))),
            f => (f, None),
        };
        MatchInfo {
            match_id: params.id,
            state: MatchState::Waiting,
            mode: params.mode,
            fill,
            fill_team: params.fill_team.clone().or(level),
            seed: params.seed,
            control_hz: game.config().control_hz,
            tick: game.tick(),
            total_ticks: game.total_ticks(),
            deadline_ms: params.deadline.as_millis() as u64,
            start_players: params.start_players,
            score: game.score(),
            taken: PerTeam::default(),
            scenario: game.scenario().map(|(name, _, team)| ScenarioInfo {
                name: name.to_owned(),
                team,
            }),
        }
    }

    pub(super) fn publish_taken(&self) {
        let mut taken = PerTeam::<[bool; PLAYERS_PER_TEAM]>::default();
        for r in RobotId::all() {
            taken.get_mut(r.team())[r.player()] = matches!(self.slots[r.index()], Slot::Client(_));
        }
        self.listing.info.send_modify(|i| i.taken = taken);
    }
}
