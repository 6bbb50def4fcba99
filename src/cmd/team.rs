//! A team's policy as the command line names it: a built-in team
//! (`scripted`, a variant `scripted:KEY=VAL,...` or `scripted:FILE.toml`,
//! `random`, `idle`) or a trained one (`ppo:DIR`,
//! `ppo-greedy:DIR`, `dqn:DIR`, `dqn-epsilon:DIR`; docs/LEARNING.md).
//! `naosoccer match` and `naosoccer client` both take it.

use naosoccer_client::TeamPolicy;
use naosoccer_policy::{Policy, PolicyKind};
use naosoccer_proto::RobotId;

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

    /// The policy of `robot` in a match of seed `seed`: the same rule the
    /// server-side clients follow, so in-process and socket matches agree.
    pub fn build(&self, seed: u64, robot: RobotId) -> anyhow::Result<Box<dyn Policy>> {
        match self {
            TeamSpec::Builtin(k) => Ok(k.build(seed, robot)),
            TeamSpec::Learned(spec) => load_learned(spec, seed),
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
