//! `naosoccer bench learn` (built with the `train` feature): PPO end to
//! end and the environment alone, in robot transitions a second.
use std::time::Instant;

use clap::Args;
use naosoccer_learn::config::{PpoConfig, Preset};
use naosoccer_learn::train::{train, Algo, TrainConfig};
use naosoccer_referee::MatchConfig;

#[derive(Args, Debug)]
pub struct BenchLearnArgs {
    /// Robot transitions to train for in the measurement.
    #[arg(long, default_value_t = 200_000)]
    steps: u64,
    /// Matches side by side.
    #[arg(long, default_value_t = 16)]
    matches: usize,
    /// Threads stepping matches.
    #[arg(long, default_value_t = 2)]
    threads: usize,
    /// libtorch's intra-op threads.
    #[arg(long, default_value_t = 1)]
    torch_threads: i32,
    /// PPO preset to measure: cleanrl (4 passes over each batch), paper
    /// (80 passes, about 20 times the update cost per transition) or team
    /// (decision-level: a forward pass only for robots that decide).
    #[arg(long, default_value = "cleanrl")]
    preset: Preset,
}

/// PPO end to end (matches vs the scripted team, inference, updates), then
/// the environment alone with random actions, in robot transitions a second.
pub fn bench_learn(a: BenchLearnArgs) -> anyhow::Result<()> {
    use naosoccer_learn::env::{EnvConfig, Opponent, VecEnv};
    use naosoccer_policy::PolicyKind;
    use rand::{Rng, SeedableRng};

    tch::set_num_threads(a.torch_threads.max(1));
    let out = std::env::temp_dir().join(format!("naosoccer-bench-learn-{}", std::process::id()));
    let mut cfg = TrainConfig::new(Algo::Ppo, MatchConfig::default());
    cfg.steps = a.steps;
    cfg.matches = a.matches;
    cfg.threads = a.threads;
    cfg.checkpoint_every = 0;
    cfg.ppo = PpoConfig::preset(a.preset);
    let start = Instant::now();
    let summary = train(&cfg, &out, &mut |_| {})?;
    let secs = start.elapsed().as_secs_f64();
    let _ = std::fs::remove_dir_all(&out);
    let e2e = summary.transitions as f64 / secs;

    let mut env = VecEnv::new(
        &cfg.match_config,
        EnvConfig {
            matches: a.matches,
            learners: vec![0, 1, 2, 3],
            teammates: PolicyKind::Idle,
            threads: a.threads,
            seed: 1,
            support_spot: Default::default(),
        },
        Opponent::Builtin(PolicyKind::Scripted),
    )?;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let mut actions = vec![0usize; env.rows()];
    let ticks = (a.steps as usize / env.rows()).max(1);
    let start = Instant::now();
    for _ in 0..ticks {
        actions.iter_mut().for_each(|x| *x = rng.random_range(0..5));
        env.step(&actions)?;
    }
    let env_rate = (ticks * env.rows()) as f64 / start.elapsed().as_secs_f64();
    println!("bench learn: PPO ({:?} preset), {} matches side by side, {} threads, 4 learning robots each vs scripted", a.preset, a.matches, a.threads);
    println!(
        "  end to end:        {:>10.0} robot transitions/s ({} transitions in {:.1} s)",
        e2e, summary.transitions, secs
    );
    println!(
        "  environment only:  {:>10.0} robot transitions/s (random actions)",
        env_rate
    );
    println!(
        "  target:            {:>10} robot transitions/s end to end: {}",
        25_000,
        if e2e >= 25_000.0 { "met" } else { "NOT met" }
    );
    Ok(())
}
