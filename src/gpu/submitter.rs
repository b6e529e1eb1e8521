//! Jobs that need several submissions. Some of galerkin's device work cannot be one recording:
//! the streamed premultiplication sorts each stage's coordinates on the host between batches,
//! the reduced evaluation takes roots and sums on the host between contractions, batched
//! solves and Gram matrices read results back chunk by chunk. Such a job takes a
//! [`Submitter`]: it records each step through a [`Recorder`] the submitter hands it, and the
//! submitter decides where the command buffer comes from, which queue it goes to, and how it
//! is synchronised — the engine's queue and fences ([`Gpu::submitter`]), or a host's own
//! command buffers, queue and fences (implement the trait; `tests/submitter.rs` has one).
//!
//! Between steps the job moves data with [`dyn Submitter::upload`] and
//! [`dyn Submitter::download`] (recorded staging copies, so a host's submitter carries them
//! too) and submits its steps through [`dyn Submitter::submit`]. Steps are ordered by their
//! declared accesses ([`super::Access`]): the first command of a step that uses an object an
//! earlier, unfinished step also used waits for all earlier commands, so each step sees
//! everything the earlier steps wrote, in submission order on one queue.

use std::collections::VecDeque;

use ash::vk;
use bytemuck::Pod;

use super::access::Access;
use super::buffer::{Buffer, STAGING_CHUNK_BYTES};
use super::commands::Submission;
use super::context::Gpu;
use super::error::{GpuError, GpuResult};
use super::memory::MemoryKind;
use super::recorder::Recorder;

/// Where a multi-submission job's recordings go (see the module docs).
///
/// Implementations must execute submissions in the order they were made (one queue, or
/// semaphores chaining them), keep each submission's [`super::Recording`] until its work has
/// completed, and make [`Submitter::complete`] return only once everything submitted has
/// completed and its recordings were released.
pub trait Submitter: Send {
    /// The device the recordings are for.
    fn gpu(&self) -> &Gpu;

    /// Records `record` into a command buffer and submits it. Jobs call
    /// [`dyn Submitter::submit`].
    fn record_and_submit(&mut self, record: &mut dyn FnMut(&mut Recorder<'_>)) -> GpuResult<()>;

    /// Waits until everything submitted has completed and its recordings are released.
    fn complete(&mut self) -> GpuResult<()>;
}

impl dyn Submitter + '_ {
    /// Submits one step of a job, `record` (ordered after the earlier steps by its declared
    /// accesses).
    pub fn submit(&mut self, record: &mut dyn FnMut(&mut Recorder<'_>)) -> GpuResult<()> {
        self.record_and_submit(record)
    }

    /// Copies `data` into elements `first ..` of `dst` through host-visible staging buffers
    /// of at most [`STAGING_CHUNK_BYTES`], one submission per chunk (ordered after earlier
    /// steps, and before later ones, by the declared accesses: an object of an unfinished
    /// submission is waited for by the first command that uses it). Panics if the range is
    /// outside `dst`.
    pub fn upload<T: Pod>(&mut self, dst: &Buffer<T>, first: u64, data: &[T]) -> GpuResult<()> {
        assert!(
            first + data.len() as u64 <= dst.len(),
            "upload of {} elements at {first} overflows `{}` ({} elements)",
            data.len(),
            dst.name(),
            dst.len()
        );
        if !dst.is_on(self.gpu()) {
            return Err(GpuError::WrongDevice { name: dst.name().to_string() });
        }
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let elem = std::mem::size_of::<T>() as u64;
        let chunk = STAGING_CHUNK_BYTES as usize;
        for (i, part) in bytes.chunks(chunk).enumerate() {
            let gpu = self.gpu().clone();
            let mut staging = gpu.staging.take(&gpu, MemoryKind::CpuToGpu, part.len() as u64)?;
            staging.mapped_mut()?[..part.len()].copy_from_slice(part);
            let at = first * elem + (i * chunk) as u64;
            let len = part.len() as u64;
            let submitted = self.submit(&mut |rec| rec.copy_bytes(&staging, 0, dst, at, len));
            // Back to the pool at once: it is handed out again only when the copy is done.
            gpu.staging.give_back(staging);
            submitted?;
        }
        Ok(())
    }

    /// A new device-local buffer holding `data` (an empty slice gets one unwritten element, so
    /// that it can still be bound), uploaded through this submitter.
    pub fn buffer_from_slice<T: Pod>(
        &mut self,
        name: &str,
        data: &[T],
        usage: vk::BufferUsageFlags,
    ) -> GpuResult<Buffer<T>> {
        let b = Buffer::new(self.gpu(), name, data.len().max(1) as u64, usage, MemoryKind::GpuOnly)?;
        self.upload(&b, 0, data)?;
        Ok(b)
    }

    /// Reads elements `first .. first + out.len()` of `src` into `out`: a recorded copy into a
    /// host-visible buffer, then [`Submitter::complete`].
    pub fn download_into<T: Pod>(&mut self, src: &Buffer<T>, first: u64, out: &mut [T]) -> GpuResult<()> {
        let readback = self.record_readback(src, first, out.len() as u64)?;
        self.complete()?;
        out.copy_from_slice(&readback.read()?);
        Ok(())
    }

    /// Reads the whole of `src` back (see [`Self::download_into`]).
    pub fn download<T: Pod>(&mut self, src: &Buffer<T>) -> GpuResult<Vec<T>> {
        let readback = self.record_readback(src, 0, src.len())?;
        self.complete()?;
        readback.read()
    }

    /// Submits a copy of `len` elements of `src` from `first` into a new host-visible buffer,
    /// readable once the work has completed ([`Readback::read`]) — for jobs that read several
    /// results after one [`Submitter::complete`].
    pub fn record_readback<T: Pod>(
        &mut self,
        src: &Buffer<T>,
        first: u64,
        len: u64,
    ) -> GpuResult<Readback<T>> {
        assert!(first + len <= src.len(), "readback of {len} elements at {first} outside `{}`", src.name());
        if !src.is_on(self.gpu()) {
            return Err(GpuError::WrongDevice { name: src.name().to_string() });
        }
        let gpu = self.gpu().clone();
        let elem = std::mem::size_of::<T>() as u64;
        let bytes = len * elem;
        // One pooled buffer when it fits a staging chunk; a buffer of its own otherwise.
        let staging = if bytes <= STAGING_CHUNK_BYTES {
            gpu.staging.take(&gpu, MemoryKind::GpuToCpu, bytes)?
        } else {
            Buffer::<u8>::new(
                &gpu,
                &format!("{} readback", src.name()),
                bytes,
                vk::BufferUsageFlags::empty(),
                MemoryKind::GpuToCpu,
            )?
        };
        self.submit(&mut |rec| {
            rec.copy_bytes(src, first * elem, &staging, 0, bytes);
            rec.access(&staging, Access::HOST_READ);
        })?;
        Ok(Readback { staging: Some(staging), len: len as usize, gpu, _t: std::marker::PhantomData })
    }
}

/// Results copied into host-visible memory by [`dyn Submitter::record_readback`].
pub struct Readback<T: Pod> {
    /// Pooled (or its own) staging buffer, returned to the pool when dropped.
    staging: Option<Buffer<u8>>,
    len: usize,
    gpu: Gpu,
    _t: std::marker::PhantomData<T>,
}

impl<T: Pod> Readback<T> {
    /// The values, once the copy has completed; [`GpuError::NotMappable`] while a recording
    /// that writes them may still be running.
    pub fn read(&self) -> GpuResult<Vec<T>> {
        let staging = self
            .staging
            .as_ref()
            .ok_or(GpuError::NotMappable { name: "a readback".into(), reason: "it was already returned" })?;
        let mapped = staging.mapped().ok_or_else(|| GpuError::NotMappable {
            name: staging.name().to_string(),
            reason: "its copy may still be running (complete the submitter first)",
        })?;
        let bytes = self.len * std::mem::size_of::<T>();
        Ok(bytemuck::pod_collect_to_vec(&mapped[..bytes]))
    }
}

impl<T: Pod> Drop for Readback<T> {
    fn drop(&mut self) {
        if let Some(b) = self.staging.take() {
            if b.size_bytes() <= STAGING_CHUNK_BYTES {
                self.gpu.staging.give_back(b);
            }
        }
    }
}

/// The engine's own [`Submitter`]: its queue and fences, with up to a few submissions in
/// flight before it waits for the oldest (so a job's host work overlaps the device's).
pub struct EngineSubmitter<'g> {
    gpu: &'g Gpu,
    in_flight: VecDeque<Submission>,
    depth: usize,
}

/// Submissions an [`EngineSubmitter`] keeps in flight.
const ENGINE_DEPTH: usize = 3;

impl Gpu {
    /// A [`Submitter`] over the engine's own queue (see [`EngineSubmitter`]).
    pub fn submitter(&self) -> EngineSubmitter<'_> {
        EngineSubmitter { gpu: self, in_flight: VecDeque::new(), depth: ENGINE_DEPTH }
    }
}

impl Submitter for EngineSubmitter<'_> {
    fn gpu(&self) -> &Gpu {
        self.gpu
    }

    fn record_and_submit(&mut self, record: &mut dyn FnMut(&mut Recorder<'_>)) -> GpuResult<()> {
        while self.in_flight.len() >= self.depth {
            if let Some(oldest) = self.in_flight.pop_front() {
                oldest.wait()?;
            }
        }
        let (submission, ()) = self.gpu.submit(|rec| record(rec))?;
        self.in_flight.push_back(submission);
        Ok(())
    }

    fn complete(&mut self) -> GpuResult<()> {
        while let Some(s) = self.in_flight.pop_front() {
            s.wait()?;
        }
        Ok(())
    }
}

impl Drop for EngineSubmitter<'_> {
    fn drop(&mut self) {
        // Submissions wait on their own fences when dropped; an error here was already a
        // device error the job returned.
        if let Err(e) = self.complete() {
            tracing::error!("an engine submitter's work failed: {e}");
        }
    }
}
