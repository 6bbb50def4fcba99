//! A team's policy as the command line names it: a built-in team
//! (`scripted`, a variant `scripted:KEY=VAL,...` or `scripted:FILE.toml`,
//! `random`, `idle`) or a trained one (`ppo:DIR`,
//! `ppo-greedy:DIR`, `dqn:DIR`, `dqn-epsilon:DIR`; docs/LEARNING.md).
//! `naosoccer match` and `naosoccer client` both take it.

use naosoccer_client::TeamPolicy;
use naosoccer_eval::run::Side;
use naosoccer_policy::{LearnedPolicy, Policy, PolicyKind};

/// A parsed team spec. A trained team has been loaded once already, so a
/// bad path or a mismatched checkpoint fails before any match starts.
#[derive(Debug, Clone)]
pub enum TeamSpec {
    Builtin(PolicyKind),
    Learned(String),
}

impl TeamSpec {
    /// `what` names the option in errors (`--policy`, `--blue`).
    pub fn parse(spec: &str, what: &str) -> anyhow::Result<TeamSpec> {
        if naosoccer_policy::is_builtin_spec(spec) {
            let kind: PolicyKind = spec.parse().map_err(|e| {
                anyhow::anyhow!("{what}: {e}, or a trained team such as ppo:DIR or dqn:DIR")
            })?;
            return Ok(TeamSpec::Builtin(kind));
        }
        check_learned(spec, what)?;
        Ok(TeamSpec::Learned(spec.to_owned()))
    }

    /// The team as the in-process runner plays it (`naosoccer_eval::run`):
    /// built-in robots built per robot from the match seed, a trained team
    /// keyed by it, as the clients play them, so in-process and socket
    /// matches agree.
    pub fn side(&self) -> anyhow::Result<Side> {
        use anyhow::Context;
        match self {
            TeamSpec::Builtin(k) => Ok(Side::Builtin(*k)),
            TeamSpec::Learned(spec) => {
                let p = LearnedPolicy::load(spec).with_context(|| format!("loading {spec}"))?;
                Ok(Side::Learned(Box::new(p)))
            }
        }
    }

    /// For the robot client loop: a trained team over a team connection
    /// answers for all its players in one forward pass.
    pub fn team_policy(&self) -> TeamPolicy {
        match self {
            TeamSpec::Builtin(k) => (*k).into(),
            TeamSpec::Learned(spec) => {
                let owned = spec.clone();
                TeamPolicy::Custom {
                    name: spec.clone(),
                    batched: true,
                    build: std::sync::Arc::new(move |seed, _robot| {
                        load_learned(&owned, seed).map_err(|e| crate::cmd::error_text(&e))
                    }),
                }
            }
        }
    }
}

impl std::fmt::Display for TeamSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TeamSpec::Builtin(k) => write!(f, "{k}"),
            TeamSpec::Learned(s) => f.write_str(s),
        }
    }
}

fn check_learned(spec: &str, what: &str) -> anyhow::Result<()> {
    use anyhow::Context;
    naosoccer_policy::load_policy(spec).with_context(|| format!("loading {what} {spec}"))?;
    Ok(())
}

fn load_learned(spec: &str, seed: u64) -> anyhow::Result<Box<dyn Policy>> {
    use anyhow::Context;
    naosoccer_policy::load_policy_for_match(spec, seed).with_context(|| format!("loading {spec}"))
}
