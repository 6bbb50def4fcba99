//! Probes a trained team on states built by hand: what does each robot do
//! with the ball just ahead, in kick reach before the goal, behind it, to
//! its left? Prints the action probabilities (the team's sampling policy,
//! with every mask the team plays with: `shoot` out of reach, and for teams
//! with them `pass` without a receiver and the roles' bans), for every
//! action the team has.
//!
//! `cargo run --release -p naosoccer-learn --example probe -- ppo:DIR`

use naosoccer_learn::obs::OBS_DIM;
use naosoccer_learn::LearnedPolicy;
use naosoccer_policy::actions::{banned_actions, mask_row, NetAction, ACTION_NAMES, MASKED_LOGIT};
use naosoccer_proto::{Observation, Team};
use naosoccer_referee::{Match, MatchConfig};

/// A case: its name, the robot's (x, y, heading) and the ball's (x, y).
type Case = (&'static str, (f32, f32, f32), (f32, f32));

fn state(base: &Observation, player: usize, me: (f32, f32, f32), ball: (f32, f32)) -> Observation {
    let mut o = base.clone();
    o.player = naosoccer_proto::Player::new(player).unwrap();
    o.own[player].x = me.0;
    o.own[player].y = me.1;
    o.own[player].heading = me.2;
    o.ball.x = ball.0;
    o.ball.y = ball.1;
    o.ball.vx = 0.0;
    o.ball.vy = 0.0;
    o.control = [false; 4];
    o.opponent_control = false;
    o.set_play = None;
    // Teammates out of the way, behind.
    for p in (0..4).filter(|&p| p != player) {
        o.own[p].x = -2.0;
        o.own[p].y = -1.5 + p as f32;
    }
    o
}

fn main() {
    let spec = std::env::args().nth(1).expect("usage: probe ppo:DIR");
    let p = LearnedPolicy::load(&spec).expect("load the policy");
    let m = Match::new(&MatchConfig::default(), 1).unwrap();
    let base = m.observe(Team::Blue, 0);
    let pi = std::f32::consts::PI;
    let cases: [Case; 6] = [
        (
            "0.3 m behind the ball, facing it",
            (-0.3, 0.0, 0.0),
            (0.0, 0.0),
        ),
        (
            "ball in kick reach, 0.8 m before the goal",
            (2.0, 0.0, 0.0),
            (2.18, 0.0),
        ),
        (
            "ball in reach, facing the own goal",
            (0.0, 0.0, pi),
            (-0.18, 0.0),
        ),
        ("ball 0.5 m behind", (0.0, 0.0, 0.0), (-0.5, 0.0)),
        ("ball 0.5 m to the left", (0.0, 0.0, 0.0), (0.0, 0.5)),
        (
            "ball 1 m ahead, 20 deg right",
            (-1.0, 0.0, 0.0),
            (-0.06, -0.34),
        ),
    ];
    let scale = p.scale();
    println!("{spec}");
    for (name, me, ball) in cases {
        println!("{name}:");
        for player in 0..4 {
            let o = state(&base, player, me, ball);
            let mut f = vec![0.0f32; OBS_DIM];
            scale.encode(&o, &mut f);
            // This player's network, masked as the team plays.
            let mut logits = p.outputs(&f, player);
            let in_reach = scale.kick.in_reach(&o);
            if p.decision().is_some_and(|d| d.mask_shoot) && !in_reach {
                logits[NetAction::Shoot.index()] = MASKED_LOGIT;
            }
            if let Some(d) = p.decision() {
                mask_row(&mut logits, banned_actions(&o, in_reach, &d));
            }
            let mx = logits.iter().cloned().fold(f32::MIN, f32::max);
            let e: Vec<f32> = logits.iter().map(|l| (l - mx).exp()).collect();
            let z: f32 = e.iter().sum();
            let probs: Vec<String> = e
                .iter()
                .zip(ACTION_NAMES)
                .map(|(x, n)| format!("{n} {:.2}", x / z))
                .collect();
            println!("  player {player}: {}", probs.join(", "));
        }
    }
}
