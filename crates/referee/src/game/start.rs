//! A match started from a scenario instead of the kick-off.

use naosoccer_proto::{Event, RobotId, SetPlayKind, Team, ROBOTS};

use super::{Match, MatchError};
use crate::config::MatchConfig;
use crate::scenario::{Scenario, Start};

/// Where an absent robot is held, in its own team's frame: player `p` at
/// x = `PARK_X0 + PARK_DX * p`, `PARK_OUT` metres outside the touch line
/// on the frame's -y side, facing +x.
pub const PARK_X0: f32 = -2.25;
pub const PARK_DX: f32 = 1.5;
pub const PARK_OUT: f32 = 1.5;

impl Match {
    /// A match of `seed` started from `scenario`, the own team playing
    /// `own`: the same world as [`Match::new`] builds (the same physics
    /// noise), put into the scenario's state drawn for this seed.
    pub fn with_scenario(
        cfg: &MatchConfig,
        seed: u64,
        scenario: &Scenario,
        own: Team,
    ) -> Result<Match, MatchError> {
        let mut m = Match::new(cfg, seed)?;
        scenario.check(cfg)?;
        let start = scenario.draw(cfg, seed, own);
        m.apply_start(&start);
        m.scenario = Some((
            scenario.name.as_str().into(),
            scenario.source.as_str().into(),
            own,
        ));
        Ok(m)
    }

    /// Puts the match into `start`, the referee's state made consistent
    /// with it: clock, score, set play and restart, falls, last touch,
    /// possession; no pass in progress. Called on a match nobody has
    /// stepped yet.
    fn apply_start(&mut self, start: &Start) {
        let tick = start.tick;
        self.tick = tick;
        self.score = start.score;
        let half_y = self.cfg.sim.field_width / 2.0;
        let mut spots = [(0.0, 0.0, 0.0); ROBOTS];
        for (i, robot) in RobotId::all().enumerate() {
            match start.robots[i] {
                Some(r) => spots[i] = (r.x, r.y, r.heading),
                None => {
                    // Out of play, in its own team's frame as documented.
                    let s = robot.team().direction();
                    let x = PARK_X0 + PARK_DX * robot.player() as f32;
                    let y = -(half_y + PARK_OUT);
                    let h = if s > 0.0 { 0.0 } else { std::f32::consts::PI };
                    self.sim.take_out_of_play(i, s * x, s * y, h);
                    self.off[i] = true;
                }
            }
        }
        self.sim.place_all(start.ball, &spots);
        let (vx, vy) = start.ball_velocity;
        if vx != 0.0 || vy != 0.0 {
            self.sim.set_ball_velocity(vx, vy);
        }
        self.fall.clear();
        for (i, r) in start.robots.iter().enumerate() {
            if let Some(r) = r.filter(|r| r.fallen) {
                self.sim.lay_down(i, r.x, r.y, r.heading);
                self.fall.lay(i, tick);
            }
        }
        self.sim
            .set_last_touch(start.last_touch.map(RobotId::index));
        self.pass.reset();
        self.set_play.clear();
        self.restart.clear();
        self.announce.clear();
        if let Some((kind, team)) = start.set_play {
            let [x, y, _] = self.sim.snapshot().ball.pos;
            self.set_play.award(kind, team, (x, y), tick);
            if kind == SetPlayKind::KickOff {
                self.restart.kick_off(team, tick);
                self.announce.push(Event::KickOff { tick, team });
            } else {
                self.restart.set_play(team, tick);
                self.announce.push(Event::SetPlay {
                    tick,
                    play: kind,
                    team,
                    x,
                    y,
                });
            }
            self.keep_out(tick);
        }
        // Last: the keep-out placement above ends any kick of a robot it moves.
        for (i, r) in start.robots.iter().enumerate() {
            if r.is_some_and(|r| r.busy) {
                self.sim.start_kick_recovery(i);
            }
        }
        let down = self.fall.down();
        self.controller = self.possession.controller(self.sim.snapshot(), &down);
    }

    /// The scenario this match started from: its name, its file's text
    /// and the colour of its own team. `Scenario::from_toml` of the text
    /// and [`Match::with_scenario`] with the config, seed and colour
    /// re-create the start exactly.
    pub fn scenario(&self) -> Option<(&str, &str, Team)> {
        self.scenario
            .as_ref()
            .map(|(name, text, own)| (&**name, &**text, *own))
    }

    /// Whether `robot` is out of play (absent from the scenario the match
    /// started from).
    pub fn is_out_of_play(&self, robot: RobotId) -> bool {
        self.off[robot.index()]
    }
}
