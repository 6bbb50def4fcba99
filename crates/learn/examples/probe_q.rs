//! What a trained team does on states built by hand: for each scenario, one
//! robot's network outputs (DQN: Q-values; PPO: action probabilities) and
//! the action it picks greedily.
//!
//!     cargo run --release -p naosoccer-learn --example probe_q -- dqn:assets/policies/dqn-seed1 ...
//!
//! Every scenario starts from the real kick-off observation of blue player 1
//! (the striker) and moves that robot and the ball; the other robots stay on
//! their kick-off places.

use naosoccer_learn::LearnedPolicy;
use naosoccer_policy::actions::ACTION_NAMES;
use naosoccer_proto::{Action, Observation, Team};
use naosoccer_referee::{Match, MatchConfig};

type Scenario = (&'static str, [f32; 3], [f32; 2], &'static [Action]);

/// (name, robot x, y, heading, ball x, y, the actions a sensible player takes)
const SCENARIOS: [Scenario; 7] = [
    (
        "kick-off, 0.3 m behind the ball, facing it",
        [-0.3, 0.0, 0.0],
        [0.0, 0.0],
        &[Action::Forward],
    ),
    (
        "ball 1.5 m straight ahead",
        [-1.5, 0.0, 0.0],
        [0.0, 0.0],
        &[Action::Forward],
    ),
    (
        "ball in kick reach, 0.8 m from goal, lined up",
        [2.0, 0.0, 0.0],
        [2.18, 0.0],
        &[Action::Shoot],
    ),
    (
        "ball in kick reach, 1.5 m from goal, lined up",
        [1.3, 0.3, 0.0],
        [1.48, 0.3],
        &[Action::Shoot],
    ),
    (
        "ball 1 m to the left",
        [0.0, 0.0, 0.0],
        [0.0, 1.0],
        &[Action::TurnLeft],
    ),
    (
        "ball 1 m to the right",
        [0.0, 0.0, 0.0],
        [0.0, -1.0],
        &[Action::TurnRight],
    ),
    (
        "ball 1 m behind",
        [0.5, 0.0, 0.0],
        [-0.5, 0.0],
        &[Action::TurnLeft, Action::TurnRight],
    ),
];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let specs: Vec<String> = std::env::args().skip(1).collect();
    if specs.is_empty() {
        return Err("usage: probe SPEC... (ppo:DIR, dqn:DIR)".into());
    }
    let m = Match::new(&MatchConfig::default(), 1)?;
    let mut base = naosoccer_referee::blank_observation();
    m.observe_into(Team::Blue, 1, &mut base);
    for spec in &specs {
        let policy = LearnedPolicy::load(spec)?;
        let scale = policy.scale();
        let is_ppo = spec.starts_with("ppo");
        println!("{spec}");
        let mut sensible = 0;
        for (name, [x, y, h], [bx, by], want) in SCENARIOS {
            let mut o: Observation = base.clone();
            o.own[1].x = x;
            o.own[1].y = y;
            o.own[1].heading = h;
            o.ball.x = bx;
            o.ball.y = by;
            let mut feats = vec![0.0; naosoccer_learn::OBS_DIM];
            scale.encode(&o, &mut feats);
            let mut out = policy.outputs(&feats, 1);
            if is_ppo {
                let max = out.iter().cloned().fold(f32::MIN, f32::max);
                let sum: f32 = out.iter().map(|v| (v - max).exp()).sum();
                out.iter_mut().for_each(|v| *v = (*v - max).exp() / sum);
            }
            let best = naosoccer_learn::dqn::argmax(&out);
            let ok = want.iter().any(|a| a.index() == best);
            sensible += usize::from(ok);
            let cells: Vec<String> = out
                .iter()
                .zip(ACTION_NAMES)
                .map(|(v, a)| format!("{a} {v:+.3}"))
                .collect();
            println!(
                "  {name:<48} -> {:<10} {} | {}",
                ACTION_NAMES[best],
                if ok { "  " } else { "!!" },
                cells.join("  ")
            );
        }
        println!("  sensible choices: {sensible} of {}", SCENARIOS.len());
    }
    Ok(())
}
