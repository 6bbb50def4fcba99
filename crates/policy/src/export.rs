//! A PPO actor trained elsewhere (in Python, on the vector env) written as
//! a team directory that everything playing `ppo:DIR` reads: `config.json`
//! (what playing needs: the observation layout and scale, the decision
//! settings) and `final.safetensors` (the actor's layers, `actor.l{i}`,
//! f32). The networks it holds are the shipped PPO teams' shape: linear
//! layers with tanh between them, the last one's outputs the action
//! logits.

use std::path::Path;

use crate::actions::ACTIONS;
use crate::{DecisionConfig, LearnedPolicy, ObsScale, PolicyError, Weights};

/// One linear layer: `weight` row-major, `rows` outputs by `cols` inputs
/// (torch's `nn.Linear.weight` layout), and `rows` biases.
#[derive(Debug, Clone, PartialEq)]
pub struct Layer {
    pub weight: Vec<f32>,
    pub rows: usize,
    pub cols: usize,
    pub bias: Vec<f32>,
}

fn bad(name: String, reason: String) -> PolicyError {
    PolicyError::Weights { name, reason }
}

/// Writes `layers` as a PPO team into `dir` (created if missing; its
/// `config.json` and `final.safetensors` are replaced), for observations
/// encoded with `scale` (its `version` is the layout) and actions under
/// `decision` (`None`: the paper's five actions, every robot deciding
/// every tick). The shapes are checked: the first layer reads the
/// layout's length, each layer the one before's outputs, the last gives
/// one logit per action. The team is then loaded back as `ppo:DIR` would
/// load it, so a directory that does not play is never left behind
/// silently.
pub fn write_ppo_team(
    dir: &Path,
    layers: &[Layer],
    scale: ObsScale,
    decision: Option<DecisionConfig>,
) -> Result<(), PolicyError> {
    let actions = decision.map_or(ACTIONS, |d| d.actions());
    if layers.is_empty() {
        return Err(bad("actor".into(), "no layers".into()));
    }
    let mut inputs = scale.dim();
    for (i, l) in layers.iter().enumerate() {
        let name = format!("actor.l{i}");
        if l.cols != inputs {
            return Err(bad(
                format!("{name}.weight"),
                format!("reads {} inputs, expected {inputs}", l.cols),
            ));
        }
        if l.weight.len() != l.rows * l.cols || l.bias.len() != l.rows || l.rows == 0 {
            return Err(bad(
                name,
                format!(
                    "a {}x{} weight needs {} values and {} biases, got {} and {}",
                    l.rows,
                    l.cols,
                    l.rows * l.cols,
                    l.rows,
                    l.weight.len(),
                    l.bias.len()
                ),
            ));
        }
        if !l.weight.iter().chain(&l.bias).all(|v| v.is_finite()) {
            return Err(bad(name, "holds a value that is not finite".into()));
        }
        inputs = l.rows;
    }
    if inputs != actions {
        return Err(bad(
            format!("actor.l{}.weight", layers.len() - 1),
            format!("gives {inputs} logits, the decision settings have {actions} actions"),
        ));
    }
    std::fs::create_dir_all(dir).map_err(|e| PolicyError::io(dir, e))?;
    let cfg_path = dir.join("config.json");
    let config = serde_json::json!({
        "algo": "ppo",
        "learners": [0, 1, 2, 3],
        "obs_version": scale.version,
        "obs_scale": scale,
        "ppo": { "decision": decision },
        "exported": "naosoccer.export_policy: a PPO actor trained outside naosoccer train",
    });
    let text = serde_json::to_string_pretty(&config).map_err(|error| PolicyError::Json {
        path: cfg_path.clone(),
        error,
    })?;
    std::fs::write(&cfg_path, text + "\n").map_err(|e| PolicyError::io(&cfg_path, e))?;
    let mut w = Weights::default();
    for (i, l) in layers.iter().enumerate() {
        w.insert(
            format!("actor.l{i}.weight"),
            vec![l.rows, l.cols],
            l.weight.clone(),
        );
        w.insert(format!("actor.l{i}.bias"), vec![l.rows], l.bias.clone());
    }
    w.write(&dir.join("final.safetensors"))?;
    LearnedPolicy::load(&format!("ppo:{}", dir.display())).map(|_| ())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Policy;

    fn layer(rows: usize, cols: usize, seed: u32) -> Layer {
        let v = |n: usize, k: u32| -> Vec<f32> {
            (0..n)
                .map(|i| {
                    (((i as u32).wrapping_mul(2_654_435_761) ^ k) % 1000) as f32 / 5000.0 - 0.1
                })
                .collect()
        };
        Layer {
            weight: v(rows * cols, seed),
            rows,
            cols,
            bias: v(rows, seed + 1),
        }
    }

    fn scale(version: u32) -> ObsScale {
        let mut s = ObsScale::from_config(&naosoccer_referee::MatchConfig::default());
        s.version = version;
        s
    }

    #[test]
    fn an_exported_actor_plays_and_reads_back_bit_for_bit() {
        let dir = std::env::temp_dir().join(format!("naosoccer-export-{}", std::process::id()));
        let s = scale(3);
        let d = DecisionConfig {
            pass: true,
            ..DecisionConfig::team()
        };
        let layers = [layer(16, s.dim(), 1), layer(16, 16, 3), layer(6, 16, 5)];
        write_ppo_team(&dir, &layers, s, Some(d)).unwrap();
        let w = Weights::read(&dir.join("final.safetensors")).unwrap();
        for (i, l) in layers.iter().enumerate() {
            let (shape, data) = w.get(&format!("actor.l{i}.weight")).unwrap();
            assert_eq!(shape, &[l.rows, l.cols][..]);
            assert_eq!(data, &l.weight[..]);
        }
        let mut p = LearnedPolicy::load(&format!("ppo:{}", dir.display())).unwrap();
        let m = naosoccer_referee::Match::new(&Default::default(), 3).unwrap();
        let o = m.observe(naosoccer_proto::Team::Blue, 1);
        let _ = p.act(&o);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn shapes_that_do_not_fit_are_refused_naming_the_layer() {
        let dir = std::env::temp_dir().join(format!("naosoccer-export-bad-{}", std::process::id()));
        let s = scale(2);
        let wrong_input = [layer(8, s.dim() + 1, 1), layer(5, 8, 2)];
        let e = write_ppo_team(&dir, &wrong_input, s, None).unwrap_err();
        assert!(e.to_string().contains("actor.l0.weight"), "{e}");
        let wrong_actions = [layer(8, s.dim(), 1), layer(6, 8, 2)];
        let e = write_ppo_team(&dir, &wrong_actions, s, None).unwrap_err();
        assert!(e.to_string().contains("5 actions"), "{e}");
        let mut nan = [layer(8, s.dim(), 1), layer(5, 8, 2)];
        nan[1].bias[0] = f32::NAN;
        let e = write_ppo_team(&dir, &nan, s, None).unwrap_err();
        assert!(e.to_string().contains("not finite"), "{e}");
        assert!(!dir.join("final.safetensors").exists(), "nothing written");
    }
}
