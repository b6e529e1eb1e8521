//! A submission's command pool, command buffer and fence, reused across submissions (the
//! free ones wait in the device's [`super::retire::Tracker`]).

use ash::vk;

use super::context::DeviceShared;
use super::error::{vk_error, GpuResult, VkContext};

/// One submission's command pool (its own, so recording on several threads needs no lock),
/// its one command buffer and its fence.
#[derive(Clone, Copy)]
pub(crate) struct Slot {
    pub pool: vk::CommandPool,
    pub cmd: vk::CommandBuffer,
    pub fence: vk::Fence,
}

impl Slot {
    pub(crate) fn new(shared: &DeviceShared) -> GpuResult<Self> {
        let info = vk::CommandPoolCreateInfo::default().queue_family_index(shared.queue_family);
        // SAFETY: plain object creation on this device.
        let pool = unsafe { shared.raw.create_command_pool(&info, None) }.vk("vkCreateCommandPool")?;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: `pool` is new and used by this thread only.
        let cmd = match unsafe { shared.raw.allocate_command_buffers(&alloc) } {
            Ok(c) => c[0],
            Err(e) => {
                // SAFETY: nothing else uses the new pool.
                unsafe { shared.raw.destroy_command_pool(pool, None) };
                return Err(vk_error("vkAllocateCommandBuffers", e));
            }
        };
        // SAFETY: plain object creation.
        match unsafe { shared.raw.create_fence(&vk::FenceCreateInfo::default(), None) } {
            Ok(fence) => Ok(Self { pool, cmd, fence }),
            Err(e) => {
                // SAFETY: the pool (and its buffer) were never submitted.
                unsafe { shared.raw.destroy_command_pool(pool, None) };
                Err(vk_error("vkCreateFence", e))
            }
        }
    }

    /// Resets the pool (and so the buffer) for reuse; the fence must already be unsignalled.
    pub(crate) fn reset(&self, shared: &DeviceShared) -> bool {
        // SAFETY: the slot's work is finished or was never submitted.
        unsafe { shared.raw.reset_command_pool(self.pool, vk::CommandPoolResetFlags::empty()) }.is_ok()
    }

    /// Destroys the slot's objects.
    pub(crate) fn destroy(self, shared: &DeviceShared) {
        // SAFETY: the slot's work is finished or was never submitted.
        unsafe {
            shared.raw.destroy_fence(self.fence, None);
            shared.raw.destroy_command_pool(self.pool, None);
        }
    }
}
