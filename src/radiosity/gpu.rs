//! Full radiosity on the device: the form factors of every pair in a compute pass
//! (`form_factors.comp`: the facing test, the BVH walked per pair, Eq. 15) and Eq. 14 by Jacobi
//! sweeps (`jacobi.comp`), F resident on the device. `F` (`n²` floats) is bound in row blocks
//! of at most one storage binding (128 MiB on lavapipe).
//!
//! The CPU path ([`super::form_factor::form_factors`], [`super::solve`]) is the f64 reference
//! and, on a CPU rasteriser such as lavapipe, the faster one ([`Backend::Auto`] picks it).
//!
//! [`Backend::Auto`]: crate::reduce::Backend::Auto

use ash::vk;
use bytemuck::Pod;

use super::bvh::Bvh;
use super::error::RadiosityError;
use super::form_factor::{bvh_of, FormFactors, NearField};
use super::mesh::SceneMesh;
use super::solve::Rgb;
use crate::gpu::{
    BindingKind, Buffer, ComputePipeline, ComputePipelineDesc, DescriptorSet, Gpu, MemoryKind, Recorder,
    Resource,
};

crate::push_constants! {
    struct Push {
        n: u32,
        row0: u32,
        rows: u32,
        extra: u32,
    }
}

/// The two compute pipelines.
pub struct GpuRadiosity {
    form_factors: [ComputePipeline; 2],
    jacobi: ComputePipeline,
}

/// The BVH flattened for `form_factors.comp`: nodes (two vec4 each) and triangles in leaf
/// order (three vec4 each, the face index's bits in corner 0's w).
pub fn flatten_bvh(bvh: &Bvh) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
    let mut nodes = Vec::with_capacity(2 * bvh.nodes.len());
    for n in &bvh.nodes {
        nodes.push([n.lo.x as f32, n.lo.y as f32, n.lo.z as f32, f32::from_bits(n.right_or_first)]);
        nodes.push([n.hi.x as f32, n.hi.y as f32, n.hi.z as f32, f32::from_bits(n.count)]);
    }
    let mut tris = Vec::with_capacity(3 * bvh.order.len());
    for &t in &bvh.order {
        let c = bvh.triangles[t as usize];
        tris.push([c[0].x as f32, c[0].y as f32, c[0].z as f32, f32::from_bits(t)]);
        for p in &c[1..] {
            tris.push([p.x as f32, p.y as f32, p.z as f32, 0.0]);
        }
    }
    (nodes, tris)
}

/// Form factors prepared for recording ([`GpuRadiosity::prepare_form_factors`]): the rows
/// to fill, their descriptor sets and the uploaded scene.
pub struct FormFactorPass {
    rows: DeviceFormFactors,
    sets: Vec<DescriptorSet>,
    near: NearField,
    bvh_nodes: u32,
    /// Faces, BVH nodes and BVH triangles.
    _inputs: [Buffer<[f32; 4]>; 3],
}

impl FormFactorPass {
    /// The rows it fills (for [`GpuRadiosity::prepare_jacobi`] and the sweeps that read them).
    pub fn rows(&self) -> &DeviceFormFactors {
        &self.rows
    }

    /// The rows, once the recording of [`GpuRadiosity::record_form_factors`] has finished.
    pub fn finish(self) -> DeviceFormFactors {
        self.rows
    }
}

/// `F` on the device, in row blocks.
pub struct DeviceFormFactors {
    n: usize,
    rows: Buffer<f32>,
    /// (first row, rows) per block.
    blocks: Vec<(u32, u32)>,
}

impl DeviceFormFactors {
    /// Number of faces.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Reads `F` back (f32 widened to f64).
    pub fn download(&self, gpu: &Gpu) -> Result<FormFactors, RadiosityError> {
        let v = self.rows.download(gpu)?;
        Ok(FormFactors { n: self.n, values: v.into_iter().map(f64::from).collect() })
    }
}

/// Rows per block: as many as fit one binding, a multiple of the rows that keep block
/// offsets aligned to `minStorageBufferOffsetAlignment`.
fn row_blocks(gpu: &Gpu, n: usize) -> Result<Vec<(u32, u32)>, RadiosityError> {
    let row_bytes = 4 * n as u64;
    let align_rows = (gpu.caps().min_storage_buffer_offset_alignment / 4).max(1);
    let per = (gpu.max_binding_bytes() / row_bytes.max(1)) / align_rows * align_rows;
    if per == 0 {
        return Err(RadiosityError::Mesh(format!(
            "{n} faces: {align_rows} rows of F exceed one storage binding ({} bytes)",
            gpu.max_binding_bytes()
        )));
    }
    let mut blocks = Vec::new();
    let mut r0 = 0u64;
    while r0 < n as u64 {
        let rows = per.min(n as u64 - r0);
        blocks.push((r0 as u32, rows as u32));
        r0 += rows;
    }
    Ok(blocks)
}

fn storage<T: Pod>(gpu: &Gpu, name: &str, data: &[T]) -> Result<Buffer<T>, RadiosityError> {
    Ok(Buffer::from_slice(gpu, name, data, vk::BufferUsageFlags::STORAGE_BUFFER)?)
}

impl GpuRadiosity {
    /// Builds the pipelines.
    pub fn new(gpu: &Gpu) -> Result<Self, RadiosityError> {
        let ff = |regularised: u32| {
            ComputePipeline::new(
                gpu,
                &ComputePipelineDesc {
                    name: "radiosity form factors",
                    spirv: crate::radiosity::shaders::FORM_FACTORS,
                    bindings: &[BindingKind::StorageBuffer; 4],
                    push: crate::gpu::PushLayout::of::<Push>(),
                    specialization: &[regularised],
                },
            )
        };
        let jacobi = ComputePipeline::new(
            gpu,
            &ComputePipelineDesc {
                name: "radiosity jacobi",
                spirv: crate::radiosity::shaders::JACOBI,
                bindings: &[BindingKind::StorageBuffer; 5],
                push: crate::gpu::PushLayout::of::<Push>(),
                specialization: &[],
            },
        )?;
        Ok(Self { form_factors: [ff(0)?, ff(1)?], jacobi })
    }

    /// Every `F_ij` of `mesh` on the device (f32; the facing test's threshold is 10⁻⁵
    /// relative instead of the CPU's 10⁻⁹, above f32's rounding of a cosine): the convenience
    /// of [`Self::prepare_form_factors`], [`Self::record_form_factors`] in one engine
    /// submission, and [`FormFactorPass::finish`].
    pub fn form_factors(
        &self,
        gpu: &Gpu,
        mesh: &SceneMesh,
        near: NearField,
    ) -> Result<DeviceFormFactors, RadiosityError> {
        let pass = self.prepare_form_factors(gpu, mesh, near)?;
        gpu.run(|rec| self.record_form_factors(rec, &pass))?;
        Ok(pass.finish())
    }

    /// Uploads `mesh`'s faces and ray-casting BVH and binds the form-factor rows (engine
    /// transfers, before a frame is recorded).
    pub fn prepare_form_factors(
        &self,
        gpu: &Gpu,
        mesh: &SceneMesh,
        near: NearField,
    ) -> Result<FormFactorPass, RadiosityError> {
        mesh.validate()?;
        let n = mesh.len();
        let g = mesh.geometry();
        let faces: Vec<[f32; 4]> = (0..n)
            .flat_map(|i| {
                let (c, m) = (g.centroids[i], g.normals[i]);
                [
                    [c.x as f32, c.y as f32, c.z as f32, g.areas[i] as f32],
                    [m.x as f32, m.y as f32, m.z as f32, g.edge_squares[i] as f32],
                ]
            })
            .collect();
        let bvh = bvh_of(mesh);
        let (nodes, tris) = flatten_bvh(&bvh);
        let faces = storage(gpu, "radiosity faces", &faces)?;
        let nodes_buf = storage(gpu, "radiosity bvh nodes", &nodes)?;
        let tris = storage(gpu, "radiosity bvh triangles", &tris)?;
        let rows = Buffer::<f32>::new(
            gpu,
            "radiosity form factors",
            (n * n).max(1) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryKind::GpuOnly,
        )?;
        let blocks = row_blocks(gpu, n)?;
        let pipeline = &self.form_factors[usize::from(near == NearField::Regularised)];
        let sets: Vec<DescriptorSet> = blocks
            .iter()
            .map(|&(r0, count)| {
                pipeline.bind(
                    gpu,
                    &[
                        Resource::Storage(faces.binding()?),
                        Resource::Storage(nodes_buf.binding()?),
                        Resource::Storage(tris.binding()?),
                        Resource::Storage(rows.binding_range(crate::gpu::Chunk {
                            first: u64::from(r0) * n as u64,
                            len: u64::from(count) * n as u64,
                        })),
                    ],
                )
            })
            .collect::<Result<_, _>>()?;
        Ok(FormFactorPass {
            rows: DeviceFormFactors { n, rows, blocks },
            sets,
            near,
            bvh_nodes: bvh.nodes.len() as u32,
            _inputs: [faces, nodes_buf, tris],
        })
    }

    /// Records the form-factor rows of `pass` (outside a render pass), one dispatch per block
    /// of rows; the dispatches' declared accesses order them after earlier reads of the rows
    /// (the previous frame's sweeps or readback) and later sweeps and readbacks after them.
    pub fn record_form_factors(&self, rec: &mut Recorder<'_>, pass: &FormFactorPass) {
        let pipeline = &self.form_factors[usize::from(pass.near == NearField::Regularised)];
        let n = pass.rows.n;
        for (&(row0, count), set) in pass.rows.blocks.iter().zip(&pass.sets) {
            let push = Push { n: n as u32, row0, rows: count, extra: pass.bvh_nodes };
            let [wx, wy, _] = pipeline.local_size();
            let groups = [(n as u32).div_ceil(wx), count.div_ceil(wy), 1];
            pipeline.record_dispatch(rec, set, &push, groups);
        }
    }

    /// Eq. 14 by Jacobi sweeps on the device from `b = e`, in batches of 8 sweeps, until the
    /// last sweep changes no value by more than `tolerance · max|b|` (f32: use ≥ 10⁻⁶).
    pub fn solve(
        &self,
        gpu: &Gpu,
        f: &DeviceFormFactors,
        albedo: &[Rgb],
        e: &[Rgb],
        tolerance: f64,
        max_sweeps: usize,
    ) -> Result<(Vec<Rgb>, usize), RadiosityError> {
        let pass = self.prepare_jacobi(gpu, f, albedo, e)?;
        const BATCH: usize = 8;
        let mut sweeps = 0;
        while sweeps < max_sweeps {
            gpu.run(|rec| self.record_jacobi_sweeps(rec, f, &pass, sweeps, BATCH))?;
            sweeps += BATCH;
            // After an even number of sweeps the newest iterate is in b[0], the one before in b[1].
            let (newest, before) = pass.iterates(gpu)?;
            let change = newest
                .iter()
                .zip(&before)
                .flat_map(|(x, y)| (0..3).map(move |c| (x[c] - y[c]).abs()))
                .fold(0f32, f32::max);
            let top = newest.iter().flat_map(|x| x[..3].iter()).fold(0f32, |m, v| m.max(v.abs()));
            if !change.is_finite() {
                return Err(RadiosityError::Solve(format!(
                    "Jacobi diverged on the device by sweep {sweeps}"
                )));
            }
            if f64::from(change) <= tolerance * f64::from(top) {
                return Ok((newest.iter().map(|x| [x[0], x[1], x[2]].map(f64::from)).collect(), sweeps));
            }
        }
        Err(RadiosityError::Solve(format!(
            "Jacobi did not converge to {tolerance:e} in {max_sweeps} sweeps on the device"
        )))
    }

    /// Uploads albedo and emission, starts both iterates at `b = e`, and binds each row block
    /// of `f` both ways (engine transfers, before a frame is recorded).
    pub fn prepare_jacobi(
        &self,
        gpu: &Gpu,
        f: &DeviceFormFactors,
        albedo: &[Rgb],
        e: &[Rgb],
    ) -> Result<JacobiPass, RadiosityError> {
        let n = f.n;
        if albedo.len() != n || e.len() != n {
            return Err(RadiosityError::Mesh(format!(
                "{} albedos and {} emissions for {n} faces",
                albedo.len(),
                e.len()
            )));
        }
        let pack =
            |v: &[Rgb]| v.iter().map(|c| [c[0] as f32, c[1] as f32, c[2] as f32, 0.0]).collect::<Vec<_>>();
        let albedo_buf = storage(gpu, "radiosity albedo", &pack(albedo))?;
        let emission = storage(gpu, "radiosity emission", &pack(e))?;
        let b = [storage(gpu, "radiosity b (even)", &pack(e))?, storage(gpu, "radiosity b (odd)", &pack(e))?];
        // Per block: the set reading b[0] and writing b[1], and the reverse.
        let mut sets = Vec::new();
        for &(r0, count) in &f.blocks {
            let chunk =
                crate::gpu::Chunk { first: u64::from(r0) * n as u64, len: u64::from(count) * n as u64 };
            let mut pair = Vec::new();
            for (src, dst) in [(0, 1), (1, 0)] {
                pair.push(self.jacobi.bind(
                    gpu,
                    &[
                        Resource::Storage(f.rows.binding_range(chunk)),
                        Resource::Storage(albedo_buf.binding()?),
                        Resource::Storage(emission.binding()?),
                        Resource::Storage(b[src].binding()?),
                        Resource::Storage(b[dst].binding()?),
                    ],
                )?);
            }
            sets.push(pair);
        }
        Ok(JacobiPass { sets, b, _inputs: (albedo_buf, emission) })
    }

    /// Records `count` Jacobi sweeps (Eq. 14) numbered from `first` (sweep k reads iterate
    /// k mod 2 and writes the other; outside a render pass; each sweep's dispatches wait for
    /// the last one's writes through their declared accesses); after an even `first + count`
    /// the newest iterate is `b[0]`.
    pub fn record_jacobi_sweeps(
        &self,
        rec: &mut Recorder<'_>,
        f: &DeviceFormFactors,
        pass: &JacobiPass,
        first: usize,
        count: usize,
    ) {
        let wx = self.jacobi.local_size()[0];
        for k in first..first + count {
            for (&(row0, rows), pair) in f.blocks.iter().zip(&pass.sets) {
                let push = Push { n: f.n as u32, row0, rows, extra: 0 };
                self.jacobi.record_dispatch(rec, &pair[k % 2], &push, [rows.div_ceil(wx), 1, 1]);
            }
        }
    }
}

/// One face's radiosity on the device: RGB and a spare lane.
pub type Radiance4 = [f32; 4];

/// A Jacobi solve prepared for recording ([`GpuRadiosity::prepare_jacobi`]): the two iterates
/// and, per row block, the descriptor sets of both sweep directions.
pub struct JacobiPass {
    sets: Vec<Vec<DescriptorSet>>,
    b: [Buffer<[f32; 4]>; 2],
    _inputs: (Buffer<[f32; 4]>, Buffer<[f32; 4]>),
}

impl JacobiPass {
    /// The iterates `(b[0], b[1])` (RGB and a spare lane per face), read back once the recorded
    /// sweeps have finished.
    pub fn iterates(&self, gpu: &Gpu) -> Result<(Vec<Radiance4>, Vec<Radiance4>), RadiosityError> {
        Ok((self.b[0].download(gpu)?, self.b[1].download(gpu)?))
    }
}
