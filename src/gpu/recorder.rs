//! Recording galerkin's GPU work. A [`Recorder`] wraps one command buffer in the recording
//! state — the engine's own ([`Gpu::run`], [`Gpu::submit`]) or a host application's
//! ([`Recorder::from_host`], the one `unsafe` entry point) — and is the only way a pass records
//! anything. Every object recorded through it is kept alive until the work is known to be
//! finished:
//!
//! - on the engine's own submissions, until their fence is seen signalled (the
//!   [`super::Submission`] holds the uses);
//! - on a host's command buffer, until the host drops the [`Recording`] that
//!   [`Recorder::finish`] returns — which it does once its own fence (or a queue or device
//!   wait) shows that the buffer completed.
//!
//! Compared with its models: wgpu-hal records unsafely and leaves lifetimes to its caller;
//! screen-13 defers drops to fences it owns; Kompute records then evaluates on its own queue.
//! Here recording is safe for the engine's and the host's buffers alike, lifetimes follow the
//! work, and the host keeps its own queue, fences and semaphores.
//!
//! Objects remember their device: recording one made on another [`Gpu`] is a bug and panics
//! naming it (fallible entry points such as uploads return [`GpuError::WrongDevice`] instead).

use std::sync::Arc;

use ash::vk;
use bytemuck::Pod;

use super::buffer::{Buffer, BufferBinding};
use super::context::Gpu;
use super::error::GpuError;
use super::lifetime::{Lifetime, Tracked, Use};

/// Recording into one command buffer (see the module docs).
pub struct Recorder<'g> {
    gpu: &'g Gpu,
    cmd: vk::CommandBuffer,
    uses: Vec<Use>,
    host: bool,
}

/// What a host's recording keeps alive: drop it once the command buffer it was recorded into
/// has completed execution (or was reset or freed without being submitted).
#[must_use = "dropping a Recording releases what it recorded: keep it until the work completed"]
pub struct Recording {
    uses: Vec<Use>,
    /// The device stays alive until the objects are released.
    _device: Arc<super::context::DeviceShared>,
}

impl std::fmt::Debug for Recording {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Recording").field("objects", &self.uses.len()).finish()
    }
}

impl Recording {
    /// Objects it keeps alive (each counted once per time it was recorded).
    pub fn objects(&self) -> usize {
        self.uses.len()
    }
}

impl<'g> Recorder<'g> {
    /// A recorder over the engine's own command buffer (begun by [`Gpu::submit`]).
    pub(crate) fn engine(gpu: &'g Gpu, cmd: vk::CommandBuffer) -> Self {
        Self { gpu, cmd, uses: Vec::new(), host: false }
    }

    /// A recorder over a host application's command buffer.
    ///
    /// # Safety
    /// - `cmd` is a primary command buffer of `gpu`'s device, in the recording state, and is
    ///   not recorded on another thread while this recorder lives;
    /// - its queue family supports graphics and compute (the passes use both);
    /// - the [`Recording`] that [`Recorder::finish`] returns is kept until `cmd` has completed
    ///   execution (its fence was seen signalled, or its queue or device waited idle) or was
    ///   reset or freed without being submitted. A recorder dropped without `finish` keeps its
    ///   objects until the [`Gpu`] is dropped.
    pub unsafe fn from_host(gpu: &'g Gpu, cmd: vk::CommandBuffer) -> Self {
        Self { gpu, cmd, uses: Vec::new(), host: true }
    }

    /// Ends recording through this recorder (the command buffer itself stays in the recording
    /// state: the host ends and submits it).
    pub fn finish(mut self) -> Recording {
        Recording { uses: std::mem::take(&mut self.uses), _device: self.gpu.shared.clone() }
    }

    /// The uses of an engine recording, for its submission.
    pub(crate) fn into_uses(mut self) -> Vec<Use> {
        std::mem::take(&mut self.uses)
    }

    /// The device context it records for.
    pub fn gpu(&self) -> &'g Gpu {
        self.gpu
    }

    /// The `ash` device (for passes that record a command the recorder has no method for;
    /// such a pass must [`Recorder::keep`] every object it names).
    pub fn device(&self) -> &'g ash::Device {
        self.gpu.device()
    }

    /// The command buffer (recording into it directly is `unsafe`, and the caller must
    /// [`Recorder::keep`] every object it records).
    pub fn raw(&self) -> vk::CommandBuffer {
        self.cmd
    }

    /// Keeps `object` alive until this recording's work has finished. Panics if the object
    /// belongs to another device (a bug: recording it would be undefined behaviour).
    pub fn keep(&mut self, object: &impl Tracked) {
        self.keep_lifetime(object.lifetime());
    }

    pub(crate) fn keep_lifetime(&mut self, life: &Arc<Lifetime>) {
        assert!(life.is_on(&self.gpu.shared), "{}", GpuError::WrongDevice { name: life.name().to_string() });
        self.uses.push(Use::new(life));
    }

    /// Records a global memory barrier (the common case between passes: one pass writes a
    /// buffer, the next reads it).
    pub fn memory_barrier(
        &mut self,
        src: (vk::PipelineStageFlags, vk::AccessFlags),
        dst: (vk::PipelineStageFlags, vk::AccessFlags),
    ) {
        let barrier = vk::MemoryBarrier::default().src_access_mask(src.1).dst_access_mask(dst.1);
        // SAFETY: `cmd` is recording on this device (the recorder's invariant).
        unsafe {
            self.device().cmd_pipeline_barrier(
                self.cmd,
                src.0,
                dst.0,
                vk::DependencyFlags::empty(),
                &[barrier],
                &[],
                &[],
            )
        };
    }

    /// Compute shader writes → compute shader reads and writes.
    pub fn compute_to_compute_barrier(&mut self) {
        self.memory_barrier(
            (vk::PipelineStageFlags::COMPUTE_SHADER, vk::AccessFlags::SHADER_WRITE),
            (
                vk::PipelineStageFlags::COMPUTE_SHADER,
                vk::AccessFlags::SHADER_READ | vk::AccessFlags::SHADER_WRITE,
            ),
        );
    }

    /// Records `vkCmdFillBuffer` of the whole of `buffer` with the 32-bit pattern `word`
    /// (outside a render pass; a transfer write).
    pub fn fill_buffer<T: Pod>(&mut self, buffer: &Buffer<T>, word: u32) {
        self.keep(buffer);
        // SAFETY: recording on this device; a whole-size fill of a live buffer is valid.
        unsafe { self.device().cmd_fill_buffer(self.cmd, buffer.raw(), 0, vk::WHOLE_SIZE, word) };
    }

    /// Records `vkCmdUpdateBuffer` of `data` at element `first` of `buffer` (outside a render
    /// pass; a transfer write). Panics unless the bytes are a multiple of 4, at most 65,536,
    /// and inside the buffer.
    pub fn update_buffer<T: Pod>(&mut self, buffer: &Buffer<T>, first: u64, data: &[T]) {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let offset = first * std::mem::size_of::<T>() as u64;
        assert!(
            bytes.len().is_multiple_of(4)
                && offset.is_multiple_of(4)
                && bytes.len() <= 65_536
                && !bytes.is_empty(),
            "vkCmdUpdateBuffer of {} bytes at {offset} into `{}`",
            bytes.len(),
            buffer.name()
        );
        assert!(
            offset + bytes.len() as u64 <= buffer.size_bytes(),
            "update of {} bytes at {offset} overflows `{}`",
            bytes.len(),
            buffer.name()
        );
        self.keep(buffer);
        // SAFETY: recording on this device; the range lies inside the live buffer.
        unsafe { self.device().cmd_update_buffer(self.cmd, buffer.raw(), offset, bytes) };
    }

    /// Records a copy of `len` elements from element `src_first` of `src` to element
    /// `dst_first` of `dst` (a transfer). Panics if either range is outside its buffer.
    pub fn copy_buffer<T: Pod>(
        &mut self,
        src: &Buffer<T>,
        src_first: u64,
        dst: &Buffer<T>,
        dst_first: u64,
        len: u64,
    ) {
        assert!(
            src_first + len <= src.len() && dst_first + len <= dst.len(),
            "copy of {len} elements from `{}`[{src_first}..] to `{}`[{dst_first}..] is out of range",
            src.name(),
            dst.name()
        );
        if len == 0 {
            return;
        }
        self.keep(src);
        self.keep(dst);
        let elem = std::mem::size_of::<T>() as u64;
        let region =
            vk::BufferCopy { src_offset: src_first * elem, dst_offset: dst_first * elem, size: len * elem };
        // SAFETY: recording on this device; both ranges lie inside live buffers.
        unsafe { self.device().cmd_copy_buffer(self.cmd, src.raw(), dst.raw(), &[region]) };
    }

    /// Records a copy of `bytes` bytes between buffers of any element types (staging copies).
    /// Panics if either range is outside its buffer.
    pub(crate) fn copy_bytes<A: Pod, B: Pod>(
        &mut self,
        src: &Buffer<A>,
        src_offset: u64,
        dst: &Buffer<B>,
        dst_offset: u64,
        bytes: u64,
    ) {
        assert!(
            src_offset + bytes <= src.size_bytes() && dst_offset + bytes <= dst.size_bytes(),
            "copy of {bytes} bytes from `{}`+{src_offset} to `{}`+{dst_offset} is out of range",
            src.name(),
            dst.name()
        );
        if bytes == 0 {
            return;
        }
        self.keep(src);
        self.keep(dst);
        let region = vk::BufferCopy { src_offset, dst_offset, size: bytes };
        // SAFETY: recording on this device; both ranges lie inside live buffers (kept alive).
        unsafe { self.device().cmd_copy_buffer(self.cmd, src.raw(), dst.raw(), &[region]) };
    }

    /// Keeps the buffer of `binding` alive and returns its handle (for passes recording a
    /// command that names it).
    pub(crate) fn bound(&mut self, binding: &BufferBinding<'_>) -> vk::Buffer {
        self.keep_lifetime(binding.lifetime());
        binding.raw()
    }
}

impl Drop for Recorder<'_> {
    fn drop(&mut self) {
        if self.host && !self.uses.is_empty() {
            // Without `finish` nobody will say when the host's buffer completed: keep its
            // objects until the device goes.
            self.gpu.shared.orphan(std::mem::take(&mut self.uses));
        }
    }
}
