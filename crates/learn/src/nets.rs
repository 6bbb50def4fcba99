//! The networks: PPO's actor and critic, DQN's Q-network. Plain MLPs built
//! under a named path in a `VarStore`, so checkpoints are safetensors files
//! whose tensor names say what they are.

use serde::{Deserialize, Serialize};
use tch::nn::{self, Module};
use tch::Tensor;

use crate::config::{PpoConfig, Preset};
use crate::obs::{ObsScale, OBS_DIM};

pub use naosoccer_policy::Activation;

/// How weights start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum InitScheme {
    /// libtorch's default (Kaiming uniform), as PyTorch's `nn.Linear`.
    Default,
    /// Orthogonal hidden layers (gain sqrt 2) and the given gain on the output
    /// layer, zero biases (the CleanRL convention).
    Orthogonal { output_gain: f64 },
}

/// An MLP `input -> hidden... -> output`, activation between layers and none
/// after the last.
#[derive(Debug)]
pub struct Mlp {
    seq: nn::Sequential,
}

impl Mlp {
    pub fn new(
        p: &nn::Path,
        input: usize,
        hidden: &[usize],
        output: usize,
        act: Activation,
        init: InitScheme,
    ) -> Mlp {
        let mut seq = nn::seq();
        let mut dims = Vec::with_capacity(hidden.len() + 2);
        dims.push(input as i64);
        dims.extend(hidden.iter().map(|&h| h as i64));
        dims.push(output as i64);
        let layers = dims.len() - 1;
        for i in 0..layers {
            let last = i + 1 == layers;
            let cfg = match init {
                InitScheme::Default => nn::LinearConfig::default(),
                InitScheme::Orthogonal { output_gain } => nn::LinearConfig {
                    ws_init: nn::Init::Orthogonal {
                        gain: if last {
                            output_gain
                        } else {
                            std::f64::consts::SQRT_2
                        },
                    },
                    bs_init: Some(nn::Init::Const(0.0)),
                    bias: true,
                },
            };
            seq = seq.add(nn::linear(p / format!("l{i}"), dims[i], dims[i + 1], cfg));
            if !last {
                seq = match act {
                    Activation::Tanh => seq.add_fn(|x| x.tanh()),
                    Activation::Relu => seq.add_fn(|x| x.relu()),
                };
            }
        }
        Mlp { seq }
    }

    pub fn forward(&self, xs: &Tensor) -> Tensor {
        self.seq.forward(xs)
    }
}

/// The actor (action logits) and critic (state value), in one `VarStore`:
/// the actor's variables in optimiser group 0, the critic's in group 1, so
/// one Adam runs both at their own learning rates.
pub struct ActorCritic {
    pub vs: nn::VarStore,
    actor: Mlp,
    critic: Mlp,
    /// Input widths: the layout's length, and the critic's (a multiple of it
    /// with a centralised critic).
    pub obs_dim: usize,
    pub critic_dim: usize,
}

impl ActorCritic {
    /// The networks of a run: observations of `scale`'s layout, `learners`
    /// robots per team (the centralised critic's input).
    pub fn for_run(cfg: &PpoConfig, scale: &ObsScale, learners: usize) -> ActorCritic {
        let d = scale.dim();
        let c = if cfg.central_critic {
            d * learners.max(1)
        } else {
            d
        };
        ActorCritic::new(cfg, d, c)
    }

    pub fn new(cfg: &PpoConfig, obs_dim: usize, critic_dim: usize) -> ActorCritic {
        let vs = nn::VarStore::new(tch::Device::Cpu);
        let (ai, ci) = match cfg.preset {
            Preset::Paper => (InitScheme::Default, InitScheme::Default),
            Preset::Cleanrl | Preset::Team => (
                InitScheme::Orthogonal { output_gain: 0.01 },
                InitScheme::Orthogonal { output_gain: 1.0 },
            ),
        };
        let root = vs.root();
        let actor = Mlp::new(
            &(root.set_group(0) / "actor"),
            obs_dim,
            &cfg.hidden,
            cfg.actions(),
            Activation::Tanh,
            ai,
        );
        let critic = Mlp::new(
            &(root.set_group(1) / "critic"),
            critic_dim,
            &cfg.hidden,
            1,
            Activation::Tanh,
            ci,
        );
        ActorCritic {
            vs,
            actor,
            critic,
            obs_dim,
            critic_dim,
        }
    }

    /// `n` rows of width `OBS_DIM` as the actor's input (their layout prefix).
    pub fn actor_input(&self, rows: &[f32], n: usize) -> Tensor {
        rows_tensor(rows, n, OBS_DIM, self.obs_dim)
    }

    /// Action logits, `[n, ACTIONS]`.
    pub fn logits(&self, obs: &Tensor) -> Tensor {
        self.actor.forward(obs)
    }

    /// State values, `[n]`.
    pub fn value(&self, obs: &Tensor) -> Tensor {
        value(&self.critic, obs)
    }

    /// The actor and the critic apart, each usable on its own thread (an
    /// update back-propagates the critic's loss beside the actor's).
    pub fn parts(&mut self) -> (&mut Mlp, &mut Mlp) {
        (&mut self.actor, &mut self.critic)
    }
}

/// The critic `critic`'s state values of `obs`, `[n]`.
pub fn value(critic: &Mlp, obs: &Tensor) -> Tensor {
    critic.forward(obs).squeeze_dim(-1)
}

/// `n` rows of `width` floats as an `[n, dim]` tensor (the first `dim` of each).
pub fn rows_tensor(rows: &[f32], n: usize, width: usize, dim: usize) -> Tensor {
    let x = Tensor::from_slice(&rows[..n * width]).view([n as i64, width as i64]);
    if dim == width {
        x
    } else {
        x.narrow(1, 0, dim as i64).contiguous()
    }
}

/// A Q-network: `input -> hidden -> actions`, where `input` is the length
/// of its observation layout and `actions` the run's action count
/// ([`crate::config::DqnConfig::actions`]: the paper's five unless the decision
/// settings add actions).
pub struct QNet {
    pub vs: nn::VarStore,
    mlp: Mlp,
    input: usize,
}

impl QNet {
    /// A network reading the first `input` features of each row (its
    /// observation layout's length), with one Q-value per action of
    /// `actions`. `name` prefixes the variables (`q0.l0.weight`, ...), so
    /// several networks can share one checkpoint file.
    pub fn with_input(input: usize, hidden: &[usize], actions: usize, name: &str) -> QNet {
        let vs = nn::VarStore::new(tch::Device::Cpu);
        let mlp = Mlp::new(
            &(vs.root() / name),
            input,
            hidden,
            actions,
            Activation::Relu,
            InitScheme::Default,
        );
        QNet { vs, mlp, input }
    }

    /// Q-values of `obs` rows, `[n, width]`: rows wider than the layout
    /// (the buffers' [`OBS_DIM`]) are cut to its prefix.
    pub fn q(&self, obs: &Tensor) -> Tensor {
        let width = obs.size()[1];
        if width as usize == self.input {
            self.mlp.forward(obs)
        } else {
            self.mlp
                .forward(&obs.narrow(1, 0, self.input as i64).contiguous())
        }
    }
}

/// Running mean and variance (Chan et al.'s parallel update), for value
/// normalisation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RunningNorm {
    pub mean: f64,
    pub var: f64,
    pub count: f64,
}

impl Default for RunningNorm {
    fn default() -> RunningNorm {
        RunningNorm {
            mean: 0.0,
            var: 1.0,
            count: 1e-4,
        }
    }
}

impl RunningNorm {
    pub fn update(&mut self, xs: &[f32]) {
        if xs.is_empty() {
            return;
        }
        let n = xs.len() as f64;
        let mean = xs.iter().map(|&x| f64::from(x)).sum::<f64>() / n;
        let var = xs
            .iter()
            .map(|&x| (f64::from(x) - mean).powi(2))
            .sum::<f64>()
            / n;
        let total = self.count + n;
        let delta = mean - self.mean;
        let m2 = self.var * self.count + var * n + delta * delta * self.count * n / total;
        self.mean += delta * n / total;
        self.var = m2 / total;
        self.count = total;
    }

    fn std(&self) -> f64 {
        self.var.max(1e-8).sqrt()
    }

    pub fn normalise(&self, x: f32) -> f32 {
        ((f64::from(x) - self.mean) / self.std()) as f32
    }

    pub fn denormalise(&self, y: f32) -> f32 {
        (f64::from(y) * self.std() + self.mean) as f32
    }
}
