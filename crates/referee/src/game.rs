//! `Match`, the one driver: apply actions, step the sim for one control tick,
//! run the rules, apply their commands, keep score and statistics.

use naosoccer_proto::msg::{Frame, Pitch};
use naosoccer_proto::{
    Action, Event, GoalPhase, MatchStats, Observation, RobotId, Score, SetPlayKind, SetPlayObs,
    Team, Tick, PLAYERS_PER_TEAM, ROBOTS,
};
use naosoccer_sim::{RobotModel, Sim, SimError, StateHasher};

use crate::config::{ConfigError, MatchConfig, RewardConfig};
use crate::observe::{self, ObsContext};
use crate::rules::{
    goal::Scored, segment_distance, Clock, Command, FallRule, Field, GoalRule, KickOff,
    OutOfBoundsRule, Outcome, PassMade, PassRule, PossessionRule, RestartRule, SetPlayRule,
};
use crate::scenario::ScenarioError;

pub use state::{StateError, MAX_BALL_SPEED};

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

mod query;
mod reward;
mod start;
mod state;

pub use reward::log_compress;
use reward::{aims_at_teammate, pass_bonus};

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
    /// Events that happened between ticks, announced with the next tick's
    /// events: the start's kick-off (or a scenario's set play), a state set
    /// from outside (`Match::set_state`).
    announce: Vec<Event>,
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
    /// The teammate each robot's latest `pass` was swung toward, set with
    /// the sim's pass target (a kick's `receiver`). Reported, never read by
    /// the rules: the sim's hashed pass target and aim decide the kick.
    receivers: [Option<RobotId>; ROBOTS],
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
            announce: Vec::new(),
            off: [false; ROBOTS],
            scenario: None,
            controller: None,
            score: Score::default(),
            stats: MatchStats::default(),
            last_goal: None,
            shaping: [0.0; ROBOTS],
            receivers: [None; ROBOTS],
            outcome: Outcome::default(),
            cfg: cfg.clone(),
        };
        m.place_for_kickoff(m.kickoff.first(), Tick::ZERO);
        m.announce.push(Event::KickOff {
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
        self.outcome.events.append(&mut self.announce);
        // A step of `forward` covers about walk_speed / control_hz: the
        // keep-out margin, so a robot on the edge cannot step inside.
        let step_margin = self.cfg.sim.walk_speed * 1.2 / self.cfg.control_hz;
        let kept_out = self.set_play.active().map(|a| a.team.other());
        for (i, &a) in actions.iter().enumerate() {
            let snap = &self.sim.snapshot().robots[i];
            let robot_team = RobotId::from_index(i).map(RobotId::team);
            let cmd = if self.fall.is_down(i) || self.off[i] {
                Action::Stay
            } else if matches!(a, Action::Shoot | Action::Pass) && robot_team == kept_out {
                // Set play: the other team may not kick.
                Action::Stay
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
                Action::Stay
            } else {
                a
            };
            if cmd == Action::Pass && !self.sim.snapshot().robots[i].kicking {
                // The receiver is chosen from the kicker's observation, as a
                // client would choose it (`proto::pass_receiver`).
                let robot = RobotId::from_index(i).expect("a robot index");
                let obs = self.observe(robot.team(), robot.player());
                let receiver = naosoccer_proto::pass_receiver(&obs);
                let target = receiver.map(|j| {
                    let r =
                        &self.sim.snapshot().robots[robot.team().index() * PLAYERS_PER_TEAM + j];
                    [r.pos[0], r.pos[1]]
                });
                self.receivers[i] = receiver.and_then(|j| RobotId::new(robot.team(), j));
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
                    let receiver = if k.aimed {
                        self.receivers[k.robot]
                    } else {
                        None
                    };
                    self.outcome.events.push(Event::Kick {
                        tick,
                        robot,
                        speed: k.speed,
                        receiver,
                    });
                    self.pass.kick(robot, ball, receiver.is_some());
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
        Event::Pass { from, aimed, .. } => {
            let t = stats.team_mut(from.team());
            t.passes += 1;
            t.aimed_passes += u32::from(aimed);
        }
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
