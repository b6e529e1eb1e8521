//! Reduced models on disk, as safetensors (so a NumPy user can open them with
//! `safetensors.numpy.load_file`): every reduced tensor `Q̂` as `tensor/<name>`, the bases that
//! project inputs and lift outputs as `basis/<name>` (n × m), all f64, and in the metadata the
//! format name and version, the composition (JSON, and in paper notation for people), each
//! tensor's axis bases, the inputs and the output's axes. Loading checks the version and that
//! every shape agrees with the metadata, and says what is wrong with which file.
//!
//! A capability built on the core (the reduced fluid) may store [`ModelExtras`] beside the
//! model: metadata strings as `extra/<key>` and f64 arrays as `data/<name>`.
//!
//! Every array file ([`save_arrays`]) carries the SHA-256 of each array's bytes in the metadata
//! key `sha256` (a JSON object, name → hex), and [`load_arrays`] refuses an array whose bytes
//! do not match (a flipped bit), or any value that is not finite or past
//! [`crate::limits::MAX_MAGNITUDE`], naming the file, the array and the entry. Files written
//! before the checksums load with the value check alone.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use safetensors::tensor::{Dtype, SafeTensors, TensorView};

use super::basis::{Bases, Basis};
use super::error::ReduceError;
use super::expr::Expr;
use super::reduced::{ReducedModel, ReducedTensor};
use crate::tensor::Tensor;

/// The `format` metadata value.
pub const FORMAT: &str = "galerkin-reduced-model";
/// The version this build writes and the newest it reads.
pub const VERSION: u32 = 1;

/// What a capability stores beside a reduced model (see the module docs).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ModelExtras {
    /// Metadata strings (stored as `extra/<key>`).
    pub metadata: BTreeMap<String, String>,
    /// f64 arrays (stored as `data/<name>`).
    pub arrays: BTreeMap<String, Tensor>,
}

fn f64_bytes(t: &Tensor) -> Vec<u8> {
    t.data().iter().flat_map(|v| v.to_le_bytes()).collect()
}

impl ReducedModel {
    /// Writes the model to `path`, whole or not at all ([`crate::atomic_file`]).
    pub fn save(&self, path: &Path) -> Result<(), ReduceError> {
        self.save_with(path, &ModelExtras::default())
    }

    /// [`ReducedModel::save`] with `extras` beside the model.
    pub fn save_with(&self, path: &Path, extras: &ModelExtras) -> Result<(), ReduceError> {
        let fail = |detail: String| ReduceError::File { path: path.to_path_buf(), detail };
        let json = |v: &dyn erased::Json| v.json().map_err(|e| fail(e.to_string()));
        let mut meta = HashMap::new();
        meta.insert("format".to_string(), FORMAT.to_string());
        meta.insert("version".to_string(), VERSION.to_string());
        meta.insert("composition".to_string(), json(&self.output)?);
        meta.insert("composition_text".to_string(), self.output.to_string());
        meta.insert("inputs".to_string(), json(&self.inputs)?);
        meta.insert("output_axes".to_string(), json(&self.output_axes)?);
        let axes: BTreeMap<&String, &Vec<String>> = self.tensors.iter().map(|(n, t)| (n, &t.axes)).collect();
        meta.insert("tensor_axes".to_string(), json(&axes)?);
        for (k, v) in &extras.metadata {
            meta.insert(format!("extra/{k}"), v.clone());
        }

        let mut arrays: Vec<(String, &Tensor)> = Vec::new();
        for (name, t) in &self.tensors {
            arrays.push((format!("tensor/{name}"), &t.data));
        }
        for (name, b) in &self.bases {
            arrays.push((format!("basis/{name}"), b.matrix()));
        }
        for (name, t) in &extras.arrays {
            arrays.push((format!("data/{name}"), t));
        }
        save_arrays(path, meta, &arrays)
    }

    /// Reads a model written by [`ReducedModel::save`] (this version or older).
    pub fn load(path: &Path) -> Result<ReducedModel, ReduceError> {
        Ok(Self::load_with(path)?.0)
    }

    /// [`ReducedModel::load`], also returning the [`ModelExtras`] stored beside the model.
    pub fn load_with(path: &Path) -> Result<(ReducedModel, ModelExtras), ReduceError> {
        let fail = |detail: String| ReduceError::File { path: path.to_path_buf(), detail };
        let (meta, mut arrays) = load_arrays(path)?;
        let get = |k: &str| meta.get(k).ok_or_else(|| fail(format!("metadata has no `{k}`")));
        if get("format")? != FORMAT {
            return Err(fail(format!("not a galerkin reduced model (format `{}`)", get("format")?)));
        }
        let version: u32 =
            get("version")?.parse().map_err(|_| fail(format!("bad version `{}`", meta["version"])))?;
        if version > VERSION {
            return Err(fail(format!(
                "written by a newer galerkin (format version {version}; this build reads up to {VERSION})"
            )));
        }
        let parse = |k: &str| -> Result<serde_json::Value, ReduceError> {
            serde_json::from_str(get(k)?).map_err(|e| fail(format!("metadata `{k}`: {e}")))
        };
        let output: Expr = serde_json::from_value(parse("composition")?)
            .map_err(|e| fail(format!("metadata `composition`: {e}")))?;
        let inputs: BTreeMap<String, String> =
            serde_json::from_value(parse("inputs")?).map_err(|e| fail(format!("metadata `inputs`: {e}")))?;
        let output_axes: Vec<String> = serde_json::from_value(parse("output_axes")?)
            .map_err(|e| fail(format!("metadata `output_axes`: {e}")))?;
        let axes: BTreeMap<String, Vec<String>> = serde_json::from_value(parse("tensor_axes")?)
            .map_err(|e| fail(format!("metadata `tensor_axes`: {e}")))?;

        let names: Vec<String> = arrays.keys().cloned().collect();
        let mut read = |name: &str| -> Result<Tensor, ReduceError> {
            arrays.remove(name).ok_or_else(|| fail(format!("`{name}` is missing")))
        };
        let mut bases = Bases::new();
        for name in names.iter().filter(|n| n.starts_with("basis/")) {
            let b = name.trim_start_matches("basis/");
            bases.insert(b.to_string(), Basis::new(b, read(name)?, 1e-9).map_err(|e| fail(e.to_string()))?);
        }
        // Reduced dimension of each basis name, learned from the tensors and checked to agree.
        let mut dims: BTreeMap<String, usize> =
            bases.iter().map(|(k, b)| (k.clone(), b.reduced_dim())).collect();
        let mut tensors = BTreeMap::new();
        for (name, axis_names) in axes {
            let data = read(&format!("tensor/{name}"))?;
            if data.order() != axis_names.len() {
                return Err(fail(format!(
                    "tensor `{name}` has {} axes but the metadata names {}",
                    data.order(),
                    axis_names.len()
                )));
            }
            for (axis, (b, &m)) in axis_names.iter().zip(data.shape()).enumerate() {
                match dims.get(b) {
                    Some(&d) if d != m => {
                        return Err(fail(format!("tensor `{name}` axis {axis} (basis `{b}`) has length {m}, but `{b}` has {d} reduced dimensions")))
                    }
                    _ => {
                        dims.insert(b.clone(), m);
                    }
                }
            }
            tensors.insert(name, ReducedTensor { axes: axis_names, data });
        }
        for b in &output_axes {
            if !bases.contains_key(b) {
                return Err(fail(format!("basis `{b}` (of the output) is missing")));
            }
        }
        // An input's basis may have been dropped (given reduced); its size is then the tensors'.
        for b in inputs.values() {
            if !bases.contains_key(b) && !dims.contains_key(b) {
                return Err(fail(format!("basis `{b}` (of an input) is missing and no tensor axis uses it")));
            }
        }
        let model = ReducedModel::new(tensors, inputs, output, output_axes, bases);
        model.check().map_err(|e| fail(format!("the composition does not fit the tensors: {e}")))?;
        let mut extras = ModelExtras::default();
        for (k, v) in &meta {
            if let Some(key) = k.strip_prefix("extra/") {
                extras.metadata.insert(key.to_string(), v.clone());
            }
        }
        for name in names.iter().filter(|n| n.starts_with("data/")) {
            extras.arrays.insert(name.trim_start_matches("data/").to_string(), read(name)?);
        }
        Ok((model, extras))
    }
}

/// Writes f64 `arrays` (name, tensor) and string `metadata` as one safetensors file at `path`
/// (whole or not at all, [`crate::atomic_file`]). The format of reduced
/// models, for capabilities that keep other arrays (a fluid's bases between training stages).
pub fn save_arrays(
    path: &Path,
    metadata: HashMap<String, String>,
    arrays: &[(String, &Tensor)],
) -> Result<(), ReduceError> {
    let fail = |detail: String| ReduceError::File { path: path.to_path_buf(), detail };
    let bytes: Vec<(String, Vec<u8>, Vec<usize>)> =
        arrays.iter().map(|(n, t)| (n.clone(), f64_bytes(t), t.shape().to_vec())).collect();
    let sums: BTreeMap<&str, String> = bytes.iter().map(|(n, b, _)| (n.as_str(), sha256_hex(b))).collect();
    let mut metadata = metadata;
    metadata.insert(CHECKSUMS.into(), serde_json::to_string(&sums).map_err(|e| fail(e.to_string()))?);
    let views = bytes
        .iter()
        .map(|(n, b, s)| TensorView::new(Dtype::F64, s.clone(), b).map(|v| (n.clone(), v)))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| fail(e.to_string()))?;
    let buffer = serialize(views, metadata).map_err(|e| fail(e.to_string()))?;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| fail(e.to_string()))?;
    }
    crate::atomic_file::write(path, &buffer).map_err(|e| fail(e.to_string()))
}

/// `safetensors::serialize` with the header's keys in sorted order, so the same arrays and
/// metadata always make the same bytes (the crate writes the metadata map in hash order; a
/// training resumed from its work directory is checked bit for bit against a straight one).
/// The header stays padded with spaces to a multiple of 8 bytes, as the format asks.
pub fn serialize<'a>(
    views: Vec<(String, TensorView<'a>)>,
    metadata: HashMap<String, String>,
) -> Result<Vec<u8>, String> {
    let buffer = safetensors::serialize(views, Some(metadata)).map_err(|e| e.to_string())?;
    let header_len = buffer
        .first_chunk::<8>()
        .and_then(|n| usize::try_from(u64::from_le_bytes(*n)).ok())
        .filter(|&n| n <= buffer.len() - 8)
        .ok_or("safetensors wrote no header")?;
    let header: serde_json::Value =
        serde_json::from_slice(&buffer[8..8 + header_len]).map_err(|e| format!("header: {e}"))?;
    // serde_json's map is ordered by key (no `preserve_order`): writing it back sorts it.
    let mut text = serde_json::to_vec(&header).map_err(|e| format!("header: {e}"))?;
    text.resize(text.len().div_ceil(8) * 8, b' ');
    let mut out = Vec::with_capacity(8 + text.len() + buffer.len() - 8 - header_len);
    out.extend_from_slice(&(text.len() as u64).to_le_bytes());
    out.extend_from_slice(&text);
    out.extend_from_slice(&buffer[8 + header_len..]);
    Ok(out)
}

/// The metadata key of the arrays' checksums (see the module docs).
const CHECKSUMS: &str = "sha256";

/// The SHA-256 of `bytes`, hex.
fn sha256_hex(bytes: &[u8]) -> String {
    use sha2::{Digest, Sha256};
    Sha256::digest(bytes).iter().map(|b| format!("{b:02x}")).collect()
}

/// What [`load_arrays`] reads: the metadata and the arrays by name.
pub type ArrayFile = (HashMap<String, String>, BTreeMap<String, Tensor>);

/// Reads a file written by [`save_arrays`]: its metadata and every f64 array by name (errors
/// name the file and the array).
pub fn load_arrays(path: &Path) -> Result<ArrayFile, ReduceError> {
    let fail = |detail: String| ReduceError::File { path: path.to_path_buf(), detail };
    let buffer = std::fs::read(path).map_err(|e| fail(e.to_string()))?;
    let (_, header) = SafeTensors::read_metadata(&buffer)
        .map_err(|e| fail(format!("not a readable safetensors file ({e})")))?;
    let file = SafeTensors::deserialize(&buffer)
        .map_err(|e| fail(format!("not a readable safetensors file ({e})")))?;
    let mut metadata = header.metadata().clone().unwrap_or_default();
    let sums: Option<BTreeMap<String, String>> = match metadata.remove(CHECKSUMS) {
        Some(text) => {
            Some(serde_json::from_str(&text).map_err(|e| fail(format!("metadata `{CHECKSUMS}`: {e}")))?)
        }
        None => None,
    };
    let mut arrays = BTreeMap::new();
    for (name, view) in file.tensors() {
        if view.dtype() != Dtype::F64 {
            return Err(fail(format!("`{name}` is {:?}, expected F64", view.dtype())));
        }
        if let Some(sums) = &sums {
            match sums.get(&name) {
                Some(sum) if *sum == sha256_hex(view.data()) => {}
                Some(_) => {
                    return Err(fail(format!(
                        "`{name}`: its bytes do not match the checksum written with it (the file is damaged)"
                    )))
                }
                None => return Err(fail(format!("`{name}` has no checksum (the file is damaged)"))),
            }
        }
        let data =
            view.data().chunks_exact(8).map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes"))).collect();
        let t = Tensor::from_vec(view.shape(), data).map_err(|e| fail(format!("`{name}`: {e}")))?;
        if let Some((i, v)) = crate::limits::first_out_of_range(t.data()) {
            return Err(fail(format!(
                "`{name}` entry {i} (of shape {:?}) is {}",
                t.shape(),
                crate::limits::out_of_range_reason(v)
            )));
        }
        arrays.insert(name, t);
    }
    if let Some(missing) = sums.iter().flat_map(|s| s.keys()).find(|n| !arrays.contains_key(*n)) {
        return Err(fail(format!(
            "`{missing}` is listed in the checksums but missing (the file is damaged)"
        )));
    }
    Ok((metadata, arrays))
}

/// `serde_json::to_string` behind a trait object, so one closure serves every type.
pub(crate) mod erased {
    /// A value that can be written as JSON, as a trait object.
    pub trait Json {
        fn json(&self) -> serde_json::Result<String>;
    }
    impl<T: serde::Serialize> Json for T {
        fn json(&self) -> serde_json::Result<String> {
            serde_json::to_string(self)
        }
    }
}
