//! Staged episodes: scenarios mixed into a run's matches, or a drill
//! instead of a match, each drawn from its episode's seed.

use std::sync::Arc;

use naosoccer_eval::run::MatchSlot;
use naosoccer_proto::{RobotId, Team, PLAYERS_PER_TEAM};
use naosoccer_referee::{MatchConfig, Scenario};

use super::{episode_seed, EnvConfig, Slot, VecEnv};
use crate::LearnError;

/// Scenarios mixed into a run's matches (docs/SCENARIOS.md, "Training on
/// drills"): the last `matches` of the matches played side by side play
/// scenario episodes instead of whole matches, each starting from one of
/// `scenarios` (drawn from the episode's seed, all equally likely), the
/// learning team as the scenario's own team, against the episode's
/// opponent from the run's mix (not the file's `opponent`).
///
/// An episode ends when its play ends (one of the file's end conditions,
/// its `duration`) and the next starts at once; every scenario match's
/// episode is also cut when a whole match's length of control ticks has
/// passed since the matches started together, so that every match still
/// starts afresh together at a match's end (a checkpoint's boundary). An
/// ending other than the match's own end is a cut: its last transition is
/// bootstrapped with the critic's value of the state reached, since the
/// match would go on. Scenario episodes are not reported among finished
/// episodes (goals, returns). Robots a file does not list are out of play:
/// a learning robot out of play does not decide.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ScenarioDrills {
    pub matches: usize,
    /// The scenario files, read: a run directory's `config.json` keeps
    /// what it trained on.
    pub scenarios: Vec<ScenarioText>,
}

/// A scenario file's name and text.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ScenarioText {
    pub name: String,
    pub text: String,
}

impl ScenarioText {
    /// Reads a scenario file (named by its stem), checking that it parses.
    pub fn read(path: &std::path::Path) -> Result<ScenarioText, LearnError> {
        let s = Scenario::from_file(path)
            .map_err(|e| LearnError::Config(format!("{}: {e}", path.display())))?;
        Ok(ScenarioText {
            name: s.name,
            text: s.source,
        })
    }

    fn parse(&self, cfg: &MatchConfig) -> Result<Scenario, LearnError> {
        let s = Scenario::from_toml(&self.text, Some(&self.name))
            .and_then(|s| s.check(cfg).map(|()| s))
            .map_err(|e| LearnError::Config(format!("scenario {}: {e}", self.name)))?;
        Ok(s)
    }
}

/// A drill instead of a match: the learning robots alone before the
/// opponent goal (every other robot stands aside, by the own goal line),
/// the ball at a random spot of the attacking half and each learner within
/// `robot_radius` of it, facing anywhere. The episode ends with a goal (a
/// success) or when the match clock runs out; it is played in one half.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Drill {
    /// Ball x range (metres, the learner's frame: attacking +x).
    pub ball_x: (f32, f32),
    /// Ball |y| bound, metres.
    pub ball_y: f32,
    /// Largest robot-ball distance at the start, metres (at least 0.25).
    pub robot_radius: f32,
    /// The learner stands at an angle in +-`spread` (radians) from the
    /// spot straight behind the ball (on the side away from the goal):
    /// pi puts it anywhere around the ball.
    pub spread: f32,
    /// It faces the ball turned by up to +-this (radians): pi, anywhere.
    pub heading_noise: f32,
}

impl Default for Drill {
    /// Anywhere around the ball, facing anywhere.
    fn default() -> Drill {
        Drill {
            ball_x: (0.5, 2.0),
            ball_y: 1.2,
            robot_radius: 0.8,
            spread: std::f32::consts::PI,
            heading_noise: std::f32::consts::PI,
        }
    }
}

impl Drill {
    /// The easier drill of the learning test: behind the ball (within 45
    /// degrees of straight behind it), roughly facing it (+-30 degrees).
    pub fn behind_the_ball() -> Drill {
        Drill {
            ball_x: (0.5, 2.0),
            ball_y: 1.0,
            robot_radius: 0.6,
            spread: std::f32::consts::FRAC_PI_4,
            heading_noise: std::f32::consts::FRAC_PI_6,
        }
    }
}

impl VecEnv {
    /// Plays `drill` episodes instead of matches (`None`: matches); every
    /// match starts its current episode afresh. A drill is played in one
    /// half (a half-time kick-off would put everything back in place).
    pub fn set_drill(&mut self, drill: Option<Drill>) -> Result<(), LearnError> {
        if drill.is_some() {
            self.cfg.rules.halves = 1;
        }
        for slot in &mut self.slots {
            slot.drill = drill;
        }
        let episodes = self.episodes();
        self.restart_at(&episodes, self.ticks)
    }

    /// Plays scenario episodes in the last `drills.matches` matches
    /// (`None`: none); every match starts its current episode afresh. See
    /// [`ScenarioDrills`].
    pub fn set_scenarios(&mut self, drills: Option<&ScenarioDrills>) -> Result<(), LearnError> {
        let mut list = None;
        if let Some(d) = drills {
            if d.matches == 0 || d.matches > self.slots.len() {
                return Err(LearnError::Config(format!(
                    "scenarios in {} matches: between 1 and the {} matches played",
                    d.matches,
                    self.slots.len()
                )));
            }
            if d.scenarios.is_empty() {
                return Err(LearnError::Config(
                    "scenario matches need a scenario".into(),
                ));
            }
            if self.slots.iter().any(|s| s.drill.is_some()) {
                return Err(LearnError::Config(
                    "scenarios mix into matches, not into drills".into(),
                ));
            }
            let parsed = d
                .scenarios
                .iter()
                .map(|t| t.parse(&self.cfg))
                .collect::<Result<Vec<_>, _>>()?;
            list = Some((d.matches, Arc::new(parsed)));
        }
        let n = self.slots.len();
        for (i, slot) in self.slots.iter_mut().enumerate() {
            slot.scenarios = list
                .as_ref()
                .filter(|(m, _)| i >= n - m)
                .map(|(_, l)| Arc::clone(l));
        }
        let episodes = self.episodes();
        self.restart_at(&episodes, self.ticks)
    }
}

impl Slot {
    /// A generator for placing this episode, seeded by the run's seed
    /// (mixed with `salt`), the match and the episode.
    fn episode_rng(&self, env: &EnvConfig, salt: u64) -> rand_chacha::ChaCha8Rng {
        use rand::SeedableRng;
        rand_chacha::ChaCha8Rng::seed_from_u64(episode_seed(
            env.seed ^ salt,
            self.index,
            self.episode,
        ))
    }

    /// The learner's frame to the world's: the sign of x and y and the
    /// turn added to a heading (red sees the world turned half round).
    fn to_world(&self) -> (f32, f32) {
        if self.team == Team::Blue {
            (1.0, 0.0)
        } else {
            (-1.0, std::f32::consts::PI)
        }
    }

    /// Starts this episode's match: from a scenario drawn from the
    /// episode's seed when the match plays scenarios, else from the
    /// kick-off (placed as a [`Drill`] when it plays one).
    pub(super) fn start_episode(
        &mut self,
        cfg: &MatchConfig,
        env: &EnvConfig,
    ) -> Result<(), LearnError> {
        let seed = episode_seed(env.seed, self.index, self.episode);
        match self.scenarios.clone() {
            Some(list) => {
                use rand::Rng;
                let k = self
                    .episode_rng(env, 0x5CE7_A410_D111)
                    .random_range(0..list.len());
                self.game = MatchSlot::new(cfg, seed, Some((&list[k], self.team)))?;
            }
            None => {
                self.game = MatchSlot::new(cfg, seed, None)?;
                self.place_drill(env);
            }
        }
        Ok(())
    }

    /// Sets up a drill episode (see [`Drill`]), placed from the episode's
    /// seed.
    pub(super) fn place_drill(&mut self, env: &EnvConfig) {
        let Some(d) = self.drill else {
            return;
        };
        use rand::Rng;
        let mut rng = self.episode_rng(env, 0xD1_11D1_11D1);
        let (sign, turn) = self.to_world();
        let bx = rng.random_range(d.ball_x.0..=d.ball_x.1);
        let by = rng.random_range(-d.ball_y..=d.ball_y);
        let sim = self.game.match_mut().sim_mut();
        sim.place_ball(sign * bx, sign * by);
        let own = self.team.index() * PLAYERS_PER_TEAM;
        let mut aside = 0;
        for r in RobotId::all() {
            let i = r.index();
            let learner =
                i >= own && i < own + PLAYERS_PER_TEAM && env.learners.contains(&(i - own));
            if learner {
                let dist = rng.random_range(0.25..=d.robot_radius.max(0.25));
                let ang = rng.random_range(-d.spread..=d.spread);
                let noise = rng.random_range(-d.heading_noise..=d.heading_noise);
                // Straight behind the ball is -x from it; the robot faces
                // the ball, turned by the noise.
                let (x, y) = (bx - dist * ang.cos(), by - dist * ang.sin());
                let h = ang + noise;
                sim.place_robot(i, sign * x, sign * y, h + turn);
            } else {
                let (x, y) = (-2.6, -2.0 + 0.55 * aside as f32);
                sim.place_robot(i, sign * x, sign * y, turn);
                aside += 1;
            }
        }
        // A staged ball, not a kick-off: nobody is held back from it, and
        // the kick-off rule does not disallow the drill's goal.
        self.game.match_mut().clear_set_play();
    }
}
