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
//! `tanh` is computed in double precision and rounded ([`tanh`]).
//!
//! This file holds the networks and their forward pass; `weights.rs` the
//! named tensors they are built from ([`Weights`]) and their files.

use serde::{Deserialize, Serialize};

use crate::PolicyError;

mod weights;

pub use weights::Weights;

/// Hidden activation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Activation {
    Tanh,
    Relu,
}

/// One fully connected layer, its weight stored transposed (`input` rows of
/// `output` values, each row padded with zeros to a multiple of [`LANES`])
/// so the forward pass runs along contiguous memory in whole vectors.
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
            let padded = padded(output);
            let mut weight_t = vec![0.0; input * padded];
            for o in 0..output {
                for k in 0..input {
                    weight_t[k * padded + o] = data[o * input + k];
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
    /// gets `n * output` values, row after row. Rows go through the layers
    /// [`BLOCK`] at a time (each weight is read once for the block), which
    /// changes no result: every output is computed as for a row alone.
    pub fn forward(&self, x: &[f32], n: usize, stride: usize, out: &mut Vec<f32>) {
        assert!(stride >= self.input(), "rows hold the network's input");
        assert!(n == 0 || x.len() >= (n - 1) * stride + self.input());
        out.clear();
        out.resize(n * self.output(), 0.0);
        let w = self.widest();
        let mut a = vec![0.0f32; BLOCK * w];
        let mut b = vec![0.0f32; BLOCK * w];
        let mut start = 0;
        while start < n {
            let rows = BLOCK.min(n - start);
            let y = &mut out[start * self.output()..(start + rows) * self.output()];
            self.forward_block(&x[start * stride..], stride, rows, &mut a, &mut b, y);
            start += rows;
        }
    }

    fn forward_block(
        &self,
        x: &[f32],
        stride: usize,
        rows: usize,
        a: &mut Vec<f32>,
        b: &mut Vec<f32>,
        out: &mut [f32],
    ) {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx512f")
                && std::arch::is_x86_feature_detected!("fma")
                && std::arch::is_x86_feature_detected!("avx2")
            {
                // SAFETY: the processor has AVX-512F, FMA and AVX2 (checked
                // just above).
                unsafe { self.forward_block_avx512(x, stride, rows, a, b, out) };
                return;
            }
            if std::arch::is_x86_feature_detected!("fma")
                && std::arch::is_x86_feature_detected!("avx2")
            {
                // SAFETY: the processor has FMA and AVX2 (checked just above).
                unsafe { self.forward_block_avx2(x, stride, rows, a, b, out) };
                return;
            }
        }
        self.forward_block_any(x, stride, rows, a, b, out);
    }

    /// [`Mlp::forward_block_any`] compiled for processors with FMA and
    /// AVX2, so the fused multiply-adds and the activation are vector
    /// instructions rather than calls: the same results, many times faster.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn forward_block_avx2(
        &self,
        x: &[f32],
        stride: usize,
        rows: usize,
        a: &mut Vec<f32>,
        b: &mut Vec<f32>,
        out: &mut [f32],
    ) {
        self.forward_block_any(x, stride, rows, a, b, out);
    }

    /// [`Mlp::forward_block_avx2`] with AVX-512 as well: the activation
    /// runs eight doubles to a vector (the layers pick their kernel
    /// themselves).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx2,fma")]
    unsafe fn forward_block_avx512(
        &self,
        x: &[f32],
        stride: usize,
        rows: usize,
        a: &mut Vec<f32>,
        b: &mut Vec<f32>,
        out: &mut [f32],
    ) {
        self.forward_block_any(x, stride, rows, a, b, out);
    }

    #[inline(always)]
    fn forward_block_any(
        &self,
        x: &[f32],
        stride: usize,
        rows: usize,
        a: &mut Vec<f32>,
        b: &mut Vec<f32>,
        out: &mut [f32],
    ) {
        let last = self.layers.len() - 1;
        for (i, layer) in self.layers.iter().enumerate() {
            let o = layer.output;
            let y: &mut [f32] = if i == last { &mut *out } else { b };
            if i == 0 {
                layer.apply(x, stride, rows, y);
            } else {
                layer.apply(a, self.layers[i - 1].output, rows, y);
            }
            if i < last {
                let y = &mut y[..rows * o];
                match self.act {
                    Activation::Tanh => y.iter_mut().for_each(|v| *v = tanh(*v)),
                    Activation::Relu => y.iter_mut().for_each(|v| *v = v.max(0.0)),
                }
                std::mem::swap(a, b);
            }
        }
    }
}

/// One kernel of [`Linear::apply_avx2`] and [`Linear::apply_avx512`], written
/// once for both vector widths: `fn NAME, lanes L: setzero, loadu, set1,
/// fmadd, storeu` defines `NAME::<R, V>` with the intrinsics of that width.
/// For `R` rows it computes the outputs from `j` on, `L * V` at a time (`R *
/// V` accumulator vectors) while whole groups are left, and returns where it
/// stopped. Each lane takes its inputs in order with one rounding per fused
/// multiply-add and its bias last, so every width gives the same bits.
///
/// # Safety (of the defined function)
/// The processor has the intrinsics' features; `x` holds `R` rows of
/// `input` values `stride` apart and `y` holds `R * output` values.
#[cfg(target_arch = "x86_64")]
macro_rules! outputs_kernel {
    (
        $(#[$attr:meta])*
        fn $name:ident, lanes $lanes:literal:
            $setzero:ident, $loadu:ident, $set1:ident, $fmadd:ident, $storeu:ident
    ) => {
        $(#[$attr])*
        unsafe fn $name<const R: usize, const V: usize>(
            &self,
            x: &[f32],
            stride: usize,
            y: &mut [f32],
            mut j: usize,
        ) -> usize {
            use std::arch::x86_64::{$fmadd, $loadu, $set1, $setzero, $storeu};
            const WIDE: usize = $lanes;
            let (n_in, o, ws) = (self.input, self.output, padded(self.output));
            let xs: [*const f32; R] = std::array::from_fn(|r| x[r * stride..].as_ptr());
            let w = self.weight_t.as_ptr();
            while j + V * WIDE <= ws {
                let mut acc = [[$setzero(); V]; R];
                for k in 0..n_in {
                    // SAFETY: row k of the padded weights holds `ws` values
                    // and j + WIDE * V <= ws; the rows hold `input` > k
                    // values.
                    let wk = w.add(k * ws + j);
                    let wv: [_; V] = std::array::from_fn(|v| $loadu(wk.add(v * WIDE)));
                    for (acc, xr) in acc.iter_mut().zip(&xs) {
                        let xk = $set1(*xr.add(k));
                        for (a, &wv) in acc.iter_mut().zip(&wv) {
                            *a = $fmadd(wv, xk, *a);
                        }
                    }
                }
                let n = (V * WIDE).min(o - j);
                for (r, acc) in acc.iter().enumerate() {
                    let mut v = [[0.0f32; WIDE]; V];
                    for (v, a) in v.iter_mut().zip(acc) {
                        $storeu(v.as_mut_ptr(), *a);
                    }
                    let y = &mut y[r * o + j..r * o + j + n];
                    for ((yc, a), b) in y.iter_mut().zip(v.as_flattened()).zip(&self.bias[j..]) {
                        *yc = a + b;
                    }
                }
                j += V * WIDE;
            }
            j
        }
    };
}

/// Rows a forward pass takes through the layers together.
pub const BLOCK: usize = 4;

/// Outputs one vector holds; a layer's transposed weight rows are padded to
/// a multiple of it, so the forward pass reads them in whole vectors.
const LANES: usize = 8;

fn padded(output: usize) -> usize {
    output.div_ceil(LANES) * LANES
}

impl Linear {
    /// `y = W x + b` for `rows` (1 to [`BLOCK`]) rows of `x` (`stride`
    /// apart), into `y` (rows of `output`): each output's products
    /// accumulated in input order with fused multiply-adds, the bias added
    /// last.
    #[inline(always)]
    fn apply(&self, x: &[f32], stride: usize, rows: usize, y: &mut [f32]) {
        assert!((1..=BLOCK).contains(&rows) && y.len() >= rows * self.output);
        assert!(x.len() >= (rows - 1) * stride + self.input);
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx512f")
                && std::arch::is_x86_feature_detected!("fma")
                && std::arch::is_x86_feature_detected!("avx2")
            {
                // SAFETY: the processor has AVX-512F, FMA and AVX2 (checked
                // just above); the rows and `y` are in bounds (asserted
                // above).
                unsafe {
                    match rows {
                        4 => self.apply_avx512::<4>(x, stride, y),
                        3 => self.apply_avx512::<3>(x, stride, y),
                        2 => self.apply_avx512::<2>(x, stride, y),
                        _ => self.apply_avx512::<1>(x, stride, y),
                    }
                }
                return;
            }
            if std::arch::is_x86_feature_detected!("fma")
                && std::arch::is_x86_feature_detected!("avx2")
            {
                // SAFETY: the processor has FMA and AVX2 (checked just
                // above); the rows and `y` are in bounds (asserted above).
                unsafe {
                    match rows {
                        4 => self.apply_avx2::<4>(x, stride, y),
                        3 => self.apply_avx2::<3>(x, stride, y),
                        2 => self.apply_avx2::<2>(x, stride, y),
                        _ => self.apply_avx2::<1>(x, stride, y),
                    }
                }
                return;
            }
        }
        self.apply_any(x, stride, rows, y);
    }

    #[inline(always)]
    fn apply_any(&self, x: &[f32], stride: usize, rows: usize, y: &mut [f32]) {
        let (o, ws) = (self.output, padded(self.output));
        y[..rows * o].fill(0.0);
        for k in 0..self.input {
            let w = &self.weight_t[k * ws..k * ws + o];
            for r in 0..rows {
                let xk = x[r * stride + k];
                for (yj, &wj) in y[r * o..(r + 1) * o].iter_mut().zip(w) {
                    *yj = wj.mul_add(xk, *yj);
                }
            }
        }
        for r in 0..rows {
            for (yj, &bj) in y[r * o..(r + 1) * o].iter_mut().zip(&self.bias) {
                *yj += bj;
            }
        }
    }

    /// [`Linear::apply`] for `R` rows in vector registers: the outputs
    /// `8 * V` at a time for all `R` rows (8 accumulator vectors: `V` is
    /// 8 / `R`), then 8 at a time, each accumulated over every input before
    /// it is stored. A vector fused multiply-add rounds each lane as the
    /// scalar one does, and every output still takes its inputs in order
    /// and its bias last: the same bits as [`Linear::apply_any`].
    ///
    /// # Safety
    /// The processor has AVX2 and FMA; `x` holds `R` rows of `input` values
    /// `stride` apart and `y` holds `R * output` values.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn apply_avx2<const R: usize>(&self, x: &[f32], stride: usize, y: &mut [f32]) {
        let ws = padded(self.output);
        let mut j = 0;
        match R {
            1 => j = self.outputs_avx2::<R, 8>(x, stride, y, j),
            2 => j = self.outputs_avx2::<R, 4>(x, stride, y, j),
            _ => j = self.outputs_avx2::<R, 2>(x, stride, y, j),
        }
        if j < ws {
            self.outputs_avx2::<R, 1>(x, stride, y, j);
        }
    }

    /// [`Linear::apply_avx2`] with 16-lane vectors where the processor has
    /// AVX-512: the outputs `16 * V` at a time for all `R` rows (16
    /// accumulator registers of the 32), the rest through the AVX2 groups.
    /// Each lane still takes its inputs in order with one rounding per
    /// fused multiply-add and its bias last: the same bits again.
    ///
    /// # Safety
    /// The processor has AVX-512F, AVX2 and FMA; `x` holds `R` rows of
    /// `input` values `stride` apart and `y` holds `R * output` values.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx2,fma")]
    unsafe fn apply_avx512<const R: usize>(&self, x: &[f32], stride: usize, y: &mut [f32]) {
        let ws = padded(self.output);
        let mut j = match R {
            1 => self.outputs_avx512::<R, 16>(x, stride, y, 0),
            2 => self.outputs_avx512::<R, 8>(x, stride, y, 0),
            _ => self.outputs_avx512::<R, 4>(x, stride, y, 0),
        };
        if j + 2 * LANES <= ws {
            j = self.outputs_avx2::<R, 2>(x, stride, y, j);
        }
        if j < ws {
            self.outputs_avx2::<R, 1>(x, stride, y, j);
        }
    }

    outputs_kernel! {
        /// Outputs from `j` on, `16 * V` at a time while whole groups are
        /// left; returns where it stopped.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx512f,avx2,fma")]
        #[inline]
        fn outputs_avx512, lanes 16:
            _mm512_setzero_ps, _mm512_loadu_ps, _mm512_set1_ps, _mm512_fmadd_ps, _mm512_storeu_ps
    }

    outputs_kernel! {
        /// Outputs from `j` on, `8 * V` at a time while whole groups are
        /// left; returns where it stopped.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2,fma")]
        #[inline]
        fn outputs_avx2, lanes 8:
            _mm256_setzero_ps, _mm256_loadu_ps, _mm256_set1_ps, _mm256_fmadd_ps, _mm256_storeu_ps
    }
}

/// `tanh(x)` in double precision, rounded to f32: an odd series near 0,
/// `1 - 2 / (e^{2|x|} + 1)` elsewhere, with `e^y` from a Cody-Waite
/// reduction and a Taylor polynomial. Only additions, multiplications and
/// divisions (no library call, no fused operation), so it is the same on
/// every machine, and the compiler vectorises it; its error before the
/// final rounding is around 1e-15, so the f32 result is the correctly
/// rounded one but in vanishingly rare cases.
#[inline(always)]
pub fn tanh(x: f32) -> f32 {
    let a = f64::from(x).abs().min(10.0);
    let a2 = a * a;
    let series = a
        * (1.0
            + a2 * (-1.0 / 3.0
                + a2 * (2.0 / 15.0
                    + a2 * (-17.0 / 315.0 + a2 * (62.0 / 2835.0 + a2 * (-1382.0 / 155925.0))))));
    let e = exp_small(2.0 * a);
    let far = 1.0 - 2.0 / (e + 1.0);
    let t = if a < 0.0625 { series } else { far };
    (t as f32).copysign(x)
}

/// `e^y` for `y` in [0, 20], relative error around 1e-16.
#[inline(always)]
fn exp_small(y: f64) -> f64 {
    const LOG2E: f64 = std::f64::consts::LOG2_E;
    // ln 2 in two parts (fdlibm's): the first has trailing zero bits, so
    // k * LN2_HI is exact for the k that occur here.
    const LN2_HI: f64 = f64::from_bits(0x3FE6_2E42_FEE0_0000);
    const LN2_LO: f64 = f64::from_bits(0x3DEA_39EF_3579_3C76);
    // Adding 1.5 * 2^52 rounds to an integer held in the low mantissa bits.
    const MAGIC: f64 = 6_755_399_441_055_744.0;
    let kk = y * LOG2E + MAGIC;
    let k = kk - MAGIC;
    let r = (y - k * LN2_HI) - k * LN2_LO;
    // Taylor series of e^r, |r| <= ln 2 / 2, to r^13 / 13!.
    let mut p = 1.0 / 6_227_020_800.0;
    for c in [
        1.0 / 479_001_600.0,
        1.0 / 39_916_800.0,
        1.0 / 3_628_800.0,
        1.0 / 362_880.0,
        1.0 / 40_320.0,
        1.0 / 5_040.0,
        1.0 / 720.0,
        1.0 / 120.0,
        1.0 / 24.0,
        1.0 / 6.0,
        0.5,
        1.0,
        1.0,
    ] {
        p = p * r + c;
    }
    // 2^k from the integer in kk's low bits (0 <= k <= 29 here).
    let scale = f64::from_bits(kk.to_bits().wrapping_add(1023) << 52);
    p * scale
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
    fn tanh_is_the_correctly_rounded_one() {
        let mut x = -12.0f32;
        while x < 12.0 {
            let want = f64::from(x).tanh() as f32;
            assert_eq!(tanh(x), want, "tanh({x})");
            x += 0.000_37;
        }
        for x in [
            0.0f32,
            -0.0,
            1e-30,
            -1e-7,
            0.0625,
            0.062_499_996,
            9.1,
            50.0,
            -50.0,
        ] {
            assert_eq!(tanh(x), f64::from(x).tanh() as f32, "tanh({x})");
        }
        assert!(tanh(-0.0).is_sign_negative());
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
    fn blocks_of_rows_and_single_rows_compute_the_same_bits() {
        // 9 rows: two full blocks and one row alone.
        let mut w = Weights::default();
        let v = |n: usize, s: f32| (0..n).map(|i| (i as f32 * s).sin() * 0.7).collect();
        w.insert("n.l0.weight", vec![16, 16], v(256, 0.37));
        w.insert("n.l0.bias", vec![16], v(16, 1.3));
        w.insert("n.l1.weight", vec![3, 16], v(48, 0.11));
        w.insert("n.l1.bias", vec![3], v(3, 2.1));
        let m = Mlp::from_weights(&w, "n", Activation::Tanh).unwrap();
        let x: Vec<f32> = v(9 * 16, 0.013);
        let mut block = Vec::new();
        m.forward(&x, 9, 16, &mut block);
        for r in 0..9 {
            let mut one = Vec::new();
            m.forward(&x[r * 16..], 1, 16, &mut one);
            assert_eq!(one, block[r * 3..r * 3 + 3], "row {r}");
        }
    }

    /// The vector kernel (where the processor has one) against the portable
    /// loop, bit for bit: every row count of a block, output counts that
    /// are and are not multiples of the vector width.
    #[test]
    fn every_kernel_computes_the_same_bits() {
        let v =
            |n: usize, s: f32| -> Vec<f32> { (0..n).map(|i| (i as f32 * s).sin() * 0.9).collect() };
        for (input, output) in [
            (3, 5),
            (16, 13),
            (75, 37),
            (48, 64),
            (9, 133),
            (75, 256),
            (256, 256),
            (128, 40),
            (5, 200),
        ] {
            let mut w = Weights::default();
            w.insert("n.l0.weight", vec![output, input], v(output * input, 0.37));
            w.insert("n.l0.bias", vec![output], v(output, 1.3));
            let m = Mlp::from_weights(&w, "n", Activation::Relu).unwrap();
            let layer = &m.layers[0];
            let stride = input + 2;
            let x = v(BLOCK * stride, 0.013);
            for rows in 1..=BLOCK {
                let mut fast = vec![f32::NAN; rows * output];
                let mut plain = vec![f32::NAN; rows * output];
                layer.apply(&x, stride, rows, &mut fast);
                layer.apply_any(&x, stride, rows, &mut plain);
                let bits = |y: &[f32]| y.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&fast), bits(&plain), "{input}-{output}, {rows} rows");
                #[cfg(target_arch = "x86_64")]
                {
                    use std::arch::is_x86_feature_detected as has;
                    let run = |kernel: &dyn Fn(&mut [f32])| {
                        let mut y = vec![f32::NAN; rows * output];
                        kernel(&mut y);
                        assert_eq!(bits(&y), bits(&plain), "{input}-{output}, {rows} rows");
                    };
                    if has!("avx2") && has!("fma") {
                        // SAFETY: the processor has AVX2 and FMA; `x` and
                        // `y` hold the rows.
                        run(&|y| unsafe {
                            match rows {
                                4 => layer.apply_avx2::<4>(&x, stride, y),
                                3 => layer.apply_avx2::<3>(&x, stride, y),
                                2 => layer.apply_avx2::<2>(&x, stride, y),
                                _ => layer.apply_avx2::<1>(&x, stride, y),
                            }
                        });
                    }
                    if has!("avx512f") && has!("avx2") && has!("fma") {
                        // SAFETY: the processor has AVX-512F, AVX2 and FMA.
                        run(&|y| unsafe {
                            match rows {
                                4 => layer.apply_avx512::<4>(&x, stride, y),
                                3 => layer.apply_avx512::<3>(&x, stride, y),
                                2 => layer.apply_avx512::<2>(&x, stride, y),
                                _ => layer.apply_avx512::<1>(&x, stride, y),
                            }
                        });
                    }
                }
            }
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
