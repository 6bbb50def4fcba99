//! One slot of a vector env: its match, its built-in robots and what its
//! last reset or step wrote; starting a slot's next match and stepping it
//! one control tick, on whichever thread takes it.

use naosoccer_eval::run::MatchSlot;
use naosoccer_policy::actions::banned_actions;
use naosoccer_policy::{NetAction, OBS_DIM};
use naosoccer_proto::Observation;

use super::setup::{match_seed, pick, Setup};
use super::{Finished, ScenarioEnding, VecEnvError};

pub(super) struct Slot {
    /// The slot's index and the seed of the last reset: with `episode`,
    /// the current match's seed.
    pub(super) index: usize,
    pub(super) reset_seed: u64,
    /// The match, its built-in opponents (none for the robots driven by
    /// the caller or by a trained opponent), its robots' observations and
    /// actions, and a scenario's judge.
    pub(super) game: MatchSlot,
    /// Matches this slot finished since the last reset.
    pub(super) episode: u64,
    /// The scenario the match started from (its index in the list).
    pub(super) drill: Option<usize>,
    /// Finished and, without restarts, kept until the next reset.
    pub(super) ended: bool,
    /// What the last reset or step wrote for this slot, kept from match to
    /// match so that stepping allocates nothing.
    pub(super) out: SlotOut,
}

/// One slot's share of a [`StepOut`], and what went wrong stepping it.
#[derive(Default)]
pub(super) struct SlotOut {
    pub(super) obs: Vec<f32>,
    pub(super) rewards: Vec<f32>,
    pub(super) masks: Vec<bool>,
    pub(super) terminated: bool,
    pub(super) finished: Option<Finished>,
    pub(super) error: Option<VecEnvError>,
}

impl SlotOut {
    pub(super) fn new(setup: &Setup) -> SlotOut {
        let rows = setup.robots.len();
        SlotOut {
            obs: vec![0.0; rows * setup.dim()],
            rewards: vec![0.0; rows],
            masks: vec![true; rows * setup.actions()],
            terminated: false,
            finished: None,
            error: None,
        }
    }
}

/// Slot `index`'s `episode`-th match after a reset with `reset_seed`, with
/// no buffers for its rows yet.
pub(super) fn new_slot(
    setup: &Setup,
    index: usize,
    reset_seed: u64,
    episode: u64,
) -> Result<Slot, VecEnvError> {
    let seed = match_seed(setup, index, reset_seed, episode);
    let drill = pick(setup, seed);
    let scenario = drill.map(|d| (&setup.drills[d].scenario, setup.own));
    let mut game = MatchSlot::new(&setup.cfg, seed, scenario)?;
    let builtin = drill
        .and_then(|d| setup.drills[d].opponent)
        .or(setup.builtin);
    game.build_policies(|r| builtin.filter(|_| !setup.robots.contains(&r)));
    Ok(Slot {
        index,
        reset_seed,
        game,
        episode,
        drill,
        ended: false,
        out: SlotOut::default(),
    })
}

/// Writes a slot's rows of observations and masks from its robots'
/// observations.
pub(super) fn write_rows(setup: &Setup, obs: &[Observation], out: &mut SlotOut) {
    let dim = setup.dim();
    let actions = setup.actions();
    let mut row = [0.0f32; OBS_DIM];
    for (k, r) in setup.robots.iter().enumerate() {
        let o = &obs[r.index()];
        setup.scale.encode(o, &mut row);
        out.obs[k * dim..(k + 1) * dim].copy_from_slice(&row[..dim]);
        let mask = &mut out.masks[k * actions..(k + 1) * actions];
        mask.fill(true);
        if let Some(d) = &setup.decision {
            let in_reach = setup.scale.kick.in_reach(o);
            let mut bans = banned_actions(o, in_reach, d);
            if d.mask_shoot && !in_reach {
                bans |= NetAction::Shoot.bit();
            }
            for (a, m) in mask.iter_mut().enumerate() {
                *m = bans & (1 << a) == 0;
            }
        }
    }
}

/// One control tick of one slot's match, on whichever thread takes it:
/// the built-in robots decide, the match steps, and the slot's rows, its
/// ending and, if it ended, its next match are written into the slot.
pub(super) fn step_slot(setup: &Setup, slot: &mut Slot) -> Result<(), VecEnvError> {
    slot.out.terminated = false;
    slot.out.finished = None;
    // The built-in robots decide, the match steps, a scenario's judge reads
    // the tick and every robot observes.
    let ending = slot.game.step();
    let m = slot.game.match_ref();
    for (k, r) in setup.robots.iter().enumerate() {
        slot.out.rewards[k] = m.reward(r.team(), r.player());
    }
    write_rows(setup, slot.game.observations(), &mut slot.out);
    if m.is_finished() || ending.is_some() {
        slot.out.terminated = true;
        slot.out.finished = Some(Finished {
            slot: slot.index,
            seed: m.seed(),
            ticks: m.tick().get(),
            score: m.score(),
            stats: m.stats(),
            state_hash: m.state_hash(),
            obs: slot.out.obs.clone(),
            scenario: ending.zip(slot.drill).map(|(e, d)| ScenarioEnding {
                name: setup.drills[d].scenario.name.clone(),
                ending: e.kind.name(),
                success: e.success,
                ticks: e.ticks,
            }),
        });
        if !setup.restart {
            slot.ended = true;
            return Ok(());
        }
        let mut next = new_slot(setup, slot.index, slot.reset_seed, slot.episode + 1)?;
        std::mem::swap(&mut next.out, &mut slot.out);
        *slot = next;
        write_rows(setup, slot.game.observations(), &mut slot.out);
    }
    Ok(())
}
