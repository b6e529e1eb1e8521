//! Compute and graphics pipelines built from embedded SPIR-V (see [`crate::gpu::shaders`]).
//! A pipeline owns its descriptor set layout (one set, bindings in order) and its pipeline
//! layout; descriptions are plain structs with sensible defaults (screen-13 style).

use std::sync::Arc;

use ash::vk;

use super::access::Access;
use super::buffer::BufferBinding;
use super::context::{DeviceShared, Gpu};
use super::descriptors::{BindingKind, DescriptorSet, DescriptorSetLayout, Resource};
use super::error::{vk_error, GpuError, GpuResult, VkContext};
use super::lifetime::{Lifetime, Tracked};
use super::push::{PushConstants, PushLayout};
use super::recorder::Recorder;
use super::renderpass::RenderPass;

/// A shader module, destroyed as soon as the pipeline using it exists.
struct ShaderModule<'a> {
    device: &'a ash::Device,
    raw: vk::ShaderModule,
}

impl<'a> ShaderModule<'a> {
    fn new(device: &'a ash::Device, spirv: &[u32]) -> GpuResult<Self> {
        let info = vk::ShaderModuleCreateInfo::default().code(spirv);
        // SAFETY: `spirv` is SPIR-V produced by glslc at build time (or by the caller).
        let raw = unsafe { device.create_shader_module(&info, None) }.vk("vkCreateShaderModule")?;
        Ok(Self { device, raw })
    }
}

impl Drop for ShaderModule<'_> {
    fn drop(&mut self) {
        // SAFETY: modules may be destroyed once pipelines are created from them.
        unsafe { self.device.destroy_shader_module(self.raw, None) };
    }
}

/// Specialization constants `constant_id = 0, 1, …` with 32-bit values.
fn specialization<'a>(
    values: &'a [u32],
    entries: &'a mut Vec<vk::SpecializationMapEntry>,
) -> vk::SpecializationInfo<'a> {
    entries.clear();
    entries.extend((0..values.len()).map(|i| vk::SpecializationMapEntry {
        constant_id: i as u32,
        offset: (i * 4) as u32,
        size: 4,
    }));
    vk::SpecializationInfo::default().map_entries(entries).data(bytemuck::cast_slice(values))
}

/// A pipeline layout: one descriptor set (bindings in order) and one push-constant range
/// visible to `stages`.
struct PipelineLayout {
    life: Arc<Lifetime>,
    _device: Arc<DeviceShared>,
    raw: vk::PipelineLayout,
    set: DescriptorSetLayout,
    push: PushLayout,
    stages: vk::ShaderStageFlags,
}

impl PipelineLayout {
    fn new(
        gpu: &Gpu,
        bindings: &[BindingKind],
        push: PushLayout,
        stages: vk::ShaderStageFlags,
        name: &str,
    ) -> GpuResult<Self> {
        let push_bytes = push.bytes;
        if push_bytes > gpu.caps().max_push_constants_size {
            return Err(GpuError::OverLimit {
                name: format!("push constants of `{name}`"),
                requested: u64::from(push_bytes),
                limit: u64::from(gpu.caps().max_push_constants_size),
                limit_name: "maxPushConstantsSize",
                unit: "bytes",
            });
        }
        let set = DescriptorSetLayout::new(gpu, bindings, stages)?;
        let ranges = [vk::PushConstantRange { stage_flags: stages, offset: 0, size: push_bytes }];
        let set_layouts = [set.raw];
        let mut info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
        if push_bytes > 0 {
            info = info.push_constant_ranges(&ranges);
        }
        // SAFETY: valid create info on this device.
        let raw = unsafe { gpu.device().create_pipeline_layout(&info, None) }.vk("vkCreatePipelineLayout")?;
        let set_life = set.lifetime().clone();
        let life = Lifetime::new(&gpu.shared, name, move |dev| {
            // SAFETY: no pipeline or recording uses the layout any more; its set layout is
            // released after it.
            unsafe { dev.raw.destroy_pipeline_layout(raw, None) };
            drop(set_life);
        });
        Ok(Self { life, _device: gpu.shared.clone(), raw, set, push, stages })
    }
}

/// What compute and graphics pipelines share: the pipeline, its layout, and the rule that a
/// recording binds the pipeline, its one descriptor set and exactly the declared push bytes.
struct PipelineCore {
    life: Arc<Lifetime>,
    raw: vk::Pipeline,
    layout: PipelineLayout,
    bind_point: vk::PipelineBindPoint,
    name: String,
    /// How its shaders use each binding (by binding number), from their SPIR-V.
    accesses: Vec<Access>,
}

/// How the shaders of a pipeline with `stages` (compute or graphics) use each of `bindings`:
/// storage buffers in `writable` are read and written, everything else read.
fn binding_accesses(
    bindings: &[BindingKind],
    writable: &std::collections::BTreeSet<u32>,
    compute: bool,
) -> Vec<Access> {
    (0..bindings.len() as u32)
        .map(|b| match (compute, writable.contains(&b)) {
            (true, true) => Access::COMPUTE_READ_WRITE,
            (true, false) => Access::COMPUTE_READ,
            (false, true) => Access::GRAPHICS_READ_WRITE,
            (false, false) => Access::GRAPHICS_READ,
        })
        .collect()
}

impl PipelineCore {
    fn new(
        gpu: &Gpu,
        raw: vk::Pipeline,
        layout: PipelineLayout,
        bind_point: vk::PipelineBindPoint,
        name: &str,
        accesses: Vec<Access>,
    ) -> Self {
        gpu.shared.set_name(raw, name);
        let layout_life = layout.life.clone();
        let life = Lifetime::new(&gpu.shared, name, move |dev| {
            // SAFETY: no recording uses the pipeline any more; its layout is released after it.
            unsafe { dev.raw.destroy_pipeline(raw, None) };
            drop(layout_life);
        });
        Self { life, raw, layout, bind_point, name: name.to_string(), accesses }
    }

    /// The accesses of a command using `set`, merged per object (a buffer bound twice is one
    /// access).
    fn set_accesses(&self, set: &DescriptorSet) -> Vec<(Arc<Lifetime>, Access)> {
        let mut merged: Vec<(Arc<Lifetime>, Access)> = Vec::new();
        for (life, access) in set.bound().iter().zip(&self.accesses) {
            match merged.iter_mut().find(|(l, _)| Arc::ptr_eq(l, life)) {
                Some((_, a)) => *a = a.and(*access),
                None => merged.push((life.clone(), *access)),
            }
        }
        merged
    }

    fn bind(&self, gpu: &Gpu, resources: &[Resource]) -> GpuResult<DescriptorSet> {
        DescriptorSet::new(gpu, &self.layout.set, resources)
    }

    /// Records the pipeline, `set` and `push` (of the type the pipeline was built with),
    /// keeping both alive. Panics if `P` is another type (a bug: its layout was never checked
    /// against the shader).
    fn record_bind<P: PushConstants + 'static>(&self, rec: &mut Recorder<'_>, set: &DescriptorSet, push: &P) {
        let l = &self.layout;
        assert!(
            std::any::TypeId::of::<P>() == l.push.type_id,
            "`{}` pushes `{}`, not `{}`",
            self.name,
            l.push.type_name,
            std::any::type_name::<P>()
        );
        let push: &[u8] = bytemuck::bytes_of(push);
        rec.keep_lifetime(&self.life);
        rec.keep(set);
        let (d, cmd) = (rec.device(), rec.cmd());
        // SAFETY: recording on this device (checked by `keep`); the set matches this pipeline's
        // layout (made by its `bind`) and both are kept alive by the recording.
        unsafe {
            d.cmd_bind_pipeline(cmd, self.bind_point, self.raw);
            d.cmd_bind_descriptor_sets(cmd, self.bind_point, l.raw, 0, &[set.raw], &[]);
            if !push.is_empty() {
                d.cmd_push_constants(cmd, l.raw, l.stages, 0, push);
            }
        }
    }
}

/// How to build a compute pipeline.
#[derive(Clone, Debug)]
pub struct ComputePipelineDesc<'a> {
    /// Name for debugging and errors.
    pub name: &'a str,
    /// SPIR-V of the `.comp` shader (entry point `main`).
    pub spirv: &'a [u32],
    /// Bindings of set 0, in order.
    pub bindings: &'a [BindingKind],
    /// The push-constant struct (checked against the shader's block member by member;
    /// [`PushLayout::none`] for none).
    pub push: PushLayout,
    /// Values of specialization constants 0, 1, ….
    pub specialization: &'a [u32],
}

/// The workgroup size of a compute shader (its `LocalSize` execution mode, read by
/// [`super::reflect`]), if the module has one and can be reflected.
pub fn spirv_local_size(spirv: &[u32]) -> Option<[u32; 3]> {
    super::reflect::reflect("a shader", spirv).ok()?.local_size
}

/// A compute pipeline with its layout.
pub struct ComputePipeline {
    core: PipelineCore,
    local_size: [u32; 3],
}

impl Tracked for ComputePipeline {
    fn lifetime(&self) -> &Arc<Lifetime> {
        &self.core.life
    }
}

impl ComputePipeline {
    /// Builds the pipeline, after checking its layout against the shader and its workgroup
    /// (size and shared memory, both read from the SPIR-V) against the device.
    pub fn new(gpu: &Gpu, desc: &ComputePipelineDesc<'_>) -> GpuResult<Self> {
        let shader = super::reflect::reflect(desc.name, desc.spirv)?;
        super::reflect::check_layout(desc.name, &shader, &desc.push, desc.bindings)?;
        let local_size = shader.local_size.unwrap_or([1, 1, 1]);
        let invocations = local_size.iter().product();
        gpu.caps().check_workgroup(desc.name, invocations, shader.shared_bytes)?;
        let layout =
            PipelineLayout::new(gpu, desc.bindings, desc.push, vk::ShaderStageFlags::COMPUTE, desc.name)?;
        let module = ShaderModule::new(gpu.device(), desc.spirv)?;
        let mut entries = Vec::new();
        let spec = specialization(desc.specialization, &mut entries);
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module.raw)
            .name(c"main")
            .specialization_info(&spec);
        let info = vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout.raw);
        // SAFETY: valid create info; the module and layout are alive.
        let raw = unsafe { gpu.device().create_compute_pipelines(vk::PipelineCache::null(), &[info], None) }
            .map_err(|(_, e)| vk_error("vkCreateComputePipelines", e))?[0];
        Ok(Self {
            core: PipelineCore::new(
                gpu,
                raw,
                layout,
                vk::PipelineBindPoint::COMPUTE,
                desc.name,
                binding_accesses(desc.bindings, &shader.writable, true),
            ),
            local_size,
        })
    }

    /// The workgroup size its shader declares (read from the SPIR-V): dispatch counts divide by
    /// it instead of repeating it.
    pub fn local_size(&self) -> [u32; 3] {
        self.local_size
    }

    /// Binds resources to this pipeline's bindings (see [`DescriptorSet::new`]).
    pub fn bind(&self, gpu: &Gpu, resources: &[Resource]) -> GpuResult<DescriptorSet> {
        self.core.bind(gpu, resources)
    }

    /// Records: bind the pipeline and `set`, push `push` (of the struct the pipeline was built
    /// with), dispatch `groups` workgroups. The dispatch declares its accesses — each bound
    /// buffer read, and written where the shader does not declare it `readonly` — so the
    /// barriers after earlier commands are recorded before it.
    pub fn record_dispatch<P: PushConstants + 'static>(
        &self,
        rec: &mut Recorder<'_>,
        set: &DescriptorSet,
        push: &P,
        groups: [u32; 3],
    ) {
        for (life, access) in self.core.set_accesses(set) {
            rec.declare_lifetime(&life, access);
        }
        rec.flush();
        self.core.record_bind(rec, set, push);
        // SAFETY: recording with this pipeline bound.
        unsafe { rec.device().cmd_dispatch(rec.cmd(), groups[0], groups[1], groups[2]) };
    }
}

/// The rectangle of the framebuffer a draw covers, in pixels (viewport and scissor alike): the
/// whole of an engine target, or the part of a host's framebuffer the host gives galerkin.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub struct Viewport {
    /// Left column.
    pub x: u32,
    /// Top row.
    pub y: u32,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl Viewport {
    /// Its size.
    pub fn extent(&self) -> vk::Extent2D {
        vk::Extent2D { width: self.width, height: self.height }
    }

    /// Width / height.
    pub fn aspect(&self) -> f64 {
        f64::from(self.width) / f64::from(self.height.max(1))
    }

    /// As a Vulkan rectangle (the scissor).
    pub fn rect(&self) -> vk::Rect2D {
        vk::Rect2D { offset: vk::Offset2D { x: self.x as i32, y: self.y as i32 }, extent: self.extent() }
    }
}

impl From<vk::Extent2D> for Viewport {
    fn from(e: vk::Extent2D) -> Self {
        Self { x: 0, y: 0, width: e.width, height: e.height }
    }
}

/// One vertex attribute: (location, format, byte offset in the vertex).
pub type VertexAttribute = (u32, vk::Format, u32);

/// How to build a graphics pipeline. Viewport and scissor are dynamic.
#[derive(Clone, Debug)]
pub struct GraphicsPipelineDesc<'a> {
    /// Name for debugging and errors.
    pub name: &'a str,
    /// SPIR-V of the vertex shader.
    pub vertex: &'a [u32],
    /// SPIR-V of the fragment shader.
    pub fragment: &'a [u32],
    /// SPIR-V of an optional geometry shader.
    pub geometry: Option<&'a [u32]>,
    /// SPIR-V of optional tessellation control and evaluation shaders, and the control points
    /// per patch (the topology must then be `PATCH_LIST`).
    pub tessellation: Option<(&'a [u32], &'a [u32], u32)>,
    /// Bindings of set 0 (visible to every stage).
    pub bindings: &'a [BindingKind],
    /// The push-constant struct (visible to every stage; checked against the shaders' block
    /// member by member; [`PushLayout::none`] for none).
    pub push: PushLayout,
    /// Stride of the one vertex buffer (0: no vertex buffer).
    pub vertex_stride: u32,
    /// Its attributes.
    pub vertex_attributes: &'a [VertexAttribute],
    /// Primitive topology.
    pub topology: vk::PrimitiveTopology,
    /// Fill or line.
    pub polygon_mode: vk::PolygonMode,
    /// Face culling.
    pub cull_mode: vk::CullModeFlags,
    /// Depth test (less-or-equal) and write.
    pub depth: bool,
    /// Alpha blending on the colour attachment.
    pub blend: bool,
    /// Depth bias (constant, slope) — pulls edge overdraw in front of faces.
    pub depth_bias: Option<(f32, f32)>,
    /// Render pass it draws in (in the pass's subpass; any render pass compatible with it, in
    /// Vulkan's sense, may be used to draw). Without a depth attachment, `depth` is ignored.
    pub render_pass: &'a RenderPass,
    /// Number of colour attachments of the render pass.
    pub color_attachments: u32,
    /// Values of specialization constants 0, 1, … (all stages).
    pub specialization: &'a [u32],
}

impl<'a> GraphicsPipelineDesc<'a> {
    /// Defaults: triangle list, filled, no culling, depth on, no blending, no vertex buffer,
    /// one colour attachment.
    pub fn new(name: &'a str, vertex: &'a [u32], fragment: &'a [u32], render_pass: &'a RenderPass) -> Self {
        Self {
            name,
            vertex,
            fragment,
            geometry: None,
            tessellation: None,
            bindings: &[],
            push: PushLayout::none(),
            vertex_stride: 0,
            vertex_attributes: &[],
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            polygon_mode: vk::PolygonMode::FILL,
            cull_mode: vk::CullModeFlags::NONE,
            depth: true,
            blend: false,
            depth_bias: None,
            render_pass,
            color_attachments: 1,
            specialization: &[],
        }
    }
}

/// A graphics pipeline with its layout.
pub struct GraphicsPipeline {
    core: PipelineCore,
}

impl Tracked for GraphicsPipeline {
    fn lifetime(&self) -> &Arc<Lifetime> {
        &self.core.life
    }
}

impl GraphicsPipeline {
    /// Builds the pipeline.
    pub fn new(gpu: &Gpu, desc: &GraphicsPipelineDesc<'_>) -> GpuResult<Self> {
        let mut stages = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT;
        if desc.geometry.is_some() {
            if !gpu.caps().geometry_shader {
                return Err(GpuError::Unsupported(format!("geometry shaders (pipeline `{}`)", desc.name)));
            }
            stages |= vk::ShaderStageFlags::GEOMETRY;
        }
        if desc.tessellation.is_some() {
            if !gpu.caps().tessellation_shader {
                return Err(GpuError::Unsupported(format!(
                    "tessellation shaders (pipeline `{}`)",
                    desc.name
                )));
            }
            stages |=
                vk::ShaderStageFlags::TESSELLATION_CONTROL | vk::ShaderStageFlags::TESSELLATION_EVALUATION;
        }
        if desc.polygon_mode != vk::PolygonMode::FILL && !gpu.caps().fill_mode_non_solid {
            return Err(GpuError::Unsupported(format!("fillModeNonSolid (pipeline `{}`)", desc.name)));
        }
        let mut modules = vec![desc.vertex, desc.fragment];
        modules.extend(desc.geometry);
        if let Some((tc, te, _)) = desc.tessellation {
            modules.extend([tc, te]);
        }
        let layouts =
            modules.iter().map(|m| super::reflect::reflect(desc.name, m)).collect::<GpuResult<Vec<_>>>()?;
        let shaders = super::reflect::merge(desc.name, &layouts)?;
        super::reflect::check_layout(desc.name, &shaders, &desc.push, desc.bindings)?;
        if !desc.render_pass.lifetime().is_on(&gpu.shared) {
            return Err(GpuError::WrongDevice {
                name: format!("the render pass of pipeline `{}`", desc.name),
            });
        }
        let layout = PipelineLayout::new(gpu, desc.bindings, desc.push, stages, desc.name)?;
        let device = gpu.device();
        let vs = ShaderModule::new(device, desc.vertex)?;
        let fs = ShaderModule::new(device, desc.fragment)?;
        let gs = desc.geometry.map(|g| ShaderModule::new(device, g)).transpose()?;
        let tess = match desc.tessellation {
            Some((tc, te, _)) => Some((ShaderModule::new(device, tc)?, ShaderModule::new(device, te)?)),
            None => None,
        };
        let mut entries = Vec::new();
        let spec = specialization(desc.specialization, &mut entries);
        let mut shader_stages = vec![
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::VERTEX)
                .module(vs.raw)
                .name(c"main")
                .specialization_info(&spec),
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::FRAGMENT)
                .module(fs.raw)
                .name(c"main")
                .specialization_info(&spec),
        ];
        if let Some(gs) = &gs {
            shader_stages.push(
                vk::PipelineShaderStageCreateInfo::default()
                    .stage(vk::ShaderStageFlags::GEOMETRY)
                    .module(gs.raw)
                    .name(c"main")
                    .specialization_info(&spec),
            );
        }
        if let Some((tc, te)) = &tess {
            for (stage, module) in [
                (vk::ShaderStageFlags::TESSELLATION_CONTROL, tc.raw),
                (vk::ShaderStageFlags::TESSELLATION_EVALUATION, te.raw),
            ] {
                shader_stages.push(
                    vk::PipelineShaderStageCreateInfo::default()
                        .stage(stage)
                        .module(module)
                        .name(c"main")
                        .specialization_info(&spec),
                );
            }
        }
        let tessellation_state = vk::PipelineTessellationStateCreateInfo::default()
            .patch_control_points(desc.tessellation.map_or(1, |t| t.2));
        let bindings = [vk::VertexInputBindingDescription {
            binding: 0,
            stride: desc.vertex_stride,
            input_rate: vk::VertexInputRate::VERTEX,
        }];
        let attributes: Vec<_> = desc
            .vertex_attributes
            .iter()
            .map(|&(location, format, offset)| vk::VertexInputAttributeDescription {
                location,
                binding: 0,
                format,
                offset,
            })
            .collect();
        let mut vertex_input = vk::PipelineVertexInputStateCreateInfo::default();
        if desc.vertex_stride > 0 {
            vertex_input = vertex_input
                .vertex_binding_descriptions(&bindings)
                .vertex_attribute_descriptions(&attributes);
        }
        let assembly = vk::PipelineInputAssemblyStateCreateInfo::default().topology(desc.topology);
        let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
        let mut raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(desc.polygon_mode)
            .cull_mode(desc.cull_mode)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        if let Some((constant, slope)) = desc.depth_bias {
            raster = raster
                .depth_bias_enable(true)
                .depth_bias_constant_factor(constant)
                .depth_bias_slope_factor(slope);
        }
        let multisample = vk::PipelineMultisampleStateCreateInfo::default()
            .rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let depth_on = desc.depth && desc.render_pass.depth_format().is_some();
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(depth_on)
            .depth_write_enable(depth_on)
            .depth_compare_op(vk::CompareOp::LESS_OR_EQUAL);
        let attachment = vk::PipelineColorBlendAttachmentState::default()
            .blend_enable(desc.blend)
            .src_color_blend_factor(vk::BlendFactor::SRC_ALPHA)
            .dst_color_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
            .color_blend_op(vk::BlendOp::ADD)
            .src_alpha_blend_factor(vk::BlendFactor::ONE)
            .dst_alpha_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
            .alpha_blend_op(vk::BlendOp::ADD)
            .color_write_mask(vk::ColorComponentFlags::RGBA);
        let attachments = vec![attachment; desc.color_attachments as usize];
        let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&attachments);
        let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        // A host's dynamic rendering: the attachment formats instead of a render pass.
        let color_formats = vec![desc.render_pass.color_format(); desc.color_attachments as usize];
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(&color_formats)
            .depth_attachment_format(desc.render_pass.depth_format().unwrap_or(vk::Format::UNDEFINED));
        let info = vk::GraphicsPipelineCreateInfo::default()
            .stages(&shader_stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(layout.raw)
            .render_pass(desc.render_pass.raw())
            .subpass(desc.render_pass.subpass());
        let info = if tess.is_some() { info.tessellation_state(&tessellation_state) } else { info };
        let info = if desc.render_pass.is_dynamic() { info.push_next(&mut rendering) } else { info };
        // SAFETY: every pointer in `info` refers to locals alive during the call.
        let raw = unsafe { device.create_graphics_pipelines(vk::PipelineCache::null(), &[info], None) }
            .map_err(|(_, e)| vk_error("vkCreateGraphicsPipelines", e))?[0];
        let accesses = binding_accesses(desc.bindings, &shaders.writable, false);
        Ok(Self {
            core: PipelineCore::new(gpu, raw, layout, vk::PipelineBindPoint::GRAPHICS, desc.name, accesses),
        })
    }

    /// Binds resources to this pipeline's bindings.
    pub fn bind(&self, gpu: &Gpu, resources: &[Resource]) -> GpuResult<DescriptorSet> {
        self.core.bind(gpu, resources)
    }

    /// Declares, before the render pass begins, what a draw of this pipeline with `set`,
    /// `vertices` and `indirect` reads and writes (no barrier can be recorded inside a render
    /// pass, so the pass that draws states its accesses first; the draw itself then checks
    /// them and panics if an earlier write of the recording was not declared).
    pub fn declare_draw(
        &self,
        rec: &mut Recorder<'_>,
        set: &DescriptorSet,
        vertices: Option<BufferBinding<'_>>,
        indirect: Option<BufferBinding<'_>>,
    ) {
        for (life, access) in self.core.set_accesses(set) {
            rec.declare_lifetime(&life, access);
        }
        if let Some(v) = vertices {
            rec.declare_lifetime(v.lifetime(), Access::VERTEX_INPUT);
        }
        if let Some(i) = indirect {
            rec.declare_lifetime(i.lifetime(), Access::INDIRECT);
        }
        rec.flush();
    }

    /// Records, inside a render pass: bind the pipeline, `set` and the vertex buffer (if any),
    /// set the viewport and scissor to `viewport` (an extent: the whole target), push `push`,
    /// and draw `vertex_count` vertices.
    pub fn record_draw<P: PushConstants + 'static>(
        &self,
        rec: &mut Recorder<'_>,
        viewport: impl Into<Viewport>,
        set: &DescriptorSet,
        push: &P,
        vertices: Option<BufferBinding<'_>>,
        vertex_count: u32,
    ) {
        self.record_state(rec, viewport.into(), set, push, vertices);
        // SAFETY: recording inside a render pass (the caller's documented state) with this
        // pipeline and its resources bound and kept alive.
        unsafe { rec.device().cmd_draw(rec.cmd(), vertex_count, 1, 0, 0) };
    }

    /// Like [`GraphicsPipeline::record_draw`], with the draw's parameters read by the device
    /// from the `VkDrawIndirectCommand` at the start of `indirect` (written by an earlier pass,
    /// whose writes a barrier has made visible to `DRAW_INDIRECT`). Panics if `indirect` is
    /// shorter than one command (16 bytes).
    pub fn record_draw_indirect<P: PushConstants + 'static>(
        &self,
        rec: &mut Recorder<'_>,
        viewport: impl Into<Viewport>,
        set: &DescriptorSet,
        push: &P,
        vertices: Option<BufferBinding<'_>>,
        indirect: BufferBinding<'_>,
    ) {
        assert!(indirect.range >= 16, "an indirect draw reads 16 bytes");
        rec.access_in_pass(indirect.lifetime(), Access::INDIRECT);
        self.record_state(rec, viewport.into(), set, push, vertices);
        let buffer = rec.bound(&indirect);
        // SAFETY: recording inside a render pass with this pipeline bound; `indirect` is kept
        // alive and holds at least one draw command at its offset.
        unsafe { rec.device().cmd_draw_indirect(rec.cmd(), buffer, indirect.offset, 1, 16) };
    }

    fn record_state<P: PushConstants + 'static>(
        &self,
        rec: &mut Recorder<'_>,
        area: Viewport,
        set: &DescriptorSet,
        push: &P,
        vertices: Option<BufferBinding<'_>>,
    ) {
        for (life, access) in self.core.set_accesses(set) {
            rec.access_in_pass(&life, access);
        }
        if let Some(v) = &vertices {
            rec.access_in_pass(v.lifetime(), Access::VERTEX_INPUT);
        }
        self.core.record_bind(rec, set, push);
        let viewport = vk::Viewport {
            x: area.x as f32,
            y: area.y as f32,
            width: area.width as f32,
            height: area.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        let scissor = area.rect();
        let vertex_buffer = vertices.map(|v| (rec.bound(&v), v.offset));
        let (d, cmd) = (rec.device(), rec.cmd());
        // SAFETY: recording with this pipeline bound; the vertex buffer is kept alive.
        unsafe {
            d.cmd_set_viewport(cmd, 0, &[viewport]);
            d.cmd_set_scissor(cmd, 0, &[scissor]);
            if let Some((v, offset)) = vertex_buffer {
                d.cmd_bind_vertex_buffers(cmd, 0, &[v], &[offset]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::spirv_local_size;

    #[test]
    fn workgroup_sizes_are_read_from_spirv() {
        assert_eq!(spirv_local_size(crate::tensor::shaders::GEMM), Some([8, 8, 1]));
        assert_eq!(spirv_local_size(crate::demo::shaders::AXPY), Some([256, 1, 1]));
        assert_eq!(spirv_local_size(crate::demo::shaders::FIELD_FRAG), None);
        assert_eq!(spirv_local_size(&[]), None);
    }
}
