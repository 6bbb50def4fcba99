//! A run's environment, built from its configuration: the matches, the
//! learning robots' teammates, the first opponents, drills; and the checks
//! of which settings go together, made before anything is built.

use naosoccer_policy::PolicyKind;

use crate::config::{run_scale, Algo, OpponentSpec, TrainConfig};
use crate::env::{EnvConfig, Opponent, VecEnv};
use crate::obs::{layout_dim, OBS_VERSION_LATEST};
use crate::policy::{self_play_snapshot, LearnedPolicy};
use crate::LearnError;

fn opponent_for(cfg: &TrainConfig) -> Result<Opponent, LearnError> {
    Ok(match &cfg.opponent {
        OpponentSpec::Builtin(name) => Opponent::Builtin(
            name.parse::<PolicyKind>()
                .map_err(|e| LearnError::Config(e.to_string()))?,
        ),
        OpponentSpec::Frozen(spec) => {
            let mut p = LearnedPolicy::load(spec)?;
            p.set_match_seed(cfg.seed);
            Opponent::Net(Box::new(p))
        }
        // The first snapshot is the untrained network, as in self-play from
        // scratch.
        OpponentSpec::SelfPlay { .. } => Opponent::Net(Box::new(self_play_snapshot(cfg, None)?)),
        // The schedule's runner sets the opponents once the learner exists
        // (a DQN learner's snapshots play greedily, as in self-play).
        OpponentSpec::Schedule(_) => Opponent::Builtin(PolicyKind::Idle),
    })
}

/// The environment `cfg` describes, once its settings are known to go
/// together.
pub(crate) fn make_env(cfg: &TrainConfig) -> Result<VecEnv, LearnError> {
    let supported = match cfg.algo {
        Algo::Ppo => layout_dim(cfg.obs_version).is_some(),
        Algo::Dqn => cfg.obs_version >= 2 && layout_dim(cfg.obs_version).is_some(),
    };
    if !supported {
        return Err(LearnError::Config(format!(
            "{} cannot train on observation layout v{} (this build encodes v1 to \
             v{OBS_VERSION_LATEST}; DQN trains on v2 and later)",
            cfg.algo, cfg.obs_version
        )));
    }
    let decisions = [cfg.ppo.decision, cfg.dqn.decision];
    if decisions.iter().flatten().any(|d| d.support && !d.pass) {
        return Err(LearnError::Config(
            "the support action comes with the pass action (--pass-action --support-action)".into(),
        ));
    }
    if decisions
        .iter()
        .flatten()
        .any(|d| d.support_hold > 0 && !d.support)
    {
        return Err(LearnError::Config(
            "--support-hold holds the support action: it needs --support-action".into(),
        ));
    }
    if decisions
        .iter()
        .flatten()
        .any(|d| d.chasers > 0 && !d.support)
    {
        return Err(LearnError::Config(
            "--support-roles sends the robots away from the ball to support: it needs \
             --support-action"
                .into(),
        ));
    }
    if decisions
        .iter()
        .flatten()
        .any(|d| d.support_only && d.chasers == 0)
    {
        return Err(LearnError::Config(
            "--support-only applies to the robots that do not chase: it needs --support-roles"
                .into(),
        ));
    }
    if decisions
        .iter()
        .flatten()
        .any(|d| (d.approach || d.defend || d.support_spot != Default::default()) && !d.support)
    {
        return Err(LearnError::Config(
            "--approach-action, --defend-action and --support-spot come with the support \
             action: they need --support-action"
                .into(),
        ));
    }
    if decisions
        .iter()
        .flatten()
        .any(|d| d.give && !(d.pass && d.approach && d.defend))
    {
        return Err(LearnError::Config(
            "--give-action lines up a pass with the walking steps: it needs --pass-action, \
             --approach-action and --defend-action"
                .into(),
        ));
    }
    if decisions
        .iter()
        .flatten()
        .any(|d| d.approach_only && !d.approach)
    {
        return Err(LearnError::Config(
            "--approach-only leaves the robots `approach` to move: it needs --approach-action"
                .into(),
        ));
    }
    if decisions.iter().flatten().any(|d| d.chasers >= 4) {
        return Err(LearnError::Config(
            "--support-roles names how many of the four robots chase: 1 to 3".into(),
        ));
    }
    if cfg.init_from.is_some() && (cfg.algo != Algo::Ppo || cfg.ppo.decision.is_none()) {
        return Err(LearnError::Config(
            "--init-from starts PPO team-preset runs (--algo ppo --preset team) only; a DQN \
             team starts from fresh weights"
                .into(),
        ));
    }
    if cfg.init_support_bias.is_some()
        && (cfg.init_from.is_none() || !cfg.ppo.decision.is_some_and(|d| d.support))
    {
        return Err(LearnError::Config(
            "--support-init-bias sets where a gained support row starts: it needs --init-from \
             and --support-action"
                .into(),
        ));
    }
    if cfg.init_support_bias.is_some_and(|b| !b.is_finite()) {
        return Err(LearnError::Config(
            "--support-init-bias must be a finite number".into(),
        ));
    }
    if cfg.init_pass_from.is_some()
        && (cfg.init_from.is_none() || !cfg.ppo.decision.is_some_and(|d| d.pass))
    {
        return Err(LearnError::Config(
            "--pass-init names where a gained pass row starts: it needs --init-from and --pass-action"
                .into(),
        ));
    }
    if cfg.ppo.decision.is_some() && cfg.obs_version < 2 {
        return Err(LearnError::Config(
            "the decision-level MDP needs observation layout v2 (busy flags, kick reach)".into(),
        ));
    }
    let teammates = cfg
        .teammates
        .parse::<PolicyKind>()
        .map_err(|e| LearnError::Config(e.to_string()))?;
    let mut env = VecEnv::new(
        &cfg.match_config,
        EnvConfig {
            matches: cfg.matches,
            learners: cfg.learners.clone(),
            teammates,
            threads: cfg.threads,
            seed: cfg.seed,
            support_spot: cfg
                .decision()
                .map_or_else(Default::default, |d| d.support_spot),
        },
        opponent_for(cfg)?,
    )?;
    env.set_obs_scale(run_scale(cfg));
    if cfg.drill.is_some() {
        env.set_drill(cfg.drill)?;
    }
    if cfg.pass_drills.is_some() {
        return Err(LearnError::Config(
            "this run was made with the pass drills of naosoccer before they became scenarios \
             (assets/scenarios/training/pass-*.toml); resume it with that version"
                .into(),
        ));
    }
    if let Some(drills) = &cfg.scenarios {
        if !matches!(cfg.algo, Algo::Ppo) || cfg.ppo.decision.is_none() {
            return Err(LearnError::Config(
                "scenarios need the PPO team preset (its loop bootstraps a scenario's cut end)"
                    .into(),
            ));
        }
        env.set_scenarios(Some(drills))?;
    }
    Ok(env)
}
