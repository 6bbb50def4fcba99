//! The cost of one decision for a team of 4 robots: the shipped networks'
//! forward pass through tch (how trained teams played before issue 14) and
//! through `naosoccer-policy`'s plain-Rust MLP (how they play now), on four
//! observation rows from a real match. tch runs one thread, as play did.
//!
//! `cargo run --release -p naosoccer-learn --example forward_cost`
//! (scripts/bench-play runs it).

use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

use naosoccer_learn::nets::QNet;
use naosoccer_learn::nets::{rows_tensor, ActorCritic};
use naosoccer_learn::obs::OBS_DIM;
use naosoccer_learn::ppo::ACTIONS;
use naosoccer_learn::train::{run_scale, Algo, TrainConfig};
use naosoccer_policy::{Activation, Mlp, Weights};
use naosoccer_proto::Team;
use naosoccer_referee::{Match, MatchConfig};
use tch::Kind;

/// Microseconds per call of `f`: the median over 21 batches of `iters / 21`
/// calls each, after a warm-up, so that a busy machine's preemptions (which
/// land in a few batches) do not move the figure much.
fn per_call(iters: u32, mut f: impl FnMut()) -> f64 {
    for _ in 0..iters / 10 {
        f();
    }
    let batch = (iters / 21).max(1);
    let mut times: Vec<f64> = (0..21)
        .map(|_| {
            let start = Instant::now();
            for _ in 0..batch {
                f();
            }
            start.elapsed().as_secs_f64() / f64::from(batch) * 1e6
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

/// `75-128-128-5`.
fn dims(input: usize, hidden: &[usize]) -> String {
    let mut v = vec![input];
    v.extend_from_slice(hidden);
    v.push(ACTIONS);
    v.iter()
        .map(|d| d.to_string())
        .collect::<Vec<_>>()
        .join("-")
}

fn main() {
    tch::set_num_threads(1);
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/policies");
    let mut m = Match::new(&MatchConfig::default(), 3).unwrap();
    for _ in 0..200 {
        m.step(&[naosoccer_proto::Action::Forward; 8]);
    }
    let obs: Vec<_> = (0..4).map(|p| m.observe(Team::Blue, p)).collect();
    println!(
        "one decision for a team of 4 robots (4 observation rows), microseconds per call \
         (median of 21 batches)"
    );
    println!(
        "  {:<16} {:>24} {:>9} {:>10} {:>9}",
        "team", "networks", "tch", "pure Rust", "speed-up"
    );
    for name in [
        "ppo-paper-seed1",
        "ppo-team-seed1",
        "dqn-seed1",
        "dqn-team-seed1",
    ] {
        let dir = root.join(name);
        let cfg: TrainConfig =
            serde_json::from_str(&std::fs::read_to_string(dir.join("config.json")).unwrap())
                .unwrap();
        let scale = run_scale(&cfg);
        let dim = scale.dim();
        let mut rows = vec![0.0f32; 4 * OBS_DIM];
        for (o, r) in obs.iter().zip(rows.chunks_exact_mut(OBS_DIM)) {
            scale.encode(o, r);
        }
        let file = dir.join("final.safetensors");
        let w = Weights::read(&file).unwrap();
        let mut out = Vec::new();
        let mut y = vec![0.0f32; 4 * ACTIONS];
        let (shape, tch_us, pure_us) = match cfg.algo {
            Algo::Ppo => {
                let mut ac = ActorCritic::for_run(&cfg.ppo, &scale, cfg.learners.len());
                ac.vs.load(&file).unwrap();
                let mlp = Mlp::from_weights(&w, "actor", Activation::Tanh).unwrap();
                let tch_us = per_call(20_000, || {
                    let x = rows_tensor(&rows, 4, OBS_DIM, dim);
                    let l = tch::no_grad(|| ac.logits(&x)).to_kind(Kind::Float);
                    l.copy_data(&mut y, 4 * ACTIONS);
                    black_box(&y);
                });
                let pure_us = per_call(20_000, || {
                    mlp.forward(black_box(&rows), 4, OBS_DIM, &mut out);
                    black_box(&out);
                });
                (
                    format!("1 actor {}", dims(dim, &cfg.ppo.hidden)),
                    tch_us,
                    pure_us,
                )
            }
            Algo::Dqn => {
                let k = if cfg.dqn.shared {
                    1
                } else {
                    cfg.learners.len()
                };
                let nets: Vec<QNet> = (0..k)
                    .map(|i| {
                        let mut q = QNet::with_input(
                            dim,
                            &cfg.dqn.hidden,
                            cfg.dqn.actions(),
                            &format!("q{i}"),
                        );
                        q.vs.load(&file).unwrap();
                        q
                    })
                    .collect();
                let mlps: Vec<Mlp> = (0..k)
                    .map(|i| Mlp::from_weights(&w, &format!("q{i}"), Activation::Relu).unwrap())
                    .collect();
                // Per-robot networks: each robot's row through its own net.
                let per = 4 / k;
                let tch_us = per_call(10_000, || {
                    for (i, q) in nets.iter().enumerate() {
                        let r = &rows[i * per * OBS_DIM..(i + 1) * per * OBS_DIM];
                        let x = rows_tensor(r, per, OBS_DIM, dim);
                        let v = tch::no_grad(|| q.q(&x));
                        v.copy_data(&mut y[..per * ACTIONS], per * ACTIONS);
                    }
                    black_box(&y);
                });
                let pure_us = per_call(10_000, || {
                    for (i, mlp) in mlps.iter().enumerate() {
                        let r = &rows[i * per * OBS_DIM..];
                        mlp.forward(black_box(r), per, OBS_DIM, &mut out);
                    }
                    black_box(&out);
                });
                (
                    format!("{k} x {}", dims(dim, &cfg.dqn.hidden)),
                    tch_us,
                    pure_us,
                )
            }
        };
        println!(
            "  {:<16} {:>24} {:>9.2} {:>10.2} {:>8.1}x",
            name,
            shape,
            tch_us,
            pure_us,
            tch_us / pure_us
        );
    }
    println!("  target: pure Rust <= 10 us for a team of 4");
}
