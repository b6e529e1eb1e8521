//! The spacetime renderer (seed 003 §4): the elements a slice can cut resident on the device
//! (a window of the data sorted by lowest time, streamed from memory or a memory-mapped
//! `.gst` file as `t` moves), two compute passes that slice the window at time `t`
//! (`shaders-glsl/spacetime/slice.comp`: the cut; `subdivide.comp`: quadrisection), and
//! graphics pipelines that draw the slice with per-vertex height and per-pixel strain energy
//! density, exact normals and Phong lighting (`slice.vert`, `slice.frag`), then overdraw every
//! polygon edge as a line to fill cracks between discontinuous neighbours (§4.3).
//!
//! The edge lines are drawn *behind* the polygons: where a polygon covers a pixel it wins and
//! the pixel shows the polygon's value at the pixel centre; a line only shows where no polygon
//! covered the pixel — a crack. Vulkan's depth bias applies to polygons only, not to lines, so
//! the vertex stage moves edge vertices back by [`EDGE_DEPTH_OFFSET`] in normalised depth (a
//! line at the same depth as the polygons would win some pixels by interpolation rounding,
//! showing the neighbour's value there).

use std::collections::HashMap;
use std::ops::Range;

use ash::vk;
use bytemuck::{Pod, Zeroable};

use super::data::{DataSummary, SpacetimeData};
use super::error::SpacetimeError;
use super::mesh::SpacetimeMesh;
use super::record::{gpu_material, ElementRecord};
use crate::gpu::{
    shaders, BindingKind, Buffer, ComputePipeline, ComputePipelineDesc, DescriptorSet, Gpu, GpuError,
    GraphicsPipeline, GraphicsPipelineDesc, MemoryKind, Profiler, Resource,
};
use crate::render::{Camera, ColorFormat, Colormap, ColormapTexture, Pixels, RenderTarget, BACKGROUND};

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct SliceVertex {
    xy: [f32; 2],
    element: u32,
    speed: f32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct SlicePushCompute {
    first: u32,
    count: u32,
    t: f32,
    max_area: f32,
    max_level: u32,
    tri_capacity: u32,
    line_capacity: u32,
    cut_capacity: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct DrawPush {
    view_proj: [f32; 16],
    eye_t: [f32; 4],
    light_scale: [f32; 4],
    ramp: [f32; 4],
    flags: [u32; 4],
}

impl DrawPush {
    /// The same push for the edge pass: vertices moved back by [`EDGE_DEPTH_OFFSET`].
    fn for_edges(&self) -> Self {
        let mut p = *self;
        p.ramp[2] = EDGE_DEPTH_OFFSET;
        p
    }
}

/// How far the edge pass moves its vertices back, in normalised depth (`slice.vert`): about
/// 300 f32 ulps of depth near 1, far above the rounding of depth interpolation (a few ulps),
/// and for the default cameras (near plane at 1 % of the domain size) a distance of ≈ 0.2 % of
/// the domain — a line is hidden only by polygons that close in front of it.
pub const EDGE_DEPTH_OFFSET: f32 = 2e-5;

/// How to show a slice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpacetimeView {
    /// Time of the slice.
    pub time: f64,
    /// Displace by the velocity magnitude (height field).
    pub height: bool,
    /// Height per unit of |v|; `None`: a tenth of the domain's size per max |v| of the data set.
    pub height_scale: Option<f64>,
    /// Overdraw polygon edges (§4.3).
    pub edges: bool,
    /// Quadrisect slice triangles larger than this area (§4.2.2), at most 6 levels.
    pub subdivide: Option<f64>,
    /// The colour ramp's `U_max`; `None`: the largest U over the slice's pixels (a data pass
    /// before the colour pass).
    pub u_max: Option<f64>,
    /// Colour from U at the vertices, interpolated (the seed's Fig. 5a baseline).
    pub per_vertex: bool,
    /// The camera.
    pub camera: Camera,
}

impl SpacetimeView {
    /// Height on, edges on, no subdivision, automatic scales, looking at the data set from
    /// above and in front.
    pub fn looking_at(data: &DataSummary, time: f64) -> Self {
        let (centre, size) = (data.centre(), data.size());
        Self {
            time,
            height: true,
            height_scale: None,
            edges: true,
            subdivide: None,
            u_max: None,
            per_vertex: false,
            camera: Camera {
                eye: [centre[0], centre[1] - 1.3 * size, 1.1 * size],
                target: [centre[0], centre[1], 0.0],
                up: [0.0, 0.0, 1.0],
                fov_y_degrees: 40.0,
                near: 0.01 * size,
                far: 10.0 * size,
            },
        }
    }

    /// Looking straight down at the data set so that it fills the image (height off): every pixel
    /// centre sees the point (x, y) of the slice plane, as the pixel-exactness tests want.
    pub fn from_above(data: &DataSummary, time: f64) -> Self {
        let (centre, size) = (data.centre(), data.size());
        let fov: f64 = 30.0;
        let distance = 0.5 * size / (0.5 * fov.to_radians()).tan();
        Self {
            height: false,
            camera: Camera {
                eye: [centre[0], centre[1], distance],
                target: [centre[0], centre[1], 0.0],
                up: [0.0, 1.0, 0.0],
                fov_y_degrees: fov,
                near: 0.1 * distance,
                far: 4.0 * distance,
            },
            ..Self::looking_at(data, time)
        }
    }
}

/// A triangle of a slice as drawn: its element and corners (f32, as on the device).
pub type SliceTriangle = (u32, [[f32; 2]; 3]);

/// An overdrawn edge of a slice: its element and endpoints.
pub type SliceLine = (u32, [[f32; 2]; 2]);

/// What one slice produced.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SliceStats {
    /// Elements in the active range (tested by the slicer).
    pub active: usize,
    /// Triangles drawn (after subdivision).
    pub triangles: usize,
    /// Edge lines drawn.
    pub lines: usize,
    /// Elements uploaded to the device for this slice (0 when the resident window already
    /// held the active range).
    pub streamed: usize,
}

/// Device times of one frame's stages from timestamp queries (milliseconds).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameTimes {
    /// The cut of the active elements (`slice.comp`).
    pub slice_ms: f64,
    /// The quadrisection of the cut triangles (`subdivide.comp`).
    pub subdivide_ms: f64,
    /// The render pass: polygons and edge lines.
    pub draw_ms: f64,
}

/// Direction to the light (unit), from the upper left front.
const LIGHT: [f64; 3] = [-0.408_248_290_463_863, -0.408_248_290_463_863, 0.816_496_580_927_726];

/// Elements of the data resident on the device: `range` of the sorted records in `buffer`.
struct Window {
    range: Range<usize>,
    buffer: Buffer<ElementRecord>,
}

/// Counters written by the slicing passes: two `VkDrawIndirectCommand`s (triangles at word 0,
/// lines at word 4), the overflow flag (word 8), the number of cut triangles (word 9).
const COUNTERS: u64 = 10;

/// vec4s per cut triangle in the buffer between the slicing passes: corners, element, |v| at
/// the corners.
const CUT_VEC4S: u64 = 3;

/// Data sets up to this many elements are made resident whole.
const RESIDENT_WHOLE: usize = 1 << 18;

/// The data, the resident window, its slice and the pipelines.
pub struct SpacetimeRenderer {
    gpu: Gpu,
    data: SpacetimeData,
    window: Option<Window>,
    materials: Buffer<[f32; 4]>,
    cuts: Buffer<[f32; 4]>,
    tris: Buffer<SliceVertex>,
    lines: Buffer<SliceVertex>,
    draws: Buffer<u32>,
    slicer: ComputePipeline,
    subdivider: ComputePipeline,
    colormap: ColormapTexture,
    pipelines: HashMap<ColorFormat, (GraphicsPipeline, GraphicsPipeline, DescriptorSet, DescriptorSet)>,
    sliced: Option<(f64, Option<f64>, SliceStats)>,
    /// The slicing passes' bindings, kept until a buffer is replaced.
    slice_sets: Option<(DescriptorSet, DescriptorSet)>,
    /// The float target of the automatic-U_max data pass, reused while the size stays.
    umax_target: Option<RenderTarget>,
    /// The most elements resident at once (besides the binding limit).
    max_window: usize,
    /// The U_max reduction (`max_u.comp`), its pixel buffer, result word and bindings.
    umax_reducer: ComputePipeline,
    umax_pixels: Option<Buffer<[f32; 4]>>,
    umax_result: Buffer<u32>,
    umax_set: Option<DescriptorSet>,
}

/// A slice output buffer: vertices written by the slicer, read by the draws.
fn slice_buffer(gpu: &Gpu, name: &str, len: u64) -> Result<Buffer<SliceVertex>, SpacetimeError> {
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::VERTEX_BUFFER;
    Buffer::new(gpu, name, len, usage, MemoryKind::GpuOnly).map_err(dev("slice buffers"))
}

fn dev(context: &str) -> impl FnOnce(GpuError) -> SpacetimeError + '_ {
    move |source| SpacetimeError::Device { context: context.to_string(), source }
}

fn compute(gpu: &Gpu, name: &'static str, spirv: &'static [u32]) -> Result<ComputePipeline, SpacetimeError> {
    ComputePipeline::new(
        gpu,
        &ComputePipelineDesc {
            name,
            spirv,
            bindings: &[BindingKind::StorageBuffer; 5],
            push_constant_bytes: std::mem::size_of::<SlicePushCompute>() as u32,
            specialization: &[],
            shared_bytes: 0,
        },
    )
    .map_err(dev("building the slicer"))
}

impl SpacetimeRenderer {
    /// A renderer of `data` on `gpu`. Nothing is uploaded until the first slice.
    pub fn new(gpu: &Gpu, data: SpacetimeData, colormap: &Colormap) -> Result<Self, SpacetimeError> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let materials: Vec<[f32; 4]> = data.materials().iter().map(gpu_material).collect();
        let materials = Buffer::from_slice(gpu, "spacetime materials", &materials, storage)
            .map_err(dev("uploading materials"))?;
        let cuts = Buffer::new(gpu, "slice cuts", CUT_VEC4S * 1024, storage, MemoryKind::GpuOnly)
            .map_err(dev("slice buffers"))?;
        let tris = slice_buffer(gpu, "slice triangles", 3 * 1024)?;
        let lines = slice_buffer(gpu, "slice edges", 8 * 1024)?;
        let draws = Buffer::new(
            gpu,
            "slice draws",
            COUNTERS,
            storage | vk::BufferUsageFlags::INDIRECT_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryKind::GpuOnly,
        )
        .map_err(dev("slice buffers"))?;
        Ok(Self {
            gpu: gpu.clone(),
            data,
            window: None,
            materials,
            cuts,
            tris,
            lines,
            draws,
            slicer: compute(gpu, "spacetime slice", shaders::spacetime::SLICE)?,
            subdivider: compute(gpu, "spacetime subdivide", shaders::spacetime::SUBDIVIDE)?,
            colormap: colormap.upload(gpu).map_err(dev("uploading the colour map"))?,
            pipelines: HashMap::new(),
            sliced: None,
            slice_sets: None,
            umax_target: None,
            max_window: usize::MAX,
            umax_reducer: ComputePipeline::new(
                gpu,
                &ComputePipelineDesc {
                    name: "spacetime U_max",
                    spirv: shaders::spacetime::MAX_U,
                    bindings: &[BindingKind::StorageBuffer; 2],
                    push_constant_bytes: 4,
                    specialization: &[],
                    shared_bytes: 0,
                },
            )
            .map_err(dev("building the U_max reduction"))?,
            umax_pixels: None,
            umax_result: Buffer::new(
                gpu,
                "U_max",
                1,
                storage | vk::BufferUsageFlags::TRANSFER_DST,
                MemoryKind::GpuOnly,
            )
            .map_err(dev("the U_max pass"))?,
            umax_set: None,
        })
    }

    /// A renderer of a validated `mesh` sorted by lowest time (see [`SpacetimeData::from_mesh`]).
    pub fn from_mesh(gpu: &Gpu, mesh: &SpacetimeMesh, colormap: &Colormap) -> Result<Self, SpacetimeError> {
        Self::new(gpu, SpacetimeData::from_mesh(mesh)?, colormap)
    }

    /// The data set.
    pub fn data(&self) -> &SpacetimeData {
        &self.data
    }

    /// The height scale used when a view does not set one: a tenth of the domain's size per
    /// the largest |v| at an element centroid.
    pub fn default_height_scale(&self) -> f64 {
        let s = self.data.summary();
        if s.max_speed > 0.0 {
            0.1 * s.size() / s.max_speed
        } else {
            1.0
        }
    }

    /// Caps the resident window at `elements` records (default: as many as one storage binding
    /// holds, 559,240 at lavapipe's 128 MiB), for applications that budget device memory; a
    /// time plane that can cut more elements than the cap is an error.
    pub fn with_window_limit(mut self, elements: usize) -> Self {
        self.max_window = elements.max(1);
        self
    }

    /// The resident window of records (elements `range` of the data), if any.
    pub fn resident(&self) -> Option<Range<usize>> {
        self.window.as_ref().map(|w| w.range.clone())
    }

    /// Makes `active` resident: a window starting at its first element (so that advancing `t`
    /// finds the next elements already there), checked, then uploaded. Returns the number of
    /// elements uploaded.
    fn make_resident(&mut self, active: Range<usize>) -> Result<usize, SpacetimeError> {
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
        self.data.check(range.clone())?;
        let buffer = match self.window.take() {
            Some(w) if w.buffer.len() as usize == capacity => w.buffer,
            _ => {
                // New bindings for everything that reads the window.
                self.slice_sets = None;
                self.pipelines.clear();
                Buffer::new(
                    &self.gpu,
                    "spacetime records",
                    capacity.max(1) as u64,
                    vk::BufferUsageFlags::STORAGE_BUFFER,
                    MemoryKind::GpuOnly,
                )
                .map_err(dev("the resident window"))?
            }
        };
        buffer
            .upload(&self.gpu, 0, &self.data.records()[range.clone()])
            .map_err(dev("streaming elements"))?;
        let streamed = range.len();
        self.window = Some(Window { range, buffer });
        Ok(streamed)
    }

    fn slice_push(&self, t: f64, subdivide: Option<f64>, active: &Range<usize>) -> SlicePushCompute {
        let first = self.window.as_ref().map_or(0, |w| active.start - w.range.start);
        SlicePushCompute {
            first: first as u32,
            count: active.len() as u32,
            t: t as f32,
            max_area: subdivide.map_or(f32::INFINITY, |a| a as f32),
            max_level: if subdivide.is_some() { 6 } else { 0 },
            tri_capacity: self.tris.len() as u32,
            line_capacity: self.lines.len() as u32,
            cut_capacity: (self.cuts.len() / CUT_VEC4S) as u32,
        }
    }

    fn bind_slicer(&mut self) -> Result<(), SpacetimeError> {
        if self.slice_sets.is_some() {
            return Ok(());
        }
        let window = self.window.as_ref().expect("made resident before slicing");
        let b = |r: crate::gpu::GpuResult<crate::gpu::BufferBinding>| {
            r.map(Resource::Storage).map_err(dev("binding the slicer"))
        };
        let records = b(window.buffer.binding())?;
        let cuts = b(self.cuts.binding())?;
        let draws = b(self.draws.binding())?;
        let materials = b(self.materials.binding())?;
        let slice = self
            .slicer
            .bind(&self.gpu, &[records, cuts, b(self.lines.binding())?, draws, materials])
            .map_err(dev("binding the slicer"))?;
        let subdivide = self
            .subdivider
            .bind(&self.gpu, &[records, cuts, b(self.tris.binding())?, draws, materials])
            .map_err(dev("binding the slicer"))?;
        self.slice_sets = Some((slice, subdivide));
        Ok(())
    }

    /// Records the two slicing passes; `scope` wraps each in a profiler scope.
    fn record_slice(
        &self,
        cmd: vk::CommandBuffer,
        push: &SlicePushCompute,
        mut profiler: Option<&mut Profiler>,
    ) {
        let (slice_set, subdivide_set) = self.slice_sets.as_ref().expect("bound before recording");
        let reset: [u32; COUNTERS as usize] = [0, 1, 0, 0, 0, 1, 0, 0, 0, 0];
        let d = self.gpu.device();
        let rw = vk::AccessFlags::SHADER_READ | vk::AccessFlags::SHADER_WRITE;
        let cs = vk::PipelineStageFlags::COMPUTE_SHADER;
        let cut = || {
            // SAFETY: the buffer is alive and was created with TRANSFER_DST; 40 bytes.
            unsafe { d.cmd_update_buffer(cmd, self.draws.raw(), 0, bytemuck::cast_slice(&reset)) };
            self.gpu.memory_barrier(
                cmd,
                (vk::PipelineStageFlags::TRANSFER, vk::AccessFlags::TRANSFER_WRITE),
                (cs, rw),
            );
            let groups = self.gpu.caps().groups_1d(u64::from(push.count.max(1)), 64);
            self.slicer.record_dispatch(cmd, slice_set, bytemuck::bytes_of(push), [groups, 1, 1]);
            self.gpu.memory_barrier(cmd, (cs, vk::AccessFlags::SHADER_WRITE), (cs, rw));
        };
        match profiler.as_deref_mut() {
            Some(p) => p.scope(cmd, "slice", cut),
            None => cut(),
        }
        let subdivide = || {
            // A polygon is cut into at most two triangles.
            let groups = self.gpu.caps().groups_1d(u64::from(push.count.max(1)) * 2, 64);
            self.subdivider.record_dispatch(cmd, subdivide_set, bytemuck::bytes_of(push), [groups, 1, 1]);
            // Later commands and submissions draw from these buffers and read the counters.
            self.gpu.memory_barrier(
                cmd,
                (cs, vk::AccessFlags::SHADER_WRITE),
                (
                    vk::PipelineStageFlags::DRAW_INDIRECT
                        | vk::PipelineStageFlags::VERTEX_INPUT
                        | vk::PipelineStageFlags::TRANSFER,
                    vk::AccessFlags::INDIRECT_COMMAND_READ
                        | vk::AccessFlags::VERTEX_ATTRIBUTE_READ
                        | vk::AccessFlags::TRANSFER_READ,
                ),
            );
        };
        match profiler {
            Some(p) => p.scope(cmd, "subdivide", subdivide),
            None => subdivide(),
        }
    }

    /// Reads the counters of the last slice: `Ok(stats)`, or `Err(())` after growing the
    /// output buffers that overflowed (the slice must be redone).
    fn finish_slice(&mut self, active: usize, streamed: usize) -> Result<Option<SliceStats>, SpacetimeError> {
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
        self.sliced = None;
        let active = self.data.active_range(t);
        let streamed = self.make_resident(active.clone())?;
        loop {
            self.bind_slicer()?;
            let push = self.slice_push(t, subdivide, &active);
            self.gpu.run(|cmd| self.record_slice(cmd, &push, None)).map_err(dev("slicing"))?;
            if let Some(stats) = self.finish_slice(active.len(), streamed)? {
                self.sliced = Some((t, subdivide, stats));
                return Ok(stats);
            }
        }
    }

    fn pipelines_for(
        &mut self,
        target: &RenderTarget,
    ) -> Result<&(GraphicsPipeline, GraphicsPipeline, DescriptorSet, DescriptorSet), SpacetimeError> {
        let format = target.format();
        if !self.pipelines.contains_key(&format) {
            let window = self.window.as_ref().expect("made resident before drawing");
            let records = window.buffer.binding().map_err(dev("binding elements"))?;
            let materials = self.materials.binding().map_err(dev("binding materials"))?;
            let make = |lines: bool| -> Result<(GraphicsPipeline, DescriptorSet), SpacetimeError> {
                let mut desc = GraphicsPipelineDesc::new(
                    if lines { "spacetime slice edges" } else { "spacetime slice" },
                    shaders::spacetime::SLICE_VERT,
                    shaders::spacetime::SLICE_FRAG,
                    target.render_pass().raw(),
                );
                desc.bindings =
                    &[BindingKind::StorageBuffer, BindingKind::Texture, BindingKind::StorageBuffer];
                desc.push_constant_bytes = std::mem::size_of::<DrawPush>() as u32;
                desc.vertex_stride = std::mem::size_of::<SliceVertex>() as u32;
                desc.vertex_attributes = &[
                    (0, vk::Format::R32G32_SFLOAT, 0),
                    (1, vk::Format::R32_UINT, 8),
                    (2, vk::Format::R32_SFLOAT, 12),
                ];
                if lines {
                    desc.topology = vk::PrimitiveTopology::LINE_LIST;
                }
                let p =
                    GraphicsPipeline::new(&self.gpu, &desc).map_err(dev("building the slice pipelines"))?;
                let set = p
                    .bind(
                        &self.gpu,
                        &[Resource::Storage(records), self.colormap.resource(), Resource::Storage(materials)],
                    )
                    .map_err(dev("binding the slice pipelines"))?;
                Ok((p, set))
            };
            let (fill, fill_set) = make(false)?;
            let (edges, edges_set) = make(true)?;
            self.pipelines.insert(format, (fill, edges, fill_set, edges_set));
        }
        Ok(&self.pipelines[&format])
    }

    /// The colour ramp's `U_max` for `view`: its own, or the largest U over the slice's
    /// pixels, from a data pass of the same view into a float target kept for the next frame
    /// of the same size, reduced on the device (on the host when the image exceeds one storage
    /// binding).
    fn resolve_u_max(&mut self, target: &RenderTarget, view: &SpacetimeView) -> Result<f64, SpacetimeError> {
        match view.u_max {
            Some(u) => Ok(u),
            None if target.format() == ColorFormat::Rgba32F => Ok(1.0),
            None => {
                let extent = target.extent();
                let data = match self.umax_target.take() {
                    Some(d) if d.extent() == extent => d,
                    _ => RenderTarget::new(
                        &self.gpu,
                        "spacetime U_max pass",
                        extent.width,
                        extent.height,
                        ColorFormat::Rgba32F,
                    )
                    .map_err(dev("the U_max pass"))?,
                };
                let data_view = SpacetimeView { u_max: Some(1.0), ..*view };
                self.slice(view.time, view.subdivide)?;
                let u_max = if data.readback_bytes() <= self.gpu.max_binding_bytes() {
                    self.data_pass_max_u(&data, &data_view)
                } else {
                    // Larger than one binding: read the pixels back and take the maximum here.
                    match self.render(&data, &data_view) {
                        Ok(Pixels::Rgba32F(v)) => Ok(v
                            .chunks_exact(4)
                            .map(|p| f64::from(p[0]))
                            .filter(|u| u.is_finite())
                            .fold(0.0, f64::max)),
                        Ok(Pixels::Rgba8(_)) => unreachable!("a float target"),
                        Err(e) => Err(e),
                    }
                };
                self.umax_target = Some(data);
                u_max
            }
        }
    }

    /// Draws the data pass of `view` into the float target `data` and reduces its U channel to
    /// the maximum on the device (`max_u.comp`); reads back 4 bytes.
    fn data_pass_max_u(&mut self, data: &RenderTarget, view: &SpacetimeView) -> Result<f64, SpacetimeError> {
        let pixels = (data.extent().width as u64) * (data.extent().height as u64);
        if self.umax_pixels.as_ref().is_none_or(|b| b.len() != pixels) {
            self.umax_pixels = Some(
                Buffer::new(
                    &self.gpu,
                    "U_max pixels",
                    pixels,
                    vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                    MemoryKind::GpuOnly,
                )
                .map_err(dev("the U_max pass"))?,
            );
            self.umax_set = None;
        }
        if self.umax_set.is_none() {
            let pix =
                self.umax_pixels.as_ref().expect("made above").binding().map_err(dev("the U_max pass"))?;
            let res = self.umax_result.binding().map_err(dev("the U_max pass"))?;
            self.umax_set = Some(
                self.umax_reducer
                    .bind(&self.gpu, &[Resource::Storage(pix), Resource::Storage(res)])
                    .map_err(dev("the U_max pass"))?,
            );
        }
        let push = self.draw_push(data, view, 1.0);
        let gpu = self.gpu.clone();
        self.pipelines_for(data)?;
        let draw = self.draw_commands(data, view, &push);
        let pix = self.umax_pixels.as_ref().expect("made above");
        let (reducer, set, result) =
            (&self.umax_reducer, self.umax_set.as_ref().expect("bound above"), &self.umax_result);
        gpu.run(|cmd| {
            data.record_begin(cmd, [f32::NAN; 4]);
            draw(cmd);
            data.record_end(cmd);
            data.record_readback(&gpu, cmd, pix.raw());
            result.record_fill(cmd, 0);
            let cs = vk::PipelineStageFlags::COMPUTE_SHADER;
            gpu.memory_barrier(
                cmd,
                (vk::PipelineStageFlags::TRANSFER, vk::AccessFlags::TRANSFER_WRITE),
                (cs, vk::AccessFlags::SHADER_READ | vk::AccessFlags::SHADER_WRITE),
            );
            let n = pixels as u32;
            reducer.record_dispatch(cmd, set, &n.to_ne_bytes(), [64, 1, 1]);
            gpu.memory_barrier(
                cmd,
                (cs, vk::AccessFlags::SHADER_WRITE),
                (vk::PipelineStageFlags::TRANSFER, vk::AccessFlags::TRANSFER_READ),
            );
        })
        .map_err(dev("the U_max pass"))?;
        let bits = self.umax_result.download(&self.gpu).map_err(dev("reading U_max"))?;
        Ok(f64::from(f32::from_bits(bits[0])))
    }

    fn draw_push(&self, target: &RenderTarget, view: &SpacetimeView, u_max: f64) -> DrawPush {
        let height_scale = view.height_scale.unwrap_or_else(|| self.default_height_scale());
        let eye = view.camera.eye.map(|x| x as f32);
        DrawPush {
            view_proj: view.camera.view_proj_f32(target.aspect()).to_cols_array(),
            eye_t: [eye[0], eye[1], eye[2], view.time as f32],
            light_scale: [LIGHT[0] as f32, LIGHT[1] as f32, LIGHT[2] as f32, height_scale as f32],
            ramp: [u_max as f32, self.colormap.texels() as f32, 0.0, 0.0],
            flags: [
                u32::from(target.format() == ColorFormat::Rgba32F),
                u32::from(view.height),
                u32::from(view.per_vertex),
                0,
            ],
        }
    }

    /// Records the render pass of the current slice into `target`.
    fn record_draw(
        &mut self,
        target: &RenderTarget,
        view: &SpacetimeView,
        push: &DrawPush,
    ) -> Result<impl FnOnce(vk::CommandBuffer) + '_, SpacetimeError> {
        self.pipelines_for(target)?;
        Ok(self.draw_commands(target, view, push))
    }

    /// The draws of the current slice (polygons, then edges if on) for a target whose pipelines
    /// exist ([`Self::pipelines_for`]).
    fn draw_commands(
        &self,
        target: &RenderTarget,
        view: &SpacetimeView,
        push: &DrawPush,
    ) -> impl FnOnce(vk::CommandBuffer) + '_ {
        let (tris, lines, draws) = (self.tris.raw(), self.lines.raw(), self.draws.raw());
        let extent = target.extent();
        let edges_on = view.edges;
        let (push, edge_push) = (*push, push.for_edges());
        let (fill, edges, fill_set, edges_set) = &self.pipelines[&target.format()];
        move |cmd| {
            fill.record_draw_indirect(
                cmd,
                extent,
                fill_set,
                bytemuck::bytes_of(&push),
                Some(tris),
                (draws, 0),
            );
            if edges_on {
                let bytes = bytemuck::bytes_of(&edge_push);
                edges.record_draw_indirect(cmd, extent, edges_set, bytes, Some(lines), (draws, 16));
            }
        }
    }

    /// The colour ramp's `U_max` for `view` in a colour `target`: the view's own, or the
    /// largest U over the slice's pixels (a data pass at the target's size). For callers that
    /// fix the ramp once, e.g. while animating t.
    pub fn u_max_for(&mut self, target: &RenderTarget, view: &SpacetimeView) -> Result<f64, SpacetimeError> {
        self.slice(view.time, view.subdivide)?;
        self.resolve_u_max(target, view)
    }

    /// Records the draw of the current slice (see [`Self::slice`]; slice at `view.time` first)
    /// into `target`'s render pass, begun and ended by the caller — for applications and the
    /// viewer that own the frame's command buffer.
    pub fn record_draw_into(
        &mut self,
        cmd: vk::CommandBuffer,
        target: &RenderTarget,
        view: &SpacetimeView,
        u_max: f64,
    ) -> Result<(), SpacetimeError> {
        let push = self.draw_push(target, view, u_max);
        let draw = self.record_draw(target, view, &push)?;
        draw(cmd);
        Ok(())
    }

    /// Renders `view` into `target` (slicing first if needed) and returns the pixels: lit
    /// colours in an RGBA8 target, `(U, |v|, n_x, n_y)` in an RGBA32F target.
    pub fn render(&mut self, target: &RenderTarget, view: &SpacetimeView) -> Result<Pixels, SpacetimeError> {
        self.slice(view.time, view.subdivide)?;
        let u_max = self.resolve_u_max(target, view)?;
        let push = self.draw_push(target, view, u_max);
        let gpu = self.gpu.clone();
        let draw = self.record_draw(target, view, &push)?;
        target.render(&gpu, clear_colour(target), draw).map_err(dev("drawing the slice"))
    }

    /// One frame as an interactive loop runs it: the slice (always redone, as when `t`
    /// advances) and the draw in one submission, without reading the image back; with a
    /// `profiler` (4 scopes), each stage's device time. `view.u_max` should be set (else a data
    /// pass runs first, as in [`Self::render`]).
    pub fn frame(
        &mut self,
        target: &RenderTarget,
        view: &SpacetimeView,
        mut profiler: Option<&mut Profiler>,
    ) -> Result<(SliceStats, Option<FrameTimes>), SpacetimeError> {
        let u_max = self.resolve_u_max(target, view)?;
        self.sliced = None;
        let active = self.data.active_range(view.time);
        let streamed = self.make_resident(active.clone())?;
        let push = self.draw_push(target, view, u_max);
        let gpu = self.gpu.clone();
        loop {
            self.bind_slicer()?;
            self.pipelines_for(target)?;
            let slice_push = self.slice_push(view.time, view.subdivide, &active);
            let clear = clear_colour(target);
            {
                let mut profiler = profiler.as_deref_mut();
                let slicer = &*self;
                let commands = slicer.draw_commands(target, view, &push);
                gpu.run(|cmd| {
                    if let Some(p) = profiler.as_deref_mut() {
                        p.record_reset(cmd);
                    }
                    slicer.record_slice(cmd, &slice_push, profiler.as_deref_mut());
                    let draw = || {
                        target.record_begin(cmd, clear);
                        commands(cmd);
                        target.record_end(cmd);
                    };
                    match profiler {
                        Some(p) => p.scope(cmd, "draw", draw),
                        None => draw(),
                    }
                })
                .map_err(dev("drawing a frame"))?;
            }
            if let Some(stats) = self.finish_slice(active.len(), streamed)? {
                self.sliced = Some((view.time, view.subdivide, stats));
                let times = match profiler {
                    Some(p) => {
                        let r = p.results().map_err(dev("reading timestamps"))?;
                        let get = |name: &str| r.iter().find(|(n, _)| n == name).map_or(0.0, |(_, ms)| *ms);
                        Some(FrameTimes {
                            slice_ms: get("slice"),
                            subdivide_ms: get("subdivide"),
                            draw_ms: get("draw"),
                        })
                    }
                    None => None,
                };
                return Ok((stats, times));
            }
        }
    }

    /// The triangles of the current slice, read back: (element of the data, corners). For
    /// tests and inspection.
    pub fn slice_triangles(&self) -> Result<Vec<SliceTriangle>, SpacetimeError> {
        let Some((_, _, stats)) = self.sliced else { return Ok(Vec::new()) };
        let base = self.window.as_ref().map_or(0, |w| w.range.start) as u32;
        let mut v = vec![SliceVertex::zeroed(); 3 * stats.triangles];
        self.tris.download_into(&self.gpu, 0, &mut v).map_err(dev("reading the slice"))?;
        Ok(v.chunks_exact(3).map(|t| (base + t[0].element, [t[0].xy, t[1].xy, t[2].xy])).collect())
    }

    /// The edge lines of the current slice, read back: (element of the data, endpoints).
    pub fn slice_lines(&self) -> Result<Vec<SliceLine>, SpacetimeError> {
        let Some((_, _, stats)) = self.sliced else { return Ok(Vec::new()) };
        let base = self.window.as_ref().map_or(0, |w| w.range.start) as u32;
        let mut v = vec![SliceVertex::zeroed(); 2 * stats.lines];
        self.lines.download_into(&self.gpu, 0, &mut v).map_err(dev("reading the slice"))?;
        Ok(v.chunks_exact(2).map(|l| (base + l[0].element, [l[0].xy, l[1].xy])).collect())
    }
}

/// Data targets clear to NaN ("no surface here", distinct from any value), colour targets to
/// the engine's opaque background.
fn clear_colour(target: &RenderTarget) -> [f32; 4] {
    if target.format() == ColorFormat::Rgba32F {
        [f32::NAN; 4]
    } else {
        BACKGROUND
    }
}
