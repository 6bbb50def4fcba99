//! Plays a trained DQN team in its own training environment, with the
//! training loop's decisions (`Decisions`: holds, masks, roles) and its
//! epsilon-greedy choice, but no learning: the goals a match it scores
//! there, to set beside what `eval` measures for the same team.
//!
//! ```sh
//! cargo run --release -p naosoccer-learn --example dqn_train_env -- \
//!     assets/policies/dqn-team-seed1 random 2 64 0.0
//! ```
//!
//! Arguments: the run directory, the opponent (a built-in spec), the match
//! length in minutes, the number of episodes, and epsilon (0: greedy).

use std::path::Path;
use std::process::ExitCode;

use naosoccer_learn::config::TrainConfig;
use naosoccer_learn::dqn::epsilon_greedy;
use naosoccer_learn::env::decisions::Decisions;
use naosoccer_learn::env::{EnvConfig, Opponent, VecEnv};
use naosoccer_learn::{LearnedPolicy, OBS_DIM};
use naosoccer_policy::actions::allowed_actions;
use naosoccer_policy::PolicyKind;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [dir, opponent, minutes, episodes, epsilon] = args.as_slice() else {
        eprintln!("usage: dqn_train_env RUN_DIR OPPONENT MINUTES EPISODES EPSILON");
        return ExitCode::from(2);
    };
    match run(dir, opponent, minutes, episodes, epsilon) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{e}");
            ExitCode::FAILURE
        }
    }
}

fn run(
    dir: &str,
    opponent: &str,
    minutes: &str,
    episodes: &str,
    epsilon: &str,
) -> Result<(), Box<dyn std::error::Error>> {
    let text = std::fs::read_to_string(Path::new(dir).join("config.json"))?;
    let mut cfg: TrainConfig = serde_json::from_str(&text)?;
    cfg.match_config.minutes = minutes.parse()?;
    let episodes: usize = episodes.parse()?;
    let epsilon: f64 = epsilon.parse()?;
    let policy = LearnedPolicy::load(&format!("dqn:{dir}"))?;
    let decision = cfg.dqn.decision;
    let mut env = VecEnv::new(
        &cfg.match_config,
        EnvConfig {
            matches: cfg.matches,
            learners: cfg.learners.clone(),
            teammates: cfg.teammates.parse::<PolicyKind>()?,
            threads: 1,
            seed: 991,
            support_spot: decision.map_or_else(Default::default, |d| d.support_spot),
        },
        Opponent::Builtin(opponent.parse::<PolicyKind>()?),
    )?;
    let scale = policy.scale();
    env.set_obs_scale(scale);
    let robots = cfg.learners.len();
    let k = policy.actions();
    let mut dec = Decisions::<()>::new(&env, decision, scale, 0, 1.0);
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let (mut n, mut gf, mut ga) = (0usize, 0u64, 0u64);
    let mut chosen = Vec::new();
    while n < episodes {
        let asked = dec.ask(&env);
        if !asked.rows.is_empty() {
            let obs = env.observations();
            chosen.clear();
            let masks = asked.shoot_ok.iter().zip(&asked.banned);
            for (&r, (&ok, &bans)) in asked.rows.iter().zip(masks) {
                let q = policy.outputs(&obs[r * OBS_DIM..(r + 1) * OBS_DIM], r % robots);
                chosen.push(epsilon_greedy(
                    &q,
                    allowed_actions(ok, bans, k),
                    epsilon,
                    &mut rng,
                ));
            }
            let none = vec![(); chosen.len()];
            dec.decide(&env, &chosen, &none, &mut |_| {});
        }
        let finished = env.step(dec.actions())?;
        dec.observe(&env, &mut |_| {});
        for e in finished {
            n += 1;
            gf += u64::from(e.goals_for);
            ga += u64::from(e.goals_against);
        }
    }
    println!(
        "{dir} against {opponent}, {n} episodes of {minutes} min, epsilon {epsilon}: \
         goals {:.3} : {:.3} an episode",
        gf as f64 / n as f64,
        ga as f64 / n as f64
    );
    Ok(())
}
