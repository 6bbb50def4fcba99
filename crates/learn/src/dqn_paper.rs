//! DQN with every robot deciding every tick: the paper's Algorithm 1 as
//! its loop runs it (`paper` preset). The learner (replay, target network,
//! TD update) is [`crate::dqn`]'s; what differs (acting on every row,
//! one-tick transitions, the loop) is here.

use std::path::Path;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tch::Tensor;

use crate::config::{run_scale, TrainConfig};
use crate::dqn::{argmax, Dqn, LossMean};
use crate::metrics::Progress;
use crate::nets::QNet;
use crate::obs::OBS_DIM;
use crate::replay::NStep;
use crate::run::{make_env, Run, TrainSummary};
use crate::LearnError;
use naosoccer_policy::actions::{all_actions, ACTIONS};

impl Dqn {
    /// Epsilon-greedy actions for `n` robots; row `i` belongs to learning
    /// robot `i % robots`. One forward pass per network over all its rows.
    pub fn act(
        &mut self,
        obs: &[f32],
        robots: usize,
        epsilon: f64,
        rng: &mut ChaCha8Rng,
        actions: &mut [usize],
    ) {
        let n = actions.len();
        greedy_actions(
            &self.nets,
            self.cfg.shared,
            obs,
            robots,
            &mut self.rows,
            &mut self.q,
            actions,
        );
        for a in actions.iter_mut().take(n) {
            if rng.random::<f64>() < epsilon {
                *a = rng.random_range(0..ACTIONS);
            }
        }
    }
}

/// Greedy actions from Q-networks: row `i` of `obs` is learning robot
/// `i % robots`; with per-robot networks the rows of each robot are gathered
/// and evaluated in one forward pass.
fn greedy_actions(
    nets: &[QNet],
    shared: bool,
    obs: &[f32],
    robots: usize,
    rows: &mut Vec<f32>,
    q: &mut Vec<f32>,
    actions: &mut [usize],
) {
    let n = actions.len();
    if shared || nets.len() == 1 {
        forward_argmax(&nets[0], obs, n, q, actions);
        return;
    }
    let per = n / robots;
    let mut acts = vec![0usize; per];
    for (k, net) in nets.iter().enumerate().take(robots) {
        rows.clear();
        for j in 0..per {
            let i = j * robots + k;
            rows.extend_from_slice(&obs[i * OBS_DIM..(i + 1) * OBS_DIM]);
        }
        forward_argmax(net, rows, per, q, &mut acts);
        for j in 0..per {
            actions[j * robots + k] = acts[j];
        }
    }
}

fn forward_argmax(net: &QNet, obs: &[f32], n: usize, q: &mut Vec<f32>, out: &mut [usize]) {
    let x = Tensor::from_slice(&obs[..n * OBS_DIM]).view([n as i64, OBS_DIM as i64]);
    let qs = tch::no_grad(|| net.q(&x));
    q.resize(n * ACTIONS, 0.0);
    qs.copy_data(q, n * ACTIONS);
    for (i, o) in out.iter_mut().enumerate().take(n) {
        *o = argmax(&q[i * ACTIONS..(i + 1) * ACTIONS]);
    }
}

/// Trains a per-tick DQN run (`paper` preset): every robot decides every
/// tick, epsilon-greedy; a learning step after every tick.
pub fn train(
    cfg: &TrainConfig,
    out: &Path,
    progress: &mut dyn FnMut(&Progress<'_>),
) -> Result<TrainSummary, LearnError> {
    let mut env = make_env(cfg)?;
    let robots = cfg.learners.len();
    let mut dqn = Dqn::new(cfg.dqn.clone(), robots, run_scale(cfg).dim())?;
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let mut run = Run::start(cfg, out, &mut env, &dqn.stores(), false, progress)?;
    let rows = env.rows();
    let mut actions = vec![0usize; rows];
    let mut prev = vec![0.0f32; rows * OBS_DIM];
    let mut nstep = NStep::new(cfg.dqn.n_step, rows);
    let mut loss = LossMean::default();
    let mut step = 0usize;
    // Every transition here lasts one control tick.
    let discount = cfg.dqn.discount(1);
    while !run.done() {
        prev.copy_from_slice(env.observations());
        let epsilon = cfg.dqn.epsilon_at(run.transitions());
        dqn.act(&prev, robots, epsilon, &mut rng, &mut actions);
        let finished = env.step(&actions)?;
        let next = env.observations();
        for i in 0..rows {
            let next_obs = &next[i * OBS_DIM..(i + 1) * OBS_DIM];
            let (obs, reward, done) = (
                &prev[i * OBS_DIM..(i + 1) * OBS_DIM],
                env.rewards()[i],
                env.dones()[i],
            );
            nstep.push(i, obs, actions[i], reward, discount, done, &mut |t| {
                dqn.remember(
                    i % robots,
                    t.obs,
                    t.action,
                    t.ret,
                    next_obs,
                    t.discount,
                    all_actions(ACTIONS),
                )
            });
        }
        run.observe(env.rewards(), finished);
        loss.add(dqn.learn(&mut rng));
        let before = run.count(rows);
        step += 1;
        if step.is_multiple_of(cfg.log_every.max(1)) || run.done() {
            run.log(&env, (loss.take(), f64::NAN, f64::NAN))?;
        }
        run.refresh_opponents(before, &mut env, &dqn.stores())?;
        if run.checkpoint_due() {
            run.checkpoint(&dqn.stores())?;
        }
    }
    run.finish(&dqn.stores())
}
