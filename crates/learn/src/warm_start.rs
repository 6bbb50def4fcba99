//! Warm starts: a PPO run that begins from a trained team's weights
//! (`--init-from`), its actor widened when the run has actions the team
//! lacked.

use std::path::Path;

use crate::ppo::Ppo;
use crate::LearnError;

/// Loads `path`'s weights (a run's `final.safetensors` or a checkpoint, or
/// a run directory holding `final.safetensors`) into `ppo`'s networks. Every
/// variable must be there with its shape, except that an actor with the
/// `pass` action may start from one without it: its extra output row (the
/// last layer's weights and bias) starts as a copy of `pass_from`'s (with
/// `shoot`, `pass` is at first as likely as `shoot` where both are
/// possible). `pass_from` must be one of the paper's five actions. A gained
/// `support` row starts as `forward`'s with its bias `support_bias` lower,
/// a gained `approach` row as an exact copy of `forward`'s, a gained
/// `defend` row as `support`'s with its bias `support_bias` lower, a gained
/// `give` row as `approach`'s with its bias `support_bias` lower.
pub fn init_weights(
    ppo: &mut Ppo,
    path: &Path,
    pass_from: naosoccer_proto::Action,
    support_bias: f32,
) -> Result<(), LearnError> {
    use naosoccer_policy::NetAction;
    let file = if path.is_dir() {
        path.join("final.safetensors")
    } else {
        path.to_path_buf()
    };
    let bad =
        |reason: String| LearnError::Config(format!("--init-from {}: {reason}", file.display()));
    if !file.is_file() {
        return Err(bad("no such weights file".into()));
    }
    let pass_row = pass_from.index();
    if pass_row >= NetAction::Pass.index() {
        return Err(bad(format!(
            "pass cannot start as a copy of {:?}: pick one of the five actions the source has",
            pass_from.name()
        )));
    }
    let named: std::collections::BTreeMap<String, tch::Tensor> =
        tch::Tensor::read_safetensors(&file)?.into_iter().collect();
    let mut vars: Vec<(String, tch::Tensor)> = ppo.net.vs.variables().into_iter().collect();
    vars.sort_by(|a, b| a.0.cmp(&b.0));
    for (name, mut var) in vars {
        let src = named
            .get(&name)
            .ok_or_else(|| bad(format!("no tensor {name:?} (a run of another shape?)")))?;
        let (want, got) = (var.size(), src.size());
        tch::no_grad(|| -> Result<(), LearnError> {
            // The actor's output layer may gain rows: `pass` (a copy of
            // `pass_from`, by default `shoot`), `support` (a copy of
            // `forward`, its bias lowered by `support_bias`, by default
            // SUPPORT_INIT_BIAS so that it starts rarer than `forward`) and
            // `approach` (an exact copy of `forward`), `defend` (a copy
            // of `support`, its bias lowered by `support_bias`) and `give`
            // (a copy of `approach`, its bias lowered the same).
            let (pass, support, approach, defend, give) = (
                NetAction::Pass.index() as i64,
                NetAction::Support.index() as i64,
                NetAction::Approach.index() as i64,
                NetAction::Defend.index() as i64,
                NetAction::Give.index() as i64,
            );
            let widen = name.starts_with("actor.")
                && !want.is_empty()
                && want[1..] == got[1..]
                && (pass..=give).contains(&got[0])
                && (pass + 1..=give + 1).contains(&want[0])
                && want[0] > got[0];
            if want == got {
                var.copy_(src);
            } else if widen {
                var.narrow(0, 0, got[0]).copy_(src);
                let forward = src.narrow(0, NetAction::Forward.index() as i64, 1);
                if got[0] <= pass {
                    var.narrow(0, pass, 1)
                        .copy_(&src.narrow(0, pass_row as i64, 1));
                }
                if got[0] <= support && want[0] > support {
                    let row = if want.len() == 1 {
                        &forward - f64::from(support_bias)
                    } else {
                        forward.shallow_clone()
                    };
                    var.narrow(0, support, 1).copy_(&row);
                }
                if got[0] <= approach && want[0] > approach {
                    var.narrow(0, approach, 1).copy_(&forward);
                }
                // A gained row as the copy of another one, its bias (not
                // its weights) lowered by `support_bias`.
                let lowered_copy = |var: &mut tch::Tensor, to: i64, from: i64| {
                    let row = var.narrow(0, from, 1).copy();
                    let row = if want.len() == 1 {
                        &row - f64::from(support_bias)
                    } else {
                        row
                    };
                    var.narrow(0, to, 1).copy_(&row);
                };
                if got[0] <= defend && want[0] > defend {
                    lowered_copy(&mut var, defend, support);
                }
                if want[0] > give {
                    lowered_copy(&mut var, give, approach);
                }
            } else {
                return Err(bad(format!(
                    "{name} is {got:?} there, the run's network needs {want:?}"
                )));
            }
            Ok(())
        })?;
    }
    Ok(())
}

/// How much lower `support`'s bias starts than `forward`'s when
/// `--init-from` widens an actor: e^-1, about 2.7 times less likely.
pub const SUPPORT_INIT_BIAS: f32 = 1.0;
