//! What an embedding application makes with plain Vulkan calls on the engine's device, for
//! the tests that play the host: a command pool with one primary command buffer and a fence,
//! and a render pass with its framebuffer over the host's images.

use galerkin::gpu::{vk, Gpu, Viewport};

/// A command pool, one primary command buffer and a fence made by the "host" on the engine's
/// device, as an embedding application would.
pub struct HostCommands<'g> {
    pub gpu: &'g Gpu,
    pub pool: vk::CommandPool,
    pub cmd: vk::CommandBuffer,
    pub fence: vk::Fence,
}

impl<'g> HostCommands<'g> {
    pub fn new(gpu: &'g Gpu) -> Self {
        let d = gpu.device();
        // SAFETY: plain object creation on a live device.
        unsafe {
            let pool = d
                .create_command_pool(
                    &vk::CommandPoolCreateInfo::default().queue_family_index(gpu.queue_family()),
                    None,
                )
                .unwrap();
            let info = vk::CommandBufferAllocateInfo::default()
                .command_pool(pool)
                .level(vk::CommandBufferLevel::PRIMARY)
                .command_buffer_count(1);
            let cmd = d.allocate_command_buffers(&info).unwrap()[0];
            let fence = d.create_fence(&vk::FenceCreateInfo::default(), None).unwrap();
            d.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default()).unwrap();
            Self { gpu, pool, cmd, fence }
        }
    }

    /// Ends, submits on the engine's queue (nothing else uses it meanwhile) and waits.
    pub fn submit_and_wait(&self) {
        let d = self.gpu.device();
        let cmds = [self.cmd];
        // SAFETY: the buffer was recorded on this device; the queue is idle otherwise.
        unsafe {
            d.end_command_buffer(self.cmd).unwrap();
            let queue = d.get_device_queue(self.gpu.queue_family(), 0);
            d.queue_submit(queue, &[vk::SubmitInfo::default().command_buffers(&cmds)], self.fence).unwrap();
            d.wait_for_fences(&[self.fence], true, u64::MAX).unwrap();
        }
    }
}

impl Drop for HostCommands<'_> {
    fn drop(&mut self) {
        // SAFETY: the buffer's work (if submitted) has completed.
        unsafe {
            self.gpu.device().destroy_fence(self.fence, None);
            self.gpu.device().destroy_command_pool(self.pool, None);
        }
    }
}

/// A host's single-subpass render pass: one colour attachment of `format` (cleared, stored,
/// left in `TRANSFER_SRC_OPTIMAL`) and optionally a depth attachment, with a framebuffer over
/// views of the given images, all made and destroyed by the "host".
pub struct HostPass<'g> {
    pub gpu: &'g Gpu,
    pub raw: vk::RenderPass,
    pub framebuffer: vk::Framebuffer,
    views: Vec<vk::ImageView>,
    pub extent: vk::Extent2D,
}

impl<'g> HostPass<'g> {
    /// A pass over `colour` (and `depth`), which are live images of the given formats.
    pub fn new(
        gpu: &'g Gpu,
        colour: (vk::Image, vk::Format),
        depth: Option<(vk::Image, vk::Format)>,
        extent: vk::Extent2D,
    ) -> Self {
        let d = gpu.device();
        let mut attachments = vec![vk::AttachmentDescription::default()
            .format(colour.1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .initial_layout(vk::ImageLayout::UNDEFINED)
            .final_layout(vk::ImageLayout::TRANSFER_SRC_OPTIMAL)];
        if let Some((_, f)) = depth {
            attachments.push(
                vk::AttachmentDescription::default()
                    .format(f)
                    .samples(vk::SampleCountFlags::TYPE_1)
                    .load_op(vk::AttachmentLoadOp::CLEAR)
                    .store_op(vk::AttachmentStoreOp::DONT_CARE)
                    .initial_layout(vk::ImageLayout::UNDEFINED)
                    .final_layout(vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL),
            );
        }
        let colour_ref =
            [vk::AttachmentReference { attachment: 0, layout: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL }];
        let depth_ref = vk::AttachmentReference {
            attachment: 1,
            layout: vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
        };
        let mut subpass = vk::SubpassDescription::default()
            .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
            .color_attachments(&colour_ref);
        if depth.is_some() {
            subpass = subpass.depth_stencil_attachment(&depth_ref);
        }
        let subpasses = [subpass];
        let dependencies = [vk::SubpassDependency {
            src_subpass: 0,
            dst_subpass: vk::SUBPASS_EXTERNAL,
            src_stage_mask: vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
            dst_stage_mask: vk::PipelineStageFlags::TRANSFER,
            src_access_mask: vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
            dst_access_mask: vk::AccessFlags::TRANSFER_READ,
            dependency_flags: vk::DependencyFlags::empty(),
        }];
        let info = vk::RenderPassCreateInfo::default()
            .attachments(&attachments)
            .subpasses(&subpasses)
            .dependencies(&dependencies);
        let view = |(image, format): (vk::Image, vk::Format), aspect| {
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
            // SAFETY: a live image of this device and format.
            unsafe { d.create_image_view(&info, None) }.unwrap()
        };
        let mut views = vec![view(colour, vk::ImageAspectFlags::COLOR)];
        views.extend(depth.map(|dp| view(dp, vk::ImageAspectFlags::DEPTH)));
        // SAFETY: plain object creation on a live device.
        unsafe {
            let raw = d.create_render_pass(&info, None).unwrap();
            let framebuffer = d
                .create_framebuffer(
                    &vk::FramebufferCreateInfo::default()
                        .render_pass(raw)
                        .attachments(&views)
                        .width(extent.width)
                        .height(extent.height)
                        .layers(1),
                    None,
                )
                .unwrap();
            Self { gpu, raw, framebuffer, views, extent }
        }
    }

    /// Records the beginning of the pass on `cmd`, clearing colour to `clear` and depth to 1.
    ///
    /// # Safety
    /// `cmd` is recording on the engine's device, outside any render pass.
    pub unsafe fn begin(&self, cmd: vk::CommandBuffer, clear: [f32; 4]) {
        let clears = [
            vk::ClearValue { color: vk::ClearColorValue { float32: clear } },
            vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } },
        ];
        let n = self.views.len();
        let info = vk::RenderPassBeginInfo::default()
            .render_pass(self.raw)
            .framebuffer(self.framebuffer)
            .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent: self.extent })
            .clear_values(&clears[..n]);
        // SAFETY: the caller's contract.
        unsafe { self.gpu.device().cmd_begin_render_pass(cmd, &info, vk::SubpassContents::INLINE) };
    }

    /// Records the end of the pass.
    ///
    /// # Safety
    /// `cmd` is recording inside this pass.
    pub unsafe fn end(&self, cmd: vk::CommandBuffer) {
        // SAFETY: the caller's contract.
        unsafe { self.gpu.device().cmd_end_render_pass(cmd) };
    }
}

impl Drop for HostPass<'_> {
    fn drop(&mut self) {
        let d = self.gpu.device();
        // SAFETY: no pending work uses them (the tests wait for their submissions).
        unsafe {
            d.destroy_framebuffer(self.framebuffer, None);
            d.destroy_render_pass(self.raw, None);
            for &v in &self.views {
                d.destroy_image_view(v, None);
            }
        }
    }
}

/// A host's own [`galerkin::gpu::Submitter`]: its command pool, a fresh primary command buffer
/// and fence per submission, submitted to the queue it owns (here the device's one queue,
/// which the engine does not use meanwhile); it keeps each submission's `Recording` until its
/// fence was waited for, as the trait requires. Counts its submissions.
pub struct HostSubmitter<'g> {
    gpu: &'g Gpu,
    pool: vk::CommandPool,
    pending: Vec<(vk::CommandBuffer, vk::Fence, galerkin::gpu::Recording)>,
    pub submissions: usize,
}

impl<'g> HostSubmitter<'g> {
    pub fn new(gpu: &'g Gpu) -> Self {
        let info = vk::CommandPoolCreateInfo::default().queue_family_index(gpu.queue_family());
        // SAFETY: plain object creation on a live device.
        let pool = unsafe { gpu.device().create_command_pool(&info, None) }.unwrap();
        Self { gpu, pool, pending: Vec::new(), submissions: 0 }
    }
}

impl galerkin::gpu::Submitter for HostSubmitter<'_> {
    fn gpu(&self) -> &Gpu {
        self.gpu
    }

    fn record_and_submit(
        &mut self,
        record: &mut dyn FnMut(&mut galerkin::gpu::Recorder<'_>),
    ) -> galerkin::gpu::GpuResult<()> {
        let d = self.gpu.device();
        // SAFETY: the host's own objects on a live device; the command buffer is recorded on
        // this thread only and its Recording is kept until its fence has been waited for.
        unsafe {
            let info = vk::CommandBufferAllocateInfo::default()
                .command_pool(self.pool)
                .level(vk::CommandBufferLevel::PRIMARY)
                .command_buffer_count(1);
            let cmd = d.allocate_command_buffers(&info).unwrap()[0];
            d.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default()).unwrap();
            let mut rec = galerkin::gpu::Recorder::from_host(self.gpu, cmd);
            record(&mut rec);
            let recording = rec.finish();
            d.end_command_buffer(cmd).unwrap();
            let fence = d.create_fence(&vk::FenceCreateInfo::default(), None).unwrap();
            let queue = d.get_device_queue(self.gpu.queue_family(), 0);
            let cmds = [cmd];
            d.queue_submit(queue, &[vk::SubmitInfo::default().command_buffers(&cmds)], fence).unwrap();
            self.pending.push((cmd, fence, recording));
        }
        self.submissions += 1;
        Ok(())
    }

    fn complete(&mut self) -> galerkin::gpu::GpuResult<()> {
        let d = self.gpu.device();
        for (cmd, fence, recording) in self.pending.drain(..) {
            // SAFETY: the fence and command buffer are the host's; the buffer is freed only
            // after its fence signalled, and then its Recording is released.
            unsafe {
                d.wait_for_fences(&[fence], true, u64::MAX).unwrap();
                d.destroy_fence(fence, None);
                d.free_command_buffers(self.pool, &[cmd]);
            }
            drop(recording);
        }
        Ok(())
    }
}

impl Drop for HostSubmitter<'_> {
    fn drop(&mut self) {
        use galerkin::gpu::Submitter;
        let _ = self.complete();
        // SAFETY: every command buffer of the pool has completed and been freed.
        unsafe { self.gpu.device().destroy_command_pool(self.pool, None) };
    }
}

/// Compares a host's RGBA8 frame of `fb` (`got`, row-major) with galerkin's offscreen render of
/// `viewport` (`want`, its top-left pixel uncovered): inside the viewport a pixel must equal
/// the render's where the render covers it and the host's clear (`grey`, opaque) elsewhere;
/// outside it, the clear. Returns how many covered pixels were compared and how many pixels
/// differ.
pub fn differing_from_offscreen(
    got: &[u8],
    want: &[u8],
    fb: vk::Extent2D,
    viewport: Viewport,
    grey: u8,
) -> (usize, usize) {
    let uncovered = &want[..4];
    let clear = [grey, grey, grey, 255];
    let (mut covered, mut differing) = (0, 0);
    for y in 0..fb.height {
        for x in 0..fb.width {
            let i = 4 * (y * fb.width + x) as usize;
            let inside = (viewport.x..viewport.x + viewport.width).contains(&x)
                && (viewport.y..viewport.y + viewport.height).contains(&y);
            let expected = if inside {
                let j = 4 * ((y - viewport.y) * viewport.width + (x - viewport.x)) as usize;
                let w = &want[j..j + 4];
                if w == uncovered {
                    clear
                } else {
                    covered += 1;
                    [w[0], w[1], w[2], w[3]]
                }
            } else {
                clear
            };
            differing += usize::from(got[i..i + 4] != expected);
        }
    }
    (covered, differing)
}
