//! The GPU backend of premultiplication: the same plan as the CPU backend, the arithmetic in
//! compute shaders (f32), the index work (sorting, grouping) on the CPU.
//!
//! Values stay on the device from stage to stage; coordinates stay on the host, where each
//! stage sorts them into groups (equal remaining coordinates) and rows (equal coordinates of
//! the unit contracted). Per batch of consecutive groups that fits the storage-binding limit,
//! `gather_rows.comp` puts the batch's values into row order, `unit_stage.comp` contracts the
//! unit (basis rows, or packed symmetrised rows of a symmetric group), and the batch's results
//! are copied into the stage's output. The final stage accumulates
//! `out += B_firstᵀ · (U_last ⊙ X)` in `premultiply_gemm.comp`: the tiled GEMM loop of
//! `include/gemm_tile.glsl` with its operands formed while the tiles load (first-unit rows
//! by reference; the row-wise Kronecker product of last-unit rows and the entries' values),
//! so the Khatri–Rao intermediate `W` is never written. Units between the first and the last
//! (final stages of three or more units) are contracted per chunk by unit stages first.
//! Buffers of the final stage are reused across its batches (fresh memory costs a page fault
//! per page on first touch, which dominated before).

use ash::vk;
use bytemuck::Pod;

use super::plan::{chunks_of_groups, sorted_entries, unit_and_key_positions, unit_positions};
use super::{unit_row, unit_size, Packing, PremultiplyOptions, PremultiplyPlan, Setup, Unit};
use crate::gpu::{
    BindingKind, Buffer, BufferBinding, ComputePipeline, ComputePipelineDesc, Gpu, GpuError, MemoryKind,
    PushLayout, Recorder, Resource, Submitter,
};
use crate::reduce::ReduceError;
use crate::tensor::gpu::GEMM_TILE;
use crate::tensor::{SparseTensor, Tensor};

use std::collections::HashMap;

crate::push_constants! {
    struct StagePush {
        groups: u32,
        size: u32,
        block: u32,
        g: u32,
        m: u32,
    }
}

crate::push_constants! {
    struct FusedPush {
        m: u32,
        k: u32,
        size: u32,
        block: u32,
        accumulate: u32,
    }
}

crate::push_constants! {
    struct GatherPush {
        rows: u32,
        block: u32,
    }
}

fn whole<T: Pod>(b: &Buffer<T>) -> BufferBinding<'_> {
    b.whole()
}

/// The pipelines of the GPU backend.
struct Kernels {
    stage: ComputePipeline,
    gather: ComputePipeline,
    fused: ComputePipeline,
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
    /// Where the steps go: each batch is one submission (the engine's queue or a host's).
    sub: std::cell::RefCell<&'a mut dyn Submitter>,
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
        .map_err(ReduceError::device(name))?;
        self.sub.borrow_mut().upload(&b, 0, data).map_err(ReduceError::device(name))?;
        Ok(b)
    }

    /// Submits one step (see [`Submitter`]).
    fn submit(&self, record: &mut dyn FnMut(&mut Recorder<'_>)) -> Result<(), GpuError> {
        self.sub.borrow_mut().submit(record)
    }

    fn scratch(&self, name: &str, len: usize) -> Result<Buffer<f32>, ReduceError> {
        Buffer::new(
            self.gpu,
            name,
            len.max(1) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryKind::GpuOnly,
        )
        .map_err(ReduceError::device(name))
    }

    fn over_limit(&self, what: &str, floats: usize) -> ReduceError {
        ReduceError::Device {
            context: "premultiplying on the device (use the CPU backend)".into(),
            cause: GpuError::OverLimit {
                name: what.to_string(),
                requested: floats as u64,
                limit: self.floats as u64,
                limit_name: "one storage binding",
                unit: "f32 values",
            },
        }
    }

    /// Records `dst[r] = Σ_{i ∈ starts[r]..starts[r+1]} src[perm[i]]` (rows of `block` floats).
    fn record_gather(
        &self,
        rec: &mut Recorder<'_>,
        set: &crate::gpu::DescriptorSet,
        rows: usize,
        block: usize,
    ) {
        let push = GatherPush { rows: rows as u32, block: block as u32 };
        let groups = self.gpu.caps().groups_1d((rows * block) as u64, self.k.gather.local_size()[0]);
        self.k.gather.record_dispatch(rec, set, &push, [groups, 1, 1]);
    }

    /// Rows `perm` of `src` (rows of `block` floats), in that order, in a new device buffer.
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
        let starts: Vec<u32> = (0..=perm.len() as u32).collect();
        let sb = self.upload("premultiply row starts", &starts)?;
        let set = self
            .k
            .gather
            .bind(self.gpu, &[whole(src), whole(&pb), whole(&sb), whole(&dst)].map(Resource::Storage))
            .map_err(ReduceError::device("binding the gather"))?;
        self.submit(&mut |rec| self.record_gather(rec, &set, perm.len(), block))
            .map_err(ReduceError::device("gathering rows"))?;
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
                let mut new: Vec<u32> = (group_rows[g1]..group_rows[g1 + 1])
                    .flat_map(|r| ucoords(idx[row_starts[r]]))
                    .filter(|c| !coords_seen.contains(c))
                    .collect();
                new.sort_unstable();
                new.dedup();
                let fits = entries * block <= self.floats
                    && (g1 + 1 - g0) * size * block <= self.floats
                    && (coords_seen.len() + new.len()) * m <= self.floats;
                if !fits {
                    break;
                }
                coords_seen.extend(new);
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
                .map_err(ReduceError::device("binding a stage"))?;
            let push = StagePush {
                groups: (g1 - g0) as u32,
                size: size as u32,
                block: block as u32,
                g: g as u32,
                m: m as u32,
            };
            let n = (g1 - g0) * size * block;
            let wg = self.gpu.caps().groups_1d(n as u64, self.k.stage.local_size()[0]);
            let dst_first = (g0 * size * block) as u64;
            self.submit(&mut |rec| {
                self.k.stage.record_dispatch(rec, &set, &push, [wg, 1, 1]);
                rec.copy_buffer(&out_b, 0, &out, dst_first, n as u64);
            })
            .map_err(ReduceError::device("running a stage"))?;
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
        let (first, last, inner) = (&units[0], &units[1], &units[2..]);
        let s = part.sparse_axes.len();
        let size = unit_size(first, self.bases, self.packings);
        let rest_size: usize = units[1..].iter().map(|u| unit_size(u, self.bases, self.packings)).product();
        let w_block = rest_size * part.block;
        if size * w_block > self.floats {
            return Err(self.over_limit("the final block", size * w_block));
        }
        let out = self.scratch("premultiply final block", size * w_block)?;
        let mut scratch = FusedScratch::default();
        let first_pos = unit_positions(&part.sparse_axes, first);
        if inner.is_empty() {
            // One sort by (first, last) coordinates; the fused GEMM streams over its rows.
            let last_pos = unit_positions(&part.sparse_axes, last);
            let idx = sorted_entries(&part.coords, s, &first_pos, &last_pos);
            let piece = Piece {
                values: &part.values,
                block: part.block,
                sparse_axes: &part.sparse_axes,
                coords: &part.coords,
            };
            self.fused_gemm(&piece, &idx, first, last, &out, &mut scratch, false, progress)?;
        } else {
            // Chunks of whole first-unit groups; the inner units are contracted per chunk by
            // unit stages, then the chunk's result goes through the fused GEMM.
            let idx = sorted_entries(&part.coords, s, &first_pos, &[]);
            let first_of = |e: usize| first_pos.iter().map(|&i| part.coords[e * s + i]).collect::<Vec<u32>>();
            let per_chunk = (self.floats / w_block.max(1)).min(self.floats / size.max(1)).max(1);
            let mut accumulate = false;
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
                for u in inner.iter().rev() {
                    w = self.contract_unit(w, u)?;
                }
                let ws = w.sparse_axes.len();
                let widx = sorted_entries(
                    &w.coords,
                    ws,
                    &unit_positions(&w.sparse_axes, first),
                    &unit_positions(&w.sparse_axes, last),
                );
                let piece = Piece {
                    values: &w.values,
                    block: w.block,
                    sparse_axes: &w.sparse_axes,
                    coords: &w.coords,
                };
                self.fused_gemm(&piece, &widx, first, last, &out, &mut scratch, accumulate, &|_| ())?;
                accumulate = true;
                progress(j as f64 / idx.len() as f64);
            }
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

    /// `out[t][s·block + b] (+)= Σ_e F_first(e)[t] · U_last(e)[s] · values[e][b]` over the
    /// entries `idx` of `piece` (sorted by first-unit, then last-unit coordinates; every sparse
    /// axis belongs to one of the two units), as `premultiply_gemm.comp` dispatches over
    /// batches of rows (entries with equal coordinates, summed) that fit one binding each.
    #[allow(clippy::too_many_arguments)]
    fn fused_gemm(
        &self,
        piece: &Piece<'_>,
        idx: &[usize],
        first: &Unit,
        last: &Unit,
        out: &Buffer<f32>,
        scratch: &mut FusedScratch,
        mut accumulate: bool,
        progress: &dyn Fn(f64),
    ) -> Result<(), ReduceError> {
        let s = piece.sparse_axes.len();
        let (fpos, lpos) =
            (unit_positions(piece.sparse_axes, first), unit_positions(piece.sparse_axes, last));
        debug_assert_eq!(fpos.len() + lpos.len(), s, "every sparse axis is in the first or last unit");
        let c = piece.coords;
        let fkey = |e: usize| fpos.iter().map(move |&i| c[e * s + i]);
        let lkey = |e: usize| lpos.iter().map(move |&i| c[e * s + i]);
        let mut row_start = vec![0usize];
        for i in 1..idx.len() {
            if !fkey(idx[i - 1]).eq(fkey(idx[i])) || !lkey(idx[i - 1]).eq(lkey(idx[i])) {
                row_start.push(i);
            }
        }
        row_start.push(idx.len());
        let rows = row_start.len() - 1;
        let size = unit_size(first, self.bases, self.packings);
        let last_size = unit_size(last, self.bases, self.packings);
        let block = piece.block;
        let mut unit = Vec::new();
        let mut r0 = 0;
        while r0 < rows {
            // The batch: as many rows as fit (their values, first-unit rows and last-unit rows).
            let (mut r1, mut firsts) = (r0, 0usize);
            while r1 < rows {
                let new_first = r1 == r0 || !fkey(idx[row_start[r1]]).eq(fkey(idx[row_start[r1 - 1]]));
                let f = firsts + usize::from(new_first);
                if (r1 + 1 - r0) * block.max(last_size) > self.floats || f * size > self.floats {
                    break;
                }
                (firsts, r1) = (f, r1 + 1);
            }
            if r1 == r0 {
                return Err(self.over_limit("one row of the final stage", block.max(last_size).max(size)));
            }
            let mut first_rows = Vec::with_capacity(firsts * size);
            let mut fref = Vec::with_capacity(r1 - r0);
            let mut last_rows = Vec::new();
            let mut uref = Vec::with_capacity(r1 - r0);
            let mut last_index: HashMap<Vec<u32>, u32> = HashMap::new();
            for r in r0..r1 {
                let e = idx[row_start[r]];
                if r == r0 || !fkey(e).eq(fkey(idx[row_start[r - 1]])) {
                    let coords: Vec<u32> = fkey(e).collect();
                    unit_row(first, &coords, self.bases, self.packings, &mut unit);
                    first_rows.extend(unit.iter().map(|&v| v as f32));
                }
                fref.push((first_rows.len() / size - 1) as u32);
                let coords: Vec<u32> = lkey(e).collect();
                let next = last_index.len() as u32;
                let k = *last_index.entry(coords).or_insert_with_key(|coords| {
                    unit_row(last, coords, self.bases, self.packings, &mut unit);
                    last_rows.extend(unit.iter().map(|&v| v as f32));
                    next
                });
                uref.push(k);
            }
            let (e0, e1) = (row_start[r0], row_start[r1]);
            let perm: Vec<u32> = idx[e0..e1].iter().map(|&e| e as u32).collect();
            let starts: Vec<u32> = row_start[r0..=r1].iter().map(|&x| (x - e0) as u32).collect();
            let n_rows = r1 - r0;
            let fb = scratch.first_rows.fill(self, "premultiply first-unit rows", &first_rows)?;
            let frb = scratch.first_ref.fill(self, "premultiply first-unit refs", &fref)?;
            let lb = scratch.last_rows.fill(self, "premultiply last-unit rows", &last_rows)?;
            let lrb = scratch.last_ref.fill(self, "premultiply last-unit refs", &uref)?;
            let gathered = match piece.values {
                Values::Host(v) => {
                    let mut x = vec![0f32; n_rows * block];
                    for (r, xr) in x.chunks_exact_mut(block.max(1)).enumerate() {
                        for &e in &perm[starts[r] as usize..starts[r + 1] as usize] {
                            for (o, &y) in xr.iter_mut().zip(&v[e as usize * block..(e as usize + 1) * block])
                            {
                                *o += y;
                            }
                        }
                    }
                    scratch.rows.fill(self, "premultiply final-stage rows", &x)?;
                    None
                }
                Values::Device(src) => {
                    scratch.rows.reserve(self, "premultiply final-stage rows", n_rows * block)?;
                    let pb = scratch.perm.fill(self, "premultiply row order", &perm)?;
                    let sb = scratch.starts.fill(self, "premultiply row starts", &starts)?;
                    let set = self
                        .k
                        .gather
                        .bind(
                            self.gpu,
                            &[whole(src), whole(pb), whole(sb), whole(scratch.rows.get())]
                                .map(Resource::Storage),
                        )
                        .map_err(ReduceError::device("binding the gather"))?;
                    Some(set)
                }
            };
            let set = self
                .k
                .fused
                .bind(
                    self.gpu,
                    &[whole(fb), whole(frb), whole(lb), whole(lrb), whole(scratch.rows.get()), whole(out)]
                        .map(Resource::Storage),
                )
                .map_err(ReduceError::device("binding the final GEMM"))?;
            let push = FusedPush {
                m: size as u32,
                k: n_rows as u32,
                size: last_size as u32,
                block: block as u32,
                accumulate: u32::from(accumulate),
            };
            let groups =
                [((last_size * block) as u32).div_ceil(GEMM_TILE), (size as u32).div_ceil(GEMM_TILE), 1];
            self.submit(&mut |rec| {
                if let Some(gather) = &gathered {
                    self.record_gather(rec, gather, n_rows, block);
                }
                self.k.fused.record_dispatch(rec, &set, &push, groups);
            })
            .map_err(ReduceError::device("the final GEMM"))?;
            accumulate = true;
            r0 = r1;
            progress(r0 as f64 / rows as f64);
        }
        Ok(())
    }
}

/// Entries with coordinates on the host and blocks of values, as the fused GEMM reads them.
struct Piece<'a> {
    values: &'a Values,
    block: usize,
    sparse_axes: &'a [usize],
    coords: &'a [u32],
}

/// A device buffer kept between batches and grown when too small, so that streaming does not
/// allocate (and page-fault in) fresh memory for every batch.
struct Reused<T: Pod>(Option<Buffer<T>>);

impl<T: Pod> Default for Reused<T> {
    fn default() -> Self {
        Self(None)
    }
}

impl<T: Pod> Reused<T> {
    /// At least `len` elements (contents undefined).
    fn reserve(&mut self, ctx: &Ctx<'_>, name: &str, len: usize) -> Result<&Buffer<T>, ReduceError> {
        if self.0.as_ref().is_none_or(|b| (b.len() as usize) < len.max(1)) {
            self.0 = None;
            let grown = len.max(1) + len / 4;
            self.0 = Some(
                Buffer::new(
                    ctx.gpu,
                    name,
                    grown as u64,
                    vk::BufferUsageFlags::STORAGE_BUFFER,
                    MemoryKind::GpuOnly,
                )
                .map_err(ReduceError::device(name))?,
            );
        }
        Ok(self.get())
    }

    /// `data` at the start of the buffer.
    fn fill(&mut self, ctx: &Ctx<'_>, name: &str, data: &[T]) -> Result<&Buffer<T>, ReduceError> {
        self.reserve(ctx, name, data.len())?;
        let b = self.get();
        ctx.sub.borrow_mut().upload(b, 0, data).map_err(ReduceError::device(name))?;
        Ok(b)
    }

    fn get(&self) -> &Buffer<T> {
        self.0.as_ref().expect("reserved before use")
    }
}

/// The buffers of the fused final stage, reused across its batches.
#[derive(Default)]
struct FusedScratch {
    first_rows: Reused<f32>,
    first_ref: Reused<u32>,
    last_rows: Reused<f32>,
    last_ref: Reused<u32>,
    rows: Reused<f32>,
    perm: Reused<u32>,
    starts: Reused<u32>,
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
    premultiply_sparse_on(&mut gpu.submitter(), q, bases, options)
}

/// [`premultiply_sparse_gpu`] through `submitter` (the engine's queue or a host's): every
/// batch of every stage is one submission — its index data and values uploaded, its gather,
/// unit-stage or fused-GEMM dispatches recorded — with the host's sorting and grouping of
/// coordinates between them; the result is read back once at the end.
pub fn premultiply_sparse_on(
    submitter: &mut dyn Submitter,
    q: &SparseTensor,
    bases: &[&Tensor],
    options: PremultiplyOptions<'_>,
) -> Result<(Tensor, PremultiplyPlan), ReduceError> {
    let gpu = &submitter.gpu().clone();
    let floats = (gpu.max_binding_bytes() / 4) as usize;
    // The planner counts 8-byte values; keep every intermediate within one binding of f32.
    let budget = options.memory_budget.min(2 * gpu.max_binding_bytes());
    let setup = Setup::new(q, bases, budget)
        .map_err(|cause| ReduceError::Tensor { context: "premultiply".into(), cause })?;
    if q.nnz() == 0 {
        return Ok((Tensor::zeros(&setup.reduced_shape), setup.plan));
    }
    let stage = |name: &str, spirv: &[u32], bindings: &[BindingKind], push: PushLayout| {
        ComputePipeline::new(gpu, &ComputePipelineDesc { name, spirv, bindings, push, specialization: &[] })
            .map_err(ReduceError::device("building a premultiply pipeline"))
    };
    let kernels = Kernels {
        stage: stage(
            "premultiply unit stage",
            crate::tensor::shaders::UNIT_STAGE,
            &[BindingKind::StorageBuffer; 7],
            PushLayout::of::<StagePush>(),
        )?,
        gather: stage(
            "premultiply gather",
            crate::tensor::shaders::GATHER_ROWS,
            &[BindingKind::StorageBuffer; 4],
            PushLayout::of::<GatherPush>(),
        )?,
        fused: stage(
            "premultiply final GEMM",
            crate::tensor::shaders::PREMULTIPLY_GEMM,
            &[BindingKind::StorageBuffer; 6],
            PushLayout::of::<FusedPush>(),
        )?,
    };
    let ctx = Ctx {
        gpu,
        sub: std::cell::RefCell::new(submitter),
        k: &kernels,
        bases,
        packings: &setup.packings,
        floats,
    };
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
        Values::Device(b) => {
            ctx.sub.borrow_mut().download(b).map_err(ReduceError::device("reading the result"))?
        }
        Values::Host(v) => v.clone(),
    }
    .into_iter()
    .map(f64::from)
    .collect();
    Ok((setup.expand(&part.dense, bases, &values), setup.plan))
}
