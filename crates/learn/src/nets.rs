//! The networks: PPO's actor and critic, DQN's Q-network. Plain MLPs built
//! under a named path in a `VarStore`, so checkpoints are safetensors files
//! whose tensor names say what they are.

use tch::nn::{self, Module};
use tch::Tensor;

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
