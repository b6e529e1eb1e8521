//! The host's own plain-Vulkan helpers (nothing of galerkin's): its validation messenger,
//! memory types, images and views, render pass, host-visible buffers and image barriers.

use std::ffi::c_void;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use ash::vk;

use super::HOST_DEPTH;

/// Validation errors the host's messenger saw.
pub static ERRORS: AtomicUsize = AtomicUsize::new(0);
/// The first of them.
pub static FIRST_ERROR: Mutex<String> = Mutex::new(String::new());

/// The host's debug-utils callback: counts validation errors and keeps the first message.
pub unsafe extern "system" fn host_messenger(
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

/// A memory type of `physical` allowed by `bits` with the properties `want`.
pub fn find_memory(
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

/// A device-local 2D image of the host's.
pub unsafe fn host_image(
    instance: &ash::Instance,
    device: &ash::Device,
    physical: vk::PhysicalDevice,
    width: u32,
    height: u32,
    format: vk::Format,
    usage: vk::ImageUsageFlags,
) -> Result<(vk::Image, vk::DeviceMemory), String> {
    // SAFETY: plain object creation on the host's device.
    unsafe {
        let image = device
            .create_image(
                &vk::ImageCreateInfo::default()
                    .image_type(vk::ImageType::TYPE_2D)
                    .format(format)
                    .extent(vk::Extent3D { width, height, depth: 1 })
                    .mip_levels(1)
                    .array_layers(1)
                    .samples(vk::SampleCountFlags::TYPE_1)
                    .tiling(vk::ImageTiling::OPTIMAL)
                    .usage(usage),
                None,
            )
            .map_err(|e| e.to_string())?;
        let req = device.get_image_memory_requirements(image);
        let memory = device
            .allocate_memory(
                &vk::MemoryAllocateInfo::default().allocation_size(req.size).memory_type_index(find_memory(
                    instance,
                    physical,
                    req.memory_type_bits,
                    vk::MemoryPropertyFlags::DEVICE_LOCAL,
                )),
                None,
            )
            .map_err(|e| e.to_string())?;
        device.bind_image_memory(image, memory, 0).map_err(|e| e.to_string())?;
        Ok((image, memory))
    }
}

/// A 2D view of one of the host's images.
pub unsafe fn host_view(
    device: &ash::Device,
    image: vk::Image,
    format: vk::Format,
    aspect: vk::ImageAspectFlags,
) -> Result<vk::ImageView, String> {
    let info = vk::ImageViewCreateInfo::default()
        .image(image)
        .view_type(vk::ImageViewType::TYPE_2D)
        .format(format)
        .subresource_range(vk::ImageSubresourceRange {
            aspect_mask: aspect,
            level_count: 1,
            layer_count: 1,
            ..Default::default()
        });
    // SAFETY: `image` is the host's live image of `format`.
    unsafe { device.create_image_view(&info, None) }.map_err(|e| e.to_string())
}

/// The host's render pass over its composite: colour cleared, stored and left in
/// TRANSFER_SRC_OPTIMAL for its post-pass and readback; depth cleared, not stored. Its external
/// dependencies order the previous frame's transfers (the blit into the composite, the
/// readback from it) before the pass's attachment writes, and those writes before later
/// transfers.
pub unsafe fn host_render_pass(device: &ash::Device, colour: vk::Format) -> Result<vk::RenderPass, String> {
    let attachments = [
        vk::AttachmentDescription::default()
            .format(colour)
            .samples(vk::SampleCountFlags::TYPE_1)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .initial_layout(vk::ImageLayout::UNDEFINED)
            .final_layout(vk::ImageLayout::TRANSFER_SRC_OPTIMAL),
        vk::AttachmentDescription::default()
            .format(HOST_DEPTH)
            .samples(vk::SampleCountFlags::TYPE_1)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::DONT_CARE)
            .initial_layout(vk::ImageLayout::UNDEFINED)
            .final_layout(vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL),
    ];
    let colour_ref =
        [vk::AttachmentReference { attachment: 0, layout: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL }];
    let depth_ref =
        vk::AttachmentReference { attachment: 1, layout: vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL };
    let subpasses = [vk::SubpassDescription::default()
        .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
        .color_attachments(&colour_ref)
        .depth_stencil_attachment(&depth_ref)];
    let tests = vk::PipelineStageFlags::EARLY_FRAGMENT_TESTS | vk::PipelineStageFlags::LATE_FRAGMENT_TESTS;
    let dependencies = [
        vk::SubpassDependency {
            src_subpass: vk::SUBPASS_EXTERNAL,
            dst_subpass: 0,
            src_stage_mask: vk::PipelineStageFlags::TRANSFER | tests,
            dst_stage_mask: vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT | tests,
            src_access_mask: vk::AccessFlags::TRANSFER_WRITE
                | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE,
            dst_access_mask: vk::AccessFlags::COLOR_ATTACHMENT_WRITE
                | vk::AccessFlags::COLOR_ATTACHMENT_READ
                | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_READ
                | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE,
            dependency_flags: vk::DependencyFlags::empty(),
        },
        vk::SubpassDependency {
            src_subpass: 0,
            dst_subpass: vk::SUBPASS_EXTERNAL,
            src_stage_mask: vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
            dst_stage_mask: vk::PipelineStageFlags::TRANSFER,
            src_access_mask: vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
            dst_access_mask: vk::AccessFlags::TRANSFER_READ | vk::AccessFlags::TRANSFER_WRITE,
            dependency_flags: vk::DependencyFlags::empty(),
        },
    ];
    let info = vk::RenderPassCreateInfo::default()
        .attachments(&attachments)
        .subpasses(&subpasses)
        .dependencies(&dependencies);
    // SAFETY: valid create info on the host's device.
    unsafe { device.create_render_pass(&info, None) }.map_err(|e| e.to_string())
}

/// A host-visible, coherent transfer-destination buffer of the host's.
pub unsafe fn host_buffer(
    instance: &ash::Instance,
    device: &ash::Device,
    physical: vk::PhysicalDevice,
    bytes: u64,
) -> Result<(vk::Buffer, vk::DeviceMemory), String> {
    // SAFETY: plain object creation on the host's device.
    unsafe {
        let buffer = device
            .create_buffer(
                &vk::BufferCreateInfo::default().size(bytes).usage(vk::BufferUsageFlags::TRANSFER_DST),
                None,
            )
            .map_err(|e| e.to_string())?;
        let req = device.get_buffer_memory_requirements(buffer);
        let host_visible = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
        let memory =
            device
                .allocate_memory(
                    &vk::MemoryAllocateInfo::default().allocation_size(req.size).memory_type_index(
                        find_memory(instance, physical, req.memory_type_bits, host_visible),
                    ),
                    None,
                )
                .map_err(|e| e.to_string())?;
        device.bind_buffer_memory(buffer, memory, 0).map_err(|e| e.to_string())?;
        Ok((buffer, memory))
    }
}

/// The host's own image barrier with a layout transition.
pub unsafe fn image_barrier(
    device: &ash::Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    from: (vk::ImageLayout, vk::PipelineStageFlags, vk::AccessFlags),
    to: (vk::ImageLayout, vk::PipelineStageFlags, vk::AccessFlags),
) {
    let barrier = vk::ImageMemoryBarrier::default()
        .old_layout(from.0)
        .new_layout(to.0)
        .src_access_mask(from.2)
        .dst_access_mask(to.2)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(vk::ImageSubresourceRange {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            level_count: 1,
            layer_count: 1,
            ..Default::default()
        });
    // SAFETY: `cmd` is recording on `device` and `image` is the host's live image.
    unsafe {
        device.cmd_pipeline_barrier(cmd, from.1, to.1, vk::DependencyFlags::empty(), &[], &[], &[barrier])
    };
}
