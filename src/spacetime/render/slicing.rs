//! The slicing half of [`SpacetimeRenderer`] (seed 003 §4.1, §4.2.2): the resident window of
//! records streamed as `t` moves, and the two compute passes — the cut (`slice.comp`) and the
//! quadrisection (`subdivide.comp`) — with their output buffers grown on overflow.

use crate::gpu::{Access, Recorder};
use std::ops::Range;

use ash::vk;
use bytemuck::Zeroable;

use super::*;

/// Rounds of slicing [`SpacetimeRenderer::slice`] tries before it gives up (each redo grows the
/// buffers to what the slice asked for; two suffice).
const MAX_SLICE_ROUNDS: usize = 4;

impl SpacetimeRenderer {
    /// Makes `active` resident. The window is a ring of `capacity` records (record `e` in slot
    /// `e mod capacity`) covering `[start, start + capacity)` from the active range's first
    /// element, so that advancing `t` finds the next elements already there; moving on uploads
    /// only the records not yet resident (checked first). Returns the number uploaded.
    pub(super) fn make_resident(&mut self, active: Range<usize>) -> Result<usize, SpacetimeError> {
        if let Some(w) = &self.window {
            if w.range.start <= active.start && active.end <= w.range.end {
                return Ok(0);
            }
        }
        let n = self.data.len();
        let limit =
            ((self.gpu.max_binding_bytes() / ElementRecord::BYTES as u64) as usize).min(self.max_window);
        if active.len() > limit {
            return Err(SpacetimeError::TooManyActive { active: active.len(), limit });
        }
        let current = self.window.as_ref().map_or(0, |w| w.buffer.len() as usize);
        let capacity = if n <= RESIDENT_WHOLE.min(limit) {
            n
        } else if active.len() <= current {
            current
        } else {
            (4 * active.len()).max(1 << 16).min(limit).min(n).max(active.len())
        };
        let range = active.start..(active.start + capacity).min(n);
        // Keep the window full: near the end of the data it reaches back.
        let range = range.end.saturating_sub(capacity)..range.end;
        let (buffer, cubics, resident) = match self.window.take() {
            Some(w) if w.buffer.len() as usize == capacity.max(1) => (w.buffer, w.cubics, w.range),
            _ => {
                // New bindings for everything that reads the window.
                self.slice_sets = None;
                self.draw_sets.clear();
                let buffer = Buffer::new(
                    &self.gpu,
                    "spacetime records",
                    capacity.max(1) as u64,
                    vk::BufferUsageFlags::STORAGE_BUFFER,
                    MemoryKind::GpuOnly,
                )
                .map_err(dev("the resident window"))?;
                let cubics = Buffer::new(
                    &self.gpu,
                    "spacetime slice cubics",
                    capacity.max(1) as u64,
                    vk::BufferUsageFlags::STORAGE_BUFFER,
                    MemoryKind::GpuOnly,
                )
                .map_err(dev("the resident window"))?;
                (buffer, cubics, 0..0)
            }
        };
        // What the new window needs beyond what is resident: at most two intervals.
        let missing = [
            range.start..range.end.min(resident.start.max(range.start)),
            resident.end.max(range.start)..range.end,
        ];
        let mut streamed = 0;
        for part in missing.into_iter().filter(|p| !p.is_empty()) {
            self.data.check(part.clone())?;
            // Each interval occupies at most two runs of slots (it may wrap around the ring).
            let mut e = part.start;
            while e < part.end {
                let slot = e % capacity;
                let run = (part.end - e).min(capacity - slot);
                buffer
                    .upload(&self.gpu, slot as u64, &self.data.records()[e..e + run])
                    .map_err(dev("streaming elements"))?;
                e += run;
            }
            streamed += part.len();
        }
        self.window = Some(Window { range, buffer, cubics });
        Ok(streamed)
    }

    /// The element of the data in ring slot `slot` of the window.
    fn element_of_slot(&self, slot: u32) -> u32 {
        match &self.window {
            Some(w) => {
                let cap = w.buffer.len() as usize;
                let start = w.range.start;
                (start + (slot as usize + cap - start % cap) % cap) as u32
            }
            None => slot,
        }
    }

    pub(super) fn slice_push(
        &self,
        t: f64,
        subdivide: Option<f64>,
        active: &Range<usize>,
    ) -> SlicePushCompute {
        let capacity = self.window.as_ref().map_or(1, |w| w.buffer.len() as usize);
        SlicePushCompute {
            first: (active.start % capacity) as u32,
            capacity: capacity as u32,
            count: active.len() as u32,
            t: t as f32,
            max_area: subdivide.map_or(f32::INFINITY, |a| a as f32),
            max_level: if subdivide.is_some() { 6 } else { 0 },
            tri_capacity: self.tris.len() as u32,
            line_capacity: self.lines.len() as u32,
            cut_capacity: (self.cuts.len() / CUT_VEC4S) as u32,
        }
    }

    pub(super) fn bind_slicer(&mut self) -> Result<(), SpacetimeError> {
        if self.slice_sets.is_some() {
            return Ok(());
        }
        let window = self.window.as_ref().expect("made resident before slicing");
        fn b(
            r: crate::gpu::GpuResult<crate::gpu::BufferBinding<'_>>,
        ) -> Result<Resource<'_>, SpacetimeError> {
            r.map(Resource::Storage).map_err(dev("binding the slicer"))
        }
        let records = b(window.buffer.binding())?;
        let cuts = b(self.cuts.binding())?;
        let draws = b(self.draws.binding())?;
        let materials = b(self.materials.binding())?;
        let cubics = b(window.cubics.binding())?;
        let slice = self
            .slicer
            .bind(&self.gpu, &[records, cuts, b(self.lines.binding())?, draws, materials, cubics])
            .map_err(dev("binding the slicer"))?;
        let subdivide = self
            .subdivider
            .bind(&self.gpu, &[records, cuts, b(self.tris.binding())?, draws, materials, cubics])
            .map_err(dev("binding the slicer"))?;
        self.slice_sets = Some((slice, subdivide));
        Ok(())
    }

    /// Records the two slicing passes; `scope` wraps each in a profiler scope.
    pub(super) fn record_slice(
        &self,
        rec: &mut Recorder<'_>,
        push: &SlicePushCompute,
        mut profiler: Option<&mut Profiler>,
    ) {
        let (slice_set, subdivide_set) = self.slice_sets.as_ref().expect("bound before recording");
        let reset: [u32; COUNTERS as usize] = [0, 1, 0, 0, 0, 1, 0, 0, 0, 0];
        let cut = |rec: &mut Recorder<'_>| {
            rec.update_buffer(&self.draws, 0, &reset);
            let groups = self.gpu.caps().groups_1d(u64::from(push.count.max(1)), self.slicer.local_size()[0]);
            self.slicer.record_dispatch(rec, slice_set, push, [groups, 1, 1]);
        };
        match profiler.as_deref_mut() {
            Some(p) => p.scope(rec, "slice", cut),
            None => cut(rec),
        }
        let subdivide = |rec: &mut Recorder<'_>| {
            // A polygon is cut into at most two triangles.
            let wg = self.subdivider.local_size()[0];
            let groups = self.gpu.caps().groups_1d(u64::from(push.count.max(1)) * 2, wg);
            self.subdivider.record_dispatch(rec, subdivide_set, push, [groups, 1, 1]);
            // The slice's draws follow (declared here, before their render pass): indirect
            // parameters and vertices, and the restricted cubics in the fragment stage.
            let mut reads: Vec<(&dyn crate::gpu::Tracked, Access)> = vec![
                (&self.draws, Access::INDIRECT),
                (&self.tris, Access::VERTEX_INPUT),
                (&self.lines, Access::VERTEX_INPUT),
            ];
            if let Some(window) = &self.window {
                reads.push((&window.cubics, Access::GRAPHICS_READ));
            }
            rec.access_all(&reads);
        };
        match profiler {
            Some(p) => p.scope(rec, "subdivide", subdivide),
            None => subdivide(rec),
        }
    }

    /// Reads the counters of the last slice: `Ok(stats)`, or `Err(())` after growing the
    /// output buffers that overflowed (the slice must be redone).
    pub(super) fn finish_slice(
        &mut self,
        active: usize,
        streamed: usize,
    ) -> Result<Option<SliceStats>, SpacetimeError> {
        let counts = self.draws.download(&self.gpu).map_err(dev("reading the slice size"))?;
        if counts[8] == 0 {
            return Ok(Some(SliceStats {
                active,
                triangles: counts[0] as usize / 3,
                lines: counts[4] as usize / 2,
                streamed,
            }));
        }
        // The counters hold what was asked for: grow to that (and a margin) and redo.
        let grow = |n: u32, cur: u64| u64::from(n).max(cur) + u64::from(n) / 4 + 64;
        self.slice_sets = None;
        if u64::from(counts[9]) > self.cuts.len() / CUT_VEC4S {
            self.cuts = Buffer::new(
                &self.gpu,
                "slice cuts",
                CUT_VEC4S * grow(counts[9], self.cuts.len() / CUT_VEC4S),
                vk::BufferUsageFlags::STORAGE_BUFFER,
                MemoryKind::GpuOnly,
            )
            .map_err(dev("slice buffers"))?;
            // The subdivision saw at most the capacity: its count is not final yet.
            return Ok(None);
        }
        if u64::from(counts[0]) > self.tris.len() {
            self.tris = slice_buffer(&self.gpu, "slice triangles", grow(counts[0], self.tris.len()))?;
        }
        if u64::from(counts[4]) > self.lines.len() {
            self.lines = slice_buffer(&self.gpu, "slice edges", grow(counts[4], self.lines.len()))?;
        }
        Ok(None)
    }

    /// Slices the data at `t` on the device (a no-op if the last slice had the same `t` and
    /// subdivision), streaming the active elements first if they are not resident. Output
    /// buffers grow when a slice needs more room, and the slice is redone.
    pub fn slice(&mut self, t: f64, subdivide: Option<f64>) -> Result<SliceStats, SpacetimeError> {
        if let Some((st, sd, stats)) = self.sliced {
            if st == t && sd == subdivide {
                return Ok(stats);
            }
        }
        let mut plan = self.prepare_slice(t, subdivide)?;
        let streamed = plan.streamed;
        let gpu = self.gpu.clone();
        // Each redo follows a growth of the buffers to what the slice asked for: the cuts
        // first, then triangles and lines; more rounds than that mean the counts are wrong.
        for _ in 0..MAX_SLICE_ROUNDS {
            gpu.run(|rec| self.record_slice_into(rec, &plan)).map_err(dev("slicing"))?;
            if let Some(stats) = self.finish_host_slice(&plan)? {
                return Ok(stats);
            }
            // The buffers grew: bind them again, with the first round's streamed count.
            plan = SlicePlan { streamed, ..self.prepare_slice(t, subdivide)? };
        }
        Err(SpacetimeError::SliceOverflow { t, rounds: MAX_SLICE_ROUNDS })
    }

    /// For a frame the host records itself: streams the elements active at `t` to the device
    /// (engine transfers, done before the frame is recorded) and binds the slicer. Then
    /// [`Self::record_slice_into`] records the slice into the host's command buffer, and
    /// [`Self::finish_host_slice`] checks it once that work has finished.
    pub fn prepare_slice(&mut self, t: f64, subdivide: Option<f64>) -> Result<SlicePlan, SpacetimeError> {
        self.sliced = None;
        let active = self.data.active_range(t);
        let streamed = self.make_resident(active.clone())?;
        self.bind_slicer()?;
        let push = self.slice_push(t, subdivide, &active);
        Ok(SlicePlan { t, subdivide, active, streamed, push })
    }

    /// Records the two slicing passes of `plan` (outside a render pass). Their declared
    /// accesses order them after every earlier use of the slice buffers (a previous frame's
    /// draw or readback, in this or an unfinished earlier recording), and they declare the
    /// draw's reads; draw it with [`Self::record_draw_into`].
    pub fn record_slice_into(&self, rec: &mut Recorder<'_>, plan: &SlicePlan) {
        self.record_slice(rec, &plan.push, None);
    }

    /// After the recording of `plan` has finished: `Ok(Some(stats))` if the slice fit its
    /// buffers, `Ok(None)` if they were grown and the frame must be recorded again.
    pub fn finish_host_slice(&mut self, plan: &SlicePlan) -> Result<Option<SliceStats>, SpacetimeError> {
        let stats = self.finish_slice(plan.active.len(), plan.streamed)?;
        if let Some(s) = stats {
            self.sliced = Some((plan.t, plan.subdivide, s));
        }
        Ok(stats)
    }

    /// The triangles of the current slice, read back: (element of the data, corners). For
    /// tests and inspection.
    pub fn slice_triangles(&self) -> Result<Vec<SliceTriangle>, SpacetimeError> {
        let Some((_, _, stats)) = self.sliced else { return Ok(Vec::new()) };
        let mut v = vec![SliceVertex::zeroed(); 3 * stats.triangles];
        self.tris.download_into(&self.gpu, 0, &mut v).map_err(dev("reading the slice"))?;
        Ok(v.chunks_exact(3)
            .map(|t| (self.element_of_slot(t[0].element), [t[0].xy, t[1].xy, t[2].xy]))
            .collect())
    }

    /// The edge lines of the current slice, read back: (element of the data, endpoints).
    pub fn slice_lines(&self) -> Result<Vec<SliceLine>, SpacetimeError> {
        let Some((_, _, stats)) = self.sliced else { return Ok(Vec::new()) };
        let mut v = vec![SliceVertex::zeroed(); 2 * stats.lines];
        self.lines.download_into(&self.gpu, 0, &mut v).map_err(dev("reading the slice"))?;
        Ok(v.chunks_exact(2).map(|l| (self.element_of_slot(l[0].element), [l[0].xy, l[1].xy])).collect())
    }
}

/// A slice prepared for a host-recorded frame ([`SpacetimeRenderer::prepare_slice`]).
#[derive(Clone, Debug)]
pub struct SlicePlan {
    t: f64,
    subdivide: Option<f64>,
    active: Range<usize>,
    streamed: usize,
    push: SlicePushCompute,
}
