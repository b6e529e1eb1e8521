//! What the device can do, read once when the context is made: limits, subgroup size, memory
//! types, the features galerkin cares about. Every size decision (binding chunks, dispatch
//! grids, shared-memory tiles) reads these, never hard-coded numbers.

use std::ffi::CStr;

use ash::vk;

use super::error::{GpuError, GpuResult};

/// The device's capabilities as galerkin uses them.
#[derive(Clone, Debug)]
pub struct Capabilities {
    /// `VkPhysicalDeviceProperties::deviceName`.
    pub device_name: String,
    /// Discrete, integrated, virtual or CPU.
    pub device_type: vk::PhysicalDeviceType,
    /// Vulkan API version the device reports, as (major, minor, patch).
    pub api_version: (u32, u32, u32),
    /// Driver name and info (`VkPhysicalDeviceDriverProperties`), e.g. "llvmpipe" / "Mesa 25.0.7".
    pub driver: String,
    /// Vendor and device ids.
    pub vendor_id: u32,
    /// Device id.
    pub device_id: u32,
    /// Largest range one storage-buffer descriptor may cover (128 MiB on lavapipe).
    pub max_storage_buffer_range: u64,
    /// Largest range one uniform-buffer descriptor may cover.
    pub max_uniform_buffer_range: u64,
    /// Alignment of storage-buffer descriptor offsets.
    pub min_storage_buffer_offset_alignment: u64,
    /// Largest single memory allocation.
    pub max_memory_allocation_size: u64,
    /// Largest buffer (`maxBufferSize`, Vulkan 1.3; `u64::MAX` when unknown).
    pub max_buffer_size: u64,
    /// `maxComputeWorkGroupCount`.
    pub max_compute_work_group_count: [u32; 3],
    /// `maxComputeWorkGroupInvocations`.
    pub max_compute_work_group_invocations: u32,
    /// `maxComputeWorkGroupSize`.
    pub max_compute_work_group_size: [u32; 3],
    /// `maxComputeSharedMemorySize` in bytes (32 KiB on lavapipe).
    pub max_compute_shared_memory_size: u32,
    /// Subgroup size (8 on lavapipe; never assume 32).
    pub subgroup_size: u32,
    /// `maxPushConstantsSize`.
    pub max_push_constants_size: u32,
    /// `maxImageDimension2D`.
    pub max_image_dimension_2d: u32,
    /// `maxFragmentInputComponents`.
    pub max_fragment_input_components: u32,
    /// Nanoseconds per timestamp tick; `None` if the queue cannot write timestamps.
    pub timestamp_period_ns: Option<f64>,
    /// `shaderFloat64`.
    pub shader_float64: bool,
    /// `geometryShader` was enabled.
    pub geometry_shader: bool,
    /// `tessellationShader` was enabled.
    pub tessellation_shader: bool,
    /// `fillModeNonSolid` was enabled (wireframe overdraw).
    pub fill_mode_non_solid: bool,
    /// Dynamic rendering was enabled (Vulkan 1.3's `dynamicRendering`, or
    /// `VK_KHR_dynamic_rendering`): galerkin's pipelines can then be built for a host's
    /// `vkCmdBeginRendering` ([`crate::gpu::RenderPass::dynamic`]).
    pub dynamic_rendering: bool,
    /// Synchronization2 was enabled (Vulkan 1.3's `synchronization2`): barriers are recorded
    /// with `vkCmdPipelineBarrier2` ([`crate::gpu::Access`]), otherwise with Vulkan 1.0's call.
    pub synchronization2: bool,
    /// Memory types: (property flags, heap index).
    pub memory_types: Vec<(vk::MemoryPropertyFlags, u32)>,
    /// Memory heaps: (size in bytes, flags).
    pub memory_heaps: Vec<(u64, vk::MemoryHeapFlags)>,
}

impl Capabilities {
    /// Reads everything from `physical`. `enabled` is the feature set the device was created
    /// with, `dynamic_rendering` and `synchronization2` whether those Vulkan 1.3 features were
    /// enabled (for an adopted device, what the host says it enabled).
    pub(crate) fn read(
        instance: &ash::Instance,
        physical: vk::PhysicalDevice,
        queue_family: u32,
        enabled: &vk::PhysicalDeviceFeatures,
        dynamic_rendering: bool,
        synchronization2: bool,
    ) -> Self {
        let mut driver = vk::PhysicalDeviceDriverProperties::default();
        let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
        let mut maint3 = vk::PhysicalDeviceMaintenance3Properties::default();
        // SAFETY: `physical` belongs to `instance`; the chained structs outlive the call.
        let api = unsafe { instance.get_physical_device_properties(physical) }.api_version;
        let mut props2 =
            vk::PhysicalDeviceProperties2::default().push_next(&mut subgroup).push_next(&mut maint3);
        if vk::api_version_minor(api) >= 2 || vk::api_version_major(api) > 1 {
            props2 = props2.push_next(&mut driver);
        }
        // SAFETY: as above; Vulkan 1.1 core entry point (galerkin requires 1.2).
        unsafe { instance.get_physical_device_properties2(physical, &mut props2) };
        let props = props2.properties;
        let limits = props.limits;
        // SAFETY: as above.
        let memory = unsafe { instance.get_physical_device_memory_properties(physical) };
        // SAFETY: as above.
        let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
        let ts_bits = families.get(queue_family as usize).map_or(0, |f| f.timestamp_valid_bits);
        let cstr = |bytes: &[std::ffi::c_char]| {
            // SAFETY: Vulkan strings in these structs are NUL-terminated within their arrays.
            unsafe { CStr::from_ptr(bytes.as_ptr()) }.to_string_lossy().into_owned()
        };
        let driver_text = {
            let name = cstr(&driver.driver_name);
            let info = cstr(&driver.driver_info);
            if name.is_empty() {
                format!("driver version {:#x}", props.driver_version)
            } else {
                format!("{name} ({info})")
            }
        };
        let max_buffer_size = {
            let mut m4 = vk::PhysicalDeviceMaintenance4Properties::default();
            if vk::api_version_minor(api) >= 3 || vk::api_version_major(api) > 1 {
                let mut p = vk::PhysicalDeviceProperties2::default().push_next(&mut m4);
                // SAFETY: Vulkan 1.3 device: the maintenance4 struct is core.
                unsafe { instance.get_physical_device_properties2(physical, &mut p) };
                m4.max_buffer_size
            } else {
                u64::MAX
            }
        };
        Self {
            device_name: cstr(&props.device_name),
            device_type: props.device_type,
            api_version: (vk::api_version_major(api), vk::api_version_minor(api), vk::api_version_patch(api)),
            driver: driver_text,
            vendor_id: props.vendor_id,
            device_id: props.device_id,
            max_storage_buffer_range: u64::from(limits.max_storage_buffer_range),
            max_uniform_buffer_range: u64::from(limits.max_uniform_buffer_range),
            min_storage_buffer_offset_alignment: limits.min_storage_buffer_offset_alignment.max(4),
            max_memory_allocation_size: maint3.max_memory_allocation_size,
            max_buffer_size,
            max_compute_work_group_count: limits.max_compute_work_group_count,
            max_compute_work_group_invocations: limits.max_compute_work_group_invocations,
            max_compute_work_group_size: limits.max_compute_work_group_size,
            max_compute_shared_memory_size: limits.max_compute_shared_memory_size,
            subgroup_size: subgroup.subgroup_size.max(1),
            max_push_constants_size: limits.max_push_constants_size,
            max_image_dimension_2d: limits.max_image_dimension2_d,
            max_fragment_input_components: limits.max_fragment_input_components,
            timestamp_period_ns: (ts_bits > 0 && limits.timestamp_compute_and_graphics == vk::TRUE)
                .then_some(f64::from(limits.timestamp_period)),
            shader_float64: enabled.shader_float64 == vk::TRUE,
            geometry_shader: enabled.geometry_shader == vk::TRUE,
            tessellation_shader: enabled.tessellation_shader == vk::TRUE,
            fill_mode_non_solid: enabled.fill_mode_non_solid == vk::TRUE,
            dynamic_rendering,
            synchronization2,
            memory_types: memory
                .memory_types_as_slice()
                .iter()
                .map(|t| (t.property_flags, t.heap_index))
                .collect(),
            memory_heaps: memory.memory_heaps_as_slice().iter().map(|h| (h.size, h.flags)).collect(),
        }
    }

    /// True when the device is a CPU rasteriser (lavapipe, SwiftShader): heavy precompute then
    /// prefers the native CPU path.
    pub fn is_cpu(&self) -> bool {
        self.device_type == vk::PhysicalDeviceType::CPU
    }

    /// Checks that a compute kernel's workgroup fits this device: `invocations` per group and
    /// `shared_bytes` of shared memory (Vulkan only promises 128 invocations and 16 KiB).
    pub fn check_workgroup(&self, kernel: &str, invocations: u32, shared_bytes: u32) -> GpuResult<()> {
        if invocations > self.max_compute_work_group_invocations {
            return Err(GpuError::OverLimit {
                name: format!("workgroup of `{kernel}`"),
                requested: u64::from(invocations),
                limit: u64::from(self.max_compute_work_group_invocations),
                limit_name: "maxComputeWorkGroupInvocations",
                unit: "invocations",
            });
        }
        if shared_bytes > self.max_compute_shared_memory_size {
            return Err(GpuError::OverLimit {
                name: format!("shared memory of `{kernel}`"),
                requested: u64::from(shared_bytes),
                limit: u64::from(self.max_compute_shared_memory_size),
                limit_name: "maxComputeSharedMemorySize",
                unit: "bytes",
            });
        }
        Ok(())
    }

    /// Workgroups for `n` items at `local_size` per group on axis x, clamped to the device's
    /// `maxComputeWorkGroupCount[0]`; kernels use a grid-stride loop for the rest.
    pub fn groups_1d(&self, n: u64, local_size: u32) -> u32 {
        let groups = n.div_ceil(u64::from(local_size)).max(1);
        groups.min(u64::from(self.max_compute_work_group_count[0])) as u32
    }
}
