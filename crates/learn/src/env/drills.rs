//! Staged episodes: a pass drill mixed into a run's matches, or a drill
//! instead of a match, each placed from its episode's seed.

use naosoccer_proto::{RobotId, Team, PLAYERS_PER_TEAM, ROBOTS};
use naosoccer_referee::rules::segment_distance;

use super::{episode_seed, EnvConfig, Slot, VecEnv};
use crate::LearnError;

/// Pass drills mixed into a run's matches: the last `matches` of the
/// matches played side by side (with an even number, as many as blue as as
/// red) play episodes of `ticks` control ticks, each staged as a pass.
///
/// In the learner's frame (attacking +x): the ball at a random spot
/// (x in -2..1.5, |y| <= 1.6), a learning robot 0.2 m behind it with the
/// ball straight ahead, facing within 60 degrees of the opponent goal;
/// a teammate 1.2-2.5 m further on, within `angle` of the kicker's heading
/// (0.15 rad, 9 degrees, by default: in its line) and ahead of the ball
/// (toward the opponent goal, so that a pass to it is paid), facing the
/// ball; the other teammates anywhere in the
/// field at least 1 m from the ball; the opponent keeper before its goal
/// and the other opponents at least 1.2 m from the ball and 0.5 m from the
/// line from ball to receiver, facing the ball. The match then plays on
/// as any match, against the episode's opponent from the run's mix.
///
/// A drill episode is cut after `ticks` ticks as a rollout's edge cuts one:
/// its last transition is bootstrapped with the critic's value of the state
/// reached, since the match would go on (the observation's clock says so).
/// `ticks` must divide a match's length, so that every match still ends
/// together at a match's end (a checkpoint's boundary). Drill episodes are
/// not reported among finished episodes (goals, returns).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PassDrills {
    pub matches: usize,
    pub ticks: u64,
    /// The receiver's largest angle off the kicker's heading, radians:
    /// small, it stands in the kicker's line; wide, the kicker must turn
    /// with the ball to pass.
    #[serde(default = "PassDrills::default_angle")]
    pub angle: f32,
}

impl PassDrills {
    /// Distance from the kicker's torso to the ball's centre at the start.
    pub const KICKER_DISTANCE: f32 = 0.2;
    /// The receiver's distance from the ball, metres.
    pub const RECEIVER: (f32, f32) = (1.2, 2.5);
    /// The receiver's largest angle off the kicker's heading by default,
    /// radians.
    pub const LANE_ANGLE: f32 = 0.15;

    fn default_angle() -> f32 {
        Self::LANE_ANGLE
    }
    /// The kicker's largest heading off +x, radians (60 degrees).
    pub const HEADING: f32 = std::f32::consts::FRAC_PI_3;
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

    /// Plays pass drills in the last `drills.matches` matches (`None`: none);
    /// every match starts its current episode afresh. See [`PassDrills`].
    pub fn set_pass_drills(&mut self, drills: Option<PassDrills>) -> Result<(), LearnError> {
        if let Some(d) = drills {
            let total = self.slots[0].m.total_ticks();
            if d.matches == 0 || d.matches > self.slots.len() {
                return Err(LearnError::Config(format!(
                    "pass drills in {} matches: between 1 and the {} matches played",
                    d.matches,
                    self.slots.len()
                )));
            }
            if d.ticks == 0 || !total.is_multiple_of(d.ticks) {
                return Err(LearnError::Config(format!(
                    "a pass drill of {} ticks must divide the match's {total} ticks",
                    d.ticks
                )));
            }
            if !(0.0..=std::f32::consts::FRAC_PI_2).contains(&d.angle) {
                return Err(LearnError::Config(format!(
                    "a pass drill's receiver angle of {} rad: between 0 and pi/2",
                    d.angle
                )));
            }
            if self.slots.iter().any(|s| s.drill.is_some()) {
                return Err(LearnError::Config(
                    "pass drills mix into matches, not into drills".into(),
                ));
            }
        }
        let n = self.slots.len();
        for (i, slot) in self.slots.iter_mut().enumerate() {
            slot.pass_drill = drills.filter(|d| i >= n - d.matches);
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

    /// Stages a pass drill episode (see [`PassDrills`]), placed from the
    /// episode's seed.
    pub(super) fn place_pass_drill(&mut self, env: &EnvConfig) {
        let Some(drill) = self.pass_drill else {
            return;
        };
        use rand::Rng;
        let mut rng = self.episode_rng(env, 0x9A55_D111_1D00);
        let half_x = self.m.config().sim.field_length * 0.5;
        let half_y = self.m.config().sim.field_width * 0.5;
        // Kicker and receiver: two own players, learners first.
        let mut own: Vec<usize> = (0..PLAYERS_PER_TEAM).collect();
        own.sort_by_key(|p| !env.learners.contains(p));
        let learners = env.learners.len().max(1);
        let kicker = own[rng.random_range(0..learners)];
        own.retain(|&p| p != kicker);
        let receiver = own.remove(rng.random_range(0..own.len().min(learners.max(2) - 1)));
        // Ball, kicker heading and receiver, drawn until the receiver stands
        // inside the field (0.3 m from the lines).
        let (mut ball, mut heading, mut recv) = ((0.0, 0.0), 0.0f32, (0.0, 0.0, 0.0));
        for _ in 0..32 {
            ball = (
                rng.random_range(-2.0..=1.5f32),
                rng.random_range(-1.6..=1.6f32),
            );
            heading = rng.random_range(-PassDrills::HEADING..=PassDrills::HEADING);
            let d = rng.random_range(PassDrills::RECEIVER.0..=PassDrills::RECEIVER.1);
            let a = heading + rng.random_range(-drill.angle..=drill.angle);
            let (x, y) = (ball.0 + d * a.cos(), ball.1 + d * a.sin());
            recv = (x, y, a + std::f32::consts::PI);
            if x.abs() <= half_x - 0.3 && y.abs() <= half_y - 0.3 && x - ball.0 >= 0.3 {
                break;
            }
        }
        recv.0 = recv.0.clamp(-half_x + 0.3, half_x - 0.3);
        recv.1 = recv.1.clamp(-half_y + 0.3, half_y - 0.3);
        let k = PassDrills::KICKER_DISTANCE;
        let mut spots = [(0.0f32, 0.0f32, 0.0f32); ROBOTS];
        let base = self.team.index() * PLAYERS_PER_TEAM;
        let foe = self.team.other().index() * PLAYERS_PER_TEAM;
        spots[base + kicker] = (
            ball.0 - k * heading.cos(),
            ball.1 - k * heading.sin(),
            heading,
        );
        spots[base + receiver] = recv;
        let facing = |x: f32, y: f32| (ball.1 - y).atan2(ball.0 - x);
        // A spot at least `min` from the ball (and `lane` from the line ball
        // to receiver), drawn in the x range given.
        let draw = |rng: &mut rand_chacha::ChaCha8Rng, xs: (f32, f32), min: f32, lane: f32| {
            let mut p = (0.0, 0.0);
            for _ in 0..32 {
                p = (
                    rng.random_range(xs.0..=xs.1),
                    rng.random_range(-(half_y - 0.45)..=(half_y - 0.45)),
                );
                let far = (p.0 - ball.0).hypot(p.1 - ball.1) >= min;
                if far && segment_distance([ball.0, ball.1], [recv.0, recv.1], [p.0, p.1]) >= lane {
                    break;
                }
            }
            (p.0, p.1, facing(p.0, p.1))
        };
        for &p in &own {
            spots[base + p] = draw(&mut rng, (-(half_x - 0.4), half_x - 0.4), 1.0, 0.0);
        }
        spots[foe] = (
            half_x - 0.4,
            rng.random_range(-0.5..=0.5f32),
            std::f32::consts::PI,
        );
        for p in 1..PLAYERS_PER_TEAM {
            spots[foe + p] = draw(&mut rng, (-2.0, half_x - 0.4), 1.2, 0.5);
        }
        let (sign, turn) = self.to_world();
        let world = spots.map(|(x, y, h)| (sign * x, sign * y, h + turn));
        self.m
            .sim_mut()
            .place_all((sign * ball.0, sign * ball.1), &world);
        self.m.clear_set_play();
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
        let sim = self.m.sim_mut();
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
        self.m.clear_set_play();
    }
}
