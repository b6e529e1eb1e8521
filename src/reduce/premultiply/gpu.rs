//! The GPU backend of premultiplication: the same plan as the CPU backend, the arithmetic in
//! compute shaders (f32), the index work (sorting, grouping) on the CPU.
//!
//! Values stay on the device from stage to stage; coordinates stay on the host, where each
//! stage sorts them into groups (equal remaining coordinates) and rows (equal coordinates of
//! the unit contracted). Per batch of consecutive groups that fits the storage-binding limit,
//! `gather_rows.comp` puts the batch's values into row order, `unit_stage.comp` contracts the
//! unit (basis rows, or packed symmetrised rows of a symmetric group), and the batch's results
//! are copied into the stage's output. The final stage streams over the first unit's
//! coordinates like the CPU backend and accumulates `B_firstᵀ · W` with the tiled GEMM
//! (`tensor/gemm.comp`).

use ash::vk;
use bytemuck::{Pod, Zeroable};

use super::plan::{chunks_of_groups, sorted_entries, unit_and_key_positions};
use super::{unit_row, unit_size, Packing, PremultiplyOptions, PremultiplyPlan, Setup, Unit};
use crate::gpu::{
    shaders, BindingKind, Buffer, BufferBinding, ComputePipeline, ComputePipelineDesc, Gpu, GpuError,
    MemoryKind, Resource,
};
use crate::reduce::ReduceError;
use crate::tensor::gpu::{Gemm, GemmShape};
use crate::tensor::{SparseTensor, Tensor};

use std::collections::HashMap;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct StagePush {
    groups: u32,
    size: u32,
    block: u32,
    g: u32,
    m: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GatherPush {
    rows: u32,
    block: u32,
}

fn dev(context: &str) -> impl FnOnce(GpuError) -> ReduceError + '_ {
    move |e| ReduceError::Device { context: context.to_string(), detail: e.to_string() }
}

fn whole<T: Pod>(b: &Buffer<T>) -> BufferBinding {
    BufferBinding { buffer: b.raw(), offset: 0, range: b.size_bytes().max(4) }
}

/// The pipelines of the GPU backend.
struct Kernels {
    stage: ComputePipeline,
    gather: ComputePipeline,
    gemm: Gemm,
}

/// Where a stage's values are: the input's on the host (uploaded batch by batch, so the input
/// may exceed one binding), every intermediate's on the device.
enum Values {
    Host(Vec<f32>),
    Device(Buffer<f32>),
}

/// A stage's input: entries (coordinates on the host) with blocks of values.
struct DevicePartial {
    sparse_axes: Vec<usize>,
    coords: Vec<u32>,
    dense: Vec<Unit>,
    block: usize,
    entries: usize,
    values: Values,
}

struct Ctx<'a> {
    gpu: &'a Gpu,
    k: &'a Kernels,
    bases: &'a [&'a Tensor],
    packings: &'a HashMap<Vec<usize>, Packing>,
    floats: usize,
}

impl Ctx<'_> {
    fn upload<T: Pod>(&self, name: &str, data: &[T]) -> Result<Buffer<T>, ReduceError> {
        let data: &[T] = if data.is_empty() { &[] } else { data };
        let b = Buffer::new(
            self.gpu,
            name,
            data.len().max(1) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryKind::GpuOnly,
        )
        .map_err(dev(name))?;
        b.upload(self.gpu, 0, data).map_err(dev(name))?;
        Ok(b)
    }

    fn scratch(&self, name: &str, len: usize) -> Result<Buffer<f32>, ReduceError> {
        Buffer::new(
            self.gpu,
            name,
            len.max(1) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryKind::GpuOnly,
        )
        .map_err(dev(name))
    }

    fn over_limit(&self, what: &str, floats: usize) -> ReduceError {
        ReduceError::Device {
            context: format!("premultiplying on the device: {what}"),
            detail: format!(
                "needs {floats} f32 values in one storage binding, the device allows {} (use the CPU backend)",
                self.floats
            ),
        }
    }

    /// Rows `perm` of `src` (rows of `block` floats), in that order, on the device.
    fn gather(&self, src: &Values, perm: &[u32], block: usize) -> Result<Buffer<f32>, ReduceError> {
        let src = match src {
            Values::Host(v) => {
                let rows: Vec<f32> = perm
                    .iter()
                    .flat_map(|&e| v[e as usize * block..(e as usize + 1) * block].iter().copied())
                    .collect();
                return self.upload("premultiply input rows", &rows);
            }
            Values::Device(b) => b,
        };
        let dst = self.scratch("premultiply rows in order", perm.len() * block)?;
        let pb = self.upload("premultiply row order", perm)?;
        let set = self
            .k
            .gather
            .bind(
                self.gpu,
                &[
                    Resource::Storage(whole(src)),
                    Resource::Storage(whole(&pb)),
                    Resource::Storage(whole(&dst)),
                ],
            )
            .map_err(dev("binding the gather"))?;
        let push = GatherPush { rows: perm.len() as u32, block: block as u32 };
        let groups = self.gpu.caps().groups_1d((perm.len() * block) as u64, 256);
        self.gpu
            .run(|cmd| self.k.gather.record_dispatch(cmd, &set, bytemuck::bytes_of(&push), [groups, 1, 1]))
            .map_err(dev("gathering rows"))?;
        Ok(dst)
    }

    /// Contracts one unit on the device (see the module docs).
    fn contract_unit(&self, part: DevicePartial, unit: &Unit) -> Result<DevicePartial, ReduceError> {
        let s = part.sparse_axes.len();
        let (unit_pos, key_pos) = unit_and_key_positions(&part.sparse_axes, unit);
        let size = unit_size(unit, self.bases, self.packings);
        let block = part.block;
        let c = &part.coords;
        let idx = sorted_entries(c, s, &key_pos, &unit_pos);
        let key = |e: usize| key_pos.iter().map(move |&i| c[e * s + i]);
        let ucoords = |e: usize| unit_pos.iter().map(move |&i| c[e * s + i]);
        // Rows (equal key and unit coordinates) and groups (equal key), as offsets into idx.
        let mut row_starts = vec![0usize];
        let mut group_rows = vec![0usize];
        for i in 1..idx.len() {
            let new_group = !key(idx[i - 1]).eq(key(idx[i]));
            if new_group || !ucoords(idx[i - 1]).eq(ucoords(idx[i])) {
                row_starts.push(i);
            }
            if new_group {
                group_rows.push(row_starts.len() - 1);
            }
        }
        row_starts.push(idx.len());
        group_rows.push(row_starts.len() - 1);
        let groups = group_rows.len() - 1;
        if groups * size * block > self.floats {
            return Err(self.over_limit("a stage's output", groups * size * block));
        }
        let out = self.scratch("premultiply stage output", groups * size * block)?;
        let basis = self.bases[unit.axes()[0]];
        let m = basis.shape()[1];
        let g = unit.axes().len();
        let tuples: Vec<u32> = match unit {
            Unit::Axis(_) => vec![0],
            Unit::Group(axes) => self.packings[axes].tuples.iter().flatten().copied().collect(),
        };
        let tuples_buf = self.upload("premultiply packed tuples", &tuples)?;
        // Batches of consecutive groups within the binding limit.
        let mut g0 = 0;
        while g0 < groups {
            let (mut g1, mut coords_seen) = (g0, std::collections::BTreeSet::new());
            loop {
                if g1 == groups {
                    break;
                }
                let (r0, r1) = (group_rows[g0], group_rows[g1 + 1]);
                let entries = row_starts[r1] - row_starts[r0];
                let mut seen = coords_seen.clone();
                for r in group_rows[g1]..group_rows[g1 + 1] {
                    seen.extend(ucoords(idx[row_starts[r]]));
                }
                let fits = entries * block <= self.floats
                    && (g1 + 1 - g0) * size * block <= self.floats
                    && seen.len() * m <= self.floats;
                if !fits {
                    break;
                }
                coords_seen = seen;
                g1 += 1;
            }
            if g1 == g0 {
                return Err(self.over_limit(
                    "one group of entries",
                    (row_starts[group_rows[g0 + 1]] - row_starts[group_rows[g0]]) * block,
                ));
            }
            // The batch: its rows, their table references, its values in row order.
            let (r0, r1) = (group_rows[g0], group_rows[g1]);
            let e0 = row_starts[r0];
            let table_coords: Vec<u32> = coords_seen.into_iter().collect();
            let table: Vec<f32> = table_coords
                .iter()
                .flat_map(|&c| basis.data()[c as usize * m..(c as usize + 1) * m].iter().map(|&v| v as f32))
                .collect();
            let row_ref: Vec<u32> = (r0..r1)
                .flat_map(|r| {
                    ucoords(idx[row_starts[r]])
                        .map(|c| table_coords.binary_search(&c).expect("in table") as u32)
                        .collect::<Vec<_>>()
                })
                .collect();
            let rs: Vec<u32> = (r0..=r1).map(|r| (row_starts[r] - e0) as u32).collect();
            let gr: Vec<u32> = (g0..=g1).map(|gi| (group_rows[gi] - r0) as u32).collect();
            let perm: Vec<u32> = idx[e0..row_starts[r1]].iter().map(|&e| e as u32).collect();
            let vals = self.gather(&part.values, &perm, block)?;
            let bufs = [
                self.upload("premultiply row starts", &rs)?,
                self.upload("premultiply group rows", &gr)?,
                self.upload("premultiply row refs", &row_ref)?,
            ];
            let table_buf = self.upload("premultiply basis rows", &table)?;
            let out_b = self.scratch("premultiply batch output", (g1 - g0) * size * block)?;
            let set = self
                .k
                .stage
                .bind(
                    self.gpu,
                    &[
                        Resource::Storage(whole(&vals)),
                        Resource::Storage(whole(&bufs[0])),
                        Resource::Storage(whole(&bufs[1])),
                        Resource::Storage(whole(&bufs[2])),
                        Resource::Storage(whole(&table_buf)),
                        Resource::Storage(whole(&tuples_buf)),
                        Resource::Storage(whole(&out_b)),
                    ],
                )
                .map_err(dev("binding a stage"))?;
            let push = StagePush {
                groups: (g1 - g0) as u32,
                size: size as u32,
                block: block as u32,
                g: g as u32,
                m: m as u32,
            };
            let n = (g1 - g0) * size * block;
            let wg = self.gpu.caps().groups_1d(n as u64, 64);
            let region = vk::BufferCopy {
                src_offset: 0,
                dst_offset: (g0 * size * block * 4) as u64,
                size: (n * 4) as u64,
            };
            self.gpu
                .run(|cmd| {
                    self.k.stage.record_dispatch(cmd, &set, bytemuck::bytes_of(&push), [wg, 1, 1]);
                    self.gpu.memory_barrier(
                        cmd,
                        (vk::PipelineStageFlags::COMPUTE_SHADER, vk::AccessFlags::SHADER_WRITE),
                        (vk::PipelineStageFlags::TRANSFER, vk::AccessFlags::TRANSFER_READ),
                    );
                    // SAFETY: both buffers are alive until the submission completes (run waits).
                    unsafe { self.gpu.device().cmd_copy_buffer(cmd, out_b.raw(), out.raw(), &[region]) };
                })
                .map_err(dev("running a stage"))?;
            g0 = g1;
        }
        let coords: Vec<u32> = group_rows[..groups].iter().flat_map(|&r| key(idx[row_starts[r]])).collect();
        let mut dense = vec![unit.clone()];
        dense.extend(part.dense);
        Ok(DevicePartial {
            sparse_axes: key_pos.iter().map(|&i| part.sparse_axes[i]).collect(),
            coords,
            dense,
            block: size * block,
            entries: groups,
            values: Values::Device(out),
        })
    }

    /// Contracts every remaining unit, streaming over the first (see the module docs).
    fn finish(
        &self,
        part: DevicePartial,
        units: &[Unit],
        progress: &dyn Fn(f64),
    ) -> Result<DevicePartial, ReduceError> {
        if units.len() == 1 {
            let r = self.contract_unit(part, &units[0]);
            progress(1.0);
            return r;
        }
        let (first, rest) = (&units[0], &units[1..]);
        let s = part.sparse_axes.len();
        let first_pos: Vec<usize> = first
            .axes()
            .iter()
            .map(|a| part.sparse_axes.iter().position(|x| x == a).expect("sparse"))
            .collect();
        let size = unit_size(first, self.bases, self.packings);
        let rest_size: usize = rest.iter().map(|u| unit_size(u, self.bases, self.packings)).product();
        let w_block = rest_size * part.block;
        if size * w_block > self.floats {
            return Err(self.over_limit("the final block", size * w_block));
        }
        let idx = sorted_entries(&part.coords, s, &first_pos, &[]);
        let first_of = |e: usize| first_pos.iter().map(|&i| part.coords[e * s + i]).collect::<Vec<u32>>();
        let per_chunk = (self.floats / w_block.max(1)).min(self.floats / size.max(1)).max(1);
        let out = self.scratch("premultiply final block", size * w_block)?;
        let mut first_chunk = true;
        let mut row = Vec::new();
        for range in chunks_of_groups(&idx, first_of, per_chunk) {
            let (i, j) = (range.start, range.end);
            let perm: Vec<u32> = idx[i..j].iter().map(|&e| e as u32).collect();
            let values = match &part.values {
                // A host chunk stays on the host: its batches are uploaded as they run.
                Values::Host(v) => Values::Host(
                    perm.iter()
                        .flat_map(|&e| {
                            v[e as usize * part.block..(e as usize + 1) * part.block].iter().copied()
                        })
                        .collect(),
                ),
                Values::Device(_) => Values::Device(self.gather(&part.values, &perm, part.block)?),
            };
            let mut w = DevicePartial {
                sparse_axes: part.sparse_axes.clone(),
                coords: idx[i..j]
                    .iter()
                    .flat_map(|&e| part.coords[e * s..(e + 1) * s].iter().copied())
                    .collect(),
                dense: Vec::new(),
                block: part.block,
                entries: j - i,
                values,
            };
            for u in rest.iter().rev() {
                w = self.contract_unit(w, u)?;
            }
            // out (size × w_block) += Rowsᵀ (size × d) · W (d × w_block).
            let d = w.entries;
            let fp = first_pos.len();
            let mut at = vec![0f32; size * d];
            for e in 0..d {
                unit_row(first, &w.coords[e * fp..(e + 1) * fp], self.bases, self.packings, &mut row);
                for (t, &v) in row.iter().enumerate() {
                    at[t * d + e] = v as f32;
                }
            }
            let a = self.upload("premultiply first-unit rows", &at)?;
            let binding = self
                .k
                .gemm
                .bind(
                    self.gpu,
                    whole(&a),
                    whole(match &w.values {
                        Values::Device(b) => b,
                        Values::Host(_) => unreachable!("a contracted stage's values are on the device"),
                    }),
                    whole(&out),
                    GemmShape { m: size as u32, n: w_block as u32, k: d as u32 },
                )
                .map_err(dev("binding the final GEMM"))?;
            self.gpu
                .run(|cmd| self.k.gemm.record(cmd, &binding, !first_chunk))
                .map_err(dev("the final GEMM"))?;
            first_chunk = false;
            progress(j as f64 / idx.len() as f64);
        }
        let mut dense = units.to_vec();
        dense.extend(part.dense);
        Ok(DevicePartial {
            sparse_axes: Vec::new(),
            coords: Vec::new(),
            dense,
            block: size * w_block,
            entries: 1,
            values: Values::Device(out),
        })
    }
}

/// `Q̂` of a sparse tensor on the GPU (f32), with the plan the CPU backend would follow (its
/// intermediates capped at one storage binding). Returns the f64 reduced tensor, axes in `Q`'s
/// order. Requests that cannot be split under the device's binding limit are an error that
/// says so.
pub fn premultiply_sparse_gpu(
    gpu: &Gpu,
    q: &SparseTensor,
    bases: &[&Tensor],
    options: PremultiplyOptions<'_>,
) -> Result<(Tensor, PremultiplyPlan), ReduceError> {
    let floats = (gpu.max_binding_bytes() / 4) as usize;
    // The planner counts 8-byte values; keep every intermediate within one binding of f32.
    let budget = options.memory_budget.min(2 * gpu.max_binding_bytes());
    let setup = Setup::new(q, bases, budget)
        .map_err(|source| ReduceError::Tensor { context: "premultiply".into(), source })?;
    if q.nnz() == 0 {
        return Ok((Tensor::zeros(&setup.reduced_shape), setup.plan));
    }
    let stage = |name: &str, spirv: &[u32], bindings: &[BindingKind], push: usize| {
        ComputePipeline::new(
            gpu,
            &ComputePipelineDesc {
                name,
                spirv,
                bindings,
                push_constant_bytes: push as u32,
                specialization: &[],
                shared_bytes: 0,
            },
        )
        .map_err(dev("building a premultiply pipeline"))
    };
    let kernels = Kernels {
        stage: stage(
            "premultiply unit stage",
            shaders::tensor::UNIT_STAGE,
            &[BindingKind::StorageBuffer; 7],
            std::mem::size_of::<StagePush>(),
        )?,
        gather: stage(
            "premultiply gather",
            shaders::tensor::GATHER_ROWS,
            &[BindingKind::StorageBuffer; 3],
            std::mem::size_of::<GatherPush>(),
        )?,
        gemm: Gemm::new(gpu).map_err(dev("building the GEMM pipeline"))?,
    };
    let ctx = Ctx { gpu, k: &kernels, bases, packings: &setup.packings, floats };
    let values: Vec<f32> = q.values().iter().map(|&v| v as f32).collect();
    let mut part = DevicePartial {
        sparse_axes: (0..q.order()).collect(),
        coords: q.coords().to_vec(),
        dense: Vec::new(),
        block: 1,
        entries: q.nnz(),
        values: Values::Host(values),
    };
    let total = setup.plan.total_flops();
    let mut done = 0.0;
    for (stage, flops) in setup.plan.stages.iter().zip(&setup.plan.flops) {
        let report = |f: f64| {
            if let Some(p) = options.progress {
                p(done + f * flops, total);
            }
        };
        let t = std::time::Instant::now();
        part = ctx.finish(part, stage, &report)?;
        tracing::debug!(
            ?stage,
            entries = part.entries,
            seconds = t.elapsed().as_secs_f64(),
            "premultiply stage (GPU)"
        );
        done += flops;
    }
    let values: Vec<f64> = match &part.values {
        Values::Device(b) => b.download(gpu).map_err(dev("reading the result"))?,
        Values::Host(v) => v.clone(),
    }
    .into_iter()
    .map(f64::from)
    .collect();
    Ok((setup.expand(&part.dense, bases, &values), setup.plan))
}
