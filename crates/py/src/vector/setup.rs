//! What every match of a vector env is played under (its [`Setup`]), and
//! how a match's seed and scenario are drawn from it: the seed of slot
//! `i`'s `e`-th match, the scenarios' weights, the opponents they name and
//! the choice of the scenario a match starts from.

use naosoccer_policy::actions::action_count;
use naosoccer_policy::{DecisionConfig, ObsScale, PolicyKind};
use naosoccer_proto::{RobotId, Team};
use naosoccer_referee::{MatchConfig, Scenario};
use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::VecEnvError;

/// What every slot's matches are played under, fixed for the env's life
/// and shared with the stepping threads.
pub(super) struct Setup {
    pub(super) matches: usize,
    pub(super) cfg: MatchConfig,
    pub(super) robots: Vec<RobotId>,
    pub(super) scale: ObsScale,
    pub(super) decision: Option<DecisionConfig>,
    /// The built-in policy of the robots the caller does not drive (`None`:
    /// a trained team, which the env's own thread runs for all slots, or
    /// each scenario's own).
    pub(super) builtin: Option<PolicyKind>,
    /// The scenarios a match may start from (none: the kick-off).
    pub(super) drills: Vec<Drill>,
    /// The running sums of the scenarios' weights, the last their total.
    pub(super) cumulative: Vec<f64>,
    /// The colour of the scenarios' own team.
    pub(super) own: Team,
    pub(super) restart: bool,
}

/// A scenario of the list.
pub(super) struct Drill {
    pub(super) scenario: Scenario,
    /// Its own opponents, when the scenarios name different built-in ones
    /// and the caller named none.
    pub(super) opponent: Option<PolicyKind>,
}

/// The stream of the scenario choice: the match seed mixed with this seeds
/// its generator, another stream than the scenario's own draws (the
/// referee's), so the start a scenario draws is the same chosen from a list
/// or played alone.
pub(super) const PICK_STREAM: u64 = 0xC401_CE5D_A11E_5EED;

impl Setup {
    pub(super) fn actions(&self) -> usize {
        action_count(self.decision)
    }

    pub(super) fn dim(&self) -> usize {
        self.scale.dim()
    }
}

pub(super) fn match_seed(setup: &Setup, slot: usize, reset_seed: u64, episode: u64) -> u64 {
    reset_seed
        .wrapping_add(slot as u64)
        .wrapping_add(episode.wrapping_mul(setup.matches as u64))
}

/// The running sums of the weights of `n` scenarios (`None`: 1 each),
/// once they are checked.
pub(super) fn cumulative_weights(
    n: usize,
    weights: Option<Vec<f64>>,
) -> Result<Vec<f64>, VecEnvError> {
    let bad = |m: String| Err(VecEnvError::Config(format!("scenario_weights: {m}")));
    let weights = match weights {
        None => vec![1.0; n],
        Some(_) if n == 0 => return bad("given without a scenario".into()),
        Some(w) if w.len() != n => {
            return bad(format!(
                "{} given for {n} scenarios: one weight a scenario",
                w.len()
            ))
        }
        Some(w) => w,
    };
    if let Some((i, w)) = weights
        .iter()
        .enumerate()
        .find(|(_, w)| !(w.is_finite() && **w >= 0.0))
    {
        return bad(format!(
            "weight {i} is {w}: a weight is a finite number, 0 or more"
        ));
    }
    let cumulative: Vec<f64> = weights
        .iter()
        .scan(0.0, |sum, w| {
            *sum += w;
            Some(*sum)
        })
        .collect();
    if let Some(&total) = cumulative.last() {
        if total == 0.0 {
            return bad("all are 0: at least one must be positive".into());
        }
        if !total.is_finite() {
            return bad("their sum is not a finite number".into());
        }
    }
    Ok(cumulative)
}

/// The opponents' spec when every match plays the same: `opponent`; else
/// the one every scenario names; else `scripted` without scenarios.
/// `None`: the scenarios name different built-in policies, each match
/// plays its own scenario's; a trained team among them is refused.
pub(super) fn resolve_opponent(
    opponent: Option<String>,
    scenarios: &[Scenario],
) -> Result<Option<String>, VecEnvError> {
    if let Some(o) = opponent {
        return Ok(Some(o));
    }
    let Some(first) = scenarios.first() else {
        return Ok(Some("scripted".to_owned()));
    };
    if scenarios.iter().all(|s| s.opponent == first.opponent) {
        return Ok(Some(first.opponent.clone()));
    }
    if let Some((i, s)) = scenarios
        .iter()
        .enumerate()
        .find(|(_, s)| !naosoccer_policy::is_builtin_spec(&s.opponent))
    {
        let named: Vec<&str> = scenarios.iter().map(|s| s.opponent.as_str()).collect();
        return Err(VecEnvError::Config(format!(
            "the scenarios name different opponents ({}) and scenario[{i}] ({}) names a \
             trained team, {:?}, which plays every match or none: pass opponent= to name \
             the policy every match's opponents play",
            named.join(", "),
            s.name,
            s.opponent
        )));
    }
    Ok(None)
}

/// Each scenario's own opponents, all built-in policies.
pub(super) fn scenario_opponents(
    scenarios: &[Scenario],
) -> Result<Vec<Option<PolicyKind>>, VecEnvError> {
    scenarios
        .iter()
        .enumerate()
        .map(|(i, s)| {
            s.opponent.parse::<PolicyKind>().map(Some).map_err(|e| {
                VecEnvError::Config(format!("scenario[{i}] ({}): opponent: {e}", s.name))
            })
        })
        .collect()
}

/// The scenario the match of `seed` starts from, as its index in the list:
/// with two or more, scenario `i` with chance `weight[i] / sum`, from a
/// uniform number in [0, 1) (the top 53 bits of the first 64-bit draw) of a
/// ChaCha8 generator seeded by `seed ^ PICK_STREAM`. `None` without
/// scenarios.
pub(super) fn pick(setup: &Setup, seed: u64) -> Option<usize> {
    match setup.drills.len() {
        0 => None,
        1 => Some(0),
        _ => {
            let mut rng = ChaCha8Rng::seed_from_u64(seed ^ PICK_STREAM);
            let u = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
            let total = *setup.cumulative.last()?;
            let x = u * total;
            // Rounding may carry `x` to the total: the last scenario with a
            // weight then, never one of weight 0.
            setup
                .cumulative
                .iter()
                .position(|&c| x < c)
                .or_else(|| setup.cumulative.iter().position(|&c| c >= total))
        }
    }
}
