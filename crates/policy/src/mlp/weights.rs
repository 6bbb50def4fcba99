//! The networks' weights as named f32 tensors, read from and written to
//! safetensors files.

use std::collections::BTreeMap;
use std::path::Path;

use crate::PolicyError;

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
