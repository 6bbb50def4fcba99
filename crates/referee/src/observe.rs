//! Observations in the player's team frame: every team attacks +x. Red sees
//! the world turned half round: x -> -x, y -> -y, heading + pi.

use std::f32::consts::PI;

use naosoccer_proto::{
    BallObs, Observation, Player, RobotId, RobotObs, Score, ScoreObs, SetPlayObs, Team, Tick,
    PLAYERS_PER_TEAM, ROBOTS,
};
use naosoccer_sim::Snapshot;

use crate::rules::wrap_angle;

/// What the referee knows beyond the snapshot.
pub(crate) struct ObsContext<'a> {
    pub tick: Tick,
    pub time_left: f32,
    /// Goals, indexed by `Team::index`.
    pub score: Score,
    pub down: &'a [bool; ROBOTS],
    pub controller: Option<RobotId>,
    pub half: u8,
    /// The set play in progress, from the observing team's side.
    pub set_play: Option<SetPlayObs>,
}

/// Fills `out` for `player` of `team`. Writes every field, so a reused
/// observation carries nothing over from its last use.
pub(crate) fn fill(
    snap: &Snapshot,
    ctx: &ObsContext<'_>,
    team: Team,
    player: usize,
    out: &mut Observation,
) {
    let (sx, rot) = match team {
        Team::Blue => (1.0, 0.0),
        Team::Red => (-1.0, PI),
    };
    let robot_obs = |i: usize| {
        let r = &snap.robots[i];
        RobotObs {
            x: sx * r.pos[0],
            y: sx * r.pos[1],
            heading: wire_angle(r.heading + rot),
            fallen: ctx.down[i],
            busy: r.kicking && !ctx.down[i],
        }
    };
    let own_base = team.index() * PLAYERS_PER_TEAM;
    let opp_base = team.other().index() * PLAYERS_PER_TEAM;
    out.tick = ctx.tick;
    out.team = team;
    out.player = Player::new(player).expect("a player number, 0..=3");
    out.time_left = ctx.time_left;
    out.score = ScoreObs {
        own: *ctx.score.get(team),
        opponent: *ctx.score.get(team.other()),
    };
    for p in 0..PLAYERS_PER_TEAM {
        out.own[p] = robot_obs(own_base + p);
        out.opponents[p] = robot_obs(opp_base + p);
        out.control[p] = ctx.controller == RobotId::new(team, p);
    }
    out.ball = BallObs {
        x: sx * snap.ball.pos[0],
        y: sx * snap.ball.pos[1],
        vx: sx * snap.ball.vel[0],
        vy: sx * snap.ball.vel[1],
    };
    out.opponent_control = ctx.controller.is_some_and(|c| c.team() != team);
    out.half = ctx.half;
    out.set_play = ctx.set_play;
}

/// An angle for the wire, in (-pi, pi] as a reader sees it: `f32`'s nearest
/// value to pi (3.1415927) is above pi when read as a double, so headings at
/// the half-turn go out as the largest `f32` below pi instead.
pub(crate) fn wire_angle(a: f32) -> f32 {
    const BELOW_PI: f32 = 3.141_592_5;
    let a = wrap_angle(a);
    let pi = std::f64::consts::PI;
    if f64::from(a) > pi || f64::from(a) <= -pi {
        BELOW_PI
    } else {
        a
    }
}

/// An observation with every field zero, to be filled by `observe_into`.
pub fn blank_observation() -> Observation {
    Observation {
        tick: Tick::ZERO,
        team: Team::Blue,
        player: Player::new(0).expect("player 0"),
        time_left: 0.0,
        score: ScoreObs::default(),
        own: [RobotObs::default(); PLAYERS_PER_TEAM],
        opponents: [RobotObs::default(); PLAYERS_PER_TEAM],
        ball: BallObs::default(),
        control: [false; PLAYERS_PER_TEAM],
        opponent_control: false,
        reward: 0.0,
        half: 1,
        set_play: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 15: red's mirrored heading of a robot facing 0 went out as
    /// 3.1415927, above pi when read as a double.
    #[test]
    fn issue_15_wire_headings_stay_in_the_half_open_interval() {
        let pi = std::f64::consts::PI;
        for a in [
            0.0f32,
            PI,
            -PI,
            PI + 1e-7,
            -PI - 1e-7,
            3.0 * PI,
            2.0 * PI,
            1.0,
            -3.1415925,
            f32::from_bits(PI.to_bits() - 1),
        ] {
            let w = f64::from(wire_angle(a));
            assert!(w > -pi && w <= pi, "{a} -> {w}");
        }
        assert_eq!(wire_angle(0.0 + PI), 3.141_592_5);
        assert_eq!(wire_angle(1.0), 1.0);
    }
}
