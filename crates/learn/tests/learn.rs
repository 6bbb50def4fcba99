//! The learning crate on the real `Match`: tiny tasks that DQN and PPO must
//! learn within a test-sized budget, checkpoints that load to identical
//! outputs, and repeatable training.

use std::path::{Path, PathBuf};

use naosoccer_client::PolicyKind;
use naosoccer_learn::env::{EnvConfig, Opponent, VecEnv};
use naosoccer_learn::train::{train, Algo, OpponentSpec, TrainConfig};
use naosoccer_learn::{LearnedPolicy, OBS_DIM};
use naosoccer_referee::MatchConfig;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// libtorch's generator is global to the process: trainings in parallel test
/// threads would draw their initial weights from it in a racy order.
static TORCH: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn torch_lock() -> std::sync::MutexGuard<'static, ()> {
    TORCH.lock().unwrap_or_else(|e| e.into_inner())
}

/// A fresh directory under the target dir (tests leave their runs there to
/// inspect; each test uses its own name).
fn out_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// The tiny task: one robot (player 1, which starts just behind the ball
/// at its team's kick-off or 1 m away when defending), everybody else
/// standing still, 6-second episodes. The referee's reward pays for being
/// close to the ball and, most, for controlling it; so the robot must walk
/// to the ball facing it and stay there.
fn tiny_config(algo: Algo, seed: u64) -> TrainConfig {
    let m = MatchConfig {
        minutes: 0.1,
        ..MatchConfig::default()
    };
    let mut c = TrainConfig::new(algo, m);
    c.seed = seed;
    c.matches = 8;
    c.threads = 2;
    c.learners = vec![1];
    c.teammates = "idle".into();
    c.opponent = OpponentSpec::Builtin("idle".into());
    c.checkpoint_every = 0;
    c
}

/// Mean episode return (per learning robot) over `episodes` whole episodes,
/// the actions coming from `decide`.
fn mean_return(cfg: &TrainConfig, seed: u64, mut decide: impl FnMut(&[f32], &mut [usize])) -> f64 {
    let mut env = VecEnv::new(
        &cfg.match_config,
        EnvConfig {
            matches: 8,
            learners: cfg.learners.clone(),
            teammates: PolicyKind::Idle,
            threads: 2,
            seed,
        },
        Opponent::Builtin(PolicyKind::Idle),
    )
    .unwrap();
    let mut actions = vec![0usize; env.rows()];
    let mut returns = Vec::new();
    while returns.len() < 16 {
        let obs = env.observations().to_vec();
        decide(&obs, &mut actions);
        for e in env.step(&actions).unwrap() {
            returns.extend(e.returns.iter().map(|&r| f64::from(r)));
        }
    }
    returns.iter().sum::<f64>() / returns.len() as f64
}

fn random_return(cfg: &TrainConfig) -> f64 {
    let mut rng = ChaCha8Rng::seed_from_u64(99);
    mean_return(cfg, 1234, |_, a| {
        a.iter_mut().for_each(|x| *x = rng.random_range(0..5))
    })
}

fn learned_return(cfg: &TrainConfig, dir: &Path) -> f64 {
    let spec = format!("{}:{}", cfg.algo, dir.display());
    let mut p = LearnedPolicy::load(&spec).unwrap();
    let players = vec![1usize; 8];
    mean_return(cfg, 1234, |obs, a| p.act_rows_players(obs, &players, a))
}

#[test]
fn ppo_learns_the_tiny_task_and_beats_random() {
    let _torch = torch_lock();
    tch::set_num_threads(1);
    let mut cfg = tiny_config(Algo::Ppo, 1);
    cfg.steps = 30_000;
    cfg.ppo.rollout = 64;
    let dir = out_dir("ppo_tiny");
    train(&cfg, &dir, &mut |_| {}).unwrap();
    let (random, learned) = (random_return(&cfg), learned_return(&cfg, &dir));
    eprintln!("tiny task, PPO: random {random:.3}, learned {learned:.3}");
    assert!(
        learned > random * 1.25,
        "PPO {learned:.3} does not beat random {random:.3}"
    );
}

#[test]
fn dqn_learns_the_tiny_task_and_beats_random() {
    let _torch = torch_lock();
    tch::set_num_threads(1);
    let mut cfg = tiny_config(Algo::Dqn, 1);
    cfg.steps = 40_000;
    cfg.dqn.warmup = 500;
    let dir = out_dir("dqn_tiny");
    train(&cfg, &dir, &mut |_| {}).unwrap();
    let (random, learned) = (random_return(&cfg), learned_return(&cfg, &dir));
    eprintln!("tiny task, DQN: random {random:.3}, learned {learned:.3}");
    assert!(
        learned > random * 1.25,
        "DQN {learned:.3} does not beat random {random:.3}"
    );
}

fn probe_rows() -> Vec<f32> {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    (0..16 * OBS_DIM)
        .map(|_| rng.random_range(-1.0..1.0))
        .collect()
}

#[test]
fn checkpoints_load_to_identical_outputs() {
    let _torch = torch_lock();
    tch::set_num_threads(1);
    for algo in [Algo::Ppo, Algo::Dqn] {
        let mut cfg = tiny_config(algo, 3);
        cfg.learners = vec![0, 1, 2, 3];
        cfg.steps = 2 * 64 * 8 * 4;
        cfg.ppo.rollout = 64;
        cfg.ppo.epochs = 2;
        cfg.dqn.warmup = 128;
        cfg.checkpoint_every = 64 * 8 * 4;
        let dir = out_dir(&format!("roundtrip_{algo}"));
        let summary = train(&cfg, &dir, &mut |_| {}).unwrap();
        let rows = probe_rows();
        let a = LearnedPolicy::load(&format!("{algo}:{}", dir.display())).unwrap();
        let b =
            LearnedPolicy::load(&format!("{algo}:{}", summary.final_weights.display())).unwrap();
        let fresh = LearnedPolicy::untrained(&cfg, "fresh".into());
        for player in 0..4 {
            let (ya, yb, yf) = (
                a.outputs(&rows, player),
                b.outputs(&rows, player),
                fresh.outputs(&rows, player),
            );
            assert_eq!(ya, yb, "{algo}: the same file loads to the same outputs");
            assert_ne!(
                ya, yf,
                "{algo}: trained weights differ from a fresh network's"
            );
        }
        // Saving what was loaded writes the same weights again.
        let again = dir.join("again.safetensors");
        a.save(&again).unwrap();
        let mut c = LearnedPolicy::untrained(&cfg, "c".into());
        c.load_weights(&again).unwrap();
        assert_eq!(c.outputs(&rows, 2), a.outputs(&rows, 2));
        let ckpt = dir.join(format!("checkpoints/step-{}.safetensors", 64 * 8 * 4));
        assert!(ckpt.exists(), "periodic checkpoint written");
        LearnedPolicy::load(&format!("{algo}:{}", ckpt.display())).unwrap();
    }
}

/// A run of three 32-tick rollouts (PPO) or as many DQN steps after a
/// short warm-up, a metrics row per rollout, in `out_dir(name_algo)`: the
/// run directory and its metrics.csv.
fn short_run(mut cfg: TrainConfig, name: &str) -> (PathBuf, String) {
    cfg.steps = 3 * 32 * 8 * cfg.learners.len() as u64;
    cfg.ppo.rollout = 32;
    cfg.dqn.warmup = 64;
    cfg.dqn.batch = 32;
    cfg.log_every = 32;
    let dir = out_dir(&format!("{name}_{}", cfg.algo));
    train(&cfg, &dir, &mut |_| {}).unwrap();
    let metrics = std::fs::read_to_string(dir.join("metrics.csv")).unwrap();
    (dir, metrics)
}

#[test]
fn same_seed_and_threads_give_identical_metrics() {
    let _torch = torch_lock();
    tch::set_num_threads(1);
    for algo in [Algo::Ppo, Algo::Dqn] {
        let run = |seed: u64, name: &str| {
            let mut cfg = tiny_config(algo, seed);
            cfg.ppo.epochs = 3;
            short_run(cfg, name).1
        };
        let a = run(11, "repeat_a");
        let b = run(11, "repeat_b");
        let c = run(12, "repeat_c");
        assert_eq!(a, b, "{algo}: same seed, same metrics");
        assert_ne!(a, c, "{algo}: another seed, other metrics");
        assert!(
            a.lines().count() >= 4,
            "{algo}: a header and three rows:\n{a}"
        );
    }
}

/// A sampling PPO team picks the same actions whether each robot has its own
/// policy (robot connections), one policy answers for the team (a team
/// connection, `act_batch`) or the evaluator batches rows of many matches
/// (`act_rows_keyed` with `sample_uniform`); another match seed gives other
/// draws, and greedy play ignores them.
#[test]
fn sampled_actions_do_not_depend_on_batching() {
    use naosoccer_client::Policy;
    use naosoccer_learn::policy::sample_uniform;
    use naosoccer_learn::ActMode;
    use naosoccer_proto::{Action, Team};
    use naosoccer_referee::Match;

    let _torch = torch_lock();
    tch::set_num_threads(1);
    tch::manual_seed(5);
    let cfg = tiny_config(Algo::Ppo, 5);
    let fresh = |seed: u64| {
        let mut p = LearnedPolicy::untrained(&cfg, "sampler".into());
        p.set_mode(ActMode::Sample);
        p.set_match_seed(seed);
        p
    };
    // Every policy below shares the same weights (one file).
    let dir = out_dir("sampling_weights");
    std::fs::create_dir_all(&dir).unwrap();
    let weights = dir.join("w.safetensors");
    fresh(0).save(&weights).unwrap();
    let loaded = |seed: u64| {
        let mut p = fresh(seed);
        p.load_weights(&weights).unwrap();
        p
    };

    let mut m = Match::new(&cfg.match_config, 77).unwrap();
    let mut single: Vec<LearnedPolicy> = (0..4).map(|_| loaded(77)).collect();
    let mut team = loaded(77);
    let mut rows = loaded(77);
    let mut other_seed = loaded(78);
    let mut greedy = loaded(77);
    greedy.set_mode(ActMode::Greedy);
    let mut greedy_other = loaded(78);
    greedy_other.set_mode(ActMode::Greedy);
    let mut eps_none = loaded(77);
    eps_none.set_mode(ActMode::EpsilonGreedy { epsilon: 0.0 });
    let mut eps_all = loaded(77);
    eps_all.set_mode(ActMode::EpsilonGreedy { epsilon: 1.0 });
    let mut uniform_actions = std::collections::BTreeSet::new();
    let (mut differs, mut varied) = (0, std::collections::BTreeSet::new());
    for _ in 0..40 {
        let obs: Vec<_> = (0..4).map(|p| m.observe(Team::Blue, p)).collect();
        let a: Vec<Action> = single.iter_mut().zip(&obs).map(|(p, o)| p.act(o)).collect();
        let mut b = [Action::Stay; 4];
        team.act_batch(&obs, &mut b);
        let mut feats = vec![0.0; 4 * OBS_DIM];
        let mut u = Vec::new();
        for (i, o) in obs.iter().enumerate() {
            rows.scale()
                .encode(o, &mut feats[i * OBS_DIM..(i + 1) * OBS_DIM]);
            u.push(sample_uniform(77, Team::Blue.index(), i, o.tick));
        }
        let mut c = [0usize; 4];
        rows.act_rows_keyed(&feats, &[0, 1, 2, 3], &u, &mut c);
        let c: Vec<Action> = c.iter().map(|&i| Action::from_index(i).unwrap()).collect();
        assert_eq!(a, b.to_vec(), "robot policies vs one team policy");
        assert_eq!(a, c, "robot policies vs keyed rows");
        let mut d = [Action::Stay; 4];
        other_seed.act_batch(&obs, &mut d);
        differs += usize::from(d.to_vec() != a);
        let mut g = [Action::Stay; 4];
        let mut h = [Action::Stay; 4];
        greedy.act_batch(&obs, &mut g);
        greedy_other.act_batch(&obs, &mut h);
        assert_eq!(g, h, "greedy play does not draw");
        let mut e = [Action::Stay; 4];
        eps_none.act_batch(&obs, &mut e);
        assert_eq!(e, g, "epsilon 0 is greedy");
        eps_all.act_batch(&obs, &mut e);
        uniform_actions.extend(e.iter().map(|x| x.index()));
        varied.extend(a.iter().map(|x| x.index()));
        let mut all = [Action::Stay; 8];
        all[..4].copy_from_slice(&a);
        m.step(&all);
    }
    assert!(
        differs > 10,
        "another match seed draws differently ({differs}/40)"
    );
    assert!(
        varied.len() >= 3,
        "an untrained sampler uses several actions"
    );
}

/// Training against self-play snapshots and against a frozen trained team
/// (the sampling `ppo:` and greedy `dqn:` specs) runs, and repeats exactly
/// with the same seed: the opponents' draws are seeded by the run.
#[test]
fn self_play_and_frozen_opponents_train_repeatably() {
    let _torch = torch_lock();
    tch::set_num_threads(1);
    for algo in [Algo::Ppo, Algo::Dqn] {
        let run = |opponent: OpponentSpec, seed: u64, name: &str| {
            let mut cfg = tiny_config(algo, seed);
            cfg.learners = vec![0, 1, 2, 3];
            cfg.opponent = opponent;
            cfg.ppo.epochs = 2;
            short_run(cfg, name)
        };
        // Snapshots every 256 transitions: three of them in the run.
        let self_play = OpponentSpec::SelfPlay { every: 256 };
        let (dir, a) = run(self_play.clone(), 21, "selfplay_a");
        let (_, b) = run(self_play, 21, "selfplay_b");
        assert_eq!(a, b, "{algo}: self-play repeats");
        assert!(a.lines().count() >= 4, "{algo}:\n{a}");

        let frozen = OpponentSpec::Frozen(format!("{algo}:{}", dir.display()));
        let (_, c) = run(frozen.clone(), 22, "frozen_a");
        let (_, d) = run(frozen, 22, "frozen_b");
        assert_eq!(c, d, "{algo}: a frozen opponent repeats");
        assert_ne!(a, c, "{algo}: another opponent and seed, other metrics");
    }
}

/// The `team` preset (Double DQN, 3-step returns, epsilon schedule, shared
/// network) on the same tiny task and budget, its schedule and warm-up
/// scaled to the budget.
#[test]
fn dqn_team_preset_learns_the_tiny_task_and_beats_random() {
    let _torch = torch_lock();
    tch::set_num_threads(1);
    let mut cfg = tiny_config(Algo::Dqn, 1);
    cfg.dqn = naosoccer_learn::dqn::DqnConfig::team();
    cfg.steps = 40_000;
    cfg.dqn.warmup = 500;
    cfg.dqn.epsilon_decay = 20_000;
    cfg.dqn.target_every = 500;
    let dir = out_dir("dqn_team_tiny");
    train(&cfg, &dir, &mut |_| {}).unwrap();
    let (random, learned) = (random_return(&cfg), learned_return(&cfg, &dir));
    eprintln!("tiny task, DQN team preset: random {random:.3}, learned {learned:.3}");
    assert!(
        learned > random * 1.25,
        "DQN team {learned:.3} does not beat random {random:.3}"
    );
}
