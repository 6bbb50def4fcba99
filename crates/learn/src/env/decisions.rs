//! The decision-level MDP over a [`VecEnv`]: the one place that holds
//! actions and keeps decisions open.
//!
//! Each control tick, a learning robot either decides (it is free to act
//! and its last decision has run out, [`Hold`]) or holds its action. With
//! no decision settings (the per-tick presets: the paper's and CleanRL's)
//! every robot decides every tick, busy or not, with no mask: each
//! decision lasts one tick and closes at the tick's end ([`End::Tick`]). A
//! decision stays open while it is held: its rewards accumulate, discounted
//! per tick (`sum gamma^i r_i`, and `gamma^ticks`). It closes, and comes out
//! as one [`Closed`] transition, when the robot next decides, when its
//! episode ends or is cut (a scenario's end), or at a rollout's edge
//! ([`Decisions::cut`]). The learners ([`crate::ppo`], [`crate::dqn`])
//! only choose actions for the deciding robots and store what closes.
//!
//! A tick, in order: [`Decisions::ask`] (who decides, with their
//! observations and masks), the learner's choice, [`Decisions::decide`],
//! [`VecEnv::step`] with [`Decisions::actions`], [`Decisions::observe`].

use naosoccer_policy::actions::{banned_actions, ActionSet, DecisionConfig, Hold, NetAction};

use crate::env::VecEnv;
use crate::obs::{ObsScale, OBS_DIM};

/// One robot's decision while it lasts.
#[derive(Debug, Clone, Copy, Default)]
struct Open<P> {
    action: usize,
    shoot_ok: bool,
    banned: ActionSet,
    /// `sum gamma^i r_i` so far, and `gamma^ticks`.
    reward: f32,
    discount: f32,
    ticks: u32,
    payload: P,
}

/// How a decision ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum End {
    /// The robot decided again, as the `next`-th of [`Decisions::ask`]'s
    /// rows: the decision's next state is the robot's current observation,
    /// in which `shoot` is possible when `shoot_ok`.
    Decided { next: usize, shoot_ok: bool },
    /// The episode ended: nothing follows.
    Ended,
    /// The episode was cut (a scenario's end) while the match would go
    /// on: the next state is the robot's row of
    /// [`VecEnv::final_observations`].
    Cut,
    /// A rollout's edge ([`Decisions::cut`]): the next state is the robot's
    /// current observation.
    Edge,
    /// Without decision settings, a decision lasts one tick: it closes at
    /// the tick's end ([`Decisions::observe`]) and the next state is the
    /// robot's current observation, where it decides next.
    Tick,
}

/// A closed decision: one decision-level transition.
#[derive(Debug, Clone, Copy)]
pub struct Closed<'a, P> {
    /// The robot's row in the environment's batch.
    pub row: usize,
    /// The observation it decided on (`OBS_DIM` wide) and the critic's
    /// input then ([`Decisions::new`]'s `critic_width`; empty with none).
    pub obs: &'a [f32],
    pub critic_obs: &'a [f32],
    pub action: usize,
    /// The masks it decided under: `shoot` possible, and the other actions
    /// banned ([`banned_actions`]).
    pub shoot_ok: bool,
    pub banned: ActionSet,
    /// The rewards of the ticks it lasted, discounted to its start, and
    /// `gamma^ticks`.
    pub reward: f32,
    pub discount: f32,
    pub ticks: u32,
    /// What the learner kept of it when it decided.
    pub payload: P,
    pub end: End,
}

/// The robots that decide this tick, in row order, and what they decide on.
#[derive(Debug, Default)]
pub struct Asked {
    pub rows: Vec<usize>,
    /// Their observation rows, `OBS_DIM` wide.
    pub obs: Vec<f32>,
    /// Their critic inputs, `critic_width` wide.
    pub critic_obs: Vec<f32>,
    /// Whether `shoot` is possible (always, without the shoot mask).
    pub shoot_ok: Vec<bool>,
    /// What else each may not choose ([`banned_actions`]).
    pub banned: Vec<ActionSet>,
}

/// Holds and open decisions of every learning robot of a [`VecEnv`];
/// `P` is what the learner keeps with each decision until it closes.
pub struct Decisions<P> {
    /// `None`: every robot decides every tick, unmasked.
    decision: Option<DecisionConfig>,
    scale: ObsScale,
    learners: usize,
    critic_width: usize,
    gamma: f32,
    holds: Vec<Hold>,
    open: Vec<Option<Open<P>>>,
    open_obs: Vec<f32>,
    open_critic: Vec<f32>,
    actions: Vec<usize>,
    asked: Asked,
}

impl<P: Copy> Decisions<P> {
    /// For `env`'s robots under `decision` (`None`: each decides every
    /// tick), rewards discounted by `gamma` per tick. `critic_width`: the critic's input ([`critic_row`]), 0 when
    /// the learner has no critic.
    pub fn new(
        env: &VecEnv,
        decision: Option<DecisionConfig>,
        scale: ObsScale,
        critic_width: usize,
        gamma: f32,
    ) -> Decisions<P> {
        let rows = env.rows();
        Decisions {
            decision,
            scale,
            learners: env.learners().len(),
            critic_width,
            gamma,
            holds: vec![Hold::default(); rows],
            open: vec![None; rows],
            open_obs: vec![0.0; rows * OBS_DIM],
            open_critic: vec![0.0; rows * critic_width],
            actions: vec![0; rows],
            asked: Asked::default(),
        }
    }

    /// Finds the robots that decide now (their masks and inputs in
    /// [`Decisions::asked`]); the others hold their actions.
    pub fn ask(&mut self, env: &VecEnv) -> &Asked {
        let a = &mut self.asked;
        a.rows.clear();
        a.obs.clear();
        a.critic_obs.clear();
        a.shoot_ok.clear();
        a.banned.clear();
        let dim = self.scale.dim();
        for (r, hold) in self.holds.iter_mut().enumerate() {
            let o = env.learner_observation(r);
            if !env.in_play(r) {
                // Absent from its scenario: its actions are ignored.
                self.actions[r] = NetAction::Stay.index();
                continue;
            }
            // What it may choose, if it decides now: every tick and
            // unmasked without decision settings.
            let masks = match &self.decision {
                None => Some((true, ActionSet::default())),
                Some(d) => hold.must_decide(o).then(|| {
                    let in_reach = self.scale.kick.in_reach(o);
                    (!d.mask_shoot || in_reach, banned_actions(o, in_reach, d))
                }),
            };
            let Some((shoot_ok, banned)) = masks else {
                self.actions[r] = hold.held(o).index();
                continue;
            };
            a.rows.push(r);
            a.obs
                .extend_from_slice(&env.observations()[r * OBS_DIM..(r + 1) * OBS_DIM]);
            critic_row(
                env.observations(),
                self.learners,
                r,
                dim,
                self.critic_width,
                &mut a.critic_obs,
            );
            a.shoot_ok.push(shoot_ok);
            a.banned.push(banned);
        }
        &self.asked
    }

    /// The robots that decide this tick ([`Decisions::ask`]).
    pub fn asked(&self) -> &Asked {
        &self.asked
    }

    /// The deciding robots' choices, in [`Decisions::ask`]'s order, and
    /// what the learner keeps of each: closes the decisions they end (to
    /// `emit`, in row order) and opens the new ones.
    pub fn decide(
        &mut self,
        env: &VecEnv,
        actions: &[usize],
        payloads: &[P],
        emit: &mut dyn FnMut(Closed<'_, P>),
    ) {
        let half = [self.scale.half_length, self.scale.half_width];
        let (w, cw) = (OBS_DIM, self.critic_width);
        for j in 0..self.asked.rows.len() {
            let r = self.asked.rows[j];
            let end = End::Decided {
                next: j,
                shoot_ok: self.asked.shoot_ok[j],
            };
            self.close(r, end, emit);
            self.open[r] = Some(Open {
                action: actions[j],
                shoot_ok: self.asked.shoot_ok[j],
                banned: self.asked.banned[j],
                reward: 0.0,
                discount: 1.0,
                ticks: 0,
                payload: payloads[j],
            });
            self.open_obs[r * w..(r + 1) * w].copy_from_slice(&self.asked.obs[j * w..(j + 1) * w]);
            self.open_critic[r * cw..(r + 1) * cw]
                .copy_from_slice(&self.asked.critic_obs[j * cw..(j + 1) * cw]);
            if let Some(decision) = &self.decision {
                let tick = env.learner_observation(r).tick;
                let a = NetAction::from_index(actions[j]).expect("a network output is an action");
                self.holds[r].start(a, tick, decision, half);
            }
            self.actions[r] = actions[j];
        }
    }

    /// Every robot's action for this tick's [`VecEnv::step`].
    pub fn actions(&self) -> &[usize] {
        &self.actions
    }

    /// What the learner keeps of robot `row`'s open decision, to complete
    /// it after [`Decisions::decide`] (e.g. with a value computed while
    /// the matches stepped); `None` without one.
    pub fn payload_mut(&mut self, row: usize) -> Option<&mut P> {
        self.open[row].as_mut().map(|d| &mut d.payload)
    }

    /// After [`VecEnv::step`]: the tick's rewards go into the open
    /// decisions; those of episodes that ended close (to `emit`, in row
    /// order) and their robots' holds start afresh. Without decision
    /// settings every decision closes here ([`End::Tick`] where the episode
    /// goes on).
    pub fn observe(&mut self, env: &VecEnv, emit: &mut dyn FnMut(Closed<'_, P>)) {
        for r in 0..self.open.len() {
            if let Some(d) = self.open[r].as_mut() {
                d.reward += d.discount * env.rewards()[r];
                d.discount *= self.gamma;
                d.ticks += 1;
            }
            if env.dones()[r] {
                let end = if env.truncated()[r] {
                    End::Cut
                } else {
                    End::Ended
                };
                self.close(r, end, emit);
                self.holds[r].reset();
            } else if self.decision.is_none() {
                self.close(r, End::Tick, emit);
            }
        }
    }

    /// The robots whose episodes were cut this tick (a drill's end,
    /// [`End::Cut`]) and their critic inputs in the state where they were
    /// cut, the state their last decisions bootstrap from.
    pub fn cut_critic_rows(&self, env: &VecEnv, rows: &mut Vec<usize>, critic_obs: &mut Vec<f32>) {
        rows.clear();
        critic_obs.clear();
        let (l, dim, cw) = (self.learners, self.scale.dim(), self.critic_width);
        for r in (0..self.open.len()).filter(|&r| env.truncated()[r]) {
            rows.push(r);
            critic_row(env.final_observations(), l, r, dim, cw, critic_obs);
        }
    }

    /// Every robot's critic input now (at a rollout's edge, the states the
    /// decisions [`Decisions::cut`] closes bootstrap from).
    pub fn critic_rows(&self, env: &VecEnv, critic_obs: &mut Vec<f32>) {
        critic_obs.clear();
        let (l, dim, cw) = (self.learners, self.scale.dim(), self.critic_width);
        for r in 0..self.open.len() {
            critic_row(env.observations(), l, r, dim, cw, critic_obs);
        }
    }

    /// A rollout's edge: every open decision closes (to `emit`, in row
    /// order); the robots go on holding their actions.
    pub fn cut(&mut self, emit: &mut dyn FnMut(Closed<'_, P>)) {
        for r in 0..self.open.len() {
            self.close(r, End::Edge, emit);
        }
    }

    /// Closes row `r`'s open decision, if any, as `end` (to `emit`).
    fn close(&mut self, r: usize, end: End, emit: &mut dyn FnMut(Closed<'_, P>)) {
        if let Some(d) = self.open[r].take() {
            let cw = self.critic_width;
            emit(closed(r, &d, &self.open_obs, &self.open_critic, cw, end));
        }
    }
}

fn closed<'a, P: Copy>(
    r: usize,
    d: &Open<P>,
    obs: &'a [f32],
    critic: &'a [f32],
    cw: usize,
    end: End,
) -> Closed<'a, P> {
    Closed {
        row: r,
        obs: &obs[r * OBS_DIM..(r + 1) * OBS_DIM],
        critic_obs: &critic[r * cw..(r + 1) * cw],
        action: d.action,
        shoot_ok: d.shoot_ok,
        banned: d.banned,
        reward: d.reward,
        discount: d.discount,
        ticks: d.ticks,
        payload: d.payload,
        end,
    }
}

/// Appends row `r`'s critic input (`cw` wide; nothing when `cw` is 0): its
/// own observation vector (the layout's `dim` entries), then, with a
/// centralised critic (`cw` > `dim`), those of the other `l` learning
/// robots of its match in order.
pub fn critic_row(feats: &[f32], l: usize, r: usize, dim: usize, cw: usize, out: &mut Vec<f32>) {
    if cw == 0 {
        return;
    }
    let row = |i: usize| &feats[i * OBS_DIM..i * OBS_DIM + dim];
    out.extend_from_slice(row(r));
    if cw > dim {
        let base = r / l * l;
        for k in 0..l {
            if base + k != r {
                out.extend_from_slice(row(base + k));
            }
        }
    }
}
