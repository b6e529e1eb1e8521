//! The spacetime renderer (seed 003 §4): the mesh resident on the device, a compute pass that
//! slices it at time `t` (`shaders-glsl/spacetime/slice.comp`), and graphics pipelines that
//! draw the slice with per-vertex height and per-pixel strain energy density, exact normals
//! and Phong lighting (`slice.vert`, `slice.frag`), then overdraw every polygon edge as a line
//! to fill cracks between discontinuous neighbours (§4.3).
//!
//! The edge lines are drawn with a depth bias that puts them *behind* the polygons: where a
//! polygon covers a pixel it wins and the pixel shows the polygon's value at the pixel centre;
//! a line only shows where no polygon covered the pixel — a crack.

use std::collections::HashMap;

use ash::vk;
use bytemuck::{Pod, Zeroable};

use super::error::SpacetimeError;
use super::mesh::{active_range, SpacetimeMesh};
use crate::gpu::{
    shaders, BindingKind, Buffer, ComputePipeline, ComputePipelineDesc, DescriptorSet, Gpu, GpuError,
    GraphicsPipeline, GraphicsPipelineDesc, MemoryKind, Resource,
};
use crate::render::{Camera, ColorFormat, Colormap, ColormapTexture, Pixels, RenderTarget, BACKGROUND};

/// One element as the shaders read it (`SpacetimeElement` in `include/spacetime_cubic.glsl`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct GpuElement {
    /// Frame centre (x, y, t) and λ.
    pub centre_lambda: [f32; 4],
    /// Frame extents (w_x, w_y, w_t) and μ.
    pub extent_mu: [f32; 4],
    /// The 20 displacement coefficients.
    pub coefficients: [[f32; 2]; 20],
}

impl GpuElement {
    /// Element `e` of `mesh`.
    pub fn of(mesh: &SpacetimeMesh, e: usize) -> Self {
        let f = &mesh.fields[e];
        let m = mesh.materials[f.material as usize];
        let c = f.frame.centre.map(|x| x as f32);
        let w = f.frame.extent.map(|x| x as f32);
        Self {
            centre_lambda: [c[0], c[1], c[2], m.lambda as f32],
            extent_mu: [w[0], w[1], w[2], m.mu as f32],
            coefficients: f.coefficients.map(|v| v.map(|x| x as f32)),
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct SliceVertex {
    xy: [f32; 2],
    element: u32,
    pad: f32,
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
    pad: u32,
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
    /// Height on, edges on, no subdivision, automatic scales, looking at `mesh` from above
    /// and in front.
    pub fn looking_at(mesh: &SpacetimeMesh, time: f64) -> Self {
        let (lo, hi) = mesh.space_bounds();
        let centre = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
        let size = (hi[0] - lo[0]).max(hi[1] - lo[1]);
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

    /// Looking straight down at `mesh` so that it fills the image (height off): every pixel
    /// centre sees the point (x, y) of the slice plane, as the pixel-exactness tests want.
    pub fn from_above(mesh: &SpacetimeMesh, time: f64) -> Self {
        let (lo, hi) = mesh.space_bounds();
        let centre = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
        let size = (hi[0] - lo[0]).max(hi[1] - lo[1]);
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
            ..Self::looking_at(mesh, time)
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
}

/// Direction to the light (unit), from the upper left front.
const LIGHT: [f64; 3] = [-0.408_248_290_463_863, -0.408_248_290_463_863, 0.816_496_580_927_726];

/// The resident mesh, its slice and the pipelines.
pub struct SpacetimeRenderer {
    gpu: Gpu,
    mesh_lowest: Vec<f64>,
    longest: f64,
    default_height_scale: f64,
    vertices: Buffer<[f32; 4]>,
    tets: Buffer<[u32; 4]>,
    elements: Buffer<GpuElement>,
    tris: Buffer<SliceVertex>,
    lines: Buffer<SliceVertex>,
    draws: Buffer<u32>,
    slicer: ComputePipeline,
    colormap: ColormapTexture,
    pipelines: HashMap<ColorFormat, (GraphicsPipeline, GraphicsPipeline, DescriptorSet, DescriptorSet)>,
    sliced: Option<(f64, Option<f64>, SliceStats)>,
    /// The slicer's bindings, kept until the output buffers grow.
    slice_set: Option<DescriptorSet>,
    /// The float target of the automatic-U_max data pass, reused while the size stays.
    umax_target: Option<RenderTarget>,
}

/// A slice output buffer: vertices written by the slicer, read by the draws.
fn slice_buffer(gpu: &Gpu, name: &str, len: u64) -> Result<Buffer<SliceVertex>, SpacetimeError> {
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::VERTEX_BUFFER;
    Buffer::new(gpu, name, len, usage, MemoryKind::GpuOnly).map_err(dev("slice buffers"))
}

fn dev(context: &str) -> impl FnOnce(GpuError) -> SpacetimeError + '_ {
    move |source| SpacetimeError::Device { context: context.to_string(), source }
}

impl SpacetimeRenderer {
    /// Validates `mesh` (it must be sorted by lowest time, see
    /// [`SpacetimeMesh::sort_by_lowest_time`]) and makes it resident on `gpu`.
    pub fn new(gpu: &Gpu, mesh: &SpacetimeMesh, colormap: &Colormap) -> Result<Self, SpacetimeError> {
        mesh.validate()?;
        let mesh_lowest = mesh.lowest_times();
        if let Some(e) = mesh_lowest.windows(2).position(|w| w[1] < w[0]) {
            return Err(SpacetimeError::Invalid {
                element: e + 1,
                what: "elements are not sorted by lowest time (SpacetimeMesh::sort_by_lowest_time)".into(),
            });
        }
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let verts: Vec<[f32; 4]> =
            mesh.vertices.iter().map(|p| [p[0] as f32, p[1] as f32, p[2] as f32, 0.0]).collect();
        let elements: Vec<GpuElement> = (0..mesh.tets.len()).map(|e| GpuElement::of(mesh, e)).collect();
        let vertices = Buffer::from_slice(gpu, "spacetime vertices", &verts, storage)
            .map_err(dev("uploading vertices"))?;
        let tets = Buffer::from_slice(gpu, "spacetime tetrahedra", &mesh.tets, storage)
            .map_err(dev("uploading tetrahedra"))?;
        let elements_buf = Buffer::from_slice(gpu, "spacetime elements", &elements, storage)
            .map_err(dev("uploading elements"))?;
        let tris = slice_buffer(gpu, "slice triangles", 3 * 1024)?;
        let lines = slice_buffer(gpu, "slice edges", 8 * 1024)?;
        let draws = Buffer::new(
            gpu,
            "slice draws",
            9,
            storage | vk::BufferUsageFlags::INDIRECT_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryKind::GpuOnly,
        )
        .map_err(dev("slice buffers"))?;
        let slicer = ComputePipeline::new(
            gpu,
            &ComputePipelineDesc {
                name: "spacetime slice",
                spirv: shaders::spacetime::SLICE,
                bindings: &[BindingKind::StorageBuffer; 5],
                push_constant_bytes: std::mem::size_of::<SlicePushCompute>() as u32,
                specialization: &[],
                shared_bytes: 0,
            },
        )
        .map_err(dev("building the slicer"))?;
        // Height scale: a tenth of the domain per the largest |v| at the element centroids.
        let (lo, hi) = mesh.space_bounds();
        let size = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        let max_speed = (0..mesh.tets.len())
            .map(|e| {
                let c = mesh.corners(e);
                let x: [f64; 3] = std::array::from_fn(|k| 0.25 * (c[0][k] + c[1][k] + c[2][k] + c[3][k]));
                let f = &mesh.fields[e];
                super::cubic::evaluate(&f.frame, &mesh.materials[f.material as usize], &f.coefficients, x)
                    .speed
            })
            .fold(0.0, f64::max);
        let default_height_scale = if max_speed > 0.0 { 0.1 * size / max_speed } else { 1.0 };
        Ok(Self {
            gpu: gpu.clone(),
            longest: mesh.longest_duration(),
            mesh_lowest,
            default_height_scale,
            vertices,
            tets,
            elements: elements_buf,
            tris,
            lines,
            draws,
            slicer,
            colormap: colormap.upload(gpu).map_err(dev("uploading the colour map"))?,
            pipelines: HashMap::new(),
            sliced: None,
            slice_set: None,
            umax_target: None,
        })
    }

    /// The height scale used when a view does not set one.
    pub fn default_height_scale(&self) -> f64 {
        self.default_height_scale
    }

    /// Slices the mesh at `t` on the device (a no-op if the last slice had the same `t` and
    /// subdivision). Output buffers grow when a slice needs more room, and the slice is redone.
    pub fn slice(&mut self, t: f64, subdivide: Option<f64>) -> Result<SliceStats, SpacetimeError> {
        if let Some((st, sd, stats)) = self.sliced {
            if st == t && sd == subdivide {
                return Ok(stats);
            }
        }
        let range = active_range(&self.mesh_lowest, t, self.longest);
        loop {
            if self.slice_set.is_none() {
                let bindings = [
                    self.vertices.binding(),
                    self.tets.binding(),
                    self.tris.binding(),
                    self.lines.binding(),
                    self.draws.binding(),
                ]
                .into_iter()
                .map(|b| b.map(Resource::Storage))
                .collect::<Result<Vec<_>, _>>()
                .map_err(dev("binding the slicer"))?;
                self.slice_set =
                    Some(self.slicer.bind(&self.gpu, &bindings).map_err(dev("binding the slicer"))?);
            }
            let set = self.slice_set.as_ref().expect("bound above");
            let push = SlicePushCompute {
                first: range.start as u32,
                count: range.len() as u32,
                t: t as f32,
                max_area: subdivide.map_or(f32::INFINITY, |a| a as f32),
                max_level: if subdivide.is_some() { 6 } else { 0 },
                tri_capacity: self.tris.len() as u32,
                line_capacity: self.lines.len() as u32,
                pad: 0,
            };
            let reset: [u32; 9] = [0, 1, 0, 0, 0, 1, 0, 0, 0];
            let groups = self.gpu.caps().groups_1d(range.len().max(1) as u64, 64);
            self.gpu
                .run(|cmd| {
                    let d = self.gpu.device();
                    // SAFETY: the buffer is alive and was created with TRANSFER_DST; 36 bytes.
                    unsafe { d.cmd_update_buffer(cmd, self.draws.raw(), 0, bytemuck::cast_slice(&reset)) };
                    self.gpu.memory_barrier(
                        cmd,
                        (vk::PipelineStageFlags::TRANSFER, vk::AccessFlags::TRANSFER_WRITE),
                        (
                            vk::PipelineStageFlags::COMPUTE_SHADER,
                            vk::AccessFlags::SHADER_READ | vk::AccessFlags::SHADER_WRITE,
                        ),
                    );
                    self.slicer.record_dispatch(cmd, set, bytemuck::bytes_of(&push), [groups, 1, 1]);
                    // Later submissions draw from these buffers: the barrier's second scope covers
                    // them (submission order).
                    self.gpu.memory_barrier(
                        cmd,
                        (vk::PipelineStageFlags::COMPUTE_SHADER, vk::AccessFlags::SHADER_WRITE),
                        (
                            vk::PipelineStageFlags::DRAW_INDIRECT
                                | vk::PipelineStageFlags::VERTEX_INPUT
                                | vk::PipelineStageFlags::TRANSFER,
                            vk::AccessFlags::INDIRECT_COMMAND_READ
                                | vk::AccessFlags::VERTEX_ATTRIBUTE_READ
                                | vk::AccessFlags::TRANSFER_READ,
                        ),
                    );
                })
                .map_err(dev("slicing"))?;
            let counts = self.draws.download(&self.gpu).map_err(dev("reading the slice size"))?;
            if counts[8] == 0 {
                let stats = SliceStats {
                    active: range.len(),
                    triangles: counts[0] as usize / 3,
                    lines: counts[4] as usize / 2,
                };
                self.sliced = Some((t, subdivide, stats));
                return Ok(stats);
            }
            // The counters hold what was asked for: grow to that (and a margin) and redo.
            let grow = |n: u32, cur: u64| u64::from(n).max(cur) + u64::from(n) / 4 + 64;
            self.slice_set = None;
            self.tris = slice_buffer(&self.gpu, "slice triangles", grow(counts[0], self.tris.len()))?;
            self.lines = slice_buffer(&self.gpu, "slice edges", grow(counts[4], self.lines.len()))?;
        }
    }

    fn pipelines_for(
        &mut self,
        target: &RenderTarget,
    ) -> Result<&(GraphicsPipeline, GraphicsPipeline, DescriptorSet, DescriptorSet), SpacetimeError> {
        let format = target.format();
        if !self.pipelines.contains_key(&format) {
            let make = |lines: bool| -> Result<(GraphicsPipeline, DescriptorSet), SpacetimeError> {
                let mut desc = GraphicsPipelineDesc::new(
                    if lines { "spacetime slice edges" } else { "spacetime slice" },
                    shaders::spacetime::SLICE_VERT,
                    shaders::spacetime::SLICE_FRAG,
                    target.render_pass().raw(),
                );
                desc.bindings = &[BindingKind::StorageBuffer, BindingKind::Texture];
                desc.push_constant_bytes = std::mem::size_of::<DrawPush>() as u32;
                desc.vertex_stride = std::mem::size_of::<SliceVertex>() as u32;
                desc.vertex_attributes = &[(0, vk::Format::R32G32_SFLOAT, 0), (1, vk::Format::R32_UINT, 8)];
                if lines {
                    desc.topology = vk::PrimitiveTopology::LINE_LIST;
                    // Behind the polygons: a line shows only where no polygon covered the pixel.
                    desc.depth_bias = Some((1000.0, 2.0));
                }
                let p =
                    GraphicsPipeline::new(&self.gpu, &desc).map_err(dev("building the slice pipelines"))?;
                let set = p
                    .bind(
                        &self.gpu,
                        &[
                            Resource::Storage(self.elements.binding().map_err(dev("binding elements"))?),
                            self.colormap.resource(),
                        ],
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

    /// Renders `view` into `target` (slicing first if needed) and returns the pixels: lit
    /// colours in an RGBA8 target, `(U, |v|, n_x, n_y)` in an RGBA32F target.
    pub fn render(&mut self, target: &RenderTarget, view: &SpacetimeView) -> Result<Pixels, SpacetimeError> {
        self.slice(view.time, view.subdivide)?;
        let u_max = match view.u_max {
            Some(u) => u,
            None if target.format() == ColorFormat::Rgba32F => 1.0,
            None => {
                // The largest U over the slice's pixels, from a data pass of the same view into a
                // float target kept for the next frame of the same size.
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
                let pixels = self.render(&data, &SpacetimeView { u_max: Some(1.0), ..*view });
                self.umax_target = Some(data);
                match pixels? {
                    Pixels::Rgba32F(v) => v
                        .chunks_exact(4)
                        .map(|p| f64::from(p[0]))
                        .filter(|u| u.is_finite())
                        .fold(0.0, f64::max),
                    Pixels::Rgba8(_) => unreachable!("a float target"),
                }
            }
        };
        let extent = target.extent();
        let aspect = target.aspect();
        let height_scale = view.height_scale.unwrap_or(self.default_height_scale);
        let push = DrawPush {
            view_proj: view.camera.view_proj_f32(aspect).to_cols_array(),
            eye_t: [
                view.camera.eye[0] as f32,
                view.camera.eye[1] as f32,
                view.camera.eye[2] as f32,
                view.time as f32,
            ],
            light_scale: [LIGHT[0] as f32, LIGHT[1] as f32, LIGHT[2] as f32, height_scale as f32],
            ramp: [u_max as f32, self.colormap_texels() as f32, 0.0, 0.0],
            flags: [
                u32::from(target.format() == ColorFormat::Rgba32F),
                u32::from(view.height),
                u32::from(view.per_vertex),
                0,
            ],
        };
        let (tris, lines, draws) = (self.tris.raw(), self.lines.raw(), self.draws.raw());
        // Data targets clear to NaN ("no surface here", distinct from any value), colour
        // targets to the engine's opaque background.
        let clear = if target.format() == ColorFormat::Rgba32F { [f32::NAN; 4] } else { BACKGROUND };
        let gpu = self.gpu.clone();
        let (fill, edges, fill_set, edges_set) = self.pipelines_for(target)?;
        target
            .render(&gpu, clear, |cmd| {
                let bytes = bytemuck::bytes_of(&push);
                fill.record_draw_indirect(cmd, extent, fill_set, bytes, Some(tris), (draws, 0));
                if view.edges {
                    edges.record_draw_indirect(cmd, extent, edges_set, bytes, Some(lines), (draws, 16));
                }
            })
            .map_err(dev("drawing the slice"))
    }

    /// The triangles of the current slice, read back: (element, corners). For tests and
    /// inspection.
    pub fn slice_triangles(&self) -> Result<Vec<SliceTriangle>, SpacetimeError> {
        let Some((_, _, stats)) = self.sliced else { return Ok(Vec::new()) };
        let mut v = vec![SliceVertex::zeroed(); 3 * stats.triangles];
        self.tris.download_into(&self.gpu, 0, &mut v).map_err(dev("reading the slice"))?;
        Ok(v.chunks_exact(3).map(|t| (t[0].element, [t[0].xy, t[1].xy, t[2].xy])).collect())
    }

    /// The edge lines of the current slice, read back: (element, endpoints).
    pub fn slice_lines(&self) -> Result<Vec<SliceLine>, SpacetimeError> {
        let Some((_, _, stats)) = self.sliced else { return Ok(Vec::new()) };
        let mut v = vec![SliceVertex::zeroed(); 2 * stats.lines];
        self.lines.download_into(&self.gpu, 0, &mut v).map_err(dev("reading the slice"))?;
        Ok(v.chunks_exact(2).map(|l| (l[0].element, [l[0].xy, l[1].xy])).collect())
    }

    fn colormap_texels(&self) -> u32 {
        self.colormap.texels()
    }
}
