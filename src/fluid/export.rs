//! A snapshot run as a ParaView time series: `RUN.pvd`, a VTK collection listing one `.vtu`
//! per frame (in the directory `RUN/`, files `RUN_000000.vtu`, …) with its time, which
//! ParaView opens as one animated data set.
//!
//! Each frame's `.vtu` holds the mesh at that frame's geometry `g` (2D meshes at z = 0) as
//! `VTK_TETRA` or `VTK_TRIANGLE` cells and, per cell (seed 000 §5's discretisation: velocity
//! per cell, flux per face),
//!
//! - `velocity` (3 components; z = 0 in 2D) and `speed`, from `u`;
//! - `flux`: the outward flux `σ f` through each of the cell's d + 1 faces, in the cell's own
//!   face order (face k opposite vertex k) — VTK has no per-face data on a cell grid, so each
//!   interior face's flux appears twice, with opposite signs;
//! - `divergence`: the net outward flux over the cell's volume, `Σ_k σ_k f_k / |c|`, which
//!   the projection drives to rounding (Eq. 10's constraint).
//!
//! The frames are written first, each to a temporary name renamed when complete, and the
//! `.pvd` last, so an interrupted export leaves no collection naming a missing frame.

use std::path::{Path, PathBuf};

use super::snapshots::SnapshotReader;
use super::FluidError;
use crate::vtk::{self, OutArray, Values};

/// `VTK_TRIANGLE`.
pub const VTK_TRIANGLE: u8 = 5;
/// `VTK_TETRA`.
pub const VTK_TETRA: u8 = 10;

/// What an export wrote.
#[derive(Clone, Debug)]
pub struct Export {
    /// The collection file.
    pub pvd: PathBuf,
    /// The frames' files, in time order.
    pub frames: Vec<PathBuf>,
    /// The largest |divergence| × cell volume / Σ|flux| over the exported frames: the run's
    /// relative discrete divergence.
    pub relative_divergence: f64,
}

/// The per-cell arrays of one frame: velocity (3 per cell), speed, outward flux (d + 1 per
/// cell) and divergence, for cells `cells` (d + 1 vertices each) at geometry `g`.
pub struct FrameArrays {
    /// `velocity`, 3 components per cell.
    pub velocity: Vec<f64>,
    /// `speed`.
    pub speed: Vec<f64>,
    /// `flux`, d + 1 components per cell.
    pub flux: Vec<f64>,
    /// `divergence`.
    pub divergence: Vec<f64>,
    /// Σ over cells of |net flux| / Σ over faces of |f| (0 for a still frame).
    pub relative_divergence: f64,
}

/// The cell arrays of frame `k` of `reader`, whose mesh and topology at that frame are
/// `mesh` and `topo` ([`SnapshotReader::mesh_at`]).
pub fn frame_arrays(
    reader: &SnapshotReader,
    k: usize,
    mesh: &crate::mesh::SimplexMesh,
    topo: &crate::mesh::Topology,
) -> Result<FrameArrays, FluidError> {
    let meta = reader.meta();
    let (d, cells) = (meta.dim, meta.cells);
    let (u, f) = (reader.frame("u", k)?, reader.frame("f", k)?);
    let volumes = mesh.volumes();
    let mut out = FrameArrays {
        velocity: vec![0.0; 3 * cells],
        speed: vec![0.0; cells],
        flux: vec![0.0; (d + 1) * cells],
        divergence: vec![0.0; cells],
        relative_divergence: 0.0,
    };
    let mut net_total = 0.0;
    for c in 0..cells {
        out.velocity[3 * c..3 * c + d].copy_from_slice(&u[d * c..d * c + d]);
        out.speed[c] = u[d * c..d * c + d].iter().map(|x| x * x).sum::<f64>().sqrt();
        let mut net = 0.0;
        for k in 0..=d {
            let q = topo.sign(c, k) * f[topo.cell_face(c, k)];
            out.flux[(d + 1) * c + k] = q;
            net += q;
        }
        out.divergence[c] = net / volumes[c];
        net_total += net.abs();
    }
    let scale: f64 = f.iter().map(|x| x.abs()).sum();
    out.relative_divergence = if scale > 0.0 { net_total / scale } else { 0.0 };
    Ok(out)
}

/// Writes the run in `dir` as the collection `pvd` (see the module docs), every `every`-th
/// frame and the last; `progress(done, total)` after each frame. Refused: an output that is
/// not a `.pvd`, `every` of 0, a run without frames.
pub fn export_run(
    dir: &Path,
    pvd: &Path,
    every: usize,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Export, FluidError> {
    let bad = |message: String| FluidError::File { path: pvd.to_path_buf(), message };
    if pvd.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() != Some("pvd") {
        return Err(bad("the collection must be a .pvd file".into()));
    }
    if every == 0 {
        return Err(bad("--every 0: export every first frame at least (1)".into()));
    }
    let reader = SnapshotReader::open(dir)?;
    let meta = reader.meta().clone();
    if meta.frames == 0 {
        return Err(FluidError::File { path: dir.to_path_buf(), message: "the run has no frames".into() });
    }
    let stem =
        pvd.file_stem().and_then(|s| s.to_str()).ok_or_else(|| bad("no file name".into()))?.to_string();
    let frames_dir = pvd.with_extension("");
    std::fs::create_dir_all(&frames_dir)
        .map_err(|e| FluidError::File { path: frames_dir.clone(), message: e.to_string() })?;
    let mut chosen: Vec<usize> = (0..meta.frames).step_by(every).collect();
    if chosen.last() != Some(&(meta.frames - 1)) {
        chosen.push(meta.frames - 1);
    }
    let cell_type = if meta.dim == 3 { VTK_TETRA } else { VTK_TRIANGLE };
    let (mut files, mut worst) = (Vec::new(), 0.0f64);
    for (done, &k) in chosen.iter().enumerate() {
        let (mesh, topo) = reader.mesh_at(k)?;
        let arrays = frame_arrays(&reader, k, &mesh, &topo)?;
        worst = worst.max(arrays.relative_divergence);
        let d = meta.dim;
        let mut points = vec![0.0; 3 * meta.vertices];
        for v in 0..meta.vertices {
            points[3 * v..3 * v + d].copy_from_slice(&mesh.g()[d * v..d * v + d]);
        }
        let connectivity: Vec<i64> = mesh.cells().iter().map(|&v| i64::from(v)).collect();
        let offsets: Vec<i64> = (1..=meta.cells).map(|c| (c * (d + 1)) as i64).collect();
        let out_arrays = vec![
            OutArray { section: "Points", name: "Points".into(), components: 3, values: Values::F64(points) },
            OutArray {
                section: "Cells",
                name: "connectivity".into(),
                components: 1,
                values: Values::I64(connectivity),
            },
            OutArray {
                section: "Cells",
                name: "offsets".into(),
                components: 1,
                values: Values::I64(offsets),
            },
            OutArray {
                section: "Cells",
                name: "types".into(),
                components: 1,
                values: Values::U8(vec![cell_type; meta.cells]),
            },
            OutArray {
                section: "CellData",
                name: "velocity".into(),
                components: 3,
                values: Values::F64(arrays.velocity),
            },
            OutArray {
                section: "CellData",
                name: "speed".into(),
                components: 1,
                values: Values::F64(arrays.speed),
            },
            OutArray {
                section: "CellData",
                name: "flux".into(),
                components: d + 1,
                values: Values::F64(arrays.flux),
            },
            OutArray {
                section: "CellData",
                name: "divergence".into(),
                components: 1,
                values: Values::F64(arrays.divergence),
            },
        ];
        let file = frames_dir.join(format!("{stem}_{k:06}.vtu"));
        let comment = format!(
            "galerkin fluid export: frame {k} of {}, t = {}",
            dir.display(),
            k as f64 * meta.frame_time
        );
        vtk::write(&file, &comment, meta.vertices, meta.cells, &out_arrays)
            .map_err(|e| FluidError::File { path: e.path, message: e.detail })?;
        files.push(file);
        progress(done + 1, chosen.len());
    }
    let mut xml = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n",
    );
    for (&k, file) in chosen.iter().zip(&files) {
        let name = file.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        xml.push_str(&format!(
            "    <DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{stem}/{name}\"/>\n",
            k as f64 * meta.frame_time
        ));
    }
    xml.push_str("  </Collection>\n</VTKFile>\n");
    crate::atomic_file::write(pvd, xml.as_bytes()).map_err(|e| bad(e.to_string()))?;
    Ok(Export { pvd: pvd.to_path_buf(), frames: files, relative_divergence: worst })
}
