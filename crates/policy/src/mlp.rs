//! The trained networks' forward pass in plain Rust: fully connected layers
//! read from a safetensors checkpoint (the files `naosoccer train` writes
//! through tch), with the hidden activation between layers and none after
//! the last.
//!
//! The arithmetic is fixed, so an output does not depend on the CPU, on
//! the batch or on where the robot plays: each output is
//! `fma(w_{n-1}, x_{n-1}, ... fma(w_1, x_1, w_0 x_0)) + b`, the inputs taken
//! in order with one rounding per fused multiply-add, then the bias. That is
//! the order of libtorch's (MKL's) matrix kernel for batches of a few dozen
//! rows, so on such batches the ReLU networks' outputs equal tch's bit for
//! bit; tch's kernel for a handful of rows sums in another order, which
//! moves the last bits (crates/learn's
//! `issue_14_the_torch_free_forward_matches_tch_on_the_shipped_teams`
//! compares the two on every shipped team). The fused
//! multiply-add is the processor's where it has one (checked at run time)
//! and the C library's `fmaf` elsewhere: the same correctly rounded result.
//! `tanh` is computed in double precision and rounded.

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::PolicyError;

/// Hidden activation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Activation {
    Tanh,
    Relu,
}

/// Named f32 tensors: a checkpoint's contents, or a live network's
/// variables handed over by the trainer.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Weights {
    tensors: BTreeMap<String, (Vec<usize>, Vec<f32>)>,
}

impl Weights {
    /// Every f32 tensor of a safetensors file.
    pub fn read(path: &Path) -> Result<Weights, PolicyError> {
        let bytes = std::fs::read(path).map_err(|e| PolicyError::io(path, e))?;
        Weights::from_safetensors(&bytes).map_err(|e| match e {
            PolicyError::Weights { name, reason } => PolicyError::Weights {
                name: format!("{}: {name}", path.display()),
                reason,
            },
            other => other,
        })
    }

    /// Every f32 tensor of a safetensors file's bytes (others are skipped).
    pub fn from_safetensors(bytes: &[u8]) -> Result<Weights, PolicyError> {
        let st =
            safetensors::SafeTensors::deserialize(bytes).map_err(|e| PolicyError::Weights {
                name: "file".into(),
                reason: format!("not a safetensors file: {e:?}"),
            })?;
        let mut w = Weights::default();
        for (name, view) in st.tensors() {
            if view.dtype() != safetensors::Dtype::F32 {
                continue;
            }
            let data = view
                .data()
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect();
            w.insert(name, view.shape().to_vec(), data);
        }
        Ok(w)
    }

    /// Adds (or replaces) a tensor; `data` is row-major in `shape`.
    pub fn insert(&mut self, name: impl Into<String>, shape: Vec<usize>, data: Vec<f32>) {
        assert_eq!(
            shape.iter().product::<usize>(),
            data.len(),
            "tensor data matches its shape"
        );
        self.tensors.insert(name.into(), (shape, data));
    }

    /// The tensor `name`, its shape and data.
    pub fn get(&self, name: &str) -> Option<(&[usize], &[f32])> {
        self.tensors
            .get(name)
            .map(|(s, d)| (s.as_slice(), d.as_slice()))
    }

    /// The tensors' names, sorted.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.tensors.keys().map(String::as_str)
    }

    /// Writes them as a safetensors file (sorted by name, so the same weights
    /// give the same bytes).
    pub fn write(&self, path: &Path) -> Result<(), PolicyError> {
        let bytes: Vec<(String, Vec<usize>, Vec<u8>)> = self
            .tensors
            .iter()
            .map(|(n, (s, d))| {
                (
                    n.clone(),
                    s.clone(),
                    d.iter().flat_map(|x| x.to_le_bytes()).collect(),
                )
            })
            .collect();
        let views = bytes
            .iter()
            .map(|(n, s, b)| {
                safetensors::tensor::TensorView::new(safetensors::Dtype::F32, s.clone(), b)
                    .map(|v| (n.clone(), v))
            })
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| PolicyError::Weights {
                name: path.display().to_string(),
                reason: format!("{e:?}"),
            })?;
        safetensors::serialize_to_file(views, &None, path).map_err(|e| PolicyError::Weights {
            name: path.display().to_string(),
            reason: format!("{e:?}"),
        })
    }
}

/// One fully connected layer, its weight stored transposed (`input` rows of
/// `output` values) so the forward pass runs along contiguous memory.
#[derive(Debug, Clone, PartialEq)]
struct Linear {
    input: usize,
    output: usize,
    weight_t: Vec<f32>,
    bias: Vec<f32>,
}

/// An MLP `input -> hidden... -> output`.
#[derive(Debug, Clone, PartialEq)]
pub struct Mlp {
    layers: Vec<Linear>,
    act: Activation,
}

impl Mlp {
    /// The layers `{prefix}.l0`, `{prefix}.l1`, ... of `w` (weights
    /// `[output, input]`, biases `[output]`, as tch's `nn::linear` names
    /// them), as many as there are, each reading the last one's output.
    pub fn from_weights(w: &Weights, prefix: &str, act: Activation) -> Result<Mlp, PolicyError> {
        let mut layers: Vec<Linear> = Vec::new();
        for i in 0.. {
            let wn = format!("{prefix}.l{i}.weight");
            let Some((shape, data)) = w.get(&wn) else {
                break;
            };
            let bad = |reason: String| PolicyError::Weights {
                name: wn.clone(),
                reason,
            };
            let &[output, input] = shape else {
                return Err(bad(format!("expected a matrix, found shape {shape:?}")));
            };
            if let Some(prev) = layers.last() {
                if prev.output != input {
                    return Err(bad(format!(
                        "reads {input} values, the layer before gives {}",
                        prev.output
                    )));
                }
            }
            let bn = format!("{prefix}.l{i}.bias");
            let bias = match w.get(&bn) {
                Some((s, b)) if s == [output] => b.to_vec(),
                Some((s, _)) => {
                    return Err(bad(format!("{bn} has shape {s:?}, expected [{output}]")))
                }
                None => return Err(bad(format!("{bn} is missing"))),
            };
            let mut weight_t = vec![0.0; input * output];
            for o in 0..output {
                for k in 0..input {
                    weight_t[k * output + o] = data[o * input + k];
                }
            }
            layers.push(Linear {
                input,
                output,
                weight_t,
                bias,
            });
        }
        if layers.is_empty() {
            return Err(PolicyError::Weights {
                name: format!("{prefix}.l0.weight"),
                reason: "missing".into(),
            });
        }
        Ok(Mlp { layers, act })
    }

    /// Values each row must hold.
    pub fn input(&self) -> usize {
        self.layers[0].input
    }

    /// Values each row gives.
    pub fn output(&self) -> usize {
        self.layers[self.layers.len() - 1].output
    }

    /// The widest layer's output (the scratch a row needs).
    fn widest(&self) -> usize {
        self.layers.iter().map(|l| l.output).max().unwrap_or(0)
    }

    /// The outputs of `n` rows: row `i` is `x[i * stride..][..input]`; `out`
    /// gets `n * output` values, row after row.
    pub fn forward(&self, x: &[f32], n: usize, stride: usize, out: &mut Vec<f32>) {
        assert!(stride >= self.input(), "rows hold the network's input");
        assert!(n == 0 || x.len() >= (n - 1) * stride + self.input());
        let w = self.widest();
        let (mut a, mut b) = (vec![0.0f32; w], vec![0.0f32; w]);
        let last = self.layers.len() - 1;
        out.clear();
        out.reserve(n * self.output());
        for r in 0..n {
            let row = &x[r * stride..r * stride + self.input()];
            for (i, layer) in self.layers.iter().enumerate() {
                let src: &[f32] = if i == 0 { row } else { &a[..layer.input] };
                layer.apply(src, &mut b[..layer.output]);
                if i < last {
                    match self.act {
                        Activation::Tanh => b[..layer.output]
                            .iter_mut()
                            .for_each(|v| *v = f64::from(*v).tanh() as f32),
                        Activation::Relu => {
                            b[..layer.output].iter_mut().for_each(|v| *v = v.max(0.0))
                        }
                    }
                }
                std::mem::swap(&mut a, &mut b);
            }
            out.extend_from_slice(&a[..self.output()]);
        }
    }
}

impl Linear {
    /// `y = W x + b`, each output's products accumulated in input order with
    /// fused multiply-adds, the bias added last.
    fn apply(&self, x: &[f32], y: &mut [f32]) {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("fma") {
                // SAFETY: the processor has FMA (checked just above).
                unsafe { self.accumulate_fma(x, y) };
                self.add_bias(y);
                return;
            }
        }
        self.accumulate(x, y);
        self.add_bias(y);
    }

    #[inline(always)]
    fn accumulate(&self, x: &[f32], y: &mut [f32]) {
        let o = self.output;
        y.fill(0.0);
        for (k, &xk) in x.iter().enumerate().take(self.input) {
            let w = &self.weight_t[k * o..(k + 1) * o];
            for (yj, &wj) in y.iter_mut().zip(w) {
                *yj = wj.mul_add(xk, *yj);
            }
        }
    }

    /// [`Linear::accumulate`] compiled for processors with FMA (and AVX2's
    /// wider registers), so the fused multiply-adds are vector instructions
    /// rather than calls: the same results, several times faster.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn accumulate_fma(&self, x: &[f32], y: &mut [f32]) {
        self.accumulate(x, y);
    }

    fn add_bias(&self, y: &mut [f32]) {
        for (yj, &bj) in y.iter_mut().zip(&self.bias) {
            *yj += bj;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tiny() -> Weights {
        let mut w = Weights::default();
        // l0: 2 -> 3, l1: 3 -> 2.
        w.insert(
            "n.l0.weight",
            vec![3, 2],
            vec![1.0, 2.0, -1.0, 0.5, 0.0, 3.0],
        );
        w.insert("n.l0.bias", vec![3], vec![0.5, -0.25, 1.0]);
        w.insert(
            "n.l1.weight",
            vec![2, 3],
            vec![1.0, -1.0, 2.0, 0.0, 1.0, 1.0],
        );
        w.insert("n.l1.bias", vec![2], vec![0.0, -1.0]);
        w
    }

    #[test]
    fn relu_network_matches_the_hand_computed_outputs() {
        let m = Mlp::from_weights(&tiny(), "n", Activation::Relu).unwrap();
        assert_eq!((m.input(), m.output()), (2, 2));
        let mut out = Vec::new();
        // x = (1, 2): l0 = (1+4+0.5, -1+1-0.25, 0+6+1) = (5.5, -0.25, 7)
        // relu -> (5.5, 0, 7); l1 = (5.5 - 0 + 14, 0 + 0 + 7 - 1) = (19.5, 6).
        m.forward(&[1.0, 2.0, 9.0], 1, 3, &mut out);
        assert_eq!(out, vec![19.5, 6.0]);
    }

    #[test]
    fn tanh_network_applies_tanh_between_layers_only() {
        let m = Mlp::from_weights(&tiny(), "n", Activation::Tanh).unwrap();
        let mut out = Vec::new();
        m.forward(&[1.0, 2.0], 1, 2, &mut out);
        let h = [5.5f64.tanh(), (-0.25f64).tanh(), 7f64.tanh()];
        let want = [h[0] - h[1] + 2.0 * h[2], h[1] + h[2] - 1.0];
        for (o, w) in out.iter().zip(want) {
            assert!((f64::from(*o) - w).abs() < 1e-6, "{o} vs {w}");
        }
    }

    #[test]
    fn rows_are_independent_of_the_batch() {
        let m = Mlp::from_weights(&tiny(), "n", Activation::Tanh).unwrap();
        let x = [0.3, -0.7, 0.1, 0.9, -2.0, 0.4];
        let mut all = Vec::new();
        m.forward(&x, 3, 2, &mut all);
        for r in 0..3 {
            let mut one = Vec::new();
            m.forward(&x[r * 2..], 1, 2, &mut one);
            assert_eq!(one, all[r * 2..r * 2 + 2]);
        }
    }

    #[test]
    fn missing_or_misshapen_tensors_are_named() {
        let mut w = tiny();
        w.insert("n.l1.bias", vec![3], vec![0.0; 3]);
        let e = Mlp::from_weights(&w, "n", Activation::Relu).unwrap_err();
        assert!(e.to_string().contains("n.l1.bias"), "{e}");
        let e = Mlp::from_weights(&tiny(), "q0", Activation::Relu).unwrap_err();
        assert!(e.to_string().contains("q0.l0.weight"), "{e}");
    }

    #[test]
    fn weights_round_trip_through_a_safetensors_file() {
        let dir = std::env::temp_dir().join(format!("naosoccer-mlp-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("w.safetensors");
        tiny().write(&path).unwrap();
        assert_eq!(Weights::read(&path).unwrap(), tiny());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
