//! Training snapshots on disk: a streaming, chunked format the reduction core's streaming PCA
//! reads without loading everything (seed 000 §6.1: "collect snapshots of simulation
//! quantities into large matrices, where each column represents a simulation frame").
//!
//! A snapshot directory holds
//!
//! - `snapshots.json`: `{"format": "galerkin-fluid-snapshots", "version": 1, "dim": d,
//!   "cells": n_c, "faces": n_f, "vertices": n_v, "frame_time": Δt, "frames": k,
//!   "periodic_axis": a | null, "viscosity": μ, "forcing": [e₀, e₁, e₂]}` (the last two
//!   optional) and `"complete": true | false`, rewritten (atomically) after every frame is
//!   flushed, so an interrupted run is a valid shorter one; it is written last when a run
//!   starts and removed first when one is overwritten. `complete` is false while a writer
//!   runs and set when it finishes (the files then hold exactly `frames` frames); a run stopped
//!   by a signal keeps `false`, and its files may hold up to one frame more (written before the
//!   header counted it), which readers ignore. Every other length is refused, as is a value that is not finite or past
//!   [`crate::limits::MAX_MAGNITUDE`];
//! - `mesh.json`: the topology, `{"dim": d, "cells": [v₀, v₁, …]}` (d + 1 indices per cell);
//! - one file per quantity, `u.f64 p.f64 f.f64 g.f64 h.f64`: little-endian f64, one frame
//!   after another (frame k of quantity q starts at byte `8·k·len_q`). u and p have d
//!   components per cell (`u[d·c + k]`), f and h one per face (outward from the face's first
//!   cell), g d per vertex. Frame 0 is the initial state (its h is zero).
//!
//! [`SnapshotReader::source`] presents one quantity as a [`SnapshotSource`] (rows × frames)
//! reading only the rows asked for.

use std::fs::{File, OpenOptions};
use std::io::{Read, Seek, SeekFrom, Write};
use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::mesh::{SimplexMesh, Topology};
use crate::reduce::{ReduceError, SnapshotSource};
use crate::tensor::Tensor;

use super::FluidError;

/// The header's format name.
pub const FORMAT: &str = "galerkin-fluid-snapshots";
/// The header's format version.
pub const VERSION: u32 = 1;

/// The quantities, in file order.
pub const QUANTITIES: [&str; 5] = ["u", "p", "f", "g", "h"];

/// The header `snapshots.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SnapshotMeta {
    /// Always [`FORMAT`].
    pub format: String,
    /// Format version ([`VERSION`]).
    pub version: u32,
    /// Spatial dimension.
    pub dim: usize,
    /// Cells.
    pub cells: usize,
    /// Faces.
    pub faces: usize,
    /// Vertices.
    pub vertices: usize,
    /// Time between frames.
    pub frame_time: f64,
    /// Frames written.
    pub frames: usize,
    /// The periodic axis, if any.
    pub periodic_axis: Option<usize>,
    /// The run's viscosity μ (absent in headers written before it was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub viscosity: Option<f64>,
    /// The run's body acceleration e (absent in older headers).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub forcing: Option<[f64; 3]>,
    /// Whether the writer finished (see the module docs; absent in older headers: finished).
    #[serde(default = "finished")]
    pub complete: bool,
}

fn finished() -> bool {
    true
}

impl SnapshotMeta {
    /// The header of a run on `mesh` (no frames written yet).
    pub fn new(mesh: &SimplexMesh, topo: &Topology, frame_time: f64, periodic_axis: Option<usize>) -> Self {
        Self {
            format: FORMAT.into(),
            version: VERSION,
            dim: mesh.dim(),
            cells: mesh.cell_count(),
            faces: topo.face_count(),
            vertices: mesh.vertex_count(),
            frame_time,
            frames: 0,
            periodic_axis,
            viscosity: None,
            forcing: None,
            complete: false,
        }
    }

    /// This header with the run's physical parameters recorded (what a reduced model trained
    /// on the run needs to take the same step).
    pub fn with_params(mut self, params: &super::FluidParams) -> Self {
        self.viscosity = Some(params.viscosity);
        self.forcing = Some(params.forcing);
        self
    }

    /// Length of one frame of `quantity`.
    pub fn len(&self, quantity: &str) -> usize {
        match quantity {
            "u" | "p" => self.dim * self.cells,
            "f" | "h" => self.faces,
            "g" => self.dim * self.vertices,
            _ => 0,
        }
    }

    /// Checks what the header declares (`path` names it in errors): the format and version,
    /// a dimension of 2 or 3, counts within [`crate::limits::MAX_COUNT`] whose files' sizes fit
    /// in a `u64`, a positive finite frame time, a periodic axis inside the dimension, a finite
    /// non-negative viscosity and a finite forcing.
    pub fn check(&self, path: &Path) -> Result<(), FluidError> {
        let bad = |m: String| Err(io(path, m));
        if self.format != FORMAT || self.version != VERSION {
            return bad(format!(
                "format {} version {}: not a galerkin fluid snapshot directory",
                self.format, self.version
            ));
        }
        if !(2..=3).contains(&self.dim) {
            return bad(format!("dim {}: 2 or 3", self.dim));
        }
        for (what, n) in [("cells", self.cells), ("faces", self.faces), ("vertices", self.vertices)] {
            if n as u64 > crate::limits::MAX_COUNT {
                return bad(format!("{what} {n}: over the limit of {}", crate::limits::MAX_COUNT));
            }
        }
        if QUANTITIES
            .iter()
            .any(|q| self.len(q).checked_mul(self.frames).and_then(|n| n.checked_mul(8)).is_none())
        {
            return bad(format!("frames {}: the files would be larger than any file can be", self.frames));
        }
        if !(self.frame_time.is_finite() && self.frame_time > 0.0) {
            return bad(format!("frame_time {}: must be positive and finite", self.frame_time));
        }
        if let Some(axis) = self.periodic_axis.filter(|&a| a >= self.dim) {
            return bad(format!("periodic_axis {axis}: the mesh is {}D", self.dim));
        }
        if let Some(mu) = self.viscosity.filter(|mu| !(mu.is_finite() && *mu >= 0.0)) {
            return bad(format!("viscosity {mu}: must be finite and ≥ 0"));
        }
        if let Some(e) = self.forcing.filter(|e| e.iter().any(|v| !v.is_finite())) {
            return bad(format!("forcing {e:?}: must be finite"));
        }
        Ok(())
    }
}

#[derive(Serialize, Deserialize)]
struct MeshFile {
    dim: usize,
    cells: Vec<u32>,
}

fn io(path: &Path, e: impl std::fmt::Display) -> FluidError {
    FluidError::File { path: path.to_path_buf(), message: e.to_string() }
}

/// Appends frames to a snapshot directory.
#[derive(Debug)]
pub struct SnapshotWriter {
    dir: PathBuf,
    meta: SnapshotMeta,
    files: Vec<File>,
    /// `DIR/.lock`, locked exclusively while this writer lives: a second writer of the same
    /// directory is refused instead of interleaving its frames with ours (the lock goes with
    /// the process, so a killed run leaves no stale lock).
    _lock: File,
}

impl SnapshotWriter {
    /// Creates the directory (refusing one that already holds snapshots unless `overwrite`)
    /// and writes the mesh.
    pub fn create(
        dir: &Path,
        meta: SnapshotMeta,
        cells: &[u32],
        overwrite: bool,
    ) -> Result<Self, FluidError> {
        if dir.join("snapshots.json").exists() && !overwrite {
            return Err(io(dir, "already holds snapshots (pass --force to overwrite)"));
        }
        std::fs::create_dir_all(dir).map_err(|e| io(dir, e))?;
        let lock_path = dir.join(".lock");
        let lock = File::options()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&lock_path)
            .map_err(|e| io(&lock_path, e))?;
        match lock.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => {
                return Err(io(
                    dir,
                    "another run is writing snapshots here; wait for it or choose another directory",
                ))
            }
            Err(std::fs::TryLockError::Error(e)) => return Err(io(&lock_path, e)),
        }
        // Overwriting: the old header goes first, so no moment of the rewrite shows the old
        // header over the new mesh or over truncated frame files (an interrupted overwrite leaves
        // a directory without a run, which every reader refuses, or a valid shorter new run).
        let header = dir.join("snapshots.json");
        match std::fs::remove_file(&header) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(io(&header, e)),
        }
        let mesh =
            serde_json::to_vec(&MeshFile { dim: meta.dim, cells: cells.to_vec() }).map_err(|e| io(dir, e))?;
        let mesh_path = dir.join("mesh.json");
        crate::atomic_file::write(&mesh_path, &mesh).map_err(|e| io(&mesh_path, e))?;
        let mut files = Vec::new();
        for q in QUANTITIES {
            let path = dir.join(format!("{q}.f64"));
            files.push(File::create(&path).map_err(|e| io(&path, e))?);
        }
        let mut writer = Self {
            dir: dir.to_path_buf(),
            meta: SnapshotMeta { frames: 0, complete: false, ..meta },
            files,
            _lock: lock,
        };
        writer.write_meta()?;
        Ok(writer)
    }

    /// Appends one frame (each quantity's length checked).
    pub fn push(&mut self, u: &[f64], p: &[f64], f: &[f64], g: &[f64], h: &[f64]) -> Result<(), FluidError> {
        for (i, (q, data)) in QUANTITIES.iter().zip([u, p, f, g, h]).enumerate() {
            if data.len() != self.meta.len(q) {
                return Err(FluidError::State(format!(
                    "snapshot {q} has {} values, the mesh needs {}",
                    data.len(),
                    self.meta.len(q)
                )));
            }
            let bytes: Vec<u8> = data.iter().flat_map(|v| v.to_le_bytes()).collect();
            let path = self.dir.join(format!("{q}.f64"));
            self.files[i].write_all(&bytes).map_err(|e| io(&path, e))?;
        }
        self.meta.frames += 1;
        self.write_meta()
    }

    /// The header as written so far.
    pub fn meta(&self) -> &SnapshotMeta {
        &self.meta
    }

    /// Cuts each file to the frames the header counts (a push that failed part way may have
    /// written some quantities of a frame) and marks the run complete.
    fn finish(&mut self) -> Result<(), FluidError> {
        for (q, file) in QUANTITIES.iter().zip(&mut self.files) {
            let path = self.dir.join(format!("{q}.f64"));
            file.flush().map_err(|e| io(&path, e))?;
            file.set_len((8 * self.meta.len(q) * self.meta.frames) as u64).map_err(|e| io(&path, e))?;
        }
        self.meta.complete = true;
        self.write_meta()
    }

    fn write_meta(&mut self) -> Result<(), FluidError> {
        for (q, file) in QUANTITIES.iter().zip(&mut self.files) {
            file.flush().map_err(|e| io(&self.dir.join(format!("{q}.f64")), e))?;
        }
        let path = self.dir.join("snapshots.json");
        let text = serde_json::to_string_pretty(&self.meta).map_err(|e| io(&path, e))?;
        crate::atomic_file::write(&path, text.as_bytes()).map_err(|e| io(&path, e))
    }
}

impl Drop for SnapshotWriter {
    /// A writer that goes out of scope (the run finished, or returned an error) leaves exactly
    /// its frames and says so; one stopped by a signal never gets here and stays incomplete.
    fn drop(&mut self) {
        if let Err(e) = self.finish() {
            tracing::warn!("snapshots in {} not marked complete: {e}", self.dir.display());
        }
    }
}

/// Reads a snapshot directory.
#[derive(Debug)]
pub struct SnapshotReader {
    dir: PathBuf,
    meta: SnapshotMeta,
    cells: Vec<u32>,
}

impl SnapshotReader {
    /// Opens `dir`, checking the header, the mesh and every file's length.
    pub fn open(dir: &Path) -> Result<Self, FluidError> {
        let path = dir.join("snapshots.json");
        let text = std::fs::read_to_string(&path).map_err(|e| io(&path, e))?;
        let meta: SnapshotMeta = serde_json::from_str(&text).map_err(|e| io(&path, e))?;
        meta.check(&path)?;
        let mpath = dir.join("mesh.json");
        let mesh: MeshFile = serde_json::from_slice(&std::fs::read(&mpath).map_err(|e| io(&mpath, e))?)
            .map_err(|e| io(&mpath, e))?;
        if mesh.dim != meta.dim || mesh.cells.len() != meta.cells * (meta.dim + 1) {
            return Err(io(
                &mpath,
                format!(
                    "{} cell indices, the header says {} cells in {}D",
                    mesh.cells.len(),
                    meta.cells,
                    meta.dim
                ),
            ));
        }
        for q in QUANTITIES {
            let qpath = dir.join(format!("{q}.f64"));
            let len = std::fs::metadata(&qpath).map_err(|e| io(&qpath, e))?.len();
            let need = (8 * meta.len(q) * meta.frames) as u64;
            // A run stopped by a signal may have written its next frame, whole or in part, before
            // the header counted it (push writes every quantity, then the header).
            let slack = if meta.complete { 0 } else { 8 * meta.len(q) as u64 };
            if len < need || len > need + slack {
                return Err(io(
                    &qpath,
                    format!(
                        "{len} bytes: {} frames of {} values need {need}{}",
                        meta.frames,
                        meta.len(q),
                        if meta.complete { "" } else { " (and at most one more, an unfinished run's)" }
                    ),
                ));
            }
        }
        Ok(Self { dir: dir.to_path_buf(), meta, cells: mesh.cells })
    }

    /// The header.
    pub fn meta(&self) -> &SnapshotMeta {
        &self.meta
    }

    /// The cells (d + 1 vertex indices each).
    pub fn cells(&self) -> &[u32] {
        &self.cells
    }

    /// Frame `k` of `quantity`.
    pub fn frame(&self, quantity: &str, k: usize) -> Result<Vec<f64>, FluidError> {
        let len = self.meta.len(quantity);
        let path = self.dir.join(format!("{quantity}.f64"));
        if len == 0 {
            return Err(io(&path, format!("unknown quantity {quantity} (one of {QUANTITIES:?})")));
        }
        if k >= self.meta.frames {
            return Err(io(&path, format!("frame {k}: the run has {} frames", self.meta.frames)));
        }
        let mut file = File::open(&path).map_err(|e| io(&path, e))?;
        let values = read_f64(&mut file, (8 * len * k) as u64, len).map_err(|e| io(&path, e))?;
        if let Some((i, v)) = crate::limits::first_out_of_range(&values) {
            return Err(io(
                &path,
                format!("frame {k}: value {i} is {}", crate::limits::out_of_range_reason(v)),
            ));
        }
        Ok(values)
    }

    /// The mesh at frame `k`'s geometry and its topology (refused if its face count is not
    /// the header's).
    pub fn mesh_at(&self, k: usize) -> Result<(SimplexMesh, Topology), FluidError> {
        let g = self.frame("g", k)?;
        let g_path = self.dir.join("g.f64");
        let mesh = SimplexMesh::new(self.meta.dim, g, self.cells.clone())
            .map_err(|e| io(&g_path, format!("frame {k}: {e}")))?;
        // The cells keep frame 0's orientation; `SimplexMesh::new` turns an inverted cell the
        // right way round, so a cell it turned has folded over in this frame.
        let corners = self.meta.dim + 1;
        if let Some(c) = (0..self.cells.len() / corners).find(|&c| {
            mesh.cells()[c * corners..(c + 1) * corners] != self.cells[c * corners..(c + 1) * corners]
        }) {
            return Err(io(&g_path, format!("frame {k}: cell {c} is inverted (the mesh folds over)")));
        }
        let topo = Topology::new(&mesh, self.meta.periodic_axis.map(|axis| crate::mesh::Periodic { axis }))?;
        if topo.face_count() != self.meta.faces {
            return Err(io(
                &self.dir.join("mesh.json"),
                format!(
                    "the snapshot mesh has {} faces, its header says {}",
                    topo.face_count(),
                    self.meta.faces
                ),
            ));
        }
        Ok((mesh, topo))
    }

    /// One quantity as rows × frames snapshots for the streaming PCA.
    pub fn source(&self, quantity: &str) -> Result<FrameSnapshots, FluidError> {
        let path = self.dir.join(format!("{quantity}.f64"));
        let len = self.meta.len(quantity);
        if len == 0 {
            return Err(io(&path, format!("unknown quantity {quantity} (one of {QUANTITIES:?})")));
        }
        let file = OpenOptions::new().read(true).open(&path).map_err(|e| io(&path, e))?;
        Ok(FrameSnapshots { path, file, len, frames: self.meta.frames })
    }
}

fn read_f64(file: &mut File, offset: u64, n: usize) -> std::io::Result<Vec<f64>> {
    let mut bytes = vec![0u8; 8 * n];
    file.seek(SeekFrom::Start(offset))?;
    file.read_exact(&mut bytes)?;
    Ok(bytes.chunks_exact(8).map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes"))).collect())
}

/// One quantity of a snapshot directory as a [`SnapshotSource`]: a block of rows is read
/// from every frame (one seek per frame), never the whole matrix.
#[derive(Debug)]
pub struct FrameSnapshots {
    path: PathBuf,
    file: File,
    len: usize,
    frames: usize,
}

impl FrameSnapshots {
    /// `frames` frames of `len` values each, frame after frame, in the open `file` at `path`
    /// (derived snapshots written by the training itself).
    pub(crate) fn over(path: PathBuf, file: File, len: usize, frames: usize) -> Self {
        Self { path, file, len, frames }
    }
}

impl SnapshotSource for FrameSnapshots {
    fn dim(&self) -> usize {
        self.len
    }
    fn count(&self) -> usize {
        self.frames
    }
    fn rows(&mut self, rows: Range<usize>) -> Result<Tensor, ReduceError> {
        let k = self.frames;
        let mut out = vec![0.0; rows.len() * k];
        for frame in 0..k {
            let offset = (8 * (frame * self.len + rows.start)) as u64;
            let col = read_f64(&mut self.file, offset, rows.len()).map_err(|e| ReduceError::BadBasis {
                basis: format!("snapshots {}", self.path.display()),
                detail: e.to_string(),
            })?;
            if let Some((i, v)) = crate::limits::first_out_of_range(&col) {
                return Err(ReduceError::BadBasis {
                    basis: format!("snapshots {}", self.path.display()),
                    detail: format!(
                        "frame {frame}: row {} is {}",
                        rows.start + i,
                        crate::limits::out_of_range_reason(v)
                    ),
                });
            }
            for (i, v) in col.into_iter().enumerate() {
                out[i * k + frame] = v;
            }
        }
        Tensor::from_vec(&[rows.len(), k], out).map_err(|e| ReduceError::BadBasis {
            basis: format!("snapshots {}", self.path.display()),
            detail: e.to_string(),
        })
    }
}
