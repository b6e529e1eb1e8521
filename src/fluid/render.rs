//! Drawing a fluid frame (seed 000 §6.5). In 2D: a graphics pipeline over the cells, each
//! showing its speed |u_c| (constant per cell, Eq. 13) on a colour ramp or a plain grey; the
//! obstacle is the hole in the mesh. In 3D: the domain's boundary (walls and obstacle
//! surface) with front faces culled — a cutaway: one looks through the near walls at the far
//! ones, shaded by a headlight. Then the marker particles as round sprites read straight from
//! the compute pass's buffer, coloured by the speed of their cell (or white over coloured
//! cells), depth-tested (in 3D a far wall nearer the eye hides the particles behind it). A
//! float target gets the raw value, the cell index and what drew the pixel (0 cell, 1
//! particle, 2 wall) instead: EXR output and the tests, whose 2D reference locates each pixel
//! centre in the mesh in f64.

use ash::vk;
use bytemuck::{Pod, Zeroable};

use super::gpu::GpuParticles;
use super::operators::CellOperators;
use super::FluidError;
use crate::gpu::{
    BindingKind, Buffer, DescriptorSet, Gpu, GraphicsPipeline, GraphicsPipelineDesc, MemoryKind, PassKey,
    Recorder, RenderPass, Resource, Viewport,
};
use crate::mesh::{SimplexMesh, Topology};
use crate::render::{
    check_pass, ColorFormat, Colormap, ColormapTexture, Draw, DrawTarget, Pixels, RenderTarget, BACKGROUND,
};

/// The visible rectangle of the plane: the mesh's bounds with a margin, widened to the
/// image's aspect ratio. Maps world (x, y) to clip space (y down, Vulkan) and pixel centres
/// back to the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View2d {
    /// Lower-left corner.
    pub lo: [f64; 2],
    /// Upper-right corner.
    pub hi: [f64; 2],
}

impl View2d {
    /// Fits `[lo, hi]` with a relative `margin` into a `width × height` image.
    pub fn fit(lo: [f64; 2], hi: [f64; 2], (width, height): (u32, u32), margin: f64) -> Self {
        let (mut w, mut h) = ((hi[0] - lo[0]) * (1.0 + 2.0 * margin), (hi[1] - lo[1]) * (1.0 + 2.0 * margin));
        let aspect = f64::from(width) / f64::from(height.max(1));
        if w / h > aspect {
            h = w / aspect;
        } else {
            w = h * aspect;
        }
        let c = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
        Self { lo: [c[0] - 0.5 * w, c[1] - 0.5 * h], hi: [c[0] + 0.5 * w, c[1] + 0.5 * h] }
    }

    /// Column-major clip transform: x → [−1, 1] left to right, y → [−1, 1] top to bottom.
    pub fn view_proj(&self) -> [f32; 16] {
        let sx = 2.0 / (self.hi[0] - self.lo[0]);
        let sy = -2.0 / (self.hi[1] - self.lo[1]);
        let tx = -1.0 - sx * self.lo[0];
        let ty = 1.0 - sy * self.lo[1];
        [
            sx as f32, 0.0, 0.0, 0.0, //
            0.0, sy as f32, 0.0, 0.0, //
            0.0, 0.0, 0.0, 0.0, //
            tx as f32, ty as f32, 0.5, 1.0,
        ]
    }

    /// The world point at the centre of pixel (px, py).
    pub fn pixel_centre(&self, px: u32, py: u32, (width, height): (u32, u32)) -> [f64; 2] {
        [
            self.lo[0] + (f64::from(px) + 0.5) / f64::from(width) * (self.hi[0] - self.lo[0]),
            self.hi[1] - (f64::from(py) + 0.5) / f64::from(height) * (self.hi[1] - self.lo[1]),
        ]
    }

    /// The pixel coordinates (continuous, from the top-left corner) of a world point.
    pub fn project(&self, p: [f64; 2], (width, height): (u32, u32)) -> [f64; 2] {
        [
            (p[0] - self.lo[0]) / (self.hi[0] - self.lo[0]) * f64::from(width),
            (self.hi[1] - p[1]) / (self.hi[1] - self.lo[1]) * f64::from(height),
        ]
    }
}

/// One corner of a cell triangle as the vertex stage reads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct CellVertex {
    /// Position (z = 0).
    pub position: [f32; 3],
    /// The cell's speed.
    pub value: f32,
    /// The cell.
    pub cell: u32,
}

/// |u_c| of every cell from the fluxes (Eq. 13).
pub fn cell_speeds(mesh: &SimplexMesh, topo: &Topology, g: &[f64], f: &[f64]) -> Vec<f64> {
    let d = mesh.dim();
    let u = CellOperators::new(mesh, topo, g).flux_to_velocity(topo, f);
    u.chunks(d).map(|v| v.iter().map(|x| x * x).sum::<f64>().sqrt()).collect()
}

/// The triangle stream of a 2D mesh at geometry `g` with per-cell `values`.
pub fn cell_vertices(mesh: &SimplexMesh, g: &[f64], values: &[f64]) -> Vec<CellVertex> {
    let mut out = Vec::with_capacity(3 * mesh.cell_count());
    for c in 0..mesh.cell_count() {
        for p in mesh.cell_points_at(g, c) {
            out.push(CellVertex {
                position: [p[0] as f32, p[1] as f32, 0.0],
                value: values[c] as f32,
                cell: c as u32,
            });
        }
    }
    out
}

/// The boundary triangles of a 3D mesh at geometry `g`, wound so their outward normal faces
/// the viewer when seen from outside, each carrying a Lambert shade (headlight from `eye`) as
/// its value and its cell: the domain's walls, the obstacle surface the particles move in.
pub fn surface_vertices(mesh: &SimplexMesh, topo: &Topology, g: &[f64], eye: [f64; 3]) -> Vec<CellVertex> {
    use crate::mesh::geometry::{face_area_normal, face_centroid};
    let mut out = Vec::with_capacity(3 * topo.boundary_faces().len());
    for &f in topo.boundary_faces() {
        let [c, _] = topo.face_cells(f as usize);
        let l = topo.face_local(f as usize)[0] as usize;
        let p = mesh.cell_points_at(g, c as usize);
        let n = face_area_normal(3, &p, l);
        let x = face_centroid(&p, l);
        let to_eye = [eye[0] - x[0], eye[1] - x[1], eye[2] - x[2]];
        let len = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt().max(1e-300);
        let cos = (n[0] * to_eye[0] + n[1] * to_eye[1] + n[2] * to_eye[2]) / (len(n) * len(to_eye));
        let shade = 0.35 + 0.65 * cos.abs();
        let mut corners: Vec<usize> = (0..4).filter(|&i| i != l).collect();
        // Counter-clockwise about the outward normal.
        let (a, b, q) = (p[corners[0]], p[corners[1]], p[corners[2]]);
        let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let e2 = [q[0] - a[0], q[1] - a[1], q[2] - a[2]];
        let cross =
            [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
        if cross[0] * n[0] + cross[1] * n[1] + cross[2] * n[2] < 0.0 {
            corners.swap(1, 2);
        }
        for i in corners {
            out.push(CellVertex {
                position: [p[i][0] as f32, p[i][1] as f32, p[i][2] as f32],
                value: shade as f32,
                cell: c,
            });
        }
    }
    out
}

/// How cells and particles are coloured.
#[derive(Clone, Debug)]
pub struct DrawStyle {
    /// The ramp.
    pub colormap: Colormap,
    /// Speed range of the ramp.
    pub range: (f64, f64),
    /// Logarithmic ramp.
    pub log: bool,
    /// Cells coloured by speed (else plain grey, particles carry the colour).
    pub colour_cells: bool,
    /// Particle sprite radius in pixels (0: no particles).
    pub sprite_px: f64,
}

impl DrawStyle {
    /// The colour bar of this style (the PNG's legend and the viewers'): the ramp over the
    /// speed range, labelled by what carries the colour (cells or particles).
    pub fn colour_bar(&self) -> crate::plot::ColourBar<'_> {
        crate::plot::ColourBar {
            colormap: &self.colormap,
            range: self.range,
            log: self.log,
            label: if self.colour_cells { "cell speed (m/s)" } else { "particle speed (m/s)" },
            shift: 0.0,
        }
    }
}

crate::push_constants! {
    struct Push {
        view_proj: [f32; 16],
        range: [f32; 4],
        sprite: [f32; 4],
    }
}

/// The sprites' resources for one particle buffer: coloured by their cells' speeds
/// ([`FluidRenderer::particle_set`]) or their own ([`FluidRenderer::own_speed_set`]).
pub struct ParticleSet {
    set: DescriptorSet,
    own_speeds: bool,
}

/// What the fragment stages write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Output {
    /// Colour (8-bit target).
    Colour,
    /// Raw speed, cell index and kind (0 cell, 1 particle), to a float target.
    Raw,
}

/// How the scene is projected: the plane (2D) or a perspective camera (3D).
#[derive(Clone, Copy, Debug)]
pub enum Projection {
    /// A 2D frame.
    Plane(View2d),
    /// A 3D frame from a camera.
    Perspective(crate::render::Camera),
}

impl Projection {
    fn view_proj(&self, extent: vk::Extent2D) -> [f32; 16] {
        match self {
            Self::Plane(v) => v.view_proj(),
            Self::Perspective(c) => {
                let aspect = f64::from(extent.width) / f64::from(extent.height.max(1));
                c.view_proj_f32(aspect).to_cols_array()
            }
        }
    }
}

/// The cell, surface and sprite pipelines for one render pass.
pub struct FluidRenderer {
    /// The render passes its pipelines can draw in.
    key: PassKey,
    cells: GraphicsPipeline,
    surface: GraphicsPipeline,
    sprites: GraphicsPipeline,
    /// Sprites coloured by each particle's own speed.
    sprites_own: GraphicsPipeline,
    colormap: ColormapTexture,
    cell_set: DescriptorSet,
    vertices: Buffer<CellVertex>,
    speeds: Buffer<f32>,
    count: u32,
}

impl FluidRenderer {
    /// Pipelines drawing into `pass` up to `triangles` triangles (cells in 2D, boundary faces
    /// in 3D) over meshes of up to `cells` cells.
    pub fn new(
        gpu: &Gpu,
        pass: &RenderPass,
        output: Output,
        colormap: &Colormap,
        triangles: usize,
        cells: usize,
    ) -> Result<Self, FluidError> {
        let spec = [u32::from(output == Output::Raw)];
        let mut desc = GraphicsPipelineDesc::new(
            "fluid cells",
            crate::fluid::shaders::CELLS_VERT,
            crate::fluid::shaders::CELLS_FRAG,
            pass,
        );
        desc.push = crate::gpu::PushLayout::of::<Push>();
        desc.vertex_stride = std::mem::size_of::<CellVertex>() as u32;
        desc.vertex_attributes = &[
            (0, vk::Format::R32G32B32_SFLOAT, 0),
            (1, vk::Format::R32_SFLOAT, 12),
            (2, vk::Format::R32_UINT, 16),
        ];
        desc.bindings = &[BindingKind::Texture];
        desc.specialization = &spec;
        let cell_pipeline = GraphicsPipeline::new(gpu, &desc).map_err(FluidError::from)?;
        // The 3D surface: the same stages, front faces culled, so from outside one sees the
        // far walls through the near ones (a cutaway) with the particles in front of them.
        desc.name = "fluid surface";
        desc.cull_mode = vk::CullModeFlags::FRONT;
        let surface = GraphicsPipeline::new(gpu, &desc).map_err(FluidError::from)?;
        let mut desc = GraphicsPipelineDesc::new(
            "fluid particles",
            crate::fluid::shaders::SPRITES_VERT,
            crate::fluid::shaders::SPRITES_FRAG,
            pass,
        );
        desc.push = crate::gpu::PushLayout::of::<Push>();
        desc.bindings = &[BindingKind::Texture, BindingKind::StorageBuffer, BindingKind::StorageBuffer];
        desc.specialization = &spec;
        let sprites = GraphicsPipeline::new(gpu, &desc).map_err(FluidError::from)?;
        let per_particle_spec = [spec[0], 1];
        desc.name = "fluid particles (their own speeds)";
        desc.specialization = &per_particle_spec;
        let sprites_own = GraphicsPipeline::new(gpu, &desc).map_err(FluidError::from)?;
        let colormap = colormap.upload(gpu).map_err(FluidError::from)?;
        let cell_set = cell_pipeline.bind(gpu, &[colormap.resource()]).map_err(FluidError::from)?;
        let vertices = Buffer::new(
            gpu,
            "fluid cell vertices",
            (3 * triangles.max(1)) as u64,
            vk::BufferUsageFlags::VERTEX_BUFFER,
            MemoryKind::CpuToGpu,
        )
        .map_err(FluidError::from)?;
        let speeds = Buffer::new(
            gpu,
            "fluid cell speeds",
            cells.max(1) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryKind::CpuToGpu,
        )
        .map_err(FluidError::from)?;
        Ok(Self {
            key: pass.key(),
            cells: cell_pipeline,
            surface,
            sprites,
            sprites_own,
            colormap,
            cell_set,
            vertices,
            speeds,
            count: 0,
        })
    }

    /// Replaces the cells and their speeds (no draw of the previous ones may be in flight).
    /// An error if a recorded draw of the previous ones is not yet known to be finished.
    pub fn update(&mut self, vertices: &[CellVertex], speeds: &[f64]) -> Result<(), FluidError> {
        let dst = self.vertices.mapped_mut().map_err(FluidError::from)?;
        let n = vertices.len().min(dst.len());
        dst[..n].copy_from_slice(&vertices[..n]);
        self.count = n as u32;
        let dst = self.speeds.mapped_mut().map_err(FluidError::from)?;
        for (d, s) in dst.iter_mut().zip(speeds) {
            *d = *s as f32;
        }
        Ok(())
    }

    /// The sprite pipeline's resources for `particles` (bind once per particle buffer).
    pub fn particle_set(&self, gpu: &Gpu, particles: &GpuParticles) -> Result<ParticleSet, FluidError> {
        self.bind_particles(gpu, particles, false)
    }

    /// The sprite resources for `particles` coloured by their own speeds (the particle pass
    /// writes them; for a reduced state, whose cells' speeds would need the full flux).
    pub fn own_speed_set(&self, gpu: &Gpu, particles: &GpuParticles) -> Result<ParticleSet, FluidError> {
        self.bind_particles(gpu, particles, true)
    }

    /// The colour map, the particles and the speeds they are coloured by: the cells' or, with
    /// `own_speeds`, each particle's.
    fn bind_particles(
        &self,
        gpu: &Gpu,
        particles: &GpuParticles,
        own_speeds: bool,
    ) -> Result<ParticleSet, FluidError> {
        let (pipeline, speeds) =
            if own_speeds { (&self.sprites_own, particles.speeds()) } else { (&self.sprites, &self.speeds) };
        let set = pipeline
            .bind(
                gpu,
                &[
                    self.colormap.resource(),
                    Resource::Storage(particles.buffer().binding().map_err(FluidError::from)?),
                    Resource::Storage(speeds.binding().map_err(FluidError::from)?),
                ],
            )
            .map_err(FluidError::from)?;
        Ok(ParticleSet { set, own_speeds })
    }

    /// Records the cells (2D) or the surface (3D: what `update` was given, from
    /// [`surface_vertices`]), then the particles (inside the target's render pass).
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        viewport: impl Into<Viewport>,
        projection: &Projection,
        style: &DrawStyle,
        particles: Option<(&ParticleSet, usize)>,
    ) {
        let viewport: Viewport = viewport.into();
        let extent = viewport.extent();
        let half = [
            (2.0 * style.sprite_px / f64::from(extent.width.max(1))) as f32,
            (2.0 * style.sprite_px / f64::from(extent.height.max(1))) as f32,
        ];
        let surface = matches!(projection, Projection::Perspective(_));
        let mode = if surface { 2.0 } else { f32::from(u8::from(style.colour_cells)) };
        let push = Push {
            view_proj: projection.view_proj(extent),
            range: [
                style.range.0 as f32,
                style.range.1 as f32,
                self.colormap.texels() as f32,
                f32::from(u8::from(style.log)),
            ],
            sprite: [half[0], half[1], mode, f32::from(u8::from(style.colour_cells && !surface))],
        };
        let pipeline = if surface { &self.surface } else { &self.cells };
        pipeline.record_draw(rec, viewport, &self.cell_set, &push, Some(self.vertices.whole()), self.count);
        if let Some((set, count)) = particles {
            if style.sprite_px > 0.0 && count > 0 {
                let pipeline = if set.own_speeds { &self.sprites_own } else { &self.sprites };
                pipeline.record_draw(rec, viewport, &set.set, &push, None, (3 * count) as u32);
            }
        }
    }
}

/// What fluid cells and particles are drawn with ([`Draw`] for [`FluidRenderer`]).
#[derive(Clone, Copy)]
pub struct FluidView<'a> {
    /// The plane (2D) or a camera (3D).
    pub projection: Projection,
    /// Colours, range and sprite size.
    pub style: &'a DrawStyle,
    /// The particles' sprite resources and how many particles to draw.
    pub particles: Option<(&'a ParticleSet, usize)>,
}

impl Draw for FluidRenderer {
    type View<'v> = FluidView<'v>;
    type Error = FluidError;

    fn device_error(_: &'static str, cause: crate::gpu::GpuError) -> FluidError {
        FluidError::Gpu(cause)
    }

    /// The cells (2D) or surface (3D) from [`FluidRenderer::update`], then the particles, in
    /// the target's viewport. Refused if the target's render pass is not of the class the
    /// renderer was made for ([`FluidRenderer::new`]'s `pass`). The particles' advection,
    /// recorded before the render pass, declares the sprites' reads
    /// ([`super::gpu::GpuParticles::record_advect`]).
    fn record_draw_into(
        &mut self,
        rec: &mut Recorder<'_>,
        target: DrawTarget<'_>,
        view: &FluidView<'_>,
    ) -> Result<(), FluidError> {
        check_pass(self.key, &target, "fluid cells")?;
        self.record(rec, target.viewport(), &view.projection, view.style, view.particles);
        Ok(())
    }
}

/// One drawn frame: sRGB bytes and raw floats (speed, cell, kind, 1; cell −1 on the background).
pub struct FluidPicture {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// RGBA8, rows from the top.
    pub rgba: Vec<u8>,
    /// RGBA32F, rows from the top.
    pub raw: Vec<f32>,
}

/// Draws the 2D `mesh` at geometry `g` with cell `speeds` and optional particles into new
/// colour and raw targets and reads them back.
#[allow(clippy::too_many_arguments)]
pub fn draw_picture(
    gpu: &Gpu,
    (mesh, topo): (&SimplexMesh, &Topology),
    g: &[f64],
    speeds: &[f64],
    particles: Option<&GpuParticles>,
    style: &DrawStyle,
    projection: &Projection,
    (width, height): (u32, u32),
) -> Result<FluidPicture, FluidError> {
    let vertices = match (mesh.dim(), projection) {
        (2, Projection::Plane(_)) => cell_vertices(mesh, g, speeds),
        (3, Projection::Perspective(camera)) => surface_vertices(mesh, topo, g, camera.eye),
        (d, _) => {
            return Err(FluidError::State(format!(
                "a {d}D frame needs the {} projection",
                if d == 2 { "plane" } else { "perspective" }
            )))
        }
    };
    draw_triangles(gpu, &vertices, speeds, particles, style, projection, (width, height))
}

/// The cross-section of a 3D mesh at geometry `g` by the plane `x_axis = level`: each cell the
/// plane cuts gives a triangle or a quadrilateral (two triangles), carrying the cell's value,
/// in the plane's two other coordinates (z = 0) — a 2D picture of per-cell values inside the
/// domain (e.g. where an error sits).
pub fn plane_section(
    mesh: &SimplexMesh,
    g: &[f64],
    values: &[f64],
    axis: usize,
    level: f64,
) -> Vec<CellVertex> {
    let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
    let mut out = Vec::new();
    for c in 0..mesh.cell_count() {
        let p = mesh.cell_points_at(g, c);
        let side: Vec<f64> = p.iter().map(|q| q[axis] - level).collect();
        let mut points = Vec::new();
        for i in 0..p.len() {
            for j in i + 1..p.len() {
                if (side[i] < 0.0) != (side[j] < 0.0) {
                    let t = side[i] / (side[i] - side[j]);
                    points.push([p[i][a] + t * (p[j][a] - p[i][a]), p[i][b] + t * (p[j][b] - p[i][b])]);
                }
            }
        }
        if points.len() < 3 {
            continue;
        }
        // Order the section's corners around their centre (a convex polygon).
        let n = points.len() as f64;
        let centre =
            [points.iter().map(|q| q[0]).sum::<f64>() / n, points.iter().map(|q| q[1]).sum::<f64>() / n];
        points.sort_by(|q, r| {
            let angle = |x: &[f64; 2]| (x[1] - centre[1]).atan2(x[0] - centre[0]);
            angle(q).total_cmp(&angle(r))
        });
        for k in 1..points.len() - 1 {
            for q in [points[0], points[k], points[k + 1]] {
                out.push(CellVertex {
                    position: [q[0] as f32, q[1] as f32, 0.0],
                    value: values[c] as f32,
                    cell: c as u32,
                });
            }
        }
    }
    out
}

/// Draws a triangle stream (2D cells or a 3D surface, with per-cell `values`) and optionally
/// the particles, into a colour and a raw picture.
pub fn draw_triangles(
    gpu: &Gpu,
    vertices: &[CellVertex],
    speeds: &[f64],
    particles: Option<&GpuParticles>,
    style: &DrawStyle,
    projection: &Projection,
    (width, height): (u32, u32),
) -> Result<FluidPicture, FluidError> {
    let colour = RenderTarget::new(gpu, "fluid colour", width, height, ColorFormat::Rgba8)
        .map_err(FluidError::from)?;
    let raw =
        RenderTarget::new(gpu, "fluid raw", width, height, ColorFormat::Rgba32F).map_err(FluidError::from)?;
    let mut out = Vec::new();
    for (target, output, clear) in
        [(&colour, Output::Colour, BACKGROUND), (&raw, Output::Raw, [0.0, -1.0, 0.0, 0.0])]
    {
        let mut r = FluidRenderer::new(
            gpu,
            target.render_pass(),
            output,
            &style.colormap,
            vertices.len() / 3,
            speeds.len(),
        )?;
        r.update(vertices, speeds)?;
        let set = particles.map(|p| r.particle_set(gpu, p)).transpose()?;
        let view = FluidView {
            projection: *projection,
            style,
            particles: set.as_ref().zip(particles.map(GpuParticles::count)),
        };
        out.push(target.draw(gpu, &mut r, &view, clear)?);
    }
    let raw_pixels = match out.pop() {
        Some(Pixels::Rgba32F(v)) => v,
        _ => return Err(FluidError::State("a float target reads back floats".into())),
    };
    let rgba = match out.pop() {
        Some(Pixels::Rgba8(v)) => v,
        _ => return Err(FluidError::State("an RGBA8 target reads back bytes".into())),
    };
    Ok(FluidPicture { width, height, rgba, raw: raw_pixels })
}
