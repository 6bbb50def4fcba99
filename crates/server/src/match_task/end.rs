//! The end of a match: its `match_end` for every client and the observer,
//! the registry's entry marked finished, whoever ended it told.

use super::{MatchTask, Stop};
use crate::match_msg::{deliver, Outgoing};
use naosoccer_proto::msg::{
    EndReason, ErrorCode, ErrorMsg, MatchEnd, MatchState, PerTeam, ScenarioEnd,
};
use naosoccer_proto::{Event, RobotId, Team, PLAYERS_PER_TEAM};

impl MatchTask {
    pub(super) fn finish(&mut self, stop: Stop) {
        let id = self.params.id;
        let reason = match stop {
            Stop::Finished => EndReason::Finished,
            Stop::Shutdown => EndReason::Shutdown,
            Stop::Panicked => EndReason::Internal,
            Stop::Ended => EndReason::Ended,
        };
        let score = self.game.score();
        let (blue, red) = (score.blue, score.red);
        let end = MatchEnd {
            match_id: id,
            reason,
            tick: self.game.tick(),
            score,
            stats: self.game.stats(),
            misses: self.misses_per_team(),
            rewards: PerTeam {
                blue: self.game.rewards(Team::Blue),
                red: self.game.rewards(Team::Red),
            },
            events: self.unsent_events(reason),
            state_hash: format!("{:016x}", self.game.state_hash()),
            scenario: self.scenario_end(),
        };
        if reason == EndReason::Internal {
            tracing::error!(match_id = %id, tick = end.tick.get(), "match task panicked; ending the match");
            // It answers the actions for the tick that failed, so a client
            // that pairs replies in order pairs it with them.
            let mut e = ErrorMsg::new(
                ErrorCode::Internal,
                format!("match {id} failed inside the server at tick {}; it has ended (the server goes on)", end.tick),
            )
            .in_reply_to("action");
            e.tick = Some(end.tick);
            for c in &self.conns {
                deliver(&c.out, Outgoing::Error(e.clone()));
            }
        }
        tracing::info!(
            match_id = %id,
            ?reason,
            ticks = end.tick.get(),
            blue = blue,
            red = red,
            misses = ?self.misses,
            lateness_p99_us = percentile(&mut self.lateness_us, 0.99),
            "match ended: blue {blue} - {red} red"
        );
        if let Some(o) = &mut self.observer {
            // An observer that panicked mid-tick may panic again here; the
            // clients still get their match_end.
            let finish = std::panic::AssertUnwindSafe(|| o.on_end(&end, &self.game));
            if std::panic::catch_unwind(finish).is_err() {
                tracing::error!(match_id = %id, "the match observer panicked in on_end");
            }
        }
        // Finished before anyone hears of it, so a client that lists matches
        // right after its match_end sees it finished.
        self.listing.finish(|i| {
            i.state = MatchState::Finished;
            i.taken = PerTeam::default();
        });
        for c in self.conns.drain(..) {
            deliver(&c.out, Outgoing::MatchEnd(end.clone()));
        }
        if let Some(reply) = self.ended_by.take() {
            let _ = reply.send(self.listing.info.borrow().clone());
        }
    }

    /// The events `match_end` carries: the last tick's, unless an
    /// observation already took them out (a match ended between ticks) or
    /// the match failed.
    fn unsent_events(&self, reason: EndReason) -> Vec<Event> {
        let sent = self.observed == Some(self.game.tick());
        if sent || reason == EndReason::Internal {
            Vec::new()
        } else {
            self.events.to_vec()
        }
    }

    /// How the scenario's play ended, for a match started from one.
    fn scenario_end(&self) -> Option<Box<ScenarioEnd>> {
        let (name, _, team) = self.game.scenario()?;
        Some(Box::new(ScenarioEnd {
            name: name.to_owned(),
            team,
            ending: self.ending.map(|e| e.kind.name().to_owned()),
            success: self.ending.map(|e| e.success),
            ticks: self.game.tick().saturating_since(self.first_tick),
        }))
    }

    fn misses_per_team(&self) -> PerTeam<[u64; PLAYERS_PER_TEAM]> {
        let mut m = PerTeam::<[u64; PLAYERS_PER_TEAM]>::default();
        for r in RobotId::all() {
            m.get_mut(r.team())[r.player()] = self.misses[r.index()];
        }
        m
    }
}

fn percentile(v: &mut [u32], q: f64) -> Option<u32> {
    if v.is_empty() {
        return None;
    }
    v.sort_unstable();
    let i = ((v.len() - 1) as f64 * q).round() as usize;
    Some(v[i])
}
