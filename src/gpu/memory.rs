//! Device memory through gpu-allocator: every allocation has a name, and its kind says where it
//! lives (Kompute/kajiya style) instead of raw property flags.

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::{AllocationError, MemoryLocation};

use super::context::DeviceShared;
use super::error::{GpuError, GpuResult};

/// Where a resource's memory lives.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum MemoryKind {
    /// Device-local, not mapped: the working set. Filled and read through staging buffers.
    GpuOnly,
    /// Host-visible and coherent, written by the CPU: staging for uploads, small uniforms.
    CpuToGpu,
    /// Host-visible, preferably cached, read by the CPU: staging for readback.
    GpuToCpu,
}

impl MemoryKind {
    fn location(self) -> MemoryLocation {
        match self {
            Self::GpuOnly => MemoryLocation::GpuOnly,
            Self::CpuToGpu => MemoryLocation::CpuToGpu,
            Self::GpuToCpu => MemoryLocation::GpuToCpu,
        }
    }
}

impl DeviceShared {
    /// Allocates named memory for a resource with the given requirements. Sizes over the
    /// device's `maxMemoryAllocationSize` are refused with [`GpuError::OverLimit`].
    pub(crate) fn allocate(
        &self,
        name: &str,
        requirements: vk::MemoryRequirements,
        kind: MemoryKind,
        linear: bool,
    ) -> GpuResult<Allocation> {
        if requirements.size > self.caps.max_memory_allocation_size {
            return Err(GpuError::OverLimit {
                name: name.to_string(),
                requested: requirements.size,
                limit: self.caps.max_memory_allocation_size,
                limit_name: "maxMemoryAllocationSize",
                unit: "bytes",
            });
        }
        self.fault.allocation(name, requirements.size)?;
        let desc = AllocationCreateDesc {
            name,
            requirements,
            location: kind.location(),
            linear,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        };
        self.allocator().allocate(&desc).map_err(|e| match e {
            AllocationError::OutOfMemory => GpuError::OutOfMemory {
                name: name.to_string(),
                bytes: requirements.size,
                detail: "the device has no memory left for it".into(),
            },
            AllocationError::NoCompatibleMemoryTypeFound => {
                GpuError::Unsupported(format!("a memory type for `{name}` ({kind:?})"))
            }
            other => GpuError::OutOfMemory {
                name: name.to_string(),
                bytes: requirements.size,
                detail: other.to_string(),
            },
        })
    }

    /// Returns memory to the allocator.
    pub(crate) fn free(&self, allocation: Allocation) {
        if let Err(e) = self.allocator().free(allocation) {
            tracing::error!("gpu-allocator free failed: {e}");
        }
    }
}
