//! Policies map an observation to an action. One file per built-in policy.

use std::fmt;
use std::str::FromStr;

use naosoccer_proto::{Action, Observation, RobotId};

pub mod idle;
pub mod random;
pub mod scripted;

pub use idle::Idle;
pub use random::RandomPolicy;
pub use scripted::{Scripted, ScriptedParams};

/// Decides one robot's action from its observation, every control tick.
///
/// A policy object may drive several robots of one team (a team client): it
/// then receives their observations together in `act_batch`, which learned
/// policies override to run one batched forward pass.
pub trait Policy: Send {
    /// The action for the robot that received `obs`.
    fn act(&mut self, obs: &Observation) -> Action;

    /// The actions for several robots of one team, in order.
    fn act_batch(&mut self, obs: &[Observation], out: &mut [Action]) {
        for (o, a) in obs.iter().zip(out.iter_mut()) {
            *a = self.act(o);
        }
    }

    /// A short name for logs and statistics.
    fn name(&self) -> &str;
}

/// The built-in policies, as named on the command line: `scripted`,
/// `scripted:KEY=VAL,...`, `scripted:FILE.toml`, `random`, `idle`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PolicyKind {
    /// The paper's rule-based team: face the ball, approach, control, shoot
    /// when the distance and angle conditions hold; player 0 keeps goal.
    Scripted,
    /// The same team with other parameters (never the defaults: those are
    /// `Scripted`, see [`PolicyKind::scripted_with`]).
    ScriptedWith(ScriptedParams),
    /// A uniformly random action every tick, from a per-robot seeded stream.
    Random,
    /// `stay`, always.
    Idle,
}

impl PolicyKind {
    /// The policy for one robot. Every player gets its own instance, built
    /// with the match seed and its robot id; the server and the in-process
    /// runner both follow this rule, so they play the same match.
    pub fn build(&self, seed: u64, robot: RobotId) -> Box<dyn Policy> {
        match self {
            PolicyKind::Scripted => Box::new(Scripted::new(ScriptedParams::default())),
            PolicyKind::ScriptedWith(p) => Box::new(Scripted::new(*p)),
            PolicyKind::Random => Box::new(RandomPolicy::new(seed, robot)),
            PolicyKind::Idle => Box::new(Idle),
        }
    }

    /// The scripted team with parameters `p`; the defaults give `Scripted`,
    /// so a kind has one spelling.
    pub fn scripted_with(p: ScriptedParams) -> PolicyKind {
        if p == ScriptedParams::default() {
            PolicyKind::Scripted
        } else {
            PolicyKind::ScriptedWith(p)
        }
    }

    /// The family's name; `Display` gives the whole spec.
    pub fn name(&self) -> &'static str {
        match self {
            PolicyKind::Scripted | PolicyKind::ScriptedWith(_) => "scripted",
            PolicyKind::Random => "random",
            PolicyKind::Idle => "idle",
        }
    }
}

/// The spec that parses back to this kind: a variant spells out the
/// parameters it changes (`scripted:shoot_range=3.5`), never a file name,
/// so a saved spec does not depend on a file that may change.
impl fmt::Display for PolicyKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PolicyKind::ScriptedWith(p) => write!(f, "scripted:{}", p.diff_spec()),
            k => f.write_str(k.name()),
        }
    }
}

/// A policy spec that is not a built-in policy, or a scripted variant that
/// does not parse.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{reason}")]
#[non_exhaustive]
pub struct ParsePolicyError {
    pub name: String,
    pub reason: String,
}

impl FromStr for PolicyKind {
    type Err = ParsePolicyError;
    /// `scripted`, `scripted:KEY=VAL,...`, `scripted:FILE.toml`, `random`, `idle`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if let Some(params) = s.strip_prefix("scripted:") {
            return ScriptedParams::parse_spec(params)
                .map(PolicyKind::scripted_with)
                .map_err(|reason| ParsePolicyError {
                    name: s.to_string(),
                    reason: format!("policy {s:?}: {reason}"),
                });
        }
        match s {
            "scripted" => Ok(PolicyKind::Scripted),
            "random" => Ok(PolicyKind::Random),
            "idle" => Ok(PolicyKind::Idle),
            other => Err(ParsePolicyError {
                name: other.to_string(),
                reason: format!(
                    "unknown policy {other:?} (expected scripted, scripted:KEY=VAL,..., \
                     scripted:FILE.toml, random or idle)"
                ),
            }),
        }
    }
}

/// Whether a spec names a built-in policy rather than a trained team
/// (`ppo:DIR`, ...): no colon, or a scripted variant.
pub fn is_builtin_spec(spec: &str) -> bool {
    !spec.contains(':') || spec.starts_with("scripted:")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for k in [PolicyKind::Scripted, PolicyKind::Random, PolicyKind::Idle] {
            assert_eq!(k.to_string().parse::<PolicyKind>(), Ok(k));
        }
        let err = "ppo".parse::<PolicyKind>().unwrap_err();
        assert!(err.to_string().contains("ppo"));
    }

    #[test]
    fn scripted_variants_parse_and_print_as_the_same_spec() {
        let k: PolicyKind = "scripted:shoot_range=3.5, b_shoot=0.4".parse().unwrap();
        let PolicyKind::ScriptedWith(p) = k else {
            panic!("{k:?}")
        };
        assert_eq!((p.shoot_range, p.b_shoot), (3.5, 0.4));
        assert_eq!(p.reach_max, ScriptedParams::default().reach_max);
        assert_eq!(k.to_string(), "scripted:b_shoot=0.4,shoot_range=3.5");
        assert_eq!(k.to_string().parse::<PolicyKind>(), Ok(k));
        // The defaults spelled out are the plain scripted team.
        assert_eq!(
            "scripted:shoot_range=2".parse::<PolicyKind>(),
            Ok(PolicyKind::Scripted)
        );
        assert!(is_builtin_spec("scripted:b_rad=0.3") && is_builtin_spec("idle"));
        assert!(!is_builtin_spec("ppo:runs/x"));
    }

    #[test]
    fn scripted_variants_read_toml_files() {
        let path =
            std::env::temp_dir().join(format!("naosoccer-variant-{}.toml", std::process::id()));
        std::fs::write(&path, "# further\nshoot_range = 3.0\nbehind = 0.2\n").unwrap();
        let k: PolicyKind = format!("scripted:{}", path.display()).parse().unwrap();
        assert_eq!(k.to_string(), "scripted:behind=0.2,shoot_range=3");
        std::fs::write(&path, "shoot_rnage = 3.0\n").unwrap();
        let err = format!("scripted:{}", path.display())
            .parse::<PolicyKind>()
            .unwrap_err();
        assert!(err.to_string().contains("shoot_rnage"), "{err}");
        std::fs::write(&path, "shoot_range = \"far\"\n").unwrap();
        let err = format!("scripted:{}", path.display())
            .parse::<PolicyKind>()
            .unwrap_err();
        assert!(err.to_string().contains("shoot_range"), "{err}");
        std::fs::remove_file(&path).unwrap();
        let err = "scripted:/nonexistent/v.toml"
            .parse::<PolicyKind>()
            .unwrap_err();
        assert!(err.to_string().contains("/nonexistent/v.toml"), "{err}");
    }

    #[test]
    fn bad_scripted_variants_say_what_is_wrong() {
        let err = |s: &str| s.parse::<PolicyKind>().unwrap_err().to_string();
        let e = err("scripted:shot_range=3");
        assert!(
            e.contains("unknown scripted parameter \"shot_range\"") && e.contains("shoot_range"),
            "{e}"
        );
        assert!(err("scripted:shoot_range=far").contains("\"far\" is not a number"));
        assert!(err("scripted:shoot_range").contains("expected KEY=VAL"));
        assert!(err("scripted:shoot_range=-1").contains("shoot_range must be a positive number"));
        assert!(err("scripted:b_rad=NaN").contains("b_rad must be a finite number"));
        assert!(err("scripted:reach_min=0.3").contains("reach_min (0.3) must be below reach_max"));
        assert!(err("scripted:turn_stop=0.5").contains("turn_stop"));
        assert!(err("scripted:").contains("expected KEY=VAL"));
    }
}
