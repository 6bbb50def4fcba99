//! What a `Match` answers about itself: observations, the clock, score,
//! statistics, state hash, configuration and the robots' state.

use super::*;

impl Match {
    /// What `player` (0..=3; panics otherwise) of `team` sees now, in its
    /// team's frame (attacking +x).
    pub fn observe(&self, team: Team, player: usize) -> Observation {
        let mut o = observe::blank_observation();
        self.observe_into(team, player, &mut o);
        o
    }

    /// `observe` into a reused observation (no allocation).
    pub fn observe_into(&self, team: Team, player: usize, out: &mut Observation) {
        let down = self.fall.down();
        let set_play = self.set_play.active().map(|a| SetPlayObs {
            kind: a.kind,
            own: a.team == team,
            ticks_left: self.set_play.ticks_left(self.tick),
        });
        let ctx = ObsContext {
            tick: self.tick,
            time_left: self.clock.time_left(self.tick),
            score: self.score,
            down: &down,
            controller: self.controller,
            half: self.clock.half(self.tick),
            set_play,
        };
        observe::fill(self.sim.snapshot(), &ctx, team, player, out);
        out.reward = self.reward(team, player);
    }

    /// Control ticks played so far.
    pub fn tick(&self) -> Tick {
        self.tick
    }

    pub fn total_ticks(&self) -> u64 {
        self.clock.total_ticks()
    }

    pub fn is_finished(&self) -> bool {
        self.finished
    }

    /// Game time played, seconds: ticks over the control rate (the config
    /// check keeps the physics steps of a tick within 1% of a tick).
    pub fn sim_seconds(&self) -> f64 {
        self.tick.get() as f64 / f64::from(self.cfg.control_hz)
    }

    /// Physics steps per control tick.
    pub fn steps_per_tick(&self) -> u32 {
        self.steps_per_tick
    }

    /// The pitch as the protocol's `joined` announces it.
    pub fn pitch(&self) -> Pitch {
        let cfg = &self.cfg;
        Pitch {
            field_length: cfg.sim.field_length,
            field_width: cfg.sim.field_width,
            goal_width: cfg.sim.goal_width,
            goal_depth: cfg.sim.goal_depth,
            goal_height: cfg.sim.goal_height,
            ball_radius: cfg.sim.ball_radius,
            b_d: cfg.rules.b_d,
            b_rad: cfg.rules.b_rad,
            frame: Frame::Team,
        }
    }

    /// Goals per team.
    pub fn score(&self) -> Score {
        self.score
    }

    /// Statistics so far; control rates are shares of the ticks in which any
    /// team controlled the ball (both 0 while nobody has).
    pub fn stats(&self) -> MatchStats {
        let mut s = self.stats;
        let total = s.blue.control_ticks + s.red.control_ticks;
        if total > 0 {
            s.blue.control_rate = s.blue.control_ticks as f64 / total as f64;
            s.red.control_rate = s.red.control_ticks as f64 / total as f64;
        }
        s
    }

    /// The sim's state hash mixed with the referee's state (clock, score,
    /// possession, falls, pass chain): equal hashes mean equal matches.
    pub fn state_hash(&self) -> u64 {
        let mut h = StateHasher::new();
        h.u64(self.sim.state_hash());
        h.u64(self.tick.get());
        h.u64(u64::from(self.finished));
        h.u64(u64::from(self.score.blue));
        h.u64(u64::from(self.score.red));
        h.u64(self.controller.map_or(u64::MAX, |c| c.index() as u64));
        for i in 0..ROBOTS {
            h.u64(self.fall.up_at(i).map_or(u64::MAX, Tick::get));
        }
        h.u64(self.pass.fingerprint());
        h.u64(self.set_play.fingerprint());
        h.u64(self.restart.fingerprint());
        h.u64(self.kickoff.first().index() as u64);
        // Only a scenario takes robots out of play, so matches without one
        // keep the hashes they had before scenarios existed.
        if self.off.contains(&true) {
            h.u64(self.off.iter().fold(0, |acc, &o| acc * 2 + u64::from(o)));
        }
        h.finish()
    }

    pub fn seed(&self) -> u64 {
        self.seed
    }

    pub fn config(&self) -> &MatchConfig {
        &self.cfg
    }

    /// The pitch as the rules see it.
    pub fn field(&self) -> &Field {
        &self.field
    }

    pub fn sim(&self) -> &Sim {
        &self.sim
    }

    /// For tests that stage situations. Changes made here are seen by the
    /// rules at the end of the next tick.
    pub fn sim_mut(&mut self) -> &mut Sim {
        &mut self.sim
    }

    /// For staged situations (training drills, tests) placed with
    /// [`Match::sim_mut`]: forgets the set play in progress (at the start,
    /// the first kick-off), so nobody is held back from the staged ball, and
    /// the restart it was (no kick-off rule, no goal from a restart).
    pub fn clear_set_play(&mut self) {
        self.set_play.clear();
        self.restart.clear();
    }

    /// Who controls the ball (the paper's `if_c`), as of the last tick.
    pub fn controller(&self) -> Option<RobotId> {
        self.controller
    }

    /// Whether the referee counts this robot as lying on the pitch.
    pub fn is_down(&self, robot: RobotId) -> bool {
        self.fall.is_down(robot.index())
    }

    /// The tick at which a lying robot will be stood up.
    pub fn up_at(&self, robot: RobotId) -> Option<Tick> {
        self.fall.up_at(robot.index())
    }
}
