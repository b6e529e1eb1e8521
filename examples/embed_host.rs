//! A host application written with plain ash — none of galerkin's helpers — that embeds
//! galerkin: the host creates its own instance (with the validation layer and its own
//! messenger), device, queue, command buffer and colour image, hands them to
//! `Gpu::from_raw`, lets galerkin record a compute dispatch and a draw into the host's command
//! buffer and the host's image, then submits, reads the image back and checks its pixels
//! itself. Dropping galerkin must leave every host object alive and destroy nothing of the
//! host's; the host then tears down and reports the validation errors it saw.
//!
//! Run: `cargo run --release --example embed_host`.

use std::ffi::c_void;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use ash::vk;
use galerkin::demo::axpy::{axpy_error_ratio, Axpy};
use galerkin::demo::field::{check_colours, FieldOutput, FieldPass, Ramp};
use galerkin::demo::polynomial::BivariateCubic;
use galerkin::gpu::{Buffer, Gpu, GpuDesc, RawDevice, Recorder};
use galerkin::render::{Camera, ColorFormat, Colormap, RenderTarget};

const W: u32 = 200;
const H: u32 = 150;

static ERRORS: AtomicUsize = AtomicUsize::new(0);
static FIRST_ERROR: Mutex<String> = Mutex::new(String::new());

unsafe extern "system" fn host_messenger(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    _user: *mut c_void,
) -> vk::Bool32 {
    if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
        ERRORS.fetch_add(1, Ordering::SeqCst);
        // SAFETY: the layer passes a valid callback struct and NUL-terminated message.
        let msg = unsafe {
            data.as_ref().and_then(|d| d.message_as_c_str()).map(|m| m.to_string_lossy().into_owned())
        };
        if let (Ok(mut first), Some(msg)) = (FIRST_ERROR.lock(), msg) {
            if first.is_empty() {
                *first = msg;
            }
        }
    }
    vk::FALSE
}

/// What the host saw.
#[derive(Debug)]
pub struct HostReport {
    /// Validation errors reported to the host's messenger over the whole run.
    pub validation_errors: usize,
    /// The first of them.
    pub first_error: String,
    /// Whether the validation layer was on.
    pub validated: bool,
    /// Covered pixels the host checked against the CPU reference.
    pub pixels_checked: usize,
    /// Pixels outside tolerance.
    pub pixel_failures: usize,
    /// Worst axpy error as a multiple of its f32 bound.
    pub axpy_error_ratio: f64,
}

fn find_memory(
    instance: &ash::Instance,
    physical: vk::PhysicalDevice,
    bits: u32,
    want: vk::MemoryPropertyFlags,
) -> u32 {
    // SAFETY: plain query.
    let props = unsafe { instance.get_physical_device_memory_properties(physical) };
    (0..props.memory_type_count)
        .find(|&i| bits & (1 << i) != 0 && props.memory_types[i as usize].property_flags.contains(want))
        .expect("a suitable memory type")
}

/// Runs the whole host; `require_validation` fails if the layer is missing.
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
        let extensions = if validated { vec![ash::ext::debug_utils::NAME.as_ptr()] } else { vec![] };
        let app =
            vk::ApplicationInfo::default().application_name(c"embed_host").api_version(vk::API_VERSION_1_2);
        let instance = entry
            .create_instance(
                &vk::InstanceCreateInfo::default()
                    .application_info(&app)
                    .enabled_layer_names(&layers)
                    .enabled_extension_names(&extensions),
                None,
            )
            .map_err(|e| format!("vkCreateInstance: {e}"))?;
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
        let features = vk::PhysicalDeviceFeatures::default();
        let device = instance
            .create_device(
                physical,
                &vk::DeviceCreateInfo::default().queue_create_infos(&queues).enabled_features(&features),
                None,
            )
            .map_err(|e| format!("vkCreateDevice: {e}"))?;
        let queue = device.get_device_queue(family, 0);
        let pool = device
            .create_command_pool(&vk::CommandPoolCreateInfo::default().queue_family_index(family), None)
            .map_err(|e| e.to_string())?;
        let cmd = device
            .allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default().command_pool(pool).command_buffer_count(1),
            )
            .map_err(|e| e.to_string())?[0];
        let fence = device.create_fence(&vk::FenceCreateInfo::default(), None).map_err(|e| e.to_string())?;

        // The host's colour image and a host-visible buffer to read it back into.
        let image = device
            .create_image(
                &vk::ImageCreateInfo::default()
                    .image_type(vk::ImageType::TYPE_2D)
                    .format(vk::Format::R8G8B8A8_UNORM)
                    .extent(vk::Extent3D { width: W, height: H, depth: 1 })
                    .mip_levels(1)
                    .array_layers(1)
                    .samples(vk::SampleCountFlags::TYPE_1)
                    .tiling(vk::ImageTiling::OPTIMAL)
                    .usage(vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC),
                None,
            )
            .map_err(|e| e.to_string())?;
        let req = device.get_image_memory_requirements(image);
        let image_memory = device
            .allocate_memory(
                &vk::MemoryAllocateInfo::default().allocation_size(req.size).memory_type_index(find_memory(
                    &instance,
                    physical,
                    req.memory_type_bits,
                    vk::MemoryPropertyFlags::DEVICE_LOCAL,
                )),
                None,
            )
            .map_err(|e| e.to_string())?;
        device.bind_image_memory(image, image_memory, 0).map_err(|e| e.to_string())?;
        let bytes = u64::from(4 * W * H);
        let readback = device
            .create_buffer(
                &vk::BufferCreateInfo::default().size(bytes).usage(vk::BufferUsageFlags::TRANSFER_DST),
                None,
            )
            .map_err(|e| e.to_string())?;
        let req = device.get_buffer_memory_requirements(readback);
        let host_visible = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
        let readback_memory =
            device
                .allocate_memory(
                    &vk::MemoryAllocateInfo::default().allocation_size(req.size).memory_type_index(
                        find_memory(&instance, physical, req.memory_type_bits, host_visible),
                    ),
                    None,
                )
                .map_err(|e| e.to_string())?;
        device.bind_buffer_memory(readback, readback_memory, 0).map_err(|e| e.to_string())?;

        // Hand everything to galerkin.
        let gpu = Gpu::from_raw(
            RawDevice {
                entry: entry.clone(),
                instance: instance.clone(),
                physical_device: physical,
                device: device.clone(),
                queue_family: family,
                queue,
                enabled_features: features,
            },
            &GpuDesc { validation: false, ..GpuDesc::default() },
        )
        .map_err(|e| e.to_string())?;

        // galerkin's resources (uploaded with galerkin's own submissions on the host's queue,
        // which the host is not using meanwhile).
        let n = 100_000;
        let x: Vec<f32> = (0..n).map(|i| (i as f32 * 0.37).sin()).collect();
        let y: Vec<f32> = (0..n).map(|i| (i as f32 * 0.11).cos()).collect();
        let a = 1.75;
        let xb = Buffer::from_slice(&gpu, "host x", &x, vk::BufferUsageFlags::STORAGE_BUFFER)
            .map_err(|e| e.to_string())?;
        let yb = Buffer::from_slice(&gpu, "host y", &y, vk::BufferUsageFlags::STORAGE_BUFFER)
            .map_err(|e| e.to_string())?;
        let axpy = Axpy::new(&gpu).map_err(|e| e.to_string())?;
        let axpy_set = axpy.bind(&gpu, &xb, &yb).map_err(|e| e.to_string())?;
        let target = RenderTarget::from_host_image(&gpu, "host image", image, ColorFormat::Rgba8, W, H)
            .map_err(|e| e.to_string())?;
        let p = BivariateCubic { coefficients: [0.2, -0.5, 0.9, 0.3, -1.1, 0.25, -0.35, 0.6, 0.15, 0.4] };
        let ramp = Ramp { lo: -2.0, hi: 2.0, log: false };
        let colormap = Colormap::cool_warm();
        let field = FieldPass::new(&gpu, target.render_pass(), &p, 6, &colormap, ramp, FieldOutput::Colour)
            .map_err(|e| e.to_string())?;
        let camera = Camera { eye: [-0.3, -2.4, 2.2], ..Camera::default() };

        // The host records its command buffer: galerkin's dispatch and draw, then its own copy.
        device
            .begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default())
            .map_err(|e| e.to_string())?;
        // The one unsafe step: galerkin records into the host's command buffer; the host keeps
        // the returned Recording until its fence shows the buffer completed.
        let mut rec = Recorder::from_host(&gpu, cmd);
        axpy.record(&gpu, &mut rec, &axpy_set, a);
        target.record_begin(&mut rec, [0.0, 0.0, 0.0, 1.0]);
        field.record(&mut rec, target.extent(), &camera);
        target.record_end(&mut rec);
        let recording = rec.finish();
        // galerkin leaves the image in TRANSFER_SRC_OPTIMAL, its writes made visible to transfers.
        let region = vk::BufferImageCopy {
            image_subresource: vk::ImageSubresourceLayers {
                aspect_mask: vk::ImageAspectFlags::COLOR,
                layer_count: 1,
                ..Default::default()
            },
            image_extent: vk::Extent3D { width: W, height: H, depth: 1 },
            ..Default::default()
        };
        device.cmd_copy_image_to_buffer(
            cmd,
            image,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            readback,
            &[region],
        );
        let host_read = vk::MemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
            .dst_access_mask(vk::AccessFlags::HOST_READ);
        device.cmd_pipeline_barrier(
            cmd,
            vk::PipelineStageFlags::TRANSFER,
            vk::PipelineStageFlags::HOST,
            vk::DependencyFlags::empty(),
            &[host_read],
            &[],
            &[],
        );
        device.end_command_buffer(cmd).map_err(|e| e.to_string())?;
        let cmds = [cmd];
        device
            .queue_submit(queue, &[vk::SubmitInfo::default().command_buffers(&cmds)], fence)
            .map_err(|e| e.to_string())?;
        device.wait_for_fences(&[fence], true, u64::MAX).map_err(|e| e.to_string())?;
        // The work completed: galerkin may release what it recorded.
        drop(recording);

        // The host reads its own image back and checks every pixel against the CPU reference.
        let mapped = device
            .map_memory(readback_memory, 0, bytes, vk::MemoryMapFlags::empty())
            .map_err(|e| e.to_string())?;
        let pixels = std::slice::from_raw_parts(mapped as *const u8, bytes as usize).to_vec();
        device.unmap_memory(readback_memory);
        let check = check_colours(&camera, &p, &colormap, ramp, W, H, &pixels, [0, 0, 0, 255]);
        // And galerkin's compute result (read back with galerkin's own submission).
        let out = yb.download(&gpu).map_err(|e| e.to_string())?;
        let (ratio, _) = axpy_error_ratio(f64::from(a), &x, &y, &out);

        // galerkin goes first and must destroy nothing of the host's.
        drop((field, target, axpy_set, axpy, xb, yb, gpu));

        // The host's device still works: use it once more, then tear down.
        device.reset_fences(&[fence]).map_err(|e| e.to_string())?;
        device.reset_command_pool(pool, vk::CommandPoolResetFlags::empty()).map_err(|e| e.to_string())?;
        device
            .begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default())
            .map_err(|e| e.to_string())?;
        device.end_command_buffer(cmd).map_err(|e| e.to_string())?;
        device
            .queue_submit(queue, &[vk::SubmitInfo::default().command_buffers(&cmds)], fence)
            .map_err(|e| e.to_string())?;
        device.wait_for_fences(&[fence], true, u64::MAX).map_err(|e| e.to_string())?;
        device.destroy_buffer(readback, None);
        device.free_memory(readback_memory, None);
        device.destroy_image(image, None);
        device.free_memory(image_memory, None);
        device.destroy_fence(fence, None);
        device.destroy_command_pool(pool, None);
        device.destroy_device(None);
        if validated {
            debug.destroy_debug_utils_messenger(messenger, None);
        }
        instance.destroy_instance(None);
        Ok(HostReport {
            validation_errors: ERRORS.load(Ordering::SeqCst),
            first_error: FIRST_ERROR.lock().map(|s| s.clone()).unwrap_or_default(),
            validated,
            pixels_checked: check.checked,
            pixel_failures: check.failures,
            axpy_error_ratio: ratio,
        })
    }
}

#[allow(dead_code)]
fn main() {
    match run_host(false) {
        Ok(r) => {
            println!("{r:#?}");
            let ok = r.validation_errors == 0
                && r.pixel_failures == 0
                && r.pixels_checked > 0
                && r.axpy_error_ratio <= 1.0;
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
