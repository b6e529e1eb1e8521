//! A training set: full-space runs on one mesh topology, as written by `galerkin fluid
//! simulate` (seed 000 §6.1: "we run a set of full-dimensional simulations and collect
//! snapshots of simulation quantities into large matrices, where each column represents a
//! simulation frame"). Every quantity is presented to the core's streaming PCA as one
//! `rows × (all frames of all runs)` matrix, read a block of rows at a time.

use std::ops::Range;
use std::path::{Path, PathBuf};

use crate::fluid::snapshots::{FrameSnapshots, SnapshotMeta, SnapshotReader};
use crate::fluid::{FluidError, FluidParams};
use crate::mesh::{Periodic, SimplexMesh, Topology};
use crate::reduce::{ReduceError, SnapshotSource};
use crate::tensor::Tensor;

/// Most runs a training set may list (a cap on a loop driven by input).
pub const MAX_RUNS: usize = 4096;

/// Runs on one topology with one set of physical parameters.
#[derive(Debug)]
pub struct TrainingSet {
    runs: Vec<SnapshotReader>,
    paths: Vec<PathBuf>,
    mesh: SimplexMesh,
    topology: Topology,
    params: FluidParams,
}

fn file_error(path: &Path, message: String) -> FluidError {
    FluidError::File { path: path.to_path_buf(), message }
}

impl TrainingSet {
    /// Opens the snapshot directories `dirs`, refusing runs whose mesh, topology or
    /// parameters differ from the first run's (naming both runs).
    pub fn open(dirs: &[PathBuf]) -> Result<Self, FluidError> {
        if dirs.is_empty() {
            return Err(FluidError::State("a training set needs at least one run directory".into()));
        }
        if dirs.len() > MAX_RUNS {
            return Err(FluidError::State(format!("{} runs: at most {MAX_RUNS}", dirs.len())));
        }
        let mut runs = Vec::with_capacity(dirs.len());
        for dir in dirs {
            let run = SnapshotReader::open(dir)?;
            if run.meta().frames == 0 {
                return Err(file_error(dir, "holds no frames".into()));
            }
            runs.push(run);
        }
        let first = runs[0].meta().clone();
        let params = params_of(&first, &dirs[0])?;
        for (run, dir) in runs.iter().zip(dirs).skip(1) {
            let m = run.meta();
            let differs = |what: &str, a: String, b: String| {
                file_error(
                    dir,
                    format!(
                        "{what} {b}, but the first run {} has {a}: runs must share one mesh",
                        dirs[0].display()
                    ),
                )
            };
            if (m.dim, m.cells, m.faces, m.vertices) != (first.dim, first.cells, first.faces, first.vertices)
            {
                return Err(differs(
                    "dimension, cells, faces, vertices",
                    format!("{:?}", (first.dim, first.cells, first.faces, first.vertices)),
                    format!("{:?}", (m.dim, m.cells, m.faces, m.vertices)),
                ));
            }
            if m.periodic_axis != first.periodic_axis {
                return Err(differs(
                    "periodic axis",
                    format!("{:?}", first.periodic_axis),
                    format!("{:?}", m.periodic_axis),
                ));
            }
            if run.cells() != runs[0].cells() {
                let c = run.cells().iter().zip(runs[0].cells()).position(|(a, b)| a != b).unwrap_or(0);
                return Err(file_error(
                    dir,
                    format!(
                        "its topology differs from the first run {} (cell {} has other vertices): runs must share one mesh",
                        dirs[0].display(),
                        c / (m.dim + 1)
                    ),
                ));
            }
            let p = params_of(m, dir)?;
            if p != params {
                return Err(differs("parameters", format!("{params:?}"), format!("{p:?}")));
            }
        }
        let g0 = runs[0].frame("g", 0)?;
        let mesh = SimplexMesh::new(first.dim, g0, runs[0].cells().to_vec())?;
        let topology = Topology::new(&mesh, first.periodic_axis.map(|axis| Periodic { axis }))?;
        if topology.face_count() != first.faces {
            return Err(file_error(
                &dirs[0],
                format!("the mesh has {} faces, its header says {}", topology.face_count(), first.faces),
            ));
        }
        Ok(Self { runs, paths: dirs.to_vec(), mesh, topology, params })
    }

    /// The mesh (topology and the first run's first geometry).
    pub fn mesh(&self) -> &SimplexMesh {
        &self.mesh
    }

    /// The topology.
    pub fn topology(&self) -> &Topology {
        &self.topology
    }

    /// The runs' physical parameters.
    pub fn params(&self) -> &FluidParams {
        &self.params
    }

    /// The runs' directories.
    pub fn paths(&self) -> &[PathBuf] {
        &self.paths
    }

    /// The runs.
    pub fn runs(&self) -> &[SnapshotReader] {
        &self.runs
    }

    /// Frames of every run, in order.
    pub fn frames(&self) -> Vec<usize> {
        self.runs.iter().map(|r| r.meta().frames).collect()
    }

    /// The header of the first run.
    pub fn meta(&self) -> &SnapshotMeta {
        self.runs[0].meta()
    }

    /// One quantity over all frames of all runs as a [`SnapshotSource`]; a non-finite value
    /// is refused naming the run, frame and row.
    pub fn source(&self, quantity: &str) -> Result<RunsSnapshots, FluidError> {
        let sources = self.runs.iter().map(|r| r.source(quantity)).collect::<Result<Vec<_>, _>>()?;
        Ok(RunsSnapshots { quantity: quantity.to_string(), paths: self.paths.clone(), sources })
    }
}

fn params_of(meta: &SnapshotMeta, dir: &Path) -> Result<FluidParams, FluidError> {
    let viscosity = meta.viscosity.ok_or_else(|| {
        file_error(
            dir,
            "the header records no viscosity (written by an older galerkin: simulate it again)".into(),
        )
    })?;
    Ok(FluidParams { viscosity, forcing: meta.forcing.unwrap_or([0.0; 3]), frame_time: meta.frame_time })
}

/// One quantity of several runs side by side: columns are run 0's frames, then run 1's, ….
#[derive(Debug)]
pub struct RunsSnapshots {
    quantity: String,
    paths: Vec<PathBuf>,
    sources: Vec<FrameSnapshots>,
}

impl RunsSnapshots {
    /// Run and frame of snapshot column `column`.
    pub fn locate(&self, column: usize) -> (usize, usize) {
        let mut c = column;
        for (r, s) in self.sources.iter().enumerate() {
            if c < s.count() {
                return (r, c);
            }
            c -= s.count();
        }
        (self.sources.len(), c)
    }
}

impl SnapshotSource for RunsSnapshots {
    fn dim(&self) -> usize {
        self.sources[0].dim()
    }
    fn count(&self) -> usize {
        self.sources.iter().map(|s| s.count()).sum()
    }
    fn rows(&mut self, rows: Range<usize>) -> Result<Tensor, ReduceError> {
        let k = self.count();
        let n = rows.len();
        let mut out = vec![0.0; n * k];
        let mut col = 0;
        for (r, source) in self.sources.iter_mut().enumerate() {
            let block = source.rows(rows.clone())?;
            let kr = block.shape()[1];
            for i in 0..n {
                for j in 0..kr {
                    let v = block.data()[i * kr + j];
                    if !v.is_finite() {
                        return Err(ReduceError::BadBasis {
                            basis: self.quantity.clone(),
                            detail: format!(
                                "{}: frame {j} of `{}` has {v} at row {}",
                                self.paths[r].display(),
                                self.quantity,
                                rows.start + i
                            ),
                        });
                    }
                    out[i * k + col + j] = v;
                }
            }
            col += kr;
        }
        Tensor::from_vec(&[n, k], out)
            .map_err(|e| ReduceError::BadBasis { basis: self.quantity.clone(), detail: e.to_string() })
    }
}
