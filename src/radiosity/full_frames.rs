//! The full radiosity of `galerkin radiosity compare`'s frames, kept on disk (`--full-frames
//! DIR`). The full solution of a frame depends on the scene file, its lighting, the form factors'
//! near-field method and the frame's parameters only — not on the reduced model — so a later comparison of another model of the
//! same scene reuses them and solves only a few full frames again, for the speed ratio measured
//! in the same run and to check the kept ones. A sequence stopped part way keeps the frames
//! solved so far (the file is rewritten every [`SAVE_EVERY`] frames), and the next run goes on
//! from there.
//!
//! One file per sequence, `DIR/sequence-<k>-<frames>.bin`: the magic `GLKFULL1`, a key (a hash of
//! the scene file's bytes, the lighting and the galerkin version), the face count, the parameter
//! count and the number of frames kept (the sequence's first ones; u64 LE each), then per frame
//! its parameters, the seconds its solve took, the radiosity (R, G, B per face) and the face
//! areas, all f64 LE. Written to a temporary name first; a file that does not match (another
//! scene, version or sequence, or truncated) is ignored and rewritten.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use super::train::DesignSpace;
use super::Rgb;

const MAGIC: &[u8; 8] = b"GLKFULL1";

/// How often (in newly solved frames) a sequence's file is rewritten while it runs.
pub const SAVE_EVERY: usize = 50;

/// One frame's full solution as `radiosity compare` uses it.
#[derive(Debug)]
pub struct FullFrame {
    /// The frame's design parameters.
    pub params: Vec<f64>,
    /// Seconds the full solve took when it was computed.
    pub seconds: f64,
    /// Radiosity per face (Eq. 14).
    pub radiosity: Vec<Rgb>,
    /// Face areas (the error's weights).
    pub areas: Vec<f64>,
}

impl FullFrame {
    /// Solves the full radiosity at `params` in `space` (mesh build included) with the form
    /// factors of `method`, timed.
    pub fn solve(
        space: &dyn DesignSpace,
        params: &[f64],
        method: super::near_field::FormFactorMethod,
    ) -> Result<Self> {
        let t = std::time::Instant::now();
        let full = super::full_radiosity_with(space.mesh(params)?, space.lights(), method)?;
        Ok(Self {
            params: params.to_vec(),
            seconds: t.elapsed().as_secs_f64(),
            radiosity: full.radiosity,
            areas: full.geometry.areas,
        })
    }
}

/// Whether a sequence's file is rewritten after this frame: every [`SAVE_EVERY`] newly solved
/// frames, and when the sequence is complete.
pub fn save_due(newly_solved: usize, kept: usize, frames: usize) -> bool {
    newly_solved.is_multiple_of(SAVE_EVERY) || kept == frames
}

/// Where one sequence's full frames are kept, and what they must match.
pub struct FullFramesFile {
    path: PathBuf,
    key: u64,
}

impl FullFramesFile {
    /// The file of sequence `which` (0-based) with `frames` frames in `dir`, keyed by the scene
    /// file's contents and the lighting.
    pub fn new(dir: &Path, scene: &Path, lights: &str, which: usize, frames: usize) -> Result<Self> {
        let bytes = std::fs::read(scene).with_context(|| format!("reading {}", scene.display()))?;
        // FNV-1a over the scene file, the lighting and the version: stable across runs and builds.
        let mut key: u64 = 0xcbf2_9ce4_8422_2325;
        for b in bytes.iter().chain(lights.as_bytes()).chain(env!("CARGO_PKG_VERSION").as_bytes()) {
            key = (key ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3);
        }
        Ok(Self { path: dir.join(format!("sequence-{}-{frames}.bin", which + 1)), key })
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The kept frames ([`Self::load`]), or none — saying why when a file was there but did not
    /// match.
    pub fn load_or_none(&self, faces: usize, params: &[Vec<f64>]) -> Vec<FullFrame> {
        self.load(faces, params).unwrap_or_else(|why| {
            if self.path.exists() {
                tracing::warn!("{}: {why}; solving every full frame again", self.path.display());
            }
            Vec::new()
        })
    }

    /// The kept frames — the first frames of the sequence whose parameters are `params`, all
    /// of them or fewer — if the file exists and matches the scene, the face count and every
    /// kept frame's parameters; `Err` says why it does not (the caller recomputes).
    pub fn load(&self, faces: usize, params: &[Vec<f64>]) -> std::result::Result<Vec<FullFrame>, String> {
        let bytes = std::fs::read(&self.path).map_err(|e| e.to_string())?;
        let mut at = 0usize;
        let mut take = |n: usize| -> std::result::Result<&[u8], String> {
            let s = bytes.get(at..at + n).ok_or_else(|| format!("truncated at byte {at}"))?;
            at += n;
            Ok(s)
        };
        if take(8)? != MAGIC {
            return Err("not a full-frames file".into());
        }
        let mut header = [0u64; 4];
        for h in &mut header {
            *h = u64::from_le_bytes(take(8)?.try_into().expect("8 bytes"));
        }
        let k = params.first().map_or(0, Vec::len);
        if header[..3] != [self.key, faces as u64, k as u64] || header[3] > params.len() as u64 {
            return Err("made for another scene, lighting, version or sequence".into());
        }
        let mut f64s = |n: usize| -> std::result::Result<Vec<f64>, String> {
            Ok(take(8 * n)?
                .chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
                .collect())
        };
        let kept = header[3] as usize;
        let mut frames = Vec::with_capacity(params.len());
        for (f, expected) in params[..kept].iter().enumerate() {
            let p = f64s(k)?;
            if p.iter().zip(expected).any(|(a, b)| a.to_bits() != b.to_bits()) {
                return Err(format!("frame {f} has other parameters"));
            }
            let seconds = f64s(1)?[0];
            let flat = f64s(3 * faces)?;
            let radiosity = flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
            let areas = f64s(faces)?;
            frames.push(FullFrame { params: p, seconds, radiosity, areas });
        }
        Ok(frames)
    }

    /// Writes `frames` (the first frames of one sequence, each with `faces` faces) to the file,
    /// whole or not at all ([`crate::atomic_file`]).
    pub fn save(&self, faces: usize, frames: &[FullFrame]) -> Result<()> {
        let k = frames.first().map_or(0, |f| f.params.len());
        let mut out = Vec::with_capacity(40 + frames.len() * 8 * (k + 1 + 4 * faces));
        out.extend_from_slice(MAGIC);
        for h in [self.key, faces as u64, k as u64, frames.len() as u64] {
            out.extend_from_slice(&h.to_le_bytes());
        }
        for frame in frames {
            let values = frame
                .params
                .iter()
                .chain(std::iter::once(&frame.seconds))
                .chain(frame.radiosity.iter().flatten())
                .chain(&frame.areas);
            for v in values {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
        if let Some(dir) = self.path.parent() {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        }
        crate::atomic_file::write(&self.path, &out)
            .with_context(|| format!("writing {}", self.path.display()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_round_trip_and_mismatches_are_refused() {
        let dir = std::env::temp_dir().join(format!("galerkin-full-frames-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let scene = dir.join("scene.toml");
        std::fs::write(&scene, "resolution = 1\n").unwrap();
        let file = FullFramesFile::new(&dir, &scene, "area", 0, 2).unwrap();
        let params = vec![vec![0.5, 1.0], vec![0.25, 2.0]];
        let frames: Vec<FullFrame> = params
            .iter()
            .enumerate()
            .map(|(f, p)| FullFrame {
                params: p.clone(),
                seconds: 0.1 * f as f64,
                radiosity: vec![[1.0, 2.0, f as f64], [3.0, 4.0, 5.0]],
                areas: vec![0.5, 0.75],
            })
            .collect();
        assert!(file.load(2, &params).is_err(), "nothing saved yet");
        // A sequence stopped after its first frame: that frame comes back, and the run goes on.
        file.save(2, &frames[..1]).unwrap();
        assert_eq!(file.load(2, &params).unwrap().len(), 1);
        assert!(file.load(2, &params[..0]).is_err(), "more frames kept than the sequence has");
        file.save(2, &frames).unwrap();
        let back = file.load(2, &params).unwrap();
        assert_eq!(back.len(), 2);
        assert_eq!(back[1].radiosity, frames[1].radiosity);
        assert_eq!(back[1].areas, frames[1].areas);
        assert_eq!(back[1].seconds, 0.1);
        // Another frame's parameters, another face count, another scene file: refused.
        assert!(file.load(2, &[params[0].clone(), vec![0.25, 2.5]]).unwrap_err().contains("frame 1"));
        assert!(file.load(3, &params).is_err());
        std::fs::write(&scene, "resolution = 2\n").unwrap();
        let other = FullFramesFile::new(&dir, &scene, "area", 0, 2).unwrap();
        assert!(other.load(2, &params).is_err());
        // A truncated file is refused, not misread.
        let bytes = std::fs::read(file.path()).unwrap();
        std::fs::write(file.path(), &bytes[..bytes.len() - 8]).unwrap();
        assert!(file.load(2, &params).unwrap_err().contains("truncated"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
