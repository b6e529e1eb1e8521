//! Where a reduced model came from (issue 53: "one model artifact whose provenance names the
//! scene file and a hash of its content, the training options, the sample set and the engine
//! version"): so that the commands that use a model need no scene argument, and refuse a scene
//! that changed since training, naming the stored and the current hash.

use std::path::Path;

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// The engine that wrote a model.
pub const ENGINE: &str = concat!("galerkin ", env!("CARGO_PKG_VERSION"));

/// A model's provenance.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Provenance {
    /// The scene file, as an absolute path when it could be made one.
    pub scene: String,
    /// SHA-256 of the scene's content: the scene file and every file it names (hex).
    pub scene_sha256: String,
    /// The training options (their debug form).
    pub options: String,
    /// SHA-256 of the training samples' parameters (hex; f64 bits, in order).
    pub samples_sha256: String,
    /// How many samples.
    pub samples: usize,
    /// The engine that trained the model ([`ENGINE`]).
    pub engine: String,
}

impl Provenance {
    /// The provenance of a model trained on the scene file `scene`, whose content hashes to
    /// `scene_sha256` ([`files_sha256`] of it and every file it names), with `options` on the
    /// samples `params`.
    pub fn new(scene: &Path, scene_sha256: String, options: String, params: &[Vec<f64>]) -> Self {
        Self {
            scene: std::path::absolute(scene).unwrap_or_else(|_| scene.to_path_buf()).display().to_string(),
            scene_sha256,
            options,
            samples_sha256: samples_sha256(params),
            samples: params.len(),
            engine: ENGINE.to_string(),
        }
    }

    /// Refuses a scene whose content hash `current` is not the stored one, naming both and the
    /// file `path`.
    pub fn check_scene(&self, path: &Path, current: &str) -> Result<(), String> {
        if current == self.scene_sha256 {
            return Ok(());
        }
        Err(format!(
            "{}: the scene changed since the model was trained from {} (stored SHA-256 {}, now {}): train the model again",
            path.display(),
            self.scene,
            self.scene_sha256,
            current
        ))
    }

    /// Refuses a model another engine version trained (its tensors, their layout and the
    /// estimate's meaning belong to that engine), naming both versions.
    pub fn check_engine(&self) -> Result<(), String> {
        if self.engine == ENGINE {
            return Ok(());
        }
        Err(format!(
            "trained by {} but this is {}: a model is read by the engine that trained it; train it again",
            self.engine, ENGINE
        ))
    }

    /// As stored in a model file's metadata (JSON).
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }

    /// Read back from [`Self::to_json`]'s form; the message says what is wrong.
    pub fn from_json(text: &str) -> Result<Self, String> {
        serde_json::from_str(text).map_err(|e| format!("provenance: {e}"))
    }
}

/// SHA-256 over files' contents, each preceded by its length (so moving bytes between files
/// changes it), in hex.
pub fn files_sha256(files: &[&Path]) -> Result<String, String> {
    let mut h = Sha256::new();
    for f in files {
        let bytes = std::fs::read(f).map_err(|e| format!("{}: {e}", f.display()))?;
        h.update((bytes.len() as u64).to_le_bytes());
        h.update(&bytes);
    }
    Ok(hex(&h.finalize()))
}

/// SHA-256 of parameter vectors (their f64 bits, each vector's length first), in hex.
pub fn samples_sha256(params: &[Vec<f64>]) -> String {
    let mut h = Sha256::new();
    for p in params {
        h.update((p.len() as u64).to_le_bytes());
        for v in p {
            h.update(v.to_bits().to_le_bytes());
        }
    }
    hex(&h.finalize())
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scene_hash_follows_every_file_and_a_change_is_refused_naming_both_hashes() {
        let dir = tempfile::Builder::new().prefix("galerkin-provenance-").tempdir().unwrap();
        let (scene, obj) = (dir.path().join("s.toml"), dir.path().join("b.obj"));
        std::fs::write(&scene, "base = \"b.obj\"\n").unwrap();
        std::fs::write(&obj, "v 0 0 0\n").unwrap();
        let p = Provenance::new(
            &scene,
            files_sha256(&[&scene, &obj]).unwrap(),
            "options".into(),
            &[vec![1.0, 2.0]],
        );
        assert_eq!(p.scene_sha256.len(), 64);
        assert_eq!(Provenance::from_json(&p.to_json()).unwrap(), p);
        assert!(p.check_scene(&scene, &files_sha256(&[&scene, &obj]).unwrap()).is_ok());
        std::fs::write(&obj, "v 0 0 1\n").unwrap();
        let now = files_sha256(&[&scene, &obj]).unwrap();
        let e = p.check_scene(&scene, &now).unwrap_err();
        assert!(e.contains(&p.scene_sha256) && e.contains(&now) && e.contains("s.toml"), "{e}");
        assert_ne!(samples_sha256(&[vec![1.0, 2.0]]), samples_sha256(&[vec![1.0], vec![2.0]]));
        assert!(files_sha256(&[&dir.path().join("missing")]).unwrap_err().contains("missing"));
        assert!(Provenance::from_json("{").is_err());
    }
}
