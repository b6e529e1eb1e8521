//! The spectral-element renderer (seed 002, done per fragment in a Vulkan graphics pipeline):
//! the element geometry, the shown field's coefficients and the two 1D bases resident on the
//! device, and
//!
//! - **planar meshes**: proxies drawn with `element.vert`/`element.frag`, whose fragment stage
//!   inverts the geometry map at the pixel centre by Newton's method and evaluates the
//!   tensor-product polynomial there (pixel-exact), in a 2D view ([`View2d`]);
//! - **surfaces in 3D** (the seed's artery and coil): each element tessellated by a compute pass
//!   (`tessellate.comp`) to an L × L grid chosen per element and frame so that every
//!   tessellated point lies within [`SpectralView::max_error_px`] pixels (default ½) of the true
//!   surface on screen (tessellation shaders did the same but ran 20× slower at level 12 on
//!   lavapipe); each fragment evaluates the field at its interpolated reference point and
//!   lights it with the geometry map's exact normal there. The shown value is therefore the
//!   polynomial at a surface point whose image is within that budget of the pixel centre (the
//!   level is capped at [`MAX_TESSELLATION`]: elements that would need more, e.g. cut by the near
//!   plane, get the cap and a larger error);
//! - the per-vertex baseline; element edges drawn as lines — behind the faces as edge overdraw
//!   (a crack between discontinuous neighbours shows the edge's own value, never the
//!   background), or in front, dark, to show the mesh.
//!
//! Memory does not grow with the order beyond the coefficient buffer: the bases are
//! specialization constants of the pipelines and the draw streams depend on the geometry's order
//! only.

use std::collections::HashMap;
use std::sync::Arc;

use ash::vk;
use bytemuck::Zeroable;
use glam::Mat4;

use super::error::SpectralError;
use super::mesh::SpectralMesh;
use super::proxy::{self, DrawVertex};
use crate::gpu::{
    Access, BindingKind, Buffer, ComputePipeline, ComputePipelineDesc, DescriptorSet, Gpu, GraphicsPipeline,
    GraphicsPipelineDesc, MemoryKind, PassKey, Profiler, Recorder, Resource,
};
use crate::render::{
    Camera, ColorFormat, Colormap, ColormapTexture, DrawTarget, Pixels, RenderTarget, BACKGROUND,
};

mod cut;
mod derived;
mod hull;
mod iso;
mod layout;
mod tessellate;
mod view;
mod volume;

pub use crate::render::camera_for_box;
pub use cut::{parse_plane, plane_span};
pub use hull::{element_hull_planes, HULL_PLANES};
pub use iso::{element_boxes, MAX_ISO_VALUES};
pub use layout::{basis_specialization, geometry_points, padded_slots, padded_values};
pub use tessellate::tessellated_vertices;
pub use view::{fit_camera, SpectralView, View2d};
pub use volume::{tile_bands, VOLUME_TILE};

/// How a spectral picture maps the world onto its pixels ([`SpectralRenderer::picture_view`]).
#[derive(Clone, Copy, Debug)]
pub enum PictureView {
    /// A planar mesh drawn flat: its 2D view.
    Plane(View2d),
    /// Surfaces, height fields, cut planes: the camera.
    Camera(crate::render::Camera),
}

type Result<T> = std::result::Result<T, SpectralError>;
fn dev(context: &str) -> impl Fn(crate::gpu::GpuError) -> SpectralError + '_ {
    SpectralError::device(context)
}

/// How far the reference point may lie outside [0, 1]² and still count as inside (then it is
/// clamped): f32 Newton converges to a few ulps of [0, 1] (≈ 1e-7), so 1e-5 accepts every pixel
/// of the element and at most a sliver of 1e-5 of an element's width beyond its true edge.
pub const INSIDE_TOLERANCE: f64 = 1e-5;

/// The largest tessellation level asked of the device (Vulkan guarantees at least 64).
pub const MAX_TESSELLATION: u32 = 64;

/// The most cut planes one view can have.
pub const MAX_CUT_PLANES: usize = 8;

/// The attributes of a [`DrawVertex`]: position, reference coordinates, element.
const DRAW_VERTEX_ATTRIBUTES: [crate::gpu::VertexAttribute; 3] =
    [(0, vk::Format::R32G32B32_SFLOAT, 0), (1, vk::Format::R32G32_SFLOAT, 12), (2, vk::Format::R32_UINT, 20)];

/// The four bindings of every spectral draw: geometry, coefficients, colour map, and the
/// patches (planar and surface meshes) or planes (cut planes).
const DRAW_BINDINGS: [BindingKind; 4] = [
    BindingKind::StorageBuffer,
    BindingKind::StorageBuffer,
    BindingKind::Texture,
    BindingKind::StorageBuffer,
];

crate::push_constants! {
    /// `spectral_push.glsl`.
    struct SpectralPush {
        view_proj: [f32; 16],
        pixel_to_world: [f32; 4],
        range: [f32; 4],
        misc: [f32; 4],
        flags: [u32; 4],
    }
}

const MODE_PER_PIXEL: u32 = 0;
const MODE_PER_VERTEX: u32 = 1;
const MODE_EDGE_OVERDRAW: u32 = 2;
const MODE_EDGE_LINES: u32 = 3;
/// Depth offsets of the line passes (edge overdraw behind the faces, mesh lines in front), in
/// normalised depth: planar passes sit at 0.5 + offset; surface passes move by the offset
/// (≈ 300 f32 ulps of depth near 1 — far above depth-interpolation rounding, far below the
/// depth differences of distinct surfaces; Vulkan's depth bias does not apply to lines).
const PLANAR_OFFSETS: [f32; 2] = [0.25, -0.25];
const SURFACE_OFFSETS: [f32; 2] = [2e-5, -2e-5];

struct Pipelines {
    fill: GraphicsPipeline,
    lines: GraphicsPipeline,
    fill_set: DescriptorSet,
    lines_set: DescriptorSet,
}

/// The cut-plane pass (`cut.comp`), its graphics pipelines (per colour format) and buffers:
/// the planes, the elements' Bernstein hulls, the indirect draw and the section rectangles.
struct Cutter {
    pass: ComputePipeline,
    pass_set: DescriptorSet,
    planes: Buffer<[f32; 4]>,
    draw: Buffer<u32>,
    vertices: Buffer<DrawVertex>,
    _hull: Buffer<[f32; 4]>,
    /// Per target and derived field (its text; `None`: the field itself).
    pipelines: HashMap<(PassKey, Option<String>), (GraphicsPipeline, DescriptorSet)>,
}

/// What a tessellation depends on: the view-projection, the focal scale, the error budget and
/// level cap (f32 bits), and which patches (geometry or a height field) it used.
type TessellationKey = [u32; 22];

/// The surface tessellation pass and its output: the vertex stream and its indirect draw
/// (`vertex_count, 1, 0, 0`, then the capacity in vertices and the elements skipped).
struct Tessellator {
    pipeline: ComputePipeline,
    draw: Buffer<u32>,
    vertices: Option<Buffer<DrawVertex>>,
    set: Option<DescriptorSet>,
}

/// A spectral-element mesh resident on the device, drawn per pixel (seed 002): quadrilaterals
/// and triangles (planar or a surface in 3D), hexahedra and tetrahedra (cut planes).
pub struct SpectralRenderer {
    gpu: Gpu,
    mesh: Arc<SpectralMesh>,
    _points: Buffer<[f32; 4]>,
    values: Buffer<f32>,
    specialization: Vec<u32>,
    proxies: Buffer<DrawVertex>,
    node_grids: Buffer<DrawVertex>,
    edges: Buffer<DrawVertex>,
    _patches: Buffer<[f32; 8]>,
    patch_bounds: Vec<[f32; 8]>,
    /// What the uploaded patches describe: the geometry (`None`) or a height field
    /// (field, step, scale bits).
    patches_for: Option<(usize, usize, u64)>,
    /// The mesh's box, computed once (views and cameras are fitted to it every frame).
    bounds: ([f64; 3], [f64; 3]),
    counts: [u32; 3],
    planar: bool,
    colormap: ColormapTexture,
    /// The field, step and derived field (its text) whose coefficients `values` holds.
    shown: (usize, usize, Option<String>),
    /// Draw pipelines per target and derived field (`None`: the field itself).
    pipelines: HashMap<(PassKey, Option<String>), Pipelines>,
    /// Colour ranges per field, step and derived field.
    ranges: HashMap<(usize, usize, Option<String>), (f64, f64)>,
    /// Fragment shaders compiled at run time, per derived field (its text).
    derived_shaders: HashMap<String, Vec<u32>>,
    tessellator: Option<Tessellator>,
    cutter: Option<Cutter>,
    /// The isosurface pass, made on the first view that asks for isosurfaces.
    iso: Option<iso::IsoPass>,
    /// The volume pass, made on the first view that asks for a volume.
    volume: Option<volume::VolumePass>,
    /// The most words one of the volume's tile buffers may hold
    /// ([`Self::set_volume_tile_budget`]).
    volume_budget: u64,
    /// Vertices the last surface frame reserved room for (the CPU bound of its tessellation).
    tessellated: u64,
    /// The inputs of the tessellation the vertex stream holds (view, scale, budget, cap,
    /// patches), set when a pass is recorded: a frame with the same inputs reuses it.
    tessellation_key: std::cell::Cell<Option<TessellationKey>>,
}

impl SpectralRenderer {
    /// Uploads `mesh` (geometry, the first field's first step, bases, draw streams) and
    /// `colormap`. Quadrilateral and triangle meshes: planar, or surfaces in 3D; hexahedral and
    /// tetrahedral meshes: by cut planes ([`SpectralView::cuts`]), isosurfaces and volumes.
    pub fn new(gpu: &Gpu, mesh: Arc<SpectralMesh>, colormap: &Colormap) -> Result<Self> {
        let hex = mesh.shape.is_volume();
        let planar = mesh.is_planar();
        if mesh.fields.is_empty() {
            return Err(SpectralError::Missing("the data set has no fields to show".into()));
        }
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let points = geometry_points(&mesh);
        let points =
            Buffer::from_slice(gpu, "spectral geometry", &points, storage).map_err(dev("uploading"))?;
        let values = padded_values(&mesh, 0, 0);
        let values =
            Buffer::from_slice(gpu, "spectral values", &values, storage).map_err(dev("uploading"))?;
        let draw = if hex {
            proxy::DrawGeometry { proxies: Vec::new(), node_grids: Vec::new(), edges: Vec::new() }
        } else {
            proxy::build(&mesh)
        };
        let vertex = vk::BufferUsageFlags::VERTEX_BUFFER;
        let upload = |name: &str, v: &[DrawVertex]| {
            // A buffer cannot be empty: an unused stream (surfaces have no proxies) gets one
            // vertex that is never drawn.
            let v = if v.is_empty() { &[DrawVertex::zeroed()][..] } else { v };
            Buffer::from_slice(gpu, name, v, vertex).map_err(dev("uploading the draw streams"))
        };
        let counts = [draw.proxies.len() as u32, draw.node_grids.len() as u32, draw.edges.len() as u32];
        let proxies = upload("spectral proxies", &draw.proxies)?;
        let node_grids = upload("spectral node grids", &draw.node_grids)?;
        let edges = upload("spectral edges", &draw.edges)?;
        let patch_bounds = if hex { Vec::new() } else { proxy::surface_patches(&mesh) };
        // A buffer cannot be empty: hexahedral meshes get one patch that is never read.
        let no_patch = [[0.0f32; 8]];
        let patch_slice = if patch_bounds.is_empty() { &no_patch[..] } else { &patch_bounds[..] };
        let patches =
            Buffer::from_slice(gpu, "spectral patches", patch_slice, storage).map_err(dev("uploading"))?;
        let colormap = colormap.upload(gpu).map_err(dev("uploading the colour map"))?;
        points.binding().map_err(dev("binding"))?;
        values.binding().map_err(dev("binding"))?;
        patches.binding().map_err(dev("binding"))?;
        let specialization = basis_specialization(&mesh);
        let bounds = mesh.bounds();
        let cutter =
            if hex { Some(Cutter::new(gpu, &mesh, &points, &values, &specialization)?) } else { None };
        Ok(Self {
            gpu: gpu.clone(),
            mesh,
            _points: points,
            values,
            specialization,
            proxies,
            node_grids,
            edges,
            _patches: patches,
            patch_bounds,
            patches_for: None,
            bounds,
            counts,
            planar,
            colormap,
            shown: (0, 0, None),
            pipelines: HashMap::new(),
            ranges: HashMap::new(),
            derived_shaders: HashMap::new(),
            tessellator: None,
            cutter,
            iso: None,
            volume: None,
            volume_budget: u64::MAX,
            tessellated: 0,
            tessellation_key: std::cell::Cell::new(None),
        })
    }

    /// Replaces the colour map (rebinding the draws); call when no frame is in flight.
    pub fn set_colormap(&mut self, gpu: &Gpu, colormap: &Colormap) -> Result<()> {
        self.colormap = colormap.upload(gpu).map_err(dev("uploading the colour map"))?;
        self.pipelines.clear();
        if let Some(t) = self.tessellator.as_mut() {
            t.set = None;
        }
        if let Some(c) = self.cutter.as_mut() {
            c.pipelines.clear();
        }
        if let Some(i) = self.iso.as_mut() {
            i.pipelines.clear();
        }
        if let Some(v) = self.volume.as_mut() {
            v.pipelines.clear();
        }
        Ok(())
    }

    /// The mesh being shown.
    pub fn mesh(&self) -> &SpectralMesh {
        &self.mesh
    }

    /// Triangles drawn per frame in per-pixel mode (planar: the proxies; surfaces: at most
    /// this many in the last frame's tessellation) and per-vertex mode, and edge lines.
    pub fn primitive_counts(&self) -> [u64; 3] {
        let flat = self.planar && self.patches_for.is_none();
        let per_pixel = if flat { u64::from(self.counts[0]) / 3 } else { self.tessellated / 3 };
        [per_pixel, u64::from(self.counts[1]) / 3, u64::from(self.counts[2]) / 2]
    }

    /// The colour range `view` uses: its own, or the sampled range of the field (isosurfaces
    /// coloured by another field: that field's; or of the
    /// derived field, [`DerivedField::range`]; (0, 1) when it has no finite value) at its step.
    pub fn range(&mut self, view: &SpectralView) -> (f64, f64) {
        if let Some(r) = view.range {
            return r;
        }
        // Isosurfaces coloured by another field: that field's range.
        let shown = view.colour_by.filter(|_| !view.iso.is_empty()).unwrap_or(view.field);
        let expression = view.expression.as_ref().filter(|_| shown == view.field);
        let key = (shown, view.step, expression.map(|d| d.expression.text.clone()));
        let mesh = &self.mesh;
        *self.ranges.entry(key).or_insert_with(|| match expression {
            Some(d) => d.range(mesh, view.field, view.step).unwrap_or((0.0, 1.0)),
            None => mesh.value_range(shown, view.step),
        })
    }

    /// Uploads the coefficients `view` draws (its field at its step, or every field its
    /// derived field reads) unless they are the ones shown.
    fn show(&mut self, view: &SpectralView) -> Result<()> {
        if view.expression.is_some() {
            return self.show_derived(view);
        }
        let (field, step) = (view.field, view.step);
        let f = self.mesh.fields.get(field).ok_or_else(|| {
            SpectralError::Missing(format!("no field {field} ({} fields)", self.mesh.fields.len()))
        })?;
        if step >= f.steps.len() {
            return Err(SpectralError::Missing(format!(
                "field {:?} has {} time steps; step {step} does not exist",
                f.name,
                f.steps.len()
            )));
        }
        // Isosurfaces coloured by another field: both fields' slots (the key cannot be an
        // expression's text).
        let colour_by = view.colour_by.filter(|_| !view.iso.is_empty());
        let key = colour_by.map(|k| format!("\u{0}colour-by {k}"));
        if self.shown != (field, step, key.clone()) {
            match colour_by {
                Some(k) => {
                    let v = padded_slots(&self.mesh, &[field, k], step);
                    self.upload_values(&v)?;
                }
                None => {
                    let v = padded_values(&self.mesh, field, step);
                    self.values.upload(&self.gpu, 0, &v).map_err(dev("uploading a time step"))?;
                }
            }
            self.shown = (field, step, key);
        }
        Ok(())
    }

    /// A pipeline description for the spectral draws: their bindings, the bases'
    /// specialization, the push constants and the [`DrawVertex`] stream.
    fn draw_desc<'a>(
        &'a self,
        name: &'a str,
        vertex: &'a [u32],
        fragment: &'a [u32],
        target: &DrawTarget<'a>,
    ) -> GraphicsPipelineDesc<'a> {
        let mut desc = GraphicsPipelineDesc::new(name, vertex, fragment, target.render_pass());
        desc.bindings = &DRAW_BINDINGS;
        desc.specialization = &self.specialization;
        desc.push = crate::gpu::PushLayout::of::<SpectralPush>();
        desc.vertex_stride = std::mem::size_of::<DrawVertex>() as u32;
        desc.vertex_attributes = &DRAW_VERTEX_ATTRIBUTES;
        desc
    }

    fn pipelines_for(&mut self, target: &DrawTarget<'_>, view: &SpectralView) -> Result<()> {
        let key = (target.key(), view.expression_key());
        if self.pipelines.contains_key(&key) {
            return Ok(());
        }
        target.require_depth("spectral elements").map_err(dev("building the spectral pipelines"))?;
        if let Some(d) = &view.expression {
            self.derived_shader(d)?;
        }
        let fragment = match &key.1 {
            Some(text) => &self.derived_shaders[text][..],
            // Planar meshes: the variant with the ownership rule at element edges.
            None if self.planar => crate::spectral::shaders::ELEMENT_PLANAR_FRAG,
            None => crate::spectral::shaders::ELEMENT_FRAG,
        };
        let make = |lines: bool| {
            let name = if lines { "spectral edges" } else { "spectral elements" };
            let mut desc = self.draw_desc(name, crate::spectral::shaders::ELEMENT_VERT, fragment, target);
            if lines {
                desc.topology = vk::PrimitiveTopology::LINE_LIST;
            }
            GraphicsPipeline::new(&self.gpu, &desc).map_err(dev("building the spectral pipelines"))
        };
        let (fill, lines) = (make(false)?, make(true)?);
        let resources = self.resources()?;
        let bind = |p: &GraphicsPipeline| p.bind(&self.gpu, &resources).map_err(dev("binding"));
        let (fill_set, lines_set) = (bind(&fill)?, bind(&lines)?);
        self.pipelines.insert(key, Pipelines { fill, lines, fill_set, lines_set });
        Ok(())
    }

    /// The four bindings of every spectral draw: geometry, coefficients, colour map, patches
    /// (each checked to fit one storage binding when the renderer was made).
    fn resources(&self) -> Result<Vec<Resource<'_>>> {
        Ok(vec![
            Resource::Storage(self._points.binding().map_err(dev("binding"))?),
            Resource::Storage(self.values.binding().map_err(dev("binding"))?),
            self.colormap.resource(),
            Resource::Storage(self._patches.binding().map_err(dev("binding"))?),
        ])
    }

    /// How `view` maps the world onto a picture of `width` × `height`: a planar mesh drawn
    /// flat through its 2D view (the view's, or fitted), anything else through a camera (the
    /// view's, the height field's, or fitted to the mesh's box) — what the draw uses, and what
    /// a picture's overlay is projected with.
    pub fn picture_view(&mut self, view: &SpectralView, width: u32, height: u32) -> PictureView {
        let scale = self.height_scale(view);
        if self.planar && scale.is_none() {
            let (lo, hi) = self.bounds;
            return PictureView::Plane(view.view.unwrap_or_else(|| View2d::fit_box(lo, hi, width, height)));
        }
        PictureView::Camera(match (view.camera, scale) {
            (Some(c), _) => c,
            (None, Some(s)) => self.height_camera(view, s),
            (None, None) => camera_for_box(self.bounds.0, self.bounds.1),
        })
    }

    fn push(&mut self, target: &DrawTarget<'_>, view: &SpectralView) -> SpectralPush {
        let e = target.extent();
        let (lo, hi) = self.range(view);
        let (view_proj, pixel_to_world) = match self.picture_view(view, e.width, e.height) {
            PictureView::Plane(v2) => (v2.view_proj(e.width, e.height), v2.pixel_to_world(e.width, e.height)),
            PictureView::Camera(camera) => {
                let aspect = target.aspect();
                // Pixels per world unit at view depth 1 (the tessellation adds each element's
                // off-axis factor).
                let pixels = camera.pixels_per_unit(e.height);
                let eye = camera.eye.map(|c| c as f32);
                (camera.view_proj_f32(aspect), [eye[0], eye[1], eye[2], pixels as f32])
            }
        };
        let flat = self.planar && self.height_scale(view).is_none();
        SpectralPush {
            view_proj: view_proj.to_cols_array(),
            pixel_to_world,
            range: [lo as f32, hi as f32, self.colormap.texels() as f32, view.isolines as f32],
            misc: if flat {
                // The fragment stage maps framebuffer pixels to world points relative to the
                // viewport's corner (exact: integers and pixel centres in f32).
                let v = target.viewport();
                [0.0, INSIDE_TOLERANCE as f32, v.x as f32, v.y as f32]
            } else {
                [0.0, INSIDE_TOLERANCE as f32, view.max_error_px.max(1e-3) as f32, MAX_TESSELLATION as f32]
            },
            flags: [
                u32::from(target.format() == ColorFormat::Rgba32F),
                u32::from(view.log),
                if view.per_vertex { MODE_PER_VERTEX } else { MODE_PER_PIXEL },
                u32::from(!flat),
            ],
        }
    }

    /// Records the draws of `view` inside `target`'s render pass, begun and ended by the
    /// caller, in its viewport — an engine target ([`RenderTarget::draw_target`]) or a host's
    /// render pass ([`crate::gpu::RenderPass::from_host`]). The pass expects
    /// [`Self::record_prepass`] of the same view and target recorded before the render pass
    /// began; it reads the mesh's buffers (vertex input, indirect, fragment storage reads) and
    /// writes only the colour and depth attachments of its viewport.
    pub fn record_draw_into(
        &mut self,
        rec: &mut Recorder<'_>,
        target: DrawTarget<'_>,
        view: &SpectralView,
    ) -> Result<()> {
        let draw = self.prepare(&target, view)?.1;
        draw(rec);
        Ok(())
    }

    /// Records the passes a frame needs before its render pass (the surface tessellation or
    /// the cut planes' sections; for planar meshes and per-vertex mode nothing) — for
    /// applications that record the frame themselves, outside any render pass, before
    /// [`Self::record_draw_into`]. Its declared accesses order it after the previous frame's
    /// draws and declare the draw's vertex-input and indirect reads of what it writes.
    pub fn record_prepass(
        &mut self,
        rec: &mut Recorder<'_>,
        target: DrawTarget<'_>,
        view: &SpectralView,
    ) -> Result<()> {
        let pre = self.prepare(&target, view)?.0;
        pre(rec);
        Ok(())
    }

    #[allow(clippy::type_complexity)]
    fn prepare(
        &mut self,
        target: &DrawTarget<'_>,
        view: &SpectralView,
    ) -> Result<(Box<dyn FnOnce(&mut Recorder<'_>) + '_>, Box<dyn FnOnce(&mut Recorder<'_>) + '_>)> {
        if view.uses_volume_pass() {
            return self.prepare_volume(target, view);
        }
        if !view.iso.is_empty() {
            return self.prepare_iso(target, view);
        }
        if self.cutter.is_some() {
            return self.prepare_cuts(target, view);
        }
        self.check_derived_view(view)?;
        self.show(view)?;
        self.pipelines_for(target, view)?;
        self.patches_for_view(view)?;
        let push = self.push(target, view);
        let lifted = !self.planar || push.flags[3] == 1;
        // A height field is always drawn from the tessellation (the node grids are flat).
        let surface = lifted && (!view.per_vertex || view.per_vertex_on_tessellation || self.planar);
        let key = self.tessellation_key_of(&push);
        let fresh = surface && self.tessellation_key.get() == Some(key);
        if surface && !fresh {
            self.tessellator_for(&push)?;
        }
        let p = &self.pipelines[&(target.key(), view.expression_key())];
        let extent = target.viewport();
        let (edges, edge_count) = (&self.edges, self.counts[2]);
        let (overdraw, mesh_lines) = (view.overdraw, view.edges);
        let offsets = if lifted { SURFACE_OFFSETS } else { PLANAR_OFFSETS };
        let tess = self.tessellator.as_ref().filter(|_| surface);
        let capacity = self.tessellated as u32;
        let elements = self.mesh.elements() as u64;
        let key_cell = &self.tessellation_key;
        let pre = move |rec: &mut Recorder<'_>| {
            let Some(t) = tess else { return };
            if fresh {
                // The stream already holds this view's tessellation (e.g. a new time step).
                return;
            }
            // The update waits for the last frame's draw (declared accesses).
            let header: [u32; 6] = [0, 1, 0, 0, capacity, 0];
            rec.update_buffer(&t.draw, 0, &header);
            // One invocation per element, 64 per workgroup.
            let groups = elements.div_ceil(u64::from(t.pipeline.local_size()[0])).max(1);
            let x = groups.min(65_535);
            let y = groups.div_ceil(x);
            let set = t.set.as_ref().expect("bound in tessellator_for");
            t.pipeline.record_dispatch(rec, set, &push, [x as u32, y as u32, 1]);
            // The draw's reads, declared before its render pass.
            match &t.vertices {
                Some(v) => rec.access_all(&[(&t.draw, Access::INDIRECT), (v, Access::VERTEX_INPUT)]),
                None => rec.access(&t.draw, Access::INDIRECT),
            }
            key_cell.set(Some(key));
        };
        let (faces, face_count) = if view.per_vertex {
            (&self.node_grids, self.counts[1])
        } else {
            (&self.proxies, self.counts[0])
        };
        let draw = move |rec: &mut Recorder<'_>| {
            let bytes = &push;
            match tess {
                Some(t) => p.fill.record_draw_indirect(
                    rec,
                    extent,
                    &p.fill_set,
                    bytes,
                    Some(t.vertices.as_ref().expect("made in tessellator_for").whole()),
                    t.draw.whole(),
                ),
                None => p.fill.record_draw(rec, extent, &p.fill_set, bytes, Some(faces.whole()), face_count),
            }
            // Edge overdraw behind the faces, then the mesh lines in front.
            for (on, mode, offset) in
                [(overdraw, MODE_EDGE_OVERDRAW, offsets[0]), (mesh_lines, MODE_EDGE_LINES, offsets[1])]
            {
                if on {
                    let mut lines = push;
                    lines.flags[2] = mode;
                    lines.misc[0] = offset;
                    let bytes = &lines;
                    p.lines.record_draw(rec, extent, &p.lines_set, bytes, Some(edges.whole()), edge_count);
                }
            }
        };
        Ok((Box::new(pre), Box::new(draw)))
    }

    /// One frame as an interactive loop draws it — the render pass in one submission, waited
    /// for, no readback — and its device time in milliseconds from timestamps around the pass
    /// (`profiler` needs one scope).
    pub fn frame(
        &mut self,
        target: &RenderTarget,
        view: &SpectralView,
        profiler: &mut Profiler,
    ) -> Result<f64> {
        let gpu = self.gpu.clone();
        let clear = if target.format() == ColorFormat::Rgba32F { [f32::NAN; 4] } else { BACKGROUND };
        let (pre, draw) = self.prepare(&target.draw_target(), view)?;
        gpu.run(|rec| {
            profiler.record_reset(rec);
            profiler.scope(rec, "draw", |rec| {
                pre(rec);
                target.record_begin(rec, clear);
                draw(rec);
                target.record_end(rec);
            });
        })
        .map_err(dev("drawing a frame"))?;
        let times = profiler.results().map_err(dev("reading timestamps"))?;
        Ok(times.first().map_or(0.0, |t| t.1))
    }

    /// Bytes resident on the device for drawing per pixel (geometry, the shown field's
    /// coefficients, bases, patches, proxies, edges) and, separately, the per-vertex node
    /// grids.
    pub fn device_bytes(&self) -> (u64, u64) {
        let per_pixel = self._points.size_bytes()
            + self.values.size_bytes()
            + self._patches.size_bytes()
            + self.proxies.size_bytes()
            + self.edges.size_bytes();
        (per_pixel, self.node_grids.size_bytes())
    }

    /// Renders `view` into `target` and returns the pixels: colour-mapped RGBA8, or in an
    /// RGBA32F target the raw `(value, ξ, η, element)` of every pixel (NaN where no element;
    /// −(element + 1) where only an edge-overdraw line drew the pixel).
    pub fn render(&mut self, target: &RenderTarget, view: &SpectralView) -> Result<Pixels> {
        let gpu = self.gpu.clone();
        let clear = if target.format() == ColorFormat::Rgba32F { [f32::NAN; 4] } else { BACKGROUND };
        let (pre, draw) = self.prepare(&target.draw_target(), view)?;
        gpu.run(|rec| pre(rec)).map_err(dev("tessellating the surface"))?;
        target.render(&gpu, clear, |rec| draw(rec)).map_err(dev("drawing the spectral elements"))
    }
}

impl crate::render::Draw for SpectralRenderer {
    type View<'v> = SpectralView;
    type Error = SpectralError;

    fn device_error(context: &'static str, cause: crate::gpu::GpuError) -> SpectralError {
        SpectralError::device(context)(cause)
    }

    /// [`SpectralRenderer::record_prepass`].
    fn record_prepass(
        &mut self,
        rec: &mut Recorder<'_>,
        target: DrawTarget<'_>,
        view: &SpectralView,
    ) -> Result<()> {
        SpectralRenderer::record_prepass(self, rec, target, view)
    }

    /// [`SpectralRenderer::record_draw_into`].
    fn record_draw_into(
        &mut self,
        rec: &mut Recorder<'_>,
        target: DrawTarget<'_>,
        view: &SpectralView,
    ) -> Result<()> {
        SpectralRenderer::record_draw_into(self, rec, target, view)
    }
}
