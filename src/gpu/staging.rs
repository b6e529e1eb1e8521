//! A small pool of host-visible staging buffers, reused by uploads and downloads so that a
//! transfer does not allocate (and page-fault in) fresh host memory every time. It belongs to
//! the [`Gpu`] handle, not to the shared device state, so pooled buffers (which hold the device
//! alive) never form a cycle with it.

use std::sync::Mutex;

use ash::vk;

use super::buffer::{Buffer, STAGING_CHUNK_BYTES};
use super::context::Gpu;
use super::error::GpuResult;
use super::memory::MemoryKind;

/// Pooled buffers kept per direction (two chunks in flight per transfer, a little slack).
const KEEP_PER_KIND: usize = 3;
/// Smallest staging buffer made, so that tiny transfers share one.
const MIN_BYTES: u64 = 64 << 10;

/// Idle staging buffers by kind.
#[derive(Default)]
pub(crate) struct StagingPool {
    idle: Mutex<Vec<Buffer<u8>>>,
}

impl StagingPool {
    /// A staging buffer of `kind` holding at least `bytes` (at most a staging chunk).
    pub(crate) fn take(&self, gpu: &Gpu, kind: MemoryKind, bytes: u64) -> GpuResult<Buffer<u8>> {
        let bytes = bytes.min(STAGING_CHUNK_BYTES);
        {
            let mut idle = self.idle.lock().unwrap_or_else(|p| p.into_inner());
            let best = idle
                .iter()
                .enumerate()
                // A buffer given back while a recording still uses it waits for that.
                .filter(|(_, b)| b.kind() == kind && b.size_bytes() >= bytes && b.is_idle())
                .min_by_key(|(_, b)| b.size_bytes())
                .map(|(i, _)| i);
            if let Some(i) = best {
                return Ok(idle.swap_remove(i));
            }
        }
        let size = bytes.next_power_of_two().clamp(MIN_BYTES, STAGING_CHUNK_BYTES.max(bytes));
        let name = match kind {
            MemoryKind::CpuToGpu => "upload staging",
            _ => "download staging",
        };
        Buffer::new(gpu, name, size, vk::BufferUsageFlags::empty(), kind)
    }

    /// Returns a buffer to the pool: one whose transfers have finished, or one a pending
    /// recording still uses ([`Self::take`] hands it out again only once that recording is
    /// known to be finished).
    pub(crate) fn give_back(&self, buffer: Buffer<u8>) {
        let mut idle = self.idle.lock().unwrap_or_else(|p| p.into_inner());
        idle.push(buffer);
        let kind = idle.last().map(Buffer::kind);
        let same: Vec<usize> = (0..idle.len()).filter(|&i| Some(idle[i].kind()) == kind).collect();
        if same.len() > KEEP_PER_KIND {
            if let Some(&smallest) = same.iter().min_by_key(|&&i| idle[i].size_bytes()) {
                drop(idle.swap_remove(smallest));
            }
        }
    }
}
