//! A host application written with plain ash — none of galerkin's helpers — that embeds
//! galerkin in its own frame loop: the host creates its own instance (with the validation layer,
//! synchronization validation and its own messenger), device, queue, command buffers, fences,
//! semaphores, images, render pass and framebuffer, hands the device to `Gpu::from_raw`, and for
//! several frames, two in flight, records into its own command buffer:
//!
//! 1. galerkin's compute passes: particle advection, the spacetime slice, a radiosity scene's
//!    form factors and eight Jacobi sweeps (continuing from the last frame's iterate), the
//!    spectral prepass;
//! 2. a polynomial field drawn by galerkin's own render pass into one of the host's images
//!    (`RenderTarget::from_host_image`: the first way to embed);
//! 3. the host's own render pass over its composite image (its clear, its depth attachment),
//!    inside which galerkin draws the spectral elements and the spacetime slice, each in a
//!    viewport the host chooses (`RenderPass::from_host` + `DrawTarget`: the second way);
//! 4. the host's own post-pass: a blit of the field image into the composite's third part.
//!
//! It submits with its own fence, signalling its own semaphore, on which its readback
//! submission waits. It checks every frame's pixels itself: the field against the CPU
//! reference, the spectral and spacetime viewports against galerkin's own offscreen renders of
//! the same views (covered pixels bit for bit, the rest the host's clear colour), the
//! particles against the closed form of the flow, and after the last frame the form factors
//! against the CPU's and the radiosity against a CPU f64 Jacobi of as many sweeps. Dropping galerkin must leave every host
//! object alive and destroy nothing of the host's; the host then tears down and reports the
//! validation errors it saw.
//!
//! Run: `cargo run --release --example embed_host`.

mod vulkan;

use std::path::Path;
use std::sync::atomic::Ordering;
use std::sync::Arc;

use ash::vk;
use galerkin::demo::field::{check_colours, FieldOutput, FieldPass, Ramp};
use galerkin::demo::polynomial::BivariateCubic;
use galerkin::fluid::gpu::GpuParticles;
use galerkin::fluid::particles::seed_particles;
use galerkin::fluid::{FluidParams, FluidSolver};
use galerkin::gpu::{Gpu, GpuDesc, HostRenderPass, RawDevice, Recorder, Recording, RenderPass, Viewport};
use galerkin::mesh::kuhn::kuhn_box;
use galerkin::mesh::{Periodic, Topology};
use galerkin::radiosity::form_factor::{form_factors, NearField};
use galerkin::radiosity::gpu::GpuRadiosity;
use galerkin::radiosity::{full_radiosity, SceneSpec};
use galerkin::render::{Camera, ColorFormat, Colormap, DrawTarget, Pixels, RenderTarget};
use galerkin::spacetime::generate::pulses;
use galerkin::spacetime::{SlicePlan, SpacetimeRenderer, SpacetimeView};
use galerkin::spectral::generate::quad_grid;
use galerkin::spectral::{NodeSet, SpectralRenderer, SpectralView, View2d};
use vulkan::{
    host_buffer, host_image, host_messenger, host_render_pass, host_view, image_barrier, ERRORS, FIRST_ERROR,
};

const W: u32 = 160;
const H: u32 = 120;
/// Frames recorded, two in flight.
const FRAMES: usize = 6;
/// Jacobi sweeps recorded per frame.
const SWEEPS: usize = 8;
/// The host's clear colour of its composite (an exact 8-bit value: 100 / 255).
const HOST_GREY: f32 = 100.0 / 255.0;
/// The composite's parts, left to right: the field blitted in by the post-pass, the spectral
/// viewport, the spacetime viewport (both away from the framebuffer's corner).
const FIELD_PART: u32 = 0;
const SPECTRAL_PART: u32 = 1;
const SPACETIME_PART: u32 = 2;
const HOST_DEPTH: vk::Format = vk::Format::D32_SFLOAT;

/// What the host saw.
#[derive(Debug)]
pub struct HostReport {
    /// Validation errors reported to the host's messenger over the whole run.
    pub validation_errors: usize,
    /// The first of them.
    pub first_error: String,
    /// Whether the validation layer was on.
    pub validated: bool,
    /// Frames recorded and checked.
    pub frames: usize,
    /// Covered field pixels the host checked against the CPU reference, over all frames.
    pub pixels_checked: usize,
    /// Field pixels outside tolerance.
    pub pixel_failures: usize,
    /// Spectral and spacetime pixels (in that order) that differ from galerkin's own offscreen
    /// renders where those cover the pixel, or from the host's clear colour where they do not.
    pub pixels_differing: [usize; 2],
    /// The largest difference of one 8-bit channel among those.
    pub largest_difference: [u8; 2],
    /// Covered pixels of the spectral and spacetime viewports, over all frames.
    pub pixels_covered: [usize; 2],
    /// Worst particle position error against the closed form after the last frame.
    pub particle_error: f64,
    /// Form factors that are visible on one side and not the other (device and CPU), and the
    /// pairs visible on the CPU.
    pub form_factor_flips: (usize, usize),
    /// Worst form factor difference relative to max(|F|, 10⁻³ max F), over pairs that agree.
    pub form_factor_error: f64,
    /// Jacobi sweeps recorded over all frames.
    pub sweeps: usize,
    /// Worst radiosity difference from the CPU f64 Jacobi (same sweeps, the device's F),
    /// relative to the largest radiosity.
    pub radiosity_error: f64,
}

/// Runs the whole host for [`FRAMES`] frames; `require_validation` fails if the layer is
/// missing.
pub fn run_host(require_validation: bool) -> Result<HostReport, String> {
    ERRORS.store(0, Ordering::SeqCst);
    // SAFETY: a host application's plain Vulkan calls, in the order the spec requires; every
    // object is destroyed by the host after galerkin is gone.
    unsafe {
        let entry = ash::Entry::load().map_err(|e| format!("no Vulkan loader: {e}"))?;
        let layer = c"VK_LAYER_KHRONOS_validation";
        let validated = entry
            .enumerate_instance_layer_properties()
            .map_err(|e| e.to_string())?
            .iter()
            .any(|l| l.layer_name_as_c_str() == Ok(layer));
        if require_validation && !validated {
            return Err("VK_LAYER_KHRONOS_validation is not installed (vulkan-validationlayers)".into());
        }
        let layers = if validated { vec![layer.as_ptr()] } else { vec![] };
        let extensions = if validated {
            vec![ash::ext::debug_utils::NAME.as_ptr(), ash::ext::validation_features::NAME.as_ptr()]
        } else {
            vec![]
        };
        // Synchronization validation too: the host's barriers and galerkin's must compose.
        let enables = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enables);
        let app =
            vk::ApplicationInfo::default().application_name(c"embed_host").api_version(vk::API_VERSION_1_2);
        let mut instance_info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        if validated {
            instance_info = instance_info.push_next(&mut features);
        }
        let instance =
            entry.create_instance(&instance_info, None).map_err(|e| format!("vkCreateInstance: {e}"))?;
        let debug = ash::ext::debug_utils::Instance::new(&entry, &instance);
        let messenger = if validated {
            let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(
                    vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
                        | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
                )
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                        | vk::DebugUtilsMessageTypeFlagsEXT::GENERAL,
                )
                .pfn_user_callback(Some(host_messenger));
            debug.create_debug_utils_messenger(&info, None).map_err(|e| e.to_string())?
        } else {
            vk::DebugUtilsMessengerEXT::null()
        };

        let (physical, family) = instance
            .enumerate_physical_devices()
            .map_err(|e| e.to_string())?
            .into_iter()
            .find_map(|p| {
                instance
                    .get_physical_device_queue_family_properties(p)
                    .iter()
                    .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE))
                    .map(|f| (p, f as u32))
            })
            .ok_or("no device with a graphics+compute queue")?;
        let priorities = [1.0];
        let queues =
            [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&priorities)];
        let features_enabled = vk::PhysicalDeviceFeatures::default();
        let device = instance
            .create_device(
                physical,
                &vk::DeviceCreateInfo::default()
                    .queue_create_infos(&queues)
                    .enabled_features(&features_enabled),
                None,
            )
            .map_err(|e| format!("vkCreateDevice: {e}"))?;
        let queue = device.get_device_queue(family, 0);
        let pool = device
            .create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .queue_family_index(family)
                    .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                None,
            )
            .map_err(|e| e.to_string())?;
        let cmds = device
            .allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default().command_pool(pool).command_buffer_count(4),
            )
            .map_err(|e| e.to_string())?;
        // Two frame slots: (frame commands, readback commands, frame fence, readback fence, the
        // semaphore the readback waits on, the readback buffer and its memory).
        let mut slots = Vec::new();
        let composite_bytes = u64::from(4 * 3 * W * H);
        for k in 0..2 {
            let fence =
                || device.create_fence(&vk::FenceCreateInfo::default(), None).map_err(|e| e.to_string());
            let semaphore = device
                .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)
                .map_err(|e| e.to_string())?;
            let (buffer, memory) = host_buffer(&instance, &device, physical, composite_bytes)?;
            slots.push(Slot {
                frame: cmds[2 * k],
                post: cmds[2 * k + 1],
                frame_fence: fence()?,
                post_fence: fence()?,
                semaphore,
                readback: buffer,
                readback_memory: memory,
                pending: None,
            });
        }
        // The host's images: the field image galerkin's own pass draws into, and the composite
        // the host's render pass draws into (galerkin's spectral and spacetime viewports) and
        // its post-pass blits the field into; the composite's depth attachment.
        let colour_format = vk::Format::R8G8B8A8_UNORM;
        let colour = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC;
        let field_image = host_image(&instance, &device, physical, W, H, colour_format, colour)?;
        let composite = host_image(
            &instance,
            &device,
            physical,
            3 * W,
            H,
            colour_format,
            colour | vk::ImageUsageFlags::TRANSFER_DST,
        )?;
        let depth_image = host_image(
            &instance,
            &device,
            physical,
            3 * W,
            H,
            HOST_DEPTH,
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
        )?;
        let composite_view = host_view(&device, composite.0, colour_format, vk::ImageAspectFlags::COLOR)?;
        let depth_view = host_view(&device, depth_image.0, HOST_DEPTH, vk::ImageAspectFlags::DEPTH)?;
        let host_pass = host_render_pass(&device, colour_format)?;
        let attachments = [composite_view, depth_view];
        let framebuffer = device
            .create_framebuffer(
                &vk::FramebufferCreateInfo::default()
                    .render_pass(host_pass)
                    .attachments(&attachments)
                    .width(3 * W)
                    .height(H)
                    .layers(1),
                None,
            )
            .map_err(|e| e.to_string())?;

        // Hand the device to galerkin.
        let gpu = Gpu::from_raw(
            RawDevice {
                entry: entry.clone(),
                instance: instance.clone(),
                physical_device: physical,
                device: device.clone(),
                queue_family: family,
                queue,
                enabled_features: features_enabled,
                // This host draws in render-pass objects only.
                dynamic_rendering: false,
                // A Vulkan 1.0-style host: galerkin records Vulkan 1.0 barriers.
                synchronization2: false,
            },
            &GpuDesc { validation: false, ..GpuDesc::default() },
        )
        .map_err(|e| e.to_string())?;
        let err = |e: &dyn std::fmt::Display| e.to_string();

        // galerkin's content, prepared with its own transfers before the loop (the host is not
        // using the queue meanwhile). A polynomial field, checked against the CPU reference:
        let field_target =
            RenderTarget::from_host_image(&gpu, "host field image", field_image.0, ColorFormat::Rgba8, W, H)
                .map_err(|e| err(&e))?;
        let p = BivariateCubic { coefficients: [0.2, -0.5, 0.9, 0.3, -1.1, 0.25, -0.35, 0.6, 0.15, 0.4] };
        let ramp = Ramp { lo: -2.0, hi: 2.0, log: false };
        let colormap = Colormap::cool_warm();
        let field =
            FieldPass::new(&gpu, field_target.render_pass(), &p, 6, &colormap, ramp, FieldOutput::Colour)
                .map_err(|e| err(&e))?;
        let camera = Camera { eye: [-0.3, -2.4, 2.2], ..Camera::default() };
        // spectral elements (order 6 on a skewed 4 × 3 grid),
        let spectral_mesh = Arc::new(quad_grid(4, 3, 0.2, 6, NodeSet::GaussLobatto).map_err(|e| err(&e))?);
        let mut spectral =
            SpectralRenderer::new(&gpu, spectral_mesh.clone(), &Colormap::viridis()).map_err(|e| err(&e))?;
        let spectral_view = SpectralView {
            view: Some(View2d::fit(&spectral_mesh, W, H)),
            edges: true,
            ..SpectralView::default()
        };
        // The host's render pass, described to galerkin (the one unsafe step of drawing inside
        // it), and the viewport of each of galerkin's draws in the composite.
        let galerkin_pass = RenderPass::from_host(
            &gpu,
            HostRenderPass {
                raw: host_pass,
                subpass: 0,
                color_format: colour_format,
                depth_format: Some(HOST_DEPTH),
            },
        )
        .map_err(|e| err(&e))?;
        let part = |k: u32| Viewport { x: k * W, y: 0, width: W, height: H };
        let spectral_target = DrawTarget::new(&galerkin_pass, part(SPECTRAL_PART)).map_err(|e| err(&e))?;
        // a spacetime mesh sliced at a time that advances every frame,
        let spacetime_mesh = pulses(600);
        let mut spacetime =
            SpacetimeRenderer::from_mesh(&gpu, &spacetime_mesh, &Colormap::viridis()).map_err(|e| err(&e))?;
        let spacetime_target = DrawTarget::new(&galerkin_pass, part(SPACETIME_PART)).map_err(|e| err(&e))?;
        let t_end = spacetime_mesh.time_range().1;
        let time_of = |frame: usize| t_end * (0.2 + 0.1 * frame as f64);
        let mut views = Vec::new();
        for frame in 0..FRAMES {
            let view = SpacetimeView::from_above(spacetime.data().summary(), time_of(frame));
            // Size the slice buffers for every frame's slice, and fix each frame's ramp.
            spacetime.slice(view.time, view.subdivide).map_err(|e| err(&e))?;
            let u_max = spacetime.u_max_for(spacetime_target, &view).map_err(|e| err(&e))?;
            views.push(SpacetimeView { u_max: Some(u_max), ..view });
        }
        // a small radiosity scene: its form factors and eight Jacobi sweeps recorded every frame
        // (a deforming scene would move its faces between frames; the sweeps go on from the
        // last frame's iterate, as progressive radiosity does),
        let spec = SceneSpec::parse(
            include_str!("../../scenes/radiosity/two_rooms_small.toml"),
            Path::new("two_rooms_small.toml"),
        )
        .map_err(|e| err(&e))?;
        let scene = full_radiosity(&spec, &spec.defaults()).map_err(|e| err(&e))?;
        let radiosity = GpuRadiosity::new(&gpu).map_err(|e| err(&e))?;
        let form_factor_pass =
            radiosity.prepare_form_factors(&gpu, &scene.mesh, NearField::Regularised).map_err(|e| err(&e))?;
        let jacobi = radiosity
            .prepare_jacobi(&gpu, form_factor_pass.rows(), &scene.mesh.albedo, &scene.emission)
            .map_err(|e| err(&e))?;
        // and marker particles in a uniform flow through a periodic box.
        let base = kuhn_box(2, [12, 6, 0], [2.0, 1.0, 1.0]).map_err(|e| err(&e))?;
        let topo = Topology::new(&base, Some(Periodic { axis: 0 })).map_err(|e| err(&e))?;
        let frame_time = 0.05;
        let params = FluidParams { viscosity: 0.0, forcing: [0.0; 3], frame_time };
        let mut solver = FluidSolver::new(base.clone(), topo.clone(), params).map_err(|e| err(&e))?;
        let velocity = [1.3, 0.0];
        let uniform: Vec<f64> = (0..base.cell_count()).flat_map(|_| velocity).collect();
        let flow = solver.initial_state(base.g().to_vec(), &uniform).map_err(|e| err(&e))?;
        let start = seed_particles(&base, 200);
        let mut particles = GpuParticles::new(&gpu, &base, &topo, &start).map_err(|e| err(&e))?;
        particles.prepare(&gpu, &base, &flow.g, &flow.g, &flow.f).map_err(|e| err(&e))?;

        // galerkin's own offscreen renders of the same views: what the host's regions must equal.
        let offscreen =
            RenderTarget::new(&gpu, "reference", W, H, ColorFormat::Rgba8).map_err(|e| err(&e))?;
        let rgba = |p: Pixels| match p {
            Pixels::Rgba8(v) => Ok(v),
            Pixels::Rgba32F(_) => Err("an RGBA8 target reads back bytes".to_string()),
        };
        let spectral_reference = rgba(spectral.render(&offscreen, &spectral_view).map_err(|e| err(&e))?)?;
        let mut spacetime_reference = Vec::new();
        for view in &views {
            let mut r = SpacetimeRenderer::from_mesh(&gpu, &spacetime_mesh, &Colormap::viridis())
                .map_err(|e| err(&e))?;
            spacetime_reference.push(rgba(r.render(&offscreen, view).map_err(|e| err(&e))?)?);
        }

        let mut report = HostReport {
            validation_errors: 0,
            first_error: String::new(),
            validated,
            frames: 0,
            pixels_checked: 0,
            pixel_failures: 0,
            pixels_differing: [0; 2],
            largest_difference: [0; 2],
            pixels_covered: [0; 2],
            particle_error: 0.0,
            form_factor_flips: (0, 0),
            form_factor_error: 0.0,
            sweeps: 0,
            radiosity_error: 0.0,
        };
        let background = [0u8, 0, 0, 255];
        // Reads a finished slot back and checks its frame; returns the frame's slice to finish.
        let check = |slot: &mut Slot, report: &mut HostReport| -> Result<Option<SlicePlan>, String> {
            let Some((frame, recording, plan)) = slot.pending.take() else { return Ok(None) };
            let fences = [slot.frame_fence, slot.post_fence];
            device.wait_for_fences(&fences, true, u64::MAX).map_err(|e| e.to_string())?;
            device.reset_fences(&fences).map_err(|e| e.to_string())?;
            // The work completed: galerkin may release what it recorded.
            drop(recording);
            let mapped = device
                .map_memory(slot.readback_memory, 0, composite_bytes, vk::MemoryMapFlags::empty())
                .map_err(|e| e.to_string())?;
            let all = std::slice::from_raw_parts(mapped as *const u8, composite_bytes as usize).to_vec();
            device.unmap_memory(slot.readback_memory);
            let region = |k: usize| -> Vec<u8> {
                (0..H as usize)
                    .flat_map(|y| {
                        let row = (y * 3 * W as usize + k * W as usize) * 4;
                        all[row..row + 4 * W as usize].to_vec()
                    })
                    .collect()
            };
            let c =
                check_colours(&camera, &p, &colormap, ramp, W, H, &region(FIELD_PART as usize), background);
            report.pixels_checked += c.checked;
            report.pixel_failures += c.failures;
            // galerkin's offscreen references are cleared to its background; where they show
            // it (their corner pixel's value), the host's viewport must show the host's clear.
            let grey = [100u8, 100, 100, 255];
            for (k, got, want) in [
                (0, region(SPECTRAL_PART as usize), &spectral_reference),
                (1, region(SPACETIME_PART as usize), &spacetime_reference[frame]),
            ] {
                let uncovered = &want[..4];
                for (a, b) in got.chunks(4).zip(want.chunks(4)) {
                    if b == uncovered {
                        report.pixels_differing[k] += usize::from(a != grey);
                        continue;
                    }
                    report.pixels_covered[k] += 1;
                    if a != b {
                        report.pixels_differing[k] += 1;
                        let d = a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).max().unwrap_or(0);
                        report.largest_difference[k] = report.largest_difference[k].max(d);
                    }
                }
            }
            report.frames += 1;
            Ok(Some(plan))
        };
        // A slice that overflowed its buffers (they were sized for every frame's slice before
        // the loop, so this is a failure here; a real loop would record the frame again).
        let finish = |spacetime: &mut SpacetimeRenderer, plan: Option<SlicePlan>| -> Result<(), String> {
            match plan {
                Some(plan) if spacetime.finish_host_slice(&plan).map_err(|e| e.to_string())?.is_none() => {
                    Err("a slice overflowed the buffers sized for it".into())
                }
                _ => Ok(()),
            }
        };

        for frame in 0..FRAMES {
            let slot = &mut slots[frame % 2];
            // The slot's previous frame (two frames ago) must have finished before it is reused.
            let done = check(slot, &mut report)?;
            finish(&mut spacetime, done)?;
            let plan =
                spacetime.prepare_slice(views[frame].time, views[frame].subdivide).map_err(|e| err(&e))?;
            let cmd = slot.frame;
            device
                .reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty())
                .map_err(|e| e.to_string())?;
            device
                .begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default())
                .map_err(|e| e.to_string())?;
            // galerkin's compute passes and its own render pass into the field image, recorded
            // into the host's buffer (the one unsafe step; the host keeps the Recording until
            // its fence shows the buffer completed). Each pass orders itself after the previous
            // frame's use of its buffers and makes its writes visible to the draws.
            let mut rec = Recorder::from_host(&gpu, cmd);
            particles.record_advect(&mut rec, frame_time, 10).map_err(|e| err(&e))?;
            spacetime.record_slice_into(&mut rec, &plan);
            radiosity.record_form_factors(&mut rec, &form_factor_pass);
            radiosity.record_jacobi_sweeps(
                &mut rec,
                form_factor_pass.rows(),
                &jacobi,
                SWEEPS * frame,
                SWEEPS,
            );
            report.sweeps += SWEEPS;
            spectral.record_prepass(&mut rec, spectral_target, &spectral_view).map_err(|e| err(&e))?;
            field_target.record_begin(&mut rec, [0.0, 0.0, 0.0, 1.0]);
            field.record(&mut rec, field_target.extent(), &camera);
            field_target.record_end(&mut rec);
            // The host's own render pass over its composite: its clear (grey, depth 1), then
            // galerkin's draws in the viewports the host gave them.
            let clears = [
                vk::ClearValue {
                    color: vk::ClearColorValue { float32: [HOST_GREY, HOST_GREY, HOST_GREY, 1.0] },
                },
                vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } },
            ];
            device.cmd_begin_render_pass(
                cmd,
                &vk::RenderPassBeginInfo::default()
                    .render_pass(host_pass)
                    .framebuffer(framebuffer)
                    .render_area(vk::Rect2D {
                        offset: vk::Offset2D::default(),
                        extent: vk::Extent2D { width: 3 * W, height: H },
                    })
                    .clear_values(&clears),
                vk::SubpassContents::INLINE,
            );
            spectral.record_draw_into(&mut rec, spectral_target, &spectral_view).map_err(|e| err(&e))?;
            let u_max = views[frame].u_max.unwrap_or(1.0);
            spacetime
                .record_draw_into(&mut rec, spacetime_target, &views[frame], u_max)
                .map_err(|e| err(&e))?;
            device.cmd_end_render_pass(cmd);
            let recording = rec.finish();
            // The host's own post-pass: the composite left its render pass in
            // TRANSFER_SRC_OPTIMAL; blit galerkin's field image (left by galerkin's pass in
            // TRANSFER_SRC_OPTIMAL, its writes visible to transfers) into the composite's first
            // part.
            let src = (
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::TRANSFER_READ,
            );
            let dst = (
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::TRANSFER_WRITE,
            );
            image_barrier(&device, cmd, composite.0, src, dst);
            let layers = vk::ImageSubresourceLayers {
                aspect_mask: vk::ImageAspectFlags::COLOR,
                layer_count: 1,
                ..Default::default()
            };
            let corner = |x: i32, w: i32| {
                [vk::Offset3D { x, y: 0, z: 0 }, vk::Offset3D { x: x + w, y: H as i32, z: 1 }]
            };
            let blit = vk::ImageBlit {
                src_subresource: layers,
                src_offsets: corner(0, W as i32),
                dst_subresource: layers,
                dst_offsets: corner((FIELD_PART * W) as i32, W as i32),
            };
            device.cmd_blit_image(
                cmd,
                field_image.0,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                composite.0,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[blit],
                vk::Filter::NEAREST,
            );
            image_barrier(&device, cmd, composite.0, dst, src);
            device.end_command_buffer(cmd).map_err(|e| e.to_string())?;
            let frame_cmds = [cmd];
            let signal = [slot.semaphore];
            device
                .queue_submit(
                    queue,
                    &[vk::SubmitInfo::default().command_buffers(&frame_cmds).signal_semaphores(&signal)],
                    slot.frame_fence,
                )
                .map_err(|e| e.to_string())?;
            // The host's readback, a second submission waiting on the frame's semaphore.
            let post = slot.post;
            device
                .reset_command_buffer(post, vk::CommandBufferResetFlags::empty())
                .map_err(|e| e.to_string())?;
            device
                .begin_command_buffer(post, &vk::CommandBufferBeginInfo::default())
                .map_err(|e| e.to_string())?;
            let region = vk::BufferImageCopy {
                image_subresource: vk::ImageSubresourceLayers {
                    aspect_mask: vk::ImageAspectFlags::COLOR,
                    layer_count: 1,
                    ..Default::default()
                },
                image_extent: vk::Extent3D { width: 3 * W, height: H, depth: 1 },
                ..Default::default()
            };
            device.cmd_copy_image_to_buffer(
                post,
                composite.0,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                slot.readback,
                &[region],
            );
            let host_read = vk::MemoryBarrier::default()
                .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                .dst_access_mask(vk::AccessFlags::HOST_READ);
            device.cmd_pipeline_barrier(
                post,
                vk::PipelineStageFlags::TRANSFER,
                vk::PipelineStageFlags::HOST,
                vk::DependencyFlags::empty(),
                &[host_read],
                &[],
                &[],
            );
            device.end_command_buffer(post).map_err(|e| e.to_string())?;
            let post_cmds = [post];
            let wait = [slot.semaphore];
            let stages = [vk::PipelineStageFlags::TRANSFER];
            device
                .queue_submit(
                    queue,
                    &[vk::SubmitInfo::default()
                        .command_buffers(&post_cmds)
                        .wait_semaphores(&wait)
                        .wait_dst_stage_mask(&stages)],
                    slot.post_fence,
                )
                .map_err(|e| e.to_string())?;
            // Two frames in flight: this frame is checked when its slot comes round.
            slot.pending = Some((frame, recording, plan));
        }
        for slot in &mut slots {
            let done = check(slot, &mut report)?;
            finish(&mut spacetime, done)?;
        }
        // The particles after FRAMES frames of the uniform flow: carried by U·t (mod the period).
        let moved = particles.download(&gpu).map_err(|e| err(&e))?;
        let t = FRAMES as f64 * frame_time;
        for (m, s) in moved.iter().zip(&start) {
            let want = (s.position[0] + velocity[0] * t).rem_euclid(2.0);
            let dx = (m.position[0] - want).abs();
            report.particle_error = report
                .particle_error
                .max(dx.min((dx - 2.0).abs()))
                .max((m.position[1] - s.position[1]).abs());
        }

        // The form factors against the CPU's, and the radiosity after every frame's sweeps
        // against a CPU f64 Jacobi of as many sweeps on the device's F (an even count: the
        // newest iterate is the first).
        let f = form_factor_pass.rows().download(&gpu).map_err(|e| err(&e))?;
        let cpu_f = form_factors(&scene.mesh, NearField::Regularised);
        let top = cpu_f.values.iter().fold(0.0f64, |m, v| m.max(*v));
        for (a, b) in cpu_f.values.iter().zip(&f.values) {
            report.form_factor_flips.1 += usize::from(*a > 0.0);
            if (*a > 0.0) != (*b > 0.0) {
                report.form_factor_flips.0 += 1;
            } else {
                report.form_factor_error =
                    report.form_factor_error.max((a - b).abs() / a.abs().max(1e-3 * top));
            }
        }
        let n = scene.mesh.len();
        let mut b = scene.emission.clone();
        for _ in 0..report.sweeps {
            b = (0..n)
                .map(|i| {
                    let row = &f.values[i * n..(i + 1) * n];
                    std::array::from_fn(|c| {
                        let gathered: f64 = row.iter().zip(&b).map(|(fij, bj)| fij * bj[c]).sum();
                        scene.emission[i][c] + scene.mesh.albedo[i][c] * gathered
                    })
                })
                .collect::<Vec<[f64; 3]>>();
        }
        let (newest, _) = jacobi.iterates(&gpu).map_err(|e| err(&e))?;
        let largest = b.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        for (want, got) in b.iter().zip(&newest) {
            for c in 0..3 {
                let e = (want[c] - f64::from(got[c])).abs() / largest;
                report.radiosity_error = report.radiosity_error.max(e);
            }
        }

        // galerkin goes first and must destroy nothing of the host's.
        drop((
            field,
            field_target,
            spectral,
            spacetime,
            particles,
            offscreen,
            form_factor_pass,
            jacobi,
            radiosity,
            galerkin_pass,
            gpu,
        ));

        // The host's device and objects still work — its render pass, framebuffer and images
        // included: one more frame of its own, then tear down.
        let cmd = slots[0].frame;
        device.reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty()).map_err(|e| e.to_string())?;
        device
            .begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default())
            .map_err(|e| e.to_string())?;
        let clears = [
            vk::ClearValue { color: vk::ClearColorValue { float32: [HOST_GREY, HOST_GREY, HOST_GREY, 1.0] } },
            vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } },
        ];
        device.cmd_begin_render_pass(
            cmd,
            &vk::RenderPassBeginInfo::default()
                .render_pass(host_pass)
                .framebuffer(framebuffer)
                .render_area(vk::Rect2D {
                    offset: vk::Offset2D::default(),
                    extent: vk::Extent2D { width: 3 * W, height: H },
                })
                .clear_values(&clears),
            vk::SubpassContents::INLINE,
        );
        device.cmd_end_render_pass(cmd);
        device.end_command_buffer(cmd).map_err(|e| e.to_string())?;
        let last = [cmd];
        device
            .queue_submit(queue, &[vk::SubmitInfo::default().command_buffers(&last)], slots[0].frame_fence)
            .map_err(|e| e.to_string())?;
        device.wait_for_fences(&[slots[0].frame_fence], true, u64::MAX).map_err(|e| e.to_string())?;
        for slot in slots {
            device.destroy_fence(slot.frame_fence, None);
            device.destroy_fence(slot.post_fence, None);
            device.destroy_semaphore(slot.semaphore, None);
            device.destroy_buffer(slot.readback, None);
            device.free_memory(slot.readback_memory, None);
        }
        device.destroy_framebuffer(framebuffer, None);
        device.destroy_render_pass(host_pass, None);
        device.destroy_image_view(composite_view, None);
        device.destroy_image_view(depth_view, None);
        for (image, memory) in [field_image, composite, depth_image] {
            device.destroy_image(image, None);
            device.free_memory(memory, None);
        }
        device.destroy_command_pool(pool, None);
        device.destroy_device(None);
        if validated {
            debug.destroy_debug_utils_messenger(messenger, None);
        }
        instance.destroy_instance(None);
        report.validation_errors = ERRORS.load(Ordering::SeqCst);
        report.first_error = FIRST_ERROR.lock().map(|s| s.clone()).unwrap_or_default();
        Ok(report)
    }
}

/// One of the host's two frame slots.
struct Slot {
    frame: vk::CommandBuffer,
    post: vk::CommandBuffer,
    frame_fence: vk::Fence,
    post_fence: vk::Fence,
    semaphore: vk::Semaphore,
    readback: vk::Buffer,
    readback_memory: vk::DeviceMemory,
    /// The frame in flight: its number, galerkin's recording, and its slice.
    pending: Option<(usize, Recording, SlicePlan)>,
}

#[allow(dead_code)]
fn main() {
    match run_host(false) {
        Ok(r) => {
            println!("{r:#?}");
            let ok = r.validation_errors == 0
                && r.frames == FRAMES
                && r.pixel_failures == 0
                && r.pixels_checked > 0
                && r.pixels_differing[0] == 0
                && r.largest_difference[1] <= 1
                && r.particle_error < 1e-4
                && r.radiosity_error <= 1e-5;
            if !ok {
                std::process::exit(1);
            }
        }
        Err(e) => {
            eprintln!("embed_host: {e}");
            std::process::exit(1);
        }
    }
}
