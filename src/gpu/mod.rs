//! The Vulkan layer: a device context that is either the engine's own or adopted from a host,
//! memory through gpu-allocator, typed buffers, images, pipelines built from embedded SPIR-V,
//! descriptor sets, submission with fences, deferred destruction, timestamp scopes, and the
//! validation canary. It knows nothing of fluids, radiosity or elements.
//!
//! Conventions (see `DESIGN.md`):
//! - The Vulkan handle field is `raw`; shared device state lives in one `Arc<DeviceShared>`
//!   that every resource holds, so the device outlives its resources.
//! - Passes record through a [`Recorder`] they are handed — over the engine's command buffer
//!   ([`Gpu::run`], which submits and waits on its own fence, never `vkDeviceWaitIdle`) or a
//!   host's ([`Recorder::from_host`]) — and never submit. Jobs that need several submissions
//!   (host work between device steps) take a [`Submitter`]: the engine's queue
//!   ([`Gpu::submitter`]) or a host's.
//! - Every object frees itself when it and every recording and descriptor set that use it are
//!   gone ([`Lifetime`]): a recording keeps what it recorded until its work is known to be
//!   finished, so no safe code can destroy an object the device may still use.
//! - Every command states what it reads and writes ([`Access`]) and the recorder derives the
//!   barriers (with synchronization2 where the device has it); images' layouts are tracked.
//! - Objects remember their device; using one with another [`Gpu`] is an error or a panic.
//! - Device limits are read once ([`Capabilities`]) and respected: arrays larger than one
//!   storage binding (128 MiB on lavapipe) are bound in chunks ([`Buffer::binding_chunks`]).

mod access;
mod buffer;
mod caps;
mod commands;
mod context;
mod debug;
mod descriptors;
mod error;
mod fault;
mod image;
mod image_ops;
mod instance;
mod lifetime;
mod memory;
mod pipeline;
mod push;
mod query;
mod recorder;
pub mod reflect;
mod renderpass;
mod retire;
pub mod shaders;
mod slot;
mod staging;
mod submitter;
#[cfg(feature = "viewer")]
mod swapchain;

pub use access::Access;
pub use ash::vk;
pub use buffer::{chunk_elements, Buffer, BufferBinding, Chunk, STAGING_CHUNK_BYTES};
/// Re-exported for [`crate::push_constants!`].
pub use bytemuck;
pub use caps::Capabilities;
pub use commands::Submission;
pub use context::{Gpu, GpuDesc, RawDevice};
pub use debug::ValidationLog;
pub use descriptors::{BindingKind, DescriptorSet, DescriptorSetLayout, Resource};
pub use error::{GpuError, GpuFailure, GpuResult};
pub use image::{texel_bytes, ForeignImage, Image, ImageDesc, ImageResource, ImageTracking, Sampler};
pub use lifetime::{Lifetime, Tracked};
pub use memory::MemoryKind;
pub use pipeline::{
    spirv_local_size, ComputePipeline, ComputePipelineDesc, GraphicsPipeline, GraphicsPipelineDesc,
    VertexAttribute, Viewport,
};
pub use push::{PushConstants, PushLayout, PushMember, PushScalar, Scalar};
pub use query::Profiler;
pub use recorder::{Recorder, Recording};
pub use renderpass::{
    is_drawable_color_format, Attachment, ForeignView, Framebuffer, HostRenderPass, PassKey, RenderPass,
};
pub use submitter::{EngineSubmitter, Readback, Submitter};
#[cfg(feature = "viewer")]
pub use swapchain::{surface_extensions, Surface, Swapchain};
