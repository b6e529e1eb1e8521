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
use crate::gpu::PassKey;
use crate::gpu::{
    BindingKind, Buffer, ComputePipeline, ComputePipelineDesc, DescriptorSet, Gpu, GpuError,
    GraphicsPipeline, GraphicsPipelineDesc, MemoryKind, Profiler, Resource,
};
use crate::render::{
    Camera, ColorFormat, Colormap, ColormapTexture, DrawTarget, Pixels, RenderTarget, BACKGROUND,
};

mod derived;
mod draw;
mod slicing;

pub use draw::SpacetimeDraw;
pub use slicing::SlicePlan;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct SliceVertex {
    xy: [f32; 2],
    element: u32,
    speed: f32,
}

crate::push_constants! {
    #[derive(Debug)]
    struct SlicePushCompute {
        /// Ring slot of the first active element.
        first: u32,
        count: u32,
        t: f32,
        max_area: f32,
        max_level: u32,
        tri_capacity: u32,
        line_capacity: u32,
        cut_capacity: u32,
        /// Records in the window's ring.
        capacity: u32,
    }
}

crate::push_constants! {
    /// `max_u.comp`: the pixels to reduce.
    struct MaxUPush {
        n: u32,
    }
}

crate::push_constants! {
    struct DrawPush {
        view_proj: [f32; 16],
        eye_t: [f32; 4],
        light_scale: [f32; 4],
        ramp: [f32; 4],
        flags: [u32; 4],
    }
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
    /// Every covered pixel in one constant colour, nothing evaluated per pixel: the cost floor
    /// of the draw (the rasteriser's own time for these primitives), for benchmarks. A colour
    /// target only; ignored by data (RGBA32F) targets.
    pub unshaded: bool,
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
            unshaded: false,
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

    /// The camera looking at the data set from `orbit`: at its box — the slice's spatial extent,
    /// and heights up to a quarter of its size when the height field is on.
    pub fn orbit(&self, data: &DataSummary, orbit: crate::render::Orbit) -> Camera {
        let (lo, hi) = self.shown_box(data);
        orbit.camera(lo, hi)
    }

    /// The box this view shows of `data`: its spatial extent in x and y, and in z from the
    /// slice plane up to the height field's top (a quarter of the data set's size) when the
    /// height is on.
    pub fn shown_box(&self, data: &DataSummary) -> ([f64; 3], [f64; 3]) {
        let top = if self.height { 0.25 * data.size() } else { 0.0 };
        ([data.space_lo[0], data.space_lo[1], 0.0], [data.space_hi[0], data.space_hi[1], top])
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

/// Elements of the data resident on the device: `range` of the sorted records, record `e` in
/// slot `e mod capacity` of the ring `buffer`.
struct Window {
    range: Range<usize>,
    buffer: Buffer<ElementRecord>,
    /// Per slot, the element's cubic restricted to the current slice's time (written by the
    /// cut pass for the cut elements; `SpacetimeSliceCubic`, 160 bytes).
    cubics: Buffer<[[f32; 4]; 10]>,
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
    /// Fill and edge pipelines per render pass class.
    pipelines: HashMap<PassKey, (GraphicsPipeline, GraphicsPipeline)>,
    /// Their bindings, dropped when the window is reallocated.
    draw_sets: HashMap<PassKey, (DescriptorSet, DescriptorSet)>,
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
    /// A derived field shown instead of U (`--expr`), its fixed colour range if given, and its
    /// compiled slice shader.
    derived: Option<(crate::spacetime::picture::Derived, Vec<u32>)>,
    /// The low end of the derived field's colour range used by the next draw (the high end
    /// travels as U_max does).
    derived_lo: f64,
}

/// A slice output buffer: vertices written by the slicer, read by the draws.
fn slice_buffer(gpu: &Gpu, name: &str, len: u64) -> Result<Buffer<SliceVertex>, SpacetimeError> {
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::VERTEX_BUFFER;
    Buffer::new(gpu, name, len, usage, MemoryKind::GpuOnly).map_err(dev("slice buffers"))
}

/// A device failure met while doing `context` ([`SpacetimeError::device`]).
fn dev(context: &str) -> impl FnOnce(GpuError) -> SpacetimeError + '_ {
    SpacetimeError::device(context)
}

fn compute(gpu: &Gpu, name: &'static str, spirv: &'static [u32]) -> Result<ComputePipeline, SpacetimeError> {
    ComputePipeline::new(
        gpu,
        &ComputePipelineDesc {
            name,
            spirv,
            bindings: &[BindingKind::StorageBuffer; 6],
            push: crate::gpu::PushLayout::of::<SlicePushCompute>(),
            specialization: &[],
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
            slicer: compute(gpu, "spacetime slice", crate::spacetime::shaders::SLICE)?,
            subdivider: compute(gpu, "spacetime subdivide", crate::spacetime::shaders::SUBDIVIDE)?,
            colormap: colormap.upload(gpu).map_err(dev("uploading the colour map"))?,
            pipelines: HashMap::new(),
            draw_sets: HashMap::new(),
            sliced: None,
            slice_sets: None,
            umax_target: None,
            max_window: usize::MAX,
            umax_reducer: ComputePipeline::new(
                gpu,
                &ComputePipelineDesc {
                    name: "spacetime U_max",
                    spirv: crate::spacetime::shaders::MAX_U,
                    bindings: &[BindingKind::StorageBuffer; 2],
                    push: crate::gpu::PushLayout::of::<MaxUPush>(),
                    specialization: &[],
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
            derived: None,
            derived_lo: 0.0,
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
