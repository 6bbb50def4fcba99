//! `Match`, the one driver: apply actions, step the sim for one control tick,
//! run the rules, apply their commands, keep score and statistics.

use naosoccer_proto::msg::{Frame, Pitch};
use naosoccer_proto::{
    Action, Event, GoalPhase, MatchStats, Observation, RobotId, Score, SetPlayKind, SetPlayObs,
    Team, Tick, PLAYERS_PER_TEAM, ROBOTS,
};
use naosoccer_sim::{Command as SimCommand, RobotModel, Sim, SimError, StateHasher};

use crate::config::{ConfigError, MatchConfig, RewardConfig};
use crate::observe::{self, ObsContext};
use crate::rules::{
    goal::Scored, segment_distance, Clock, Command, FallRule, Field, GoalRule, KickOff,
    OutOfBoundsRule, Outcome, PassMade, PassRule, PossessionRule, RestartRule, SetPlayRule,
};
use crate::scenario::ScenarioError;

/// Why a match could not be set up.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MatchError {
    #[error(transparent)]
    Config(#[from] ConfigError),
    #[error("cannot build the simulation: {0}")]
    Sim(#[from] SimError),
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
}

mod start;

/// One match: the sim, the rules and everything they remember.
pub struct Match {
    cfg: MatchConfig,
    seed: u64,
    sim: Sim,
    field: Field,
    steps_per_tick: u32,
    clock: Clock,
    kickoff: KickOff,
    goal: GoalRule,
    out_of_bounds: OutOfBoundsRule,
    fall: FallRule,
    possession: PossessionRule,
    pass: PassRule,
    set_play: SetPlayRule,
    restart: RestartRule,
    /// Control ticks played.
    tick: Tick,
    finished: bool,
    /// The start's kick-off (or a scenario's set play), announced with the
    /// first tick's events.
    announce: Option<Event>,
    /// Robots out of play (a scenario's absent robots): the sim holds them
    /// off the pitch and their actions are ignored.
    off: [bool; ROBOTS],
    /// The scenario the match started from: its name, its file's text and
    /// the own team's colour (what a recording needs to re-create the start).
    scenario: Option<(std::sync::Arc<str>, std::sync::Arc<str>, Team)>,
    controller: Option<RobotId>,
    /// Goals, indexed by `Team::index`.
    score: Score,
    stats: MatchStats,
    /// The team that scored during the last tick (for the reward).
    last_goal: Option<Team>,
    /// The shaping terms of the last tick's reward, by robot index: the
    /// potential-based terms and the pass bonus (see `RewardConfig`).
    shaping: [f32; ROBOTS],
    outcome: Outcome,
}

impl Match {
    /// A match at its kick-off: every robot in its place, the ball on the centre spot.
    pub fn new(cfg: &MatchConfig, seed: u64) -> Result<Match, MatchError> {
        cfg.validate()?;
        let model = RobotModel::builtin()?;
        let sim = Sim::new(&cfg.sim, &model, seed)?;
        let field = Field::from_sim(&cfg.sim);
        let r = &cfg.rules;
        let steps_per_tick = crate::sim_glue::steps_per_tick(&cfg.sim, cfg.control_hz);
        let standup_ticks =
            (f64::from(r.standup_seconds) * f64::from(cfg.control_hz)).round() as u64;
        let mut m = Match {
            seed,
            sim,
            field,
            steps_per_tick,
            clock: Clock::new(cfg.minutes, cfg.control_hz, r.halves),
            kickoff: KickOff::new(r, KickOff::first_team(r.first_kickoff, seed)),
            goal: GoalRule::new(field, r.goal_area_depth, r.goal_area_width),
            out_of_bounds: OutOfBoundsRule::new(
                field,
                r.ball_inset,
                r.robot_out_margin,
                r.goal_area_depth,
                r.goal_area_width,
            ),
            fall: FallRule::new(r.fall_height, r.fall_tilt, standup_ticks),
            possession: PossessionRule::new(r.b_d, r.b_rad),
            pass: PassRule::new(),
            set_play: SetPlayRule::new(
                r.set_play_distance,
                (f64::from(r.set_play_seconds) * f64::from(cfg.control_hz)).round() as u64,
            ),
            restart: RestartRule::new(
                !r.direct_kick_off_goals,
                (f64::from(r.restart_goal_seconds) * f64::from(cfg.control_hz)).round() as u64,
            ),
            tick: Tick::ZERO,
            finished: false,
            announce: None,
            off: [false; ROBOTS],
            scenario: None,
            controller: None,
            score: Score::default(),
            stats: MatchStats::default(),
            last_goal: None,
            shaping: [0.0; ROBOTS],
            outcome: Outcome::default(),
            cfg: cfg.clone(),
        };
        m.place_for_kickoff(m.kickoff.first(), Tick::ZERO);
        m.announce = Some(Event::KickOff {
            tick: Tick::ZERO,
            team: m.kickoff.first(),
        });
        Ok(m)
    }

    /// The team that kicks off the first half (the configuration's
    /// `first_kickoff`: a named team or the seeded coin toss).
    pub fn first_kickoff(&self) -> Team {
        self.kickoff.first()
    }

    /// The half being played at the current tick: 1 or 2.
    pub fn half(&self) -> u8 {
        self.clock.half(self.tick)
    }

    /// The set play in progress: its kind, the team taking it and the
    /// control ticks left before the other team may approach anyway.
    pub fn set_play(&self) -> Option<(SetPlayKind, Team, u32)> {
        self.set_play
            .active()
            .map(|a| (a.kind, a.team, self.set_play.ticks_left(self.tick)))
    }

    /// Plays one control tick with these actions (robot index order: blue
    /// players 0..=3, then red 0..=3) and returns the tick's events. A robot
    /// lying on the pitch ignores its action. After the end, does nothing.
    pub fn step(&mut self, actions: &[Action; ROBOTS]) -> &[Event] {
        self.step_observed(actions, |_| {})
    }

    /// [`Match::step`], calling `after_physics` with the sim after each of
    /// the tick's physics steps (before the rules run): for tests and
    /// audits that check what happens between two control ticks.
    pub fn step_observed(
        &mut self,
        actions: &[Action; ROBOTS],
        mut after_physics: impl FnMut(&Sim),
    ) -> &[Event] {
        self.outcome.clear();
        self.last_goal = None;
        if self.finished {
            return &self.outcome.events;
        }
        let tick = self.tick;
        if let Some(e) = self.announce.take() {
            self.outcome.events.push(e);
        }
        // A step of `forward` covers about walk_speed / control_hz: the
        // keep-out margin, so a robot on the edge cannot step inside.
        let step_margin = self.cfg.sim.walk_speed * 1.2 / self.cfg.control_hz;
        let kept_out = self.set_play.active().map(|a| a.team.other());
        for (i, &a) in actions.iter().enumerate() {
            let snap = &self.sim.snapshot().robots[i];
            let robot_team = RobotId::from_index(i).map(RobotId::team);
            let cmd = if self.fall.is_down(i) || self.off[i] {
                SimCommand::Stay
            } else if matches!(a, Action::Shoot | Action::Pass) && robot_team == kept_out {
                // Set play: the other team may not kick.
                SimCommand::Stay
            } else if a == Action::Forward
                && RobotId::from_index(i).is_some_and(|robot| {
                    self.set_play.blocks_forward(
                        robot,
                        snap.pos[0],
                        snap.pos[1],
                        snap.heading,
                        step_margin,
                    )
                })
            {
                // Set play: the other team keeps its distance.
                SimCommand::Stay
            } else {
                sim_command(a)
            };
            if cmd == SimCommand::Pass && !self.sim.snapshot().robots[i].kicking {
                // The receiver is chosen from the kicker's observation, as a
                // client would choose it (`proto::pass_receiver`).
                let robot = RobotId::from_index(i).expect("a robot index");
                let obs = self.observe(robot.team(), robot.player());
                let target = naosoccer_proto::pass_receiver(&obs).map(|j| {
                    let r =
                        &self.sim.snapshot().robots[robot.team().index() * PLAYERS_PER_TEAM + j];
                    [r.pos[0], r.pos[1]]
                });
                self.sim.set_pass_target(i, target);
            }
            self.sim.set_command(i, cmd);
        }
        let potential_before = self.potentials();
        let first_step = self.sim.snapshot().step;
        let mut aimed = [false; ROBOTS];
        for _ in 0..self.steps_per_tick {
            self.sim.step();
            after_physics(&self.sim);
            // Kicks are reported per physics step; gather the tick's.
            let snap = self.sim.snapshot();
            let ball = [snap.ball.pos[0], snap.ball.pos[1]];
            for k in &snap.kicks {
                if let Some(robot) = RobotId::from_index(k.robot) {
                    self.outcome.events.push(Event::Kick {
                        tick,
                        robot,
                        speed: k.speed,
                    });
                    self.pass.kick(robot, ball);
                    if self.cfg.reward.aim > 0.0 {
                        aimed[k.robot] |=
                            aims_at_teammate(&self.cfg.reward, snap, &self.fall.down(), robot);
                    }
                }
            }
        }
        // Shaping between the state the tick started from and the state its
        // physics reached, before any restart: a restart's jump (the ball
        // back to the centre after a goal, out to a set-play spot) is
        // neither paid nor charged, so a goal is not charged the progress
        // it took to score it.
        let potential_after = self.potentials();
        let gamma = self.cfg.reward.shaping_gamma;
        for ((s, before), after) in self
            .shaping
            .iter_mut()
            .zip(potential_before)
            .zip(potential_after)
        {
            *s = gamma * after - before;
        }
        for (s, aimed) in self.shaping.iter_mut().zip(aimed) {
            if aimed {
                *s += self.cfg.reward.aim;
            }
        }
        if self.cfg.reward.crowd > 0.0 {
            self.charge_crowding();
        }
        if self.cfg.reward.ahead > 0.0 {
            self.pay_ahead();
        }
        // The robots that touched the ball during the tick's physics steps.
        let touched: [bool; ROBOTS] = std::array::from_fn(|i| {
            self.sim.snapshot().robots[i]
                .last_ball_touch_step
                .is_some_and(|s| s > first_step)
        });
        self.restart.touches(&touched);
        self.run_rules(tick);
        self.apply_commands(tick);
        self.keep_out(tick);
        for e in &self.outcome.events {
            apply_stats(&mut self.stats, e);
        }
        self.tick = self.tick.next();
        &self.outcome.events
    }

    /// Each robot's shaping potential in the current state: `progress`
    /// times the ball's x in its team's frame minus `approach` times its
    /// distance to the ball; with `support`, the approach term only for its
    /// team's chaser, `support` times the distance to its support spot for
    /// the `support_robots` next nearest, and neither for the rest
    /// (`RewardConfig::support`).
    fn potentials(&self) -> [f32; ROBOTS] {
        let w = &self.cfg.reward;
        let snap = self.sim.snapshot();
        let [bx, by, _] = snap.ball.pos;
        let dist = ball_distances(snap);
        if w.support <= 0.0 {
            return std::array::from_fn(|i| {
                let sx = if i < PLAYERS_PER_TEAM { 1.0 } else { -1.0 };
                w.progress * sx * bx - w.approach * dist[i]
            });
        }
        // Each robot's rank in its team by distance to the ball (the lower
        // index first on a tie): 0 is the team's chaser.
        let rank = |i: usize| teammates(i).filter(|&j| nearer_ball(&dist, j, i)).count();
        let (lx, ly) = (
            (self.field.half_length - 0.3).max(0.0),
            (self.field.half_width - 0.3).max(0.0),
        );
        std::array::from_fn(|i| {
            let team = i / PLAYERS_PER_TEAM;
            let sx = if team == 0 { 1.0 } else { -1.0 };
            let progress = w.progress * sx * bx;
            match rank(i) {
                0 => return progress - w.approach * dist[i],
                r if r > w.support_robots as usize => return progress,
                _ => {}
            }
            let r = &snap.robots[i];
            let side = if r.pos[1] >= by { 1.0 } else { -1.0 };
            let spot_x = (bx + sx * w.support_ahead).clamp(-lx, lx);
            let spot_y = (by + side * w.support_side).clamp(-ly, ly);
            progress - w.support * (spot_x - r.pos[0]).hypot(spot_y - r.pos[1])
        })
    }

    /// `RewardConfig::crowd`: charges each standing robot within
    /// `crowd_radius` of a standing teammate nearer the ball, in the state
    /// the tick's physics reached (before any restart).
    fn charge_crowding(&mut self) {
        let w = &self.cfg.reward;
        let snap = self.sim.snapshot();
        let down = self.fall.down();
        let dist = ball_distances(snap);
        for i in 0..ROBOTS {
            if down[i] {
                continue;
            }
            let [x, y, _] = snap.robots[i].pos;
            let crowded = teammates(i).any(|j| {
                let [xj, yj, _] = snap.robots[j].pos;
                !down[j] && nearer_ball(&dist, j, i) && (xj - x).hypot(yj - y) < w.crowd_radius
            });
            if crowded {
                self.shaping[i] -= w.crowd;
            }
        }
    }

    /// `RewardConfig::ahead`: pays each standing robot but its team's
    /// chaser that stands ahead of the ball, in the state the tick's
    /// physics reached (before any restart), while its team has the ball
    /// (a teammate controlled it at the start of the tick).
    fn pay_ahead(&mut self) {
        let Some(holder) = self.controller else {
            return;
        };
        let w = &self.cfg.reward;
        let snap = self.sim.snapshot();
        let down = self.fall.down();
        let bx = snap.ball.pos[0];
        let dist = ball_distances(snap);
        let sx = if holder.index() < PLAYERS_PER_TEAM {
            1.0
        } else {
            -1.0
        };
        for i in teammates(holder.index()) {
            let chaser = !teammates(i).any(|j| nearer_ball(&dist, j, i));
            if down[i] || chaser || dist[i] < w.ahead_min || dist[i] > w.ahead_max {
                continue;
            }
            if sx * (snap.robots[i].pos[0] - bx) < w.ahead_by {
                continue;
            }
            self.shaping[i] += w.ahead;
        }
    }

    fn run_rules(&mut self, tick: Tick) {
        let snap = self.sim.snapshot();
        let out = &mut self.outcome;
        let scored = self.goal.check(snap, tick, &self.restart, out);
        if let Some(Scored::Goal(team)) = scored {
            *self.score.get_mut(team) += 1;
            self.last_goal = Some(team);
        }
        let ball_replaced =
            scored.is_some() || self.out_of_bounds.check_ball(snap, tick, out).is_some();
        if !matches!(scored, Some(Scored::Goal(_))) {
            // After a goal every robot goes to its kick-off place anyway.
            self.out_of_bounds
                .check_robots(snap, &self.kickoff, &self.off, tick, out);
        }
        self.fall.check(snap, tick, out);
        if !ball_replaced {
            self.set_play.check(snap, tick);
        }
        if ball_replaced {
            // The ball is taken out of play: nobody controls it and no pass spans the restart.
            self.controller = None;
            self.pass.reset();
        } else {
            self.controller = self.possession.controller(snap, &self.fall.down());
            let ball = [snap.ball.pos[0], snap.ball.pos[1]];
            if let Some(p) = self.pass.control(self.controller, ball, tick, out) {
                pass_bonus(&self.cfg.reward, &mut self.shaping, p);
            }
        }
        if let Some(c) = self.controller {
            self.stats.team_mut(c.team()).control_ticks += 1;
        }
        if self
            .clock
            .check_half_time(tick, self.kickoff.second(), &mut Outcome::default())
        {
            // The half-time kick-off replaces any restart this tick asked for.
            out.commands
                .retain(|c| !matches!(c, Command::KickOff { .. } | Command::SetPlay { .. }));
            self.clock.check_half_time(tick, self.kickoff.second(), out);
        }
        self.finished = self.clock.check(tick, out);
    }

    fn apply_commands(&mut self, tick: Tick) {
        for i in 0..self.outcome.commands.len() {
            match self.outcome.commands[i] {
                Command::SetPlay { kind, team, x, y } => {
                    // The ball goes on its spot; robots standing there step aside.
                    let moved = self.sim.place_ball_exact(x, y);
                    for (i, robot) in RobotId::all().enumerate() {
                        if moved[i] && self.fall.is_down(i) {
                            self.fall.clear_robot(i);
                            self.outcome.events.push(Event::GetUp { tick, robot });
                        }
                    }
                    self.set_play.award(kind, team, (x, y), tick.next());
                    self.restart.set_play(team, tick.next());
                    SetPlayRule::event(tick, kind, team, (x, y), &mut self.outcome);
                    self.pass.reset();
                    self.controller = None;
                }
                Command::ResetRobot {
                    robot,
                    x,
                    y,
                    heading,
                } => {
                    self.sim.place_robot(robot.index(), x, y, heading);
                    // It fell on its way out this very tick: reset means upright.
                    if self.fall.is_down(robot.index()) {
                        self.fall.clear_robot(robot.index());
                        self.outcome.events.push(Event::GetUp { tick, robot });
                    }
                }
                Command::StandUp { robot } => {
                    self.sim.stand_up(robot.index());
                }
                Command::KickOff { team } => {
                    // Robots lying at a kick-off are stood up in their places.
                    for robot in RobotId::all() {
                        if self.fall.is_down(robot.index()) {
                            self.outcome.events.push(Event::GetUp { tick, robot });
                        }
                    }
                    self.place_for_kickoff(team, tick.next());
                    self.outcome.events.push(Event::KickOff { tick, team });
                }
            }
        }
    }

    /// While a set play lasts (from the tick it is awarded on), robots of
    /// the team not taking it that are inside the keep-out circle at the
    /// end of a tick (there at the award, pushed in, or fallen in) go
    /// straight out to the free spot nearest its edge, upright: every
    /// observation during a set play has them at least `set_play_distance`
    /// from the ball's spot.
    fn keep_out(&mut self, tick: Tick) {
        let Some(active) = self.set_play.active().copied() else {
            return;
        };
        let radius = self.set_play.distance();
        for robot in RobotId::all() {
            let i = robot.index();
            let r = self.sim.snapshot().robots[i];
            let Some(target) = self.set_play.push_out(robot.team(), r.pos[0], r.pos[1]) else {
                continue;
            };
            self.sim
                .place_robot_outside(i, target, r.heading, active.spot, radius);
            if self.fall.is_down(i) {
                self.fall.clear_robot(i);
                self.outcome.events.push(Event::GetUp { tick, robot });
            }
        }
    }

    fn place_for_kickoff(&mut self, team: Team, first_tick: Tick) {
        let mut spots = [(0.0, 0.0, 0.0); ROBOTS];
        for (spot, robot) in spots.iter_mut().zip(RobotId::all()) {
            let [x, y, h] = self.kickoff.place(robot, team);
            *spot = (x, y, h);
        }
        self.sim.place_all((0.0, 0.0), &spots);
        self.fall.clear();
        self.pass.reset();
        self.controller = None;
        self.set_play
            .award(SetPlayKind::KickOff, team, (0.0, 0.0), first_tick);
        self.restart.kick_off(team, first_tick);
    }

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

    /// Per-robot reward of the last tick for `team` (learn's MDP):
    /// `s = r_goal + r_close + r_control - r_opponent_control`, returned as
    /// `sign(s) * ln(1 + |s|)` (DESIGN.md explains why not the paper's
    /// `-log(s)`), plus the shaping terms outside the log: potential-based
    /// progress and approach, and the pass and aim bonuses (`RewardConfig`). All 0
    /// before the first tick.
    pub fn rewards(&self, team: Team) -> [f32; PLAYERS_PER_TEAM] {
        let shared = self.shared_reward(team);
        std::array::from_fn(|p| self.player_reward(team, p, shared))
    }

    /// One robot's entry of [`Match::rewards`].
    pub fn reward(&self, team: Team, player: usize) -> f32 {
        self.player_reward(team, player, self.shared_reward(team))
    }

    /// The terms every robot of `team` shares: goal, opponent control.
    fn shared_reward(&self, team: Team) -> [f32; 2] {
        let w = &self.cfg.reward;
        let goal = match self.last_goal {
            Some(t) if t == team => w.goal,
            Some(_) => -w.goal,
            None => 0.0,
        };
        let opponent = match self.controller {
            Some(c) if c.team() != team => -w.opponent_control,
            _ => 0.0,
        };
        [goal, opponent]
    }

    fn player_reward(&self, team: Team, player: usize, shared: [f32; 2]) -> f32 {
        let Some(robot) = RobotId::new(team, player) else {
            return 0.0;
        };
        if self.tick == Tick::ZERO {
            return 0.0;
        }
        let w = &self.cfg.reward;
        let snap = self.sim.snapshot();
        let r = &snap.robots[robot.index()];
        let d = (snap.ball.pos[0] - r.pos[0]).hypot(snap.ball.pos[1] - r.pos[1]);
        let close = w.close * (-d / w.close_scale).exp();
        let control = if self.controller == Some(robot) {
            w.control
        } else {
            0.0
        };
        let [goal, opponent] = shared;
        // The order of the sum is part of the reward's bits (and of every
        // training run's): keep it.
        log_compress(goal + close + control + opponent) + self.shaping[robot.index()]
    }
}

/// Each robot's horizontal distance to the ball.
fn ball_distances(snap: &naosoccer_sim::Snapshot) -> [f32; ROBOTS] {
    let [bx, by, _] = snap.ball.pos;
    std::array::from_fn(|i| {
        let r = &snap.robots[i];
        (bx - r.pos[0]).hypot(by - r.pos[1])
    })
}

/// The robot indices of robot `i`'s team, `i` included.
fn teammates(i: usize) -> std::ops::Range<usize> {
    let first = i / PLAYERS_PER_TEAM * PLAYERS_PER_TEAM;
    first..first + PLAYERS_PER_TEAM
}

/// Whether robot `j` is nearer the ball than robot `i` (the lower index on
/// a tie; never `i` itself): the order that picks a team's chaser.
fn nearer_ball(dist: &[f32; ROBOTS], j: usize, i: usize) -> bool {
    dist[j] < dist[i] || (dist[j] == dist[i] && j < i)
}

/// The pass bonus of `RewardConfig::pass`, for a long enough forward pass.
fn pass_bonus(w: &RewardConfig, shaping: &mut [f32; ROBOTS], p: PassMade) {
    if w.pass <= 0.0 {
        return;
    }
    let long = (p.end[0] - p.start[0]).hypot(p.end[1] - p.start[1]) >= w.pass_min_distance;
    let forward = (p.end[0] - p.start[0]) * p.from.team().direction() > 0.0;
    if long && forward {
        shaping[p.from.index()] += w.pass;
        shaping[p.to.index()] += w.pass;
    }
}

/// Whether `kicker`'s kick, just made, sends the ball at a standing
/// teammate ahead (`RewardConfig::aim`).
fn aims_at_teammate(
    w: &RewardConfig,
    snap: &naosoccer_sim::Snapshot,
    down: &[bool; ROBOTS],
    kicker: RobotId,
) -> bool {
    let [bx, by, _] = snap.ball.pos;
    let [vx, vy, _] = snap.ball.vel;
    let speed = vx.hypot(vy);
    if speed <= 0.0 {
        return false;
    }
    let team = kicker.team();
    let cos_max = w.aim_angle.cos();
    (0..PLAYERS_PER_TEAM).any(|p| {
        let Some(mate) = RobotId::new(team, p) else {
            return false;
        };
        if mate == kicker || down[mate.index()] {
            return false;
        }
        let r = &snap.robots[mate.index()].pos;
        let (dx, dy) = (r[0] - bx, r[1] - by);
        let d = dx.hypot(dy);
        d >= w.pass_min_distance
            && d <= w.aim_range
            && dx * team.direction() > 0.0
            && (dx * vx + dy * vy) >= cos_max * d * speed
            && (w.aim_lane <= 0.0 || lane_clear(snap, team, [bx, by], [r[0], r[1]], w.aim_lane))
    })
}

/// Whether no robot of the other team stands or lies within `width` metres
/// of the segment from `from` to `to` (world frame).
fn lane_clear(
    snap: &naosoccer_sim::Snapshot,
    team: Team,
    from: [f32; 2],
    to: [f32; 2],
    width: f32,
) -> bool {
    (0..PLAYERS_PER_TEAM)
        .filter_map(|p| RobotId::new(team.other(), p))
        .all(|o| {
            let q = &snap.robots[o.index()].pos;
            segment_distance(from, to, [q[0], q[1]]) > width
        })
}

/// `sign(s) * ln(1 + |s|)`: keeps the sign, compresses the size.
pub fn log_compress(s: f32) -> f32 {
    s.signum() * s.abs().ln_1p()
}

fn sim_command(a: Action) -> SimCommand {
    match a {
        Action::Forward => SimCommand::Forward,
        Action::TurnLeft => SimCommand::TurnLeft,
        Action::TurnRight => SimCommand::TurnRight,
        Action::Shoot => SimCommand::Shoot,
        Action::Stay => SimCommand::Stay,
        Action::Pass => SimCommand::Pass,
    }
}

/// Statistics follow from the event stream alone.
fn apply_stats(stats: &mut MatchStats, e: &Event) {
    match *e {
        Event::Goal { team, phase, .. } => {
            let t = stats.team_mut(team);
            t.goals += 1;
            match phase {
                Some(GoalPhase::Restart) => t.goals_restart += 1,
                Some(GoalPhase::OwnGoal) => t.goals_own_goal += 1,
                Some(GoalPhase::OpenPlay) | None => t.goals_open_play += 1,
            }
        }
        Event::GoalDisallowed { team, .. } => stats.team_mut(team).goals_disallowed += 1,
        Event::Kick { robot, .. } => stats.team_mut(robot.team()).shots += 1,
        Event::Pass { from, .. } => stats.team_mut(from.team()).passes += 1,
        Event::Fall { robot, .. } => stats.team_mut(robot.team()).falls += 1,
        // A ball out counts against the team that touched it last.
        Event::BallOut {
            last_touch: Some(team),
            ..
        } => stats.team_mut(team).out_of_bounds += 1,
        Event::RobotOut { robot, .. } => stats.team_mut(robot.team()).out_of_bounds += 1,
        Event::SetPlay {
            play: kind, team, ..
        } => {
            let t = stats.team_mut(team);
            match kind {
                SetPlayKind::KickIn => t.kick_ins += 1,
                SetPlayKind::GoalKick => t.goal_kicks += 1,
                SetPlayKind::CornerKick => t.corner_kicks += 1,
                SetPlayKind::KickOff => {}
            }
        }
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_compress_keeps_sign_and_zero() {
        assert_eq!(log_compress(0.0), 0.0);
        assert!((log_compress(1.0) - 2f32.ln()).abs() < 1e-6);
        assert!((log_compress(-1.0) + 2f32.ln()).abs() < 1e-6);
    }
}
