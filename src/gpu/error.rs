//! Errors of the Vulkan layer: only what a caller cannot anticipate or must tell a user —
//! a missing package, no device, out of memory, device loss, a request over the device's limits.
//! Misuse of the API (wrong buffer length, recording outside a command buffer) is a bug and
//! panics with a message instead.

use ash::vk;

/// Everything that can go wrong in [`crate::gpu`].
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GpuError {
    /// The Vulkan loader library could not be opened.
    #[error(
        "cannot load the Vulkan loader ({detail}); install the Debian package `libvulkan1` \
         (scripts/install-deps.sh installs everything galerkin needs)"
    )]
    NoLoader {
        /// What the dynamic loader said.
        detail: String,
    },
    /// The loader works but no usable device was found.
    #[error(
        "no usable Vulkan device{detail}; for the CPU rasteriser install the Debian package \
         `mesa-vulkan-drivers` (lavapipe; scripts/install-deps.sh does) or check VK_DRIVER_FILES"
    )]
    NoDevice {
        /// Extra context: the devices seen, the name asked for.
        detail: String,
    },
    /// Validation was asked for (`GALERKIN_VALIDATION=1` or [`crate::gpu::GpuDesc::validation`])
    /// but the Khronos layer is not installed.
    #[error(
        "validation was requested but the layer VK_LAYER_KHRONOS_validation is not installed; \
         install the Debian package `vulkan-validationlayers` (or unset GALERKIN_VALIDATION)"
    )]
    NoValidationLayer,
    /// A device memory allocation failed: the device (or host) is out of memory.
    #[error("out of memory allocating `{name}` ({bytes} bytes): {detail}")]
    OutOfMemory {
        /// The allocation's name.
        name: String,
        /// Requested size.
        bytes: u64,
        /// What the allocator said.
        detail: String,
    },
    /// The device was lost (driver reset, hang, or a fault in a shader).
    #[error("the Vulkan device was lost during {during}")]
    DeviceLost {
        /// What was happening.
        during: &'static str,
    },
    /// A submission did not finish within [`crate::gpu::GpuDesc::fence_timeout`].
    #[error("GPU work did not finish within {seconds} s during {during}; the device may be hung")]
    Timeout {
        /// What was being waited for.
        during: &'static str,
        /// The limit that was exceeded.
        seconds: f64,
    },
    /// A request is larger than the device allows and cannot be split.
    #[error("`{name}` needs {requested} {unit} but the device allows at most {limit} ({limit_name})")]
    OverLimit {
        /// What was being created.
        name: String,
        /// The size asked for.
        requested: u64,
        /// The device limit.
        limit: u64,
        /// The limit's Vulkan name.
        limit_name: &'static str,
        /// Unit of both numbers.
        unit: &'static str,
    },
    /// A pipeline's description disagrees with what its shaders declare (push-constant bytes,
    /// bindings), read from their SPIR-V.
    #[error("pipeline `{pipeline}`: {detail}")]
    ShaderLayout {
        /// The pipeline's name.
        pipeline: String,
        /// What disagrees.
        detail: String,
    },
    /// An object made on one device was used with another [`crate::gpu::Gpu`].
    #[error("`{name}` belongs to another Vulkan device than the one it was used with")]
    WrongDevice {
        /// The object's name.
        name: String,
    },
    /// Host access to a buffer's memory that is not host-visible, or that recorded GPU work
    /// not yet known to be finished may still use.
    #[error("cannot map `{name}` from the host: {reason}")]
    NotMappable {
        /// The buffer's name.
        name: String,
        /// Why.
        reason: &'static str,
    },
    /// The device lacks a feature or extension the request needs.
    #[error("the device does not support {0}")]
    Unsupported(String),
    /// Any other Vulkan error, with the call that returned it.
    #[error("{call} failed: {result:?}")]
    Vk {
        /// The Vulkan entry point.
        call: &'static str,
        /// Its result code.
        result: vk::Result,
    },
}

/// Result alias of the Vulkan layer.
pub type GpuResult<T> = Result<T, GpuError>;

/// An error of any capability (spectral, spacetime, fluid, radiosity, the reduction core, the
/// render layer) that may stand for a device failure: how a host embedding galerkin tells
/// device loss and out-of-memory from a bad input, whichever capability returned it.
pub trait GpuFailure {
    /// The device error underneath, if this is one.
    fn gpu_error(&self) -> Option<&GpuError>;

    /// True if the Vulkan device was lost (the host must recreate it).
    fn is_device_lost(&self) -> bool {
        matches!(self.gpu_error(), Some(GpuError::DeviceLost { .. }))
    }

    /// True if device or host memory ran out.
    fn is_out_of_memory(&self) -> bool {
        matches!(self.gpu_error(), Some(GpuError::OutOfMemory { .. }))
    }
}

impl GpuFailure for GpuError {
    fn gpu_error(&self) -> Option<&GpuError> {
        Some(self)
    }
}

/// Adds the name of the failing Vulkan call to a raw `VkResult`, mapping out-of-memory and
/// device loss to their own variants.
pub(crate) trait VkContext<T> {
    /// Names the call that produced this result.
    fn vk(self, call: &'static str) -> GpuResult<T>;
}

impl<T> VkContext<T> for Result<T, vk::Result> {
    fn vk(self, call: &'static str) -> GpuResult<T> {
        self.map_err(|result| vk_error(call, result))
    }
}

/// The error for `result` returned by `call`: device loss and out-of-memory get their own
/// variants, anything else names the call.
pub(crate) fn vk_error(call: &'static str, result: vk::Result) -> GpuError {
    match result {
        vk::Result::ERROR_DEVICE_LOST => GpuError::DeviceLost { during: call },
        vk::Result::ERROR_OUT_OF_DEVICE_MEMORY | vk::Result::ERROR_OUT_OF_HOST_MEMORY => {
            GpuError::OutOfMemory { name: call.to_string(), bytes: 0, detail: format!("{result:?}") }
        }
        _ => GpuError::Vk { call, result },
    }
}
