//! Marker particles on the device (seed 000 §6.5): `particles.comp` advects every particle
//! through a frame's substeps in one dispatch, the twin of
//! [`super::particles::advect_particles`] (the CPU f64 reference) in f32. The topology is
//! uploaded once. On the full state each frame uploads the two geometries, the fluxes and the
//! grid hash; on the reduced state ([`GpuParticles::new_reduced`], the twin of
//! [`super::reduced::particles::ReducedParticles`]) `B_g`, `B_f` and the grid are uploaded once
//! and a frame records only its reduced coordinates (ĝ_t, ĝ_{t+1}, f̂: a few hundred floats)
//! into the command buffer. The particle buffer stays on the device, where the renderer reads
//! it.

use ash::vk;
use bytemuck::Pod;

use super::particles::{AdvectReport, GridHash, Particle};
use super::reduced::particles::ReducedParticles;
use super::FluidError;
use crate::gpu::{
    Access, BindingKind, Buffer, ComputePipeline, ComputePipelineDesc, DescriptorSet, Gpu, Recorder, Resource,
};
use crate::mesh::{FaceKind, Point, SimplexMesh, Topology};

crate::push_constants! {
    struct Push {
        count: u32,
        substeps: u32,
        frame_time: f32,
        /// Reduced: the first face whose `B_f` row is in the second buffer.
        split: u32,
        grid_lo: [f32; 4],
        grid_size: [f32; 4],
        grid_dims: [u32; 4],
    }
}

fn storage<T: Pod>(gpu: &Gpu, name: &str, data: &[T]) -> Result<Buffer<T>, FluidError> {
    Buffer::from_slice(gpu, name, data, vk::BufferUsageFlags::STORAGE_BUFFER).map_err(FluidError::from)
}

/// Per (cell, local face) links for the walk: neighbour + 1 (bits 0–27, 0 for a wall), the
/// neighbour's local index of the face (bits 28–29), wrap flag (bit 30).
pub fn walk_links(topo: &Topology) -> Result<Vec<u32>, FluidError> {
    let d = topo.dim();
    if topo.cell_count() >= (1 << 28) - 1 {
        return Err(FluidError::State(format!(
            "{} cells: the device walk packs cells in 28 bits",
            topo.cell_count()
        )));
    }
    let mut out = Vec::with_capacity(topo.cell_count() * (d + 1));
    for c in 0..topo.cell_count() {
        for l in 0..=d {
            let f = topo.cell_face(c, l);
            let link = match topo.neighbour(c, l) {
                None => 0,
                Some(e) => {
                    let [a, _] = topo.face_cells(f);
                    let locals = topo.face_local(f);
                    let theirs = if a as usize == c { locals[1] } else { locals[0] };
                    let wrap = u32::from(topo.kind(f) == FaceKind::Wrap);
                    (e as u32 + 1) | (u32::from(theirs) << 28) | (wrap << 30)
                }
            };
            out.push(link);
        }
    }
    Ok(out)
}

/// Whether the pass reads the full state or the reduced one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    Full,
    /// `m_g`, `m_f`, and the first face whose `B_f` row is in the second buffer.
    Reduced {
        m_g: usize,
        m_f: usize,
        split: usize,
    },
}

/// The particle pass with its topology and particles resident.
pub struct GpuParticles {
    pipeline: ComputePipeline,
    mode: Mode,
    count: usize,
    cells: Buffer<u32>,
    faces: Buffer<u32>,
    links: Buffer<u32>,
    particles: Buffer<[f32; 4]>,
    /// Each particle's speed after the last advection (its cell's velocity, Eq. 13).
    speeds: Buffer<f32>,
    counts: Buffer<u32>,
    /// Full: the frame's geometries and fluxes (f32), rewritten per frame. Reduced: `B_g`, the
    /// reduced coordinates (rewritten per frame) and `B_f` (two buffers when it exceeds one
    /// binding; the second is the first again otherwise). All four are read as `vec4`s
    /// ([`pack_vec4`], [`pack_rows_vec4`]): a row of `B_g` or `B_f` is a few 16-byte loads
    /// instead of `m` scalar ones.
    g0: Buffer<[f32; 4]>,
    g1: Buffer<[f32; 4]>,
    flux: Buffer<[f32; 4]>,
    flux_high: Option<Buffer<[f32; 4]>>,
    /// Full: the geometry's coordinates and the faces, as the frames must give them.
    full_sizes: (usize, usize),
    /// The grid hash and descriptor set of the last geometries, kept while they repeat (a
    /// static mesh builds and uploads its grid once).
    frame: Option<FrameGeometry>,
}

/// What depends on a frame's two geometries.
struct FrameGeometry {
    g0: Vec<f64>,
    g1: Vec<f64>,
    grid: (Point, Point, [usize; 3]),
    _grid_buffers: (Buffer<u32>, Buffer<u32>),
    set: DescriptorSet,
}

/// The particle pipeline for a `dim`-dimensional mesh, full or reduced: the mode, the
/// dimension and the bases' widths are its specialization constants.
fn pipeline(gpu: &Gpu, mode: Mode, dim: usize) -> Result<ComputePipeline, FluidError> {
    let (reduced, m_g, m_f) = match mode {
        Mode::Full => (false, 0, 0),
        Mode::Reduced { m_g, m_f, .. } => (true, m_g, m_f),
    };
    let width = |m: usize| {
        u32::try_from(m).map_err(|_| FluidError::State(format!("reduced particles: a basis of {m} columns")))
    };
    ComputePipeline::new(
        gpu,
        &ComputePipelineDesc {
            name: if reduced { "fluid particles (reduced state)" } else { "fluid particles" },
            spirv: crate::fluid::shaders::PARTICLES,
            bindings: &[BindingKind::StorageBuffer; 12],
            push: crate::gpu::PushLayout::of::<Push>(),
            specialization: &[u32::from(reduced), dim as u32, width(m_g)?, width(m_f)?],
        },
    )
    .map_err(FluidError::from)
}

/// Per (cell, local face): the face's index, bit 31 set if the cell's sign σ is −1.
fn face_info(mesh: &SimplexMesh, topo: &Topology) -> Vec<u32> {
    let d = mesh.dim();
    (0..mesh.cell_count())
        .flat_map(|c| {
            (0..=d).map(move |l| {
                let f = topo.cell_face(c, l) as u32;
                if topo.sign(c, l) < 0.0 {
                    f | 0x8000_0000
                } else {
                    f
                }
            })
        })
        .collect()
}

impl GpuParticles {
    /// Uploads `mesh`'s topology and `particles`.
    pub fn new(
        gpu: &Gpu,
        mesh: &SimplexMesh,
        topo: &Topology,
        particles: &[Particle],
    ) -> Result<Self, FluidError> {
        let d = mesh.dim();
        let links = walk_links(topo)?;
        Ok(Self {
            pipeline: pipeline(gpu, Mode::Full, d)?,
            mode: Mode::Full,
            count: particles.len(),
            cells: storage(gpu, "fluid cells", mesh.cells())?,
            faces: storage(gpu, "fluid cell faces", &face_info(mesh, topo))?,
            links: storage(gpu, "fluid walk links", &links)?,
            particles: storage(gpu, "fluid particles", &pack(particles))?,
            speeds: storage(gpu, "fluid particle speeds", &vec![0f32; particles.len().max(1)])?,
            counts: storage(gpu, "fluid particle counts", &[0u32; 3])?,
            g0: storage(gpu, "fluid g0", &vec![[0f32; 4]; mesh.g().len().div_ceil(4)])?,
            g1: storage(gpu, "fluid g1", &vec![[0f32; 4]; mesh.g().len().div_ceil(4)])?,
            flux: storage(gpu, "fluid flux", &vec![[0f32; 4]; topo.face_count().div_ceil(4)])?,
            flux_high: None,
            full_sizes: (mesh.g().len(), topo.face_count()),
            frame: None,
        })
    }

    /// The pass on the reduced state of `model` (seed 000 §6.5): uploads the topology, `B_g`
    /// and `B_f` (in f32; `B_f` split over two storage bindings when one cannot hold it), the
    /// grid hash of the training motions' vertex boxes, and `particles`. Frames then record
    /// their reduced coordinates with [`Self::record_reduced_frame`]. A `B_f` larger than two
    /// bindings is [`FluidError::State`] naming the sizes.
    pub fn new_reduced(
        gpu: &Gpu,
        model: &ReducedParticles,
        particles: &[Particle],
    ) -> Result<Self, FluidError> {
        let (mesh, topo) = (model.mesh(), model.topology());
        let (b_g, b_f) = (model.geometry_basis(), model.flux_basis());
        let (m_g, m_f) = (b_g.shape()[1], b_f.shape()[1]);
        let faces = b_f.shape()[0];
        let row_bytes = 16 * m_f.div_ceil(4).max(1) as u64;
        let rows_per_binding = (gpu.max_binding_bytes() / row_bytes) as usize;
        if faces > 2 * rows_per_binding {
            return Err(FluidError::State(format!(
                "reduced particles: B_f is {faces} rows of {m_f} floats ({row_bytes} bytes each, padded to whole vec4s); two storage bindings of {} bytes hold {} rows",
                gpu.max_binding_bytes(),
                2 * rows_per_binding
            )));
        }
        let split = faces.min(rows_per_binding);
        let flux = storage(gpu, "fluid B_f", &pack_rows_vec4(&b_f.data()[..split * m_f], m_f))?;
        let flux_high = if split < faces {
            Some(storage(gpu, "fluid B_f (second part)", &pack_rows_vec4(&b_f.data()[split * m_f..], m_f))?)
        } else {
            None
        };
        let links = walk_links(topo)?;
        let mut pass = Self {
            pipeline: pipeline(gpu, Mode::Reduced { m_g, m_f, split }, mesh.dim())?,
            mode: Mode::Reduced { m_g, m_f, split },
            count: particles.len(),
            cells: storage(gpu, "fluid cells", mesh.cells())?,
            faces: storage(gpu, "fluid cell faces", &face_info(mesh, topo))?,
            links: storage(gpu, "fluid walk links", &links)?,
            particles: storage(gpu, "fluid particles", &pack(particles))?,
            speeds: storage(gpu, "fluid particle speeds", &vec![0f32; particles.len().max(1)])?,
            counts: storage(gpu, "fluid particle counts", &[0u32; 3])?,
            g0: storage(gpu, "fluid B_g", &pack_rows_vec4(b_g.data(), m_g))?,
            g1: storage(
                gpu,
                "fluid reduced coordinates",
                &vec![[0f32; 4]; 2 * m_g.div_ceil(4) + m_f.div_ceil(4)],
            )?,
            flux,
            flux_high,
            full_sizes: (0, 0),
            frame: None,
        };
        pass.bind(gpu, model.grid(), None)?;
        Ok(pass)
    }

    /// Uploads `grid` and binds every buffer; keeps `geometries` (the full frame's) to reuse
    /// the set while they repeat.
    fn bind(
        &mut self,
        gpu: &Gpu,
        grid: &GridHash,
        geometries: Option<(Vec<f64>, Vec<f64>)>,
    ) -> Result<(), FluidError> {
        let (lo, size, dims, start, grid_cells) = grid.parts();
        let sb = storage(gpu, "fluid grid start", start)?;
        let cb = storage(gpu, "fluid grid cells", grid_cells)?;
        fn bind<T: Pod>(x: &Buffer<T>) -> Result<Resource<'_>, FluidError> {
            x.binding().map(Resource::Storage).map_err(FluidError::from)
        }
        let set = self
            .pipeline
            .bind(
                gpu,
                &[
                    bind(&self.g0)?,
                    bind(&self.g1)?,
                    bind(&self.cells)?,
                    bind(&self.faces)?,
                    bind(&self.links)?,
                    bind(&self.flux)?,
                    bind(&self.particles)?,
                    bind(&sb)?,
                    bind(&cb)?,
                    bind(&self.counts)?,
                    bind(self.flux_high.as_ref().unwrap_or(&self.flux))?,
                    bind(&self.speeds)?,
                ],
            )
            .map_err(FluidError::from)?;
        let (g0, g1) = geometries.unwrap_or_default();
        self.frame = Some(FrameGeometry { g0, g1, grid: (lo, size, dims), _grid_buffers: (sb, cb), set });
        Ok(())
    }

    /// Number of particles.
    pub fn count(&self) -> usize {
        self.count
    }

    /// The particle buffer (xyz position, w the cell's bits) for drawing.
    pub fn buffer(&self) -> &Buffer<[f32; 4]> {
        &self.particles
    }

    /// Each particle's speed after the last recorded advection (for colouring sprites without
    /// the full flux).
    pub fn speeds(&self) -> &Buffer<f32> {
        &self.speeds
    }

    /// Replaces the particles.
    pub fn upload(&mut self, gpu: &Gpu, particles: &[Particle]) -> Result<(), FluidError> {
        if particles.len() != self.count {
            return Err(FluidError::State(format!(
                "{} particles for a pass of {}",
                particles.len(),
                self.count
            )));
        }
        self.particles.upload(gpu, 0, &pack(particles)).map_err(FluidError::from)
    }

    /// Advects through one frame (see [`super::particles::advect_particles`]): the
    /// convenience of [`Self::prepare`], [`Self::record_advect`] in one engine submission, and
    /// [`Self::report`].
    #[allow(clippy::too_many_arguments)]
    pub fn advect(
        &mut self,
        gpu: &Gpu,
        mesh: &SimplexMesh,
        g0: &[f64],
        g1: &[f64],
        f: &[f64],
        frame_time: f64,
        substeps: usize,
    ) -> Result<AdvectReport, FluidError> {
        if self.count == 0 {
            return Ok(AdvectReport::default());
        }
        self.prepare(gpu, mesh, g0, g1, f)?;
        gpu.run(|rec| self.record_advect(rec, frame_time, substeps)).map_err(FluidError::from)??;
        self.report(gpu)
    }

    /// Uploads a frame's geometries `g0 → g1` and flux `f` and binds them (the grid hash of the
    /// two geometries is rebuilt only when they change). Engine transfers, done before a frame
    /// is recorded; no recording of this pass may be pending.
    pub fn prepare(
        &mut self,
        gpu: &Gpu,
        mesh: &SimplexMesh,
        g0: &[f64],
        g1: &[f64],
        f: &[f64],
    ) -> Result<(), FluidError> {
        if self.mode != Mode::Full {
            return Err(FluidError::State("particles: a reduced pass takes reduced frames".into()));
        }
        let (coordinates, faces) = self.full_sizes;
        if g0.len() != coordinates || g1.len() != g0.len() || f.len() != faces {
            return Err(FluidError::State(format!(
                "particles: geometries of {} and {} coordinates and {} fluxes for a mesh of {coordinates} and {faces}",
                g0.len(),
                g1.len(),
                f.len(),
            )));
        }
        self.flux.upload(gpu, 0, &pack_vec4(f)).map_err(FluidError::from)?;
        if !self.frame.as_ref().is_some_and(|fr| fr.g0 == g0 && fr.g1 == g1) {
            self.g0.upload(gpu, 0, &pack_vec4(g0)).map_err(FluidError::from)?;
            self.g1.upload(gpu, 0, &pack_vec4(g1)).map_err(FluidError::from)?;
            let grid = GridHash::new(mesh, &[g0, g1]);
            self.bind(gpu, &grid, Some((g0.to_vec(), g1.to_vec())))?;
        }
        Ok(())
    }

    /// Records a frame's reduced coordinates for a reduced pass: the geometry `g0 → g1` (ĝ)
    /// and the end state's fluxes `f` (f̂), written into the command buffer (outside a render
    /// pass; no engine transfer). It records an execution barrier after the previous
    /// advection's reads of the coordinates, the write, and a barrier that makes it visible to
    /// [`Self::record_advect`], which follows.
    pub fn record_reduced_frame(
        &self,
        rec: &mut Recorder<'_>,
        g0: &[f64],
        g1: &[f64],
        f: &[f64],
    ) -> Result<(), FluidError> {
        let Mode::Reduced { m_g, m_f, .. } = self.mode else {
            return Err(FluidError::State("particles: a full pass takes full frames (prepare)".into()));
        };
        if g0.len() != m_g || g1.len() != m_g || f.len() != m_f {
            return Err(FluidError::State(format!(
                "reduced particles: ĝ of {} and {} and f̂ of {} for bases of {m_g} and {m_f}",
                g0.len(),
                g1.len(),
                f.len()
            )));
        }
        let coefficients = reduced_coordinates(g0, g1, f);
        if coefficients.len() * 16 > 65_536 {
            return Err(FluidError::State(format!(
                "reduced particles: {} reduced coordinates exceed one command-buffer update",
                coefficients.len()
            )));
        }
        // The update waits for the last advection's reads of `g1`, and the next advection for
        // the update (declared accesses).
        rec.update_buffer(&self.g1, 0, &coefficients);
        Ok(())
    }

    /// Advects through one frame of the reduced state (see [`Self::record_reduced_frame`]):
    /// the convenience that records it and the advection in one engine submission.
    pub fn advect_reduced(
        &mut self,
        gpu: &Gpu,
        g0: &[f64],
        g1: &[f64],
        f: &[f64],
        frame_time: f64,
        substeps: usize,
    ) -> Result<AdvectReport, FluidError> {
        if self.count == 0 {
            return Ok(AdvectReport::default());
        }
        gpu.run(|rec| {
            self.record_reduced_frame(rec, g0, g1, f)?;
            self.record_advect(rec, frame_time, substeps)
        })
        .map_err(FluidError::from)??;
        self.report(gpu)
    }

    /// Records the advection through one frame of `frame_time` in `substeps` steps, from the
    /// frame [`Self::prepare`] uploaded. Outside a render pass. Before: the prepared buffers'
    /// transfers are finished (they were waited for). It records the reset of its counters (a
    /// transfer) and the dispatch, and declares the sprite draw's reads of the particles (so a
    /// draw may follow in the frame's render pass). An error if nothing was prepared.
    pub fn record_advect(
        &self,
        rec: &mut Recorder<'_>,
        frame_time: f64,
        substeps: usize,
    ) -> Result<(), FluidError> {
        let Some(frame) = self.frame.as_ref() else {
            return Err(FluidError::State("particles: record_advect before prepare".into()));
        };
        if self.count == 0 {
            return Ok(());
        }
        let (lo, size, dims) = frame.grid;
        let set = &frame.set;
        let push = Push {
            count: self.count as u32,
            substeps: substeps.max(1) as u32,
            frame_time: frame_time as f32,
            grid_lo: [lo[0] as f32, lo[1] as f32, lo[2] as f32, 0.0],
            grid_size: [size[0] as f32, size[1] as f32, size[2] as f32, 0.0],
            grid_dims: [dims[0] as u32, dims[1] as u32, dims[2] as u32, 0],
            split: match self.mode {
                Mode::Full => u32::MAX,
                Mode::Reduced { split, .. } => split as u32,
            },
        };
        rec.fill_buffer(&self.counts, 0);
        self.pipeline.record_dispatch(
            rec,
            set,
            &push,
            [(self.count as u32).div_ceil(self.pipeline.local_size()[0]), 1, 1],
        );
        // The sprite draw that follows in the frame reads the particles and their speeds
        // (draws declare before their render pass begins).
        rec.access_all(&[(&self.particles, Access::GRAPHICS_READ), (&self.speeds, Access::GRAPHICS_READ)]);
        Ok(())
    }

    /// What the last recorded advection counted (read once its work has finished).
    pub fn report(&self, gpu: &Gpu) -> Result<AdvectReport, FluidError> {
        let counts = self.counts.download(gpu).map_err(FluidError::from)?;
        Ok(AdvectReport {
            walked: counts[0] as usize,
            hashed: counts[1] as usize,
            clamped: counts[2] as usize,
        })
    }

    /// Reads the particles back.
    pub fn download(&self, gpu: &Gpu) -> Result<Vec<Particle>, FluidError> {
        let v = self.particles.download(gpu).map_err(FluidError::from)?;
        Ok(v.into_iter()
            .take(self.count)
            .map(|p| Particle {
                position: [f64::from(p[0]), f64::from(p[1]), f64::from(p[2])],
                cell: p[3].to_bits(),
            })
            .collect())
    }
}

/// `x` in f32, four to a `vec4`, the last one padded with zeros (the shader reads scalar `i`
/// as `x[i >> 2][i & 3]`).
fn pack_vec4(x: &[f64]) -> Vec<[f32; 4]> {
    x.chunks(4)
        .map(|c| {
            let mut v = [0f32; 4];
            for (o, &a) in v.iter_mut().zip(c) {
                *o = a as f32;
            }
            v
        })
        .collect()
}

/// A row-major matrix of rows of `m` in f32, each row padded with zeros to whole `vec4`s
/// (`m.div_ceil(4)` of them), so the shader dots a row with the reduced coordinates four at a
/// time.
fn pack_rows_vec4(rows: &[f64], m: usize) -> Vec<[f32; 4]> {
    if m == 0 {
        return Vec::new();
    }
    rows.chunks(m).flat_map(pack_vec4).collect()
}

/// The reduced coordinates a reduced frame writes: ĝ₀, ĝ₁ and f̂, each padded to whole `vec4`s
/// as the rows of [`pack_rows_vec4`] are.
fn reduced_coordinates(g0: &[f64], g1: &[f64], f: &[f64]) -> Vec<[f32; 4]> {
    [g0, g1, f].iter().flat_map(|x| pack_vec4(x)).collect()
}

fn pack(particles: &[Particle]) -> Vec<[f32; 4]> {
    particles
        .iter()
        .map(|p| [p.position[0] as f32, p.position[1] as f32, p.position[2] as f32, f32::from_bits(p.cell)])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_and_coordinates_are_padded_to_whole_vec4s() {
        // Two rows of 5: each takes two vec4s, its last three floats zero.
        let rows: Vec<f64> = (1..=10).map(f64::from).collect();
        let packed = pack_rows_vec4(&rows, 5);
        assert_eq!(
            packed,
            vec![[1.0, 2.0, 3.0, 4.0], [5.0, 0.0, 0.0, 0.0], [6.0, 7.0, 8.0, 9.0], [10.0, 0.0, 0.0, 0.0]]
        );
        // ĝ₀, ĝ₁ of 5 and f̂ of 3: the shader finds ĝ₁ at vec4 2 and f̂ at vec4 4.
        let c = reduced_coordinates(&[1.0; 5], &[2.0; 5], &[3.0; 3]);
        assert_eq!(c.len(), 5);
        assert_eq!(
            (c[1], c[2], c[3], c[4]),
            ([1.0, 0.0, 0.0, 0.0], [2.0; 4], [2.0, 0.0, 0.0, 0.0], [3.0, 3.0, 3.0, 0.0])
        );
        // Scalar i of a full array is component i & 3 of vec4 i >> 2.
        let x: Vec<f64> = (0..7).map(f64::from).collect();
        let v = pack_vec4(&x);
        assert!((0..7).all(|i| v[i >> 2][i & 3] == i as f32));
    }
}
