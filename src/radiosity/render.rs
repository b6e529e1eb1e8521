//! Drawing a radiosity solution: a graphics pipeline over the scene's faces, back faces culled
//! (faces are lit on one side only, so from outside the rooms one looks in through the walls:
//! the "dollhouse" view), each face showing its radiance `bᵢ/π` (flat shading) or the
//! area-weighted average over the faces around each vertex (smooth shading), tone-mapped
//! with an exposure ([`crate::render::tone_map`], GLSL twin `tonemap.glsl`). A float target
//! gets the raw radiance and the face index instead (EXR output and the tests).
//!
//! The reference for the tests casts the ray through each pixel centre against the faces in
//! f64 ([`Bvh::closest_front_hit`]): the face a pixel must show.

use std::collections::HashMap;
use std::f64::consts::PI;

use ash::vk;
use bytemuck::{Pod, Zeroable};
use glam::DVec3;

use super::bvh::Bvh;
use super::mesh::{FaceGeometry, FaceKind, SceneMesh};
use super::scene::{LightMode, Lights, SceneSpec};
use super::solve::Rgb;
use crate::gpu::{
    Buffer, DescriptorSet, Gpu, GpuError, GpuResult, GraphicsPipeline, GraphicsPipelineDesc, MemoryKind,
    PassKey, Recorder, RenderPass, Viewport,
};
use crate::render::{check_pass, Camera, Draw, DrawTarget};

/// How radiance varies over a face.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Shading {
    /// Each face its own radiance (what Eq. 14 computes).
    #[default]
    Flat,
    /// Radiance interpolated from the vertices (area-weighted averages of the faces of the
    /// same part around each vertex; walls do not share vertices and openings are separate
    /// parts, so corners and window edges stay sharp).
    Smooth,
}

/// One corner of a face as the vertex stage reads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SceneVertex {
    /// Position.
    pub position: [f32; 3],
    /// Radiance to show at this corner.
    pub radiance: [f32; 3],
    /// The face.
    pub face: u32,
}

/// The radiance each face shows: `bᵢ/π` for surfaces (Lambertian); for openings in area mode
/// their exitance `window_exitance/π` (which is `bᵢ/π` of the full solution, albedo 0, and what
/// a reduced solution only approximates), in sky mode the sky's radiance looking out through
/// them.
pub fn display_radiance(mesh: &SceneMesh, geometry: &FaceGeometry, lights: &Lights, b: &[Rgb]) -> Vec<Rgb> {
    (0..mesh.len())
        .map(|i| match (mesh.kind[i], lights.mode) {
            (FaceKind::Surface, _) => b[i].map(|v| v / PI),
            (_, LightMode::Area) => lights.window_exitance.map(|v| v / PI),
            (_, LightMode::Sky) => super::lighting::sky_radiance(lights, -geometry.normals[i].normalize()),
        })
        .collect()
}

/// The vertex stream: three corners per face, in face order.
pub fn scene_vertices(
    mesh: &SceneMesh,
    geometry: &FaceGeometry,
    radiance: &[Rgb],
    shading: Shading,
) -> Vec<SceneVertex> {
    let vertex_radiance: Vec<Rgb> = match shading {
        Shading::Flat => Vec::new(),
        Shading::Smooth => {
            // Averages per (vertex, part): an opening does not bleed into its wall.
            let mut sum: HashMap<(u32, u16), ([f64; 3], f64)> = HashMap::new();
            for (i, f) in mesh.faces.iter().enumerate() {
                for &v in f {
                    let entry = sum.entry((v, mesh.part[i])).or_insert(([0.0; 3], 0.0));
                    for (acc, r) in entry.0.iter_mut().zip(radiance[i]) {
                        *acc += geometry.areas[i] * r;
                    }
                    entry.1 += geometry.areas[i];
                }
            }
            mesh.faces
                .iter()
                .enumerate()
                .flat_map(|(i, f)| {
                    let sum = &sum;
                    f.iter().map(move |&v| {
                        let (s, w) = sum[&(v, mesh.part[i])];
                        s.map(|x| x / w)
                    })
                })
                .collect()
        }
    };
    let mut out = Vec::with_capacity(3 * mesh.len());
    for (i, f) in mesh.faces.iter().enumerate() {
        for (k, &v) in f.iter().enumerate() {
            let r = match shading {
                Shading::Flat => radiance[i],
                Shading::Smooth => vertex_radiance[3 * i + k],
            };
            out.push(SceneVertex {
                position: mesh.vertices[v as usize].as_vec3().to_array(),
                radiance: r.map(|x| x as f32),
                face: i as u32,
            });
        }
    }
    out
}

/// What the fragment stage writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Output {
    /// Tone-mapped sRGB colour (8-bit target).
    Colour,
    /// Raw radiance (RGB) and the face index (A), to a float target.
    Raw,
}

/// The resident renderer: pipeline and a host-visible vertex buffer rewritten per frame.
pub struct SceneRenderer {
    /// The render passes its pipeline can draw in.
    key: PassKey,
    pipeline: GraphicsPipeline,
    set: DescriptorSet,
    vertices: Buffer<SceneVertex>,
    count: u32,
}

crate::push_constants! {
    struct Push {
        view_proj: [f32; 16],
        tone: [f32; 4],
    }
}

impl SceneRenderer {
    /// A renderer for meshes of `faces` faces drawing into targets of `pass`.
    pub fn new(gpu: &Gpu, pass: &RenderPass, output: Output, faces: usize) -> GpuResult<Self> {
        let spec = [u32::from(output == Output::Raw)];
        let mut desc = GraphicsPipelineDesc::new(
            "radiosity scene",
            crate::radiosity::shaders::SCENE_VERT,
            crate::radiosity::shaders::SCENE_FRAG,
            pass,
        );
        desc.push = crate::gpu::PushLayout::of::<Push>();
        desc.vertex_stride = std::mem::size_of::<SceneVertex>() as u32;
        desc.vertex_attributes = &[
            (0, vk::Format::R32G32B32_SFLOAT, 0),
            (1, vk::Format::R32G32B32_SFLOAT, 12),
            (2, vk::Format::R32_UINT, 24),
        ];
        desc.cull_mode = vk::CullModeFlags::BACK;
        desc.specialization = &spec;
        let pipeline = GraphicsPipeline::new(gpu, &desc)?;
        let set = pipeline.bind(gpu, &[])?;
        let vertices = Buffer::new(
            gpu,
            "radiosity scene vertices",
            (3 * faces.max(1)) as u64,
            vk::BufferUsageFlags::VERTEX_BUFFER,
            MemoryKind::CpuToGpu,
        )?;
        Ok(Self { key: pass.key(), pipeline, set, vertices, count: 0 })
    }

    /// Replaces the vertex stream (at most `3 · faces` vertices; the rest is dropped). The
    /// caller must not have a draw of the previous stream in flight.
    /// An error if a recorded draw of the previous stream is not yet known to be finished.
    pub fn update(&mut self, vertices: &[SceneVertex]) -> GpuResult<()> {
        let dst = self.vertices.mapped_mut()?;
        let n = vertices.len().min(dst.len());
        dst[..n].copy_from_slice(&vertices[..n]);
        self.count = n as u32;
        Ok(())
    }

    /// Records the draw (inside the target's render pass) in `viewport`.
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        viewport: impl Into<Viewport>,
        camera: &Camera,
        exposure: f64,
    ) {
        let extent: Viewport = viewport.into();
        let aspect = extent.aspect();
        let push = Push {
            view_proj: camera.view_proj_f32(aspect).to_cols_array(),
            tone: [exposure as f32, 0.0, 0.0, 0.0],
        };
        self.pipeline.record_draw(rec, extent, &self.set, &push, Some(self.vertices.whole()), self.count);
    }
}

/// What a radiosity scene is drawn with ([`Draw`] for [`SceneRenderer`]).
#[derive(Clone, Copy, Debug)]
pub struct SceneView {
    /// The camera.
    pub camera: Camera,
    /// The tone map's exposure (radiance at white).
    pub exposure: f64,
}

impl Draw for SceneRenderer {
    type View<'v> = SceneView;
    type Error = super::RadiosityError;

    fn device_error(_: &'static str, cause: GpuError) -> Self::Error {
        super::RadiosityError::Gpu(cause)
    }

    /// The scene's faces (their vertices, uploaded by [`SceneRenderer::update`]) in the
    /// target's viewport. Refused if the target's render pass is not of the class the renderer
    /// was made for ([`SceneRenderer::new`]'s `pass`).
    fn record_draw_into(
        &mut self,
        rec: &mut Recorder<'_>,
        target: DrawTarget<'_>,
        view: &SceneView,
    ) -> Result<(), Self::Error> {
        check_pass(self.key, &target, "a radiosity scene")?;
        self.record(rec, target.viewport(), &view.camera, view.exposure);
        Ok(())
    }
}

/// Named viewpoints of the two-room scene.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Viewpoint {
    /// Inside the living room, from its north-west corner towards the window and the door.
    #[default]
    Living,
    /// Inside the bedroom, from its north-east corner towards the window and the door.
    Bedroom,
    /// From above the south-west, looking down into both rooms through the culled ceilings.
    Overview,
}

/// The camera of a viewpoint.
pub fn camera_for(spec: &SceneSpec, view: Viewpoint) -> Camera {
    let [l1, w, h] = spec.rooms.living;
    let [l2, _, _] = spec.rooms.bedroom;
    let x2 = l1 + spec.rooms.wall_thickness;
    let (eye, target, fov) = match view {
        Viewpoint::Living => ([0.3, w - 0.3, 1.7], [0.62 * l1, 0.25 * w, 0.9], 70.0),
        Viewpoint::Bedroom => ([x2 + l2 - 0.3, w - 0.3, 1.7], [x2 + 0.2 * l2, 0.3 * w, 0.8], 70.0),
        Viewpoint::Overview => {
            let c = DVec3::new(0.5 * (x2 + l2), 0.5 * w, 0.0);
            let eye = c + DVec3::new(-0.55 * (x2 + l2), -1.3 * w, 3.2 * h);
            (eye.to_array(), c.to_array(), 45.0)
        }
    };
    Camera { eye, target, up: [0.0, 0.0, 1.0], fov_y_degrees: fov, near: 0.05, far: 200.0 }
}

/// The face the pixel centre `(px, py)` shows (culling back faces), by casting its ray in f64.
pub fn reference_face(bvh: &Bvh, camera: &Camera, px: u32, py: u32, width: u32, height: u32) -> Option<u32> {
    let (origin, dir) = camera.pixel_ray(px, py, width, height);
    bvh.closest_front_hit(origin, dir).map(|(f, _)| f)
}

/// One picture of a solution: the tone-mapped sRGB bytes and the raw float pixels
/// (radiance RGB, face index; −1 where no face).
pub struct Picture {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// RGBA8 sRGB, row-major from the top.
    pub rgba: Vec<u8>,
    /// RGBA32F: radiance and face, row-major from the top.
    pub raw: Vec<f32>,
}

/// Draws `vertices` from `camera` into a new pair of targets (colour and raw) and reads them back.
pub fn draw_picture(
    gpu: &Gpu,
    vertices: &[SceneVertex],
    camera: &Camera,
    exposure: f64,
    (width, height): (u32, u32),
) -> Result<Picture, super::RadiosityError> {
    use crate::render::{ColorFormat, Pixels, RenderTarget, BACKGROUND};
    let faces = vertices.len() / 3;
    let colour = RenderTarget::new(gpu, "radiosity colour", width, height, ColorFormat::Rgba8)?;
    let raw = RenderTarget::new(gpu, "radiosity raw", width, height, ColorFormat::Rgba32F)?;
    let mut colour_pass = SceneRenderer::new(gpu, colour.render_pass(), Output::Colour, faces)?;
    let mut raw_pass = SceneRenderer::new(gpu, raw.render_pass(), Output::Raw, faces)?;
    colour_pass.update(vertices)?;
    raw_pass.update(vertices)?;
    let view = SceneView { camera: *camera, exposure };
    let rgba = match colour.draw(gpu, &mut colour_pass, &view, BACKGROUND)? {
        Pixels::Rgba8(v) => v,
        Pixels::Rgba32F(_) => unreachable!("an RGBA8 target reads back bytes"),
    };
    let raw = match raw.draw(gpu, &mut raw_pass, &view, [0.0, 0.0, 0.0, -1.0])? {
        Pixels::Rgba32F(v) => v,
        Pixels::Rgba8(_) => unreachable!("a float target reads back floats"),
    };
    Ok(Picture { width, height, rgba, raw })
}

/// The default exposure of a solution: the 90th percentile (by area) of the surfaces'
/// displayed luminance at 78 % of white ([`crate::render::auto_exposure`]).
pub fn default_exposure(mesh: &SceneMesh, geometry: &FaceGeometry, radiance: &[Rgb]) -> f64 {
    let surfaces: Vec<usize> = (0..mesh.len()).filter(|&i| !mesh.kind[i].is_opening()).collect();
    let lum: Vec<f64> = surfaces
        .iter()
        .map(|&i| 0.2126 * radiance[i][0] + 0.7152 * radiance[i][1] + 0.0722 * radiance[i][2])
        .collect();
    let w: Vec<f64> = surfaces.iter().map(|&i| geometry.areas[i]).collect();
    crate::render::auto_exposure(&lum, &w, 0.9)
}
