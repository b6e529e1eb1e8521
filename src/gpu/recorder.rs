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

use std::collections::HashMap;
use std::sync::Arc;

use ash::vk;
use bytemuck::Pod;

use super::access::{Access, Key, State, Tracker};
use super::buffer::{Buffer, BufferBinding};
use super::context::Gpu;
use super::error::GpuError;
use super::lifetime::{Lifetime, Tracked, Use};

/// Recording into one command buffer (see the module docs).
pub struct Recorder<'g> {
    gpu: &'g Gpu,
    cmd: vk::CommandBuffer,
    uses: Vec<Use>,
    /// How many of `uses` each object has (by lifetime), to tell its uses by other pending
    /// recordings from this one's.
    kept: HashMap<usize, usize>,
    /// Declared accesses and the barriers they still need ([`super::access`]).
    pub(crate) tracker: Tracker,
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
        Self::new(gpu, cmd, false)
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
        Self::new(gpu, cmd, true)
    }

    fn new(gpu: &'g Gpu, cmd: vk::CommandBuffer, host: bool) -> Self {
        Self { gpu, cmd, uses: Vec::new(), kept: HashMap::new(), tracker: Tracker::default(), host }
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

    /// The command buffer, for a command the recorder has no method for.
    ///
    /// # Safety
    /// Whatever the caller records into it must keep the recorder's promises, which the
    /// engine's destruction relies on:
    /// - every engine object a command names is passed to [`Recorder::keep`] (an object is
    ///   destroyed as soon as its last reference goes; a recording holds a reference only to
    ///   what it was told about, so an unkept object can be destroyed while the command that
    ///   names it still runs);
    /// - every engine buffer or image it reads or writes is declared with
    ///   [`Recorder::access`] before the command (the recorder derives the barriers of later
    ///   commands from the declared accesses).
    pub unsafe fn raw(&mut self) -> vk::CommandBuffer {
        self.flush();
        self.cmd
    }

    /// The command buffer, for the engine's own recording methods (which keep and declare
    /// what they record).
    pub(crate) fn cmd(&self) -> vk::CommandBuffer {
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
        *self.kept.entry(Arc::as_ptr(life) as usize).or_default() += 1;
    }

    /// Declares that the commands that follow use `object` (a buffer, or an image already in
    /// the layout they need) as `access`, and keeps it alive: the recorder records now the
    /// barrier the access needs after what this recording (or an earlier, unfinished one) did
    /// to it. For commands recorded through [`Recorder::raw`] or by a host, and for the draws
    /// of a render pass, which declare before the pass begins.
    pub fn access(&mut self, object: &impl Tracked, access: Access) {
        self.access_all(&[(object, access)]);
    }

    /// [`Recorder::access`] of several objects, their barriers recorded as one.
    pub fn access_all(&mut self, objects: &[(&dyn Tracked, Access)]) {
        for (object, access) in objects {
            self.declare_lifetime(object.lifetime(), *access);
        }
        self.flush();
    }

    /// Declares an access, leaving its barrier pending until [`Self::flush`].
    pub(crate) fn declare_lifetime(&mut self, life: &Arc<Lifetime>, access: Access) {
        let key = Key::Object(Arc::as_ptr(life) as usize);
        let state = self.state(key, Some(life));
        if let Some((src, dst)) = state.access(access, false) {
            self.tracker.pending.memory(src, dst);
        }
        self.keep_lifetime(life);
    }

    /// The tracked state of `key`, first met now if it is not yet known.
    pub(crate) fn state(&mut self, key: Key, life: Option<&Arc<Lifetime>>) -> &mut State {
        let own = life.map_or(0, |l| self.kept.get(&(Arc::as_ptr(l) as usize)).copied().unwrap_or(0));
        // A foreign image's earlier recordings are the host's business (its layout says where
        // they left it); an engine object used by other pending recordings waits for them.
        let elsewhere = life.is_some_and(|l| l.pending() > own);
        self.tracker.states.entry(key).or_insert_with(|| State::first(elsewhere))
    }

    /// Declares a use by a draw inside a render pass, where no barrier can be recorded: the
    /// pass that drew must have declared it before the render pass began. Panics if it did
    /// not (a missing declaration is a bug in the pass).
    pub(crate) fn access_in_pass(&mut self, life: &Arc<Lifetime>, access: Access) {
        let key = Key::Object(Arc::as_ptr(life) as usize);
        let ok = self.state(key, Some(life)).access_in_pass(access);
        assert!(
            ok,
            "`{}` is read by a draw after a write that no barrier made visible to it: declare the \
             draw's access (Recorder::access) before the render pass begins",
            life.name()
        );
        self.keep_lifetime(life);
    }

    /// Records the barriers the declared accesses need (before a command, outside a render
    /// pass).
    pub(crate) fn flush(&mut self) {
        if self.tracker.pending.is_empty() {
            return;
        }
        let caps = self.gpu.caps();
        let mut enabled = vk::PipelineStageFlags2::from_raw(u64::MAX);
        if !caps.tessellation_shader {
            enabled &= !(vk::PipelineStageFlags2::TESSELLATION_CONTROL_SHADER
                | vk::PipelineStageFlags2::TESSELLATION_EVALUATION_SHADER);
        }
        if !caps.geometry_shader {
            enabled &= !vk::PipelineStageFlags2::GEOMETRY_SHADER;
        }
        // SAFETY: recording on this device outside a render pass (every caller records a
        // transfer or dispatch next, or declares before a render pass); the images named are
        // kept by this recording.
        unsafe { self.tracker.pending.record(self.gpu.device(), self.cmd, caps.synchronization2, enabled) };
    }

    /// Records a global memory barrier by hand, after the barriers declared accesses need. The
    /// engine's passes do not use it (their declared accesses derive their barriers); it is for
    /// commands recorded through [`Recorder::raw`] that need an ordering no declaration states.
    pub fn memory_barrier(
        &mut self,
        src: (vk::PipelineStageFlags, vk::AccessFlags),
        dst: (vk::PipelineStageFlags, vk::AccessFlags),
    ) {
        self.flush();
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

    /// Records `vkCmdFillBuffer` of the whole of `buffer` with the 32-bit pattern `word`
    /// (outside a render pass; a transfer write).
    pub fn fill_buffer<T: Pod>(&mut self, buffer: &Buffer<T>, word: u32) {
        self.declare_lifetime(buffer.lifetime(), Access::TRANSFER_WRITE);
        self.flush();
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
        self.declare_lifetime(buffer.lifetime(), Access::TRANSFER_WRITE);
        self.flush();
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
        self.declare_lifetime(src.lifetime(), Access::TRANSFER_READ);
        self.declare_lifetime(dst.lifetime(), Access::TRANSFER_WRITE);
        self.flush();
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
        self.declare_lifetime(src.lifetime(), Access::TRANSFER_READ);
        self.declare_lifetime(dst.lifetime(), Access::TRANSFER_WRITE);
        self.flush();
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
