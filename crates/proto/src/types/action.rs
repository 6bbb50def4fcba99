//! The actions a player sends, and the rule that picks the teammate a
//! `pass` goes to.

use serde::{Deserialize, Serialize};

use super::Observation;

/// The paper's five actions, and `pass` (protocol 1.3): a kick toward the
/// teammate [`pass_receiver`] names. One holds for one control tick.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize, Default,
)]
#[serde(rename_all = "snake_case")]
///
/// The same enum drives the physics (`naosoccer_sim` re-exports it): what
/// the wire says is what the robot's controller does, with no second list
/// to keep in step.
pub enum Action {
    /// Walk ahead at the walk speed (with gait drift).
    Forward,
    /// Turn on the spot, counter-clockwise (heading grows).
    TurnLeft,
    /// Turn on the spot, clockwise (heading shrinks).
    TurnRight,
    /// Kick: wind-up, strike, recovery. Once started a kick runs to its end;
    /// while `Shoot` is held the robot kicks again and again.
    Shoot,
    /// Stand still (and resist pushes with the bounded drive force).
    #[default]
    Stay,
    /// Kick toward the teammate [`pass_receiver`] names, at a speed that
    /// rolls the ball about half a metre past it (the sim swings it from
    /// the ball toward the point the referee gives it, along the heading if
    /// none); with no such teammate, a `shoot`. Protocol 1.3.
    Pass,
}

impl Action {
    /// Every action, in index order.
    pub const ALL: [Action; 6] = [
        Action::Forward,
        Action::TurnLeft,
        Action::TurnRight,
        Action::Shoot,
        Action::Stay,
        Action::Pass,
    ];

    /// The paper's five actions (the first five of [`Action::ALL`]).
    pub const PAPER: [Action; 5] = [
        Action::Forward,
        Action::TurnLeft,
        Action::TurnRight,
        Action::Shoot,
        Action::Stay,
    ];

    /// Index in [`Action::ALL`] (the learning crate's discrete action id).
    pub fn index(self) -> usize {
        match self {
            Action::Forward => 0,
            Action::TurnLeft => 1,
            Action::TurnRight => 2,
            Action::Shoot => 3,
            Action::Stay => 4,
            Action::Pass => 5,
        }
    }

    pub fn from_index(i: usize) -> Option<Action> {
        Action::ALL.get(i).copied()
    }

    pub fn name(self) -> &'static str {
        match self {
            Action::Forward => "forward",
            Action::TurnLeft => "turn_left",
            Action::TurnRight => "turn_right",
            Action::Shoot => "shoot",
            Action::Stay => "stay",
            Action::Pass => "pass",
        }
    }
}

impl std::str::FromStr for Action {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Action::ALL
            .into_iter()
            .find(|a| a.name() == s)
            .ok_or_else(|| format!("unknown action {s:?}"))
    }
}

/// Who a `pass` goes to: the teammates it may reach and how it picks one.
/// A candidate is a standing teammate other than the kicker, between
/// [`PASS_MIN_DISTANCE`] and [`PASS_MAX_DISTANCE`] from the ball, whose
/// direction from the ball lies within [`PASS_CONE`] of the kicker's heading,
/// with no opponent (standing or lying) within [`PASS_LANE`] of the straight
/// line from the ball to it. Of the candidates the one nearest the opponent
/// goal (largest `x` in the team frame) receives; on a tie, the lower player
/// number.
pub const PASS_MIN_DISTANCE: f32 = 0.8;
/// See [`PASS_MIN_DISTANCE`].
pub const PASS_MAX_DISTANCE: f32 = 4.0;
/// See [`PASS_MIN_DISTANCE`]; radians either side of the heading.
pub const PASS_CONE: f32 = 0.8;
/// See [`PASS_MIN_DISTANCE`]; metres either side of the lane.
pub const PASS_LANE: f32 = 0.3;

/// The teammate (player number) a `pass` by the robot that received `obs`
/// would go to, if any: see [`PASS_MIN_DISTANCE`] for the rule. Computed
/// from the observation alone, so a client knows whether `pass` is a pass
/// before sending it; the referee applies the same function to the
/// kicker's observation.
pub fn pass_receiver(obs: &Observation) -> Option<usize> {
    let me = obs.player.index();
    let heading = obs.own[me].heading;
    let (bx, by) = (obs.ball.x, obs.ball.y);
    let mut best: Option<(usize, f32)> = None;
    for (j, r) in obs.own.iter().enumerate() {
        if j == me || r.fallen {
            continue;
        }
        let (dx, dy) = (r.x - bx, r.y - by);
        let d = dx.hypot(dy);
        if !(PASS_MIN_DISTANCE..=PASS_MAX_DISTANCE).contains(&d) {
            continue;
        }
        let mut off = dy.atan2(dx) - heading;
        off = (off + std::f32::consts::PI).rem_euclid(std::f32::consts::TAU) - std::f32::consts::PI;
        if off.abs() > PASS_CONE {
            continue;
        }
        if lane_blocked(obs, [bx, by], [dx, dy], PASS_LANE) {
            continue;
        }
        if best.is_none_or(|(_, x)| r.x > x) {
            best = Some((j, r.x));
        }
    }
    best.map(|(j, _)| j)
}

/// Whether an opponent of the robot that received `obs` (standing or
/// lying) is within `width` metres of the segment from `from` along
/// `delta` (a nonzero vector), e.g. from the ball to a teammate: the pass
/// rule's lane test ([`PASS_LANE`]).
pub fn lane_blocked(obs: &Observation, from: [f32; 2], delta: [f32; 2], width: f32) -> bool {
    let ([bx, by], [dx, dy]) = (from, delta);
    let d = dx.hypot(dy);
    obs.opponents.iter().any(|o| {
        // Distance from the opponent to the segment.
        let t = (((o.x - bx) * dx + (o.y - by) * dy) / (d * d)).clamp(0.0, 1.0);
        (o.x - (bx + t * dx)).hypot(o.y - (by + t * dy)) <= width
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::{BallObs, Player, RobotObs, ScoreObs, Team, Tick};

    /// Player 1 at (-1, 0) facing +x, the ball at (-0.8, 0); teammates 0, 2
    /// and 3 and the opponents far off unless moved.
    fn obs() -> Observation {
        let far = |x: f32| RobotObs {
            x,
            y: -2.9,
            ..Default::default()
        };
        let mut own = [far(-4.0), far(-3.5), far(-3.0), far(-2.5)];
        own[1] = RobotObs {
            x: -1.0,
            ..Default::default()
        };
        Observation {
            tick: Tick::new(5),
            team: Team::Blue,
            player: Player::new(1).unwrap(),
            time_left: 100.0,
            score: ScoreObs::default(),
            own,
            opponents: [far(2.0), far(2.5), far(3.0), far(3.5)],
            ball: BallObs {
                x: -0.8,
                ..Default::default()
            },
            control: [false, true, false, false],
            opponent_control: false,
            reward: 0.0,
            half: 1,
            set_play: None,
        }
    }

    fn at(x: f32, y: f32) -> RobotObs {
        RobotObs {
            x,
            y,
            ..Default::default()
        }
    }

    #[test]
    fn the_most_advanced_open_teammate_in_the_cone_receives() {
        let mut o = obs();
        assert_eq!(pass_receiver(&o), None, "nobody in range");
        o.own[2] = at(0.5, 0.5);
        assert_eq!(pass_receiver(&o), Some(2));
        o.own[3] = at(1.5, -0.8);
        assert_eq!(pass_receiver(&o), Some(3), "the more advanced one");
        o.own[3].fallen = true;
        assert_eq!(pass_receiver(&o), Some(2), "a lying robot cannot receive");
        o.own[3].fallen = false;
        // An opponent on the lane to 3 (lying ones block too).
        o.opponents[0] = RobotObs {
            fallen: true,
            ..at(0.35, -0.4)
        };
        assert_eq!(pass_receiver(&o), Some(2));
    }

    #[test]
    fn distance_and_cone_limit_the_receivers() {
        let mut o = obs();
        o.own[2] = at(-0.2, 0.0); // 0.6 m from the ball: too near
        assert_eq!(pass_receiver(&o), None);
        o.own[2] = at(3.5, 0.0); // 4.3 m: too far
        assert_eq!(pass_receiver(&o), None);
        o.own[2] = at(0.2, 1.2); // atan2(1.2, 1.0) = 0.88 rad off the heading
        assert_eq!(pass_receiver(&o), None);
        o.own[1].heading = 0.5; // turned toward it
        assert_eq!(pass_receiver(&o), Some(2));
        // The kicker itself never receives, whatever its place.
        o.own[2] = at(-3.0, 2.0);
        assert_eq!(pass_receiver(&o), None);
    }

    #[test]
    fn pass_is_an_action_with_a_name() {
        assert_eq!(Action::Pass.index(), 5);
        assert_eq!(Action::from_index(5), Some(Action::Pass));
        assert_eq!("pass".parse::<Action>(), Ok(Action::Pass));
        assert_eq!(Action::PAPER.len(), 5);
        assert!(!Action::PAPER.contains(&Action::Pass));
    }
}
