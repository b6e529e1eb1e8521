//! Typed buffers. `Buffer<T>` holds `len` elements of a plain-old-data `T`; device-local
//! buffers are filled and read back through staging buffers in bounded chunks (never relying
//! on device-local memory being host-visible, which holds on lavapipe but not on discrete GPUs).
//! Arrays larger than one storage-buffer binding (128 MiB on lavapipe) are bound in chunks:
//! see [`Buffer::binding_chunks`].

use std::marker::PhantomData;
use std::ptr::NonNull;
use std::sync::Arc;

use ash::vk;
use bytemuck::Pod;

use super::access::Access;
use super::context::{DeviceShared, Gpu};
use super::error::{vk_error, GpuError, GpuResult, VkContext};
use super::lifetime::{Lifetime, Tracked};
use super::memory::MemoryKind;

/// Bytes per staging chunk for uploads and downloads (two are in flight at once).
pub const STAGING_CHUNK_BYTES: u64 = 32 << 20;

/// A byte range of a buffer as one descriptor (or a vertex or indirect binding) binds it. It
/// borrows the buffer, so the buffer cannot be dropped while a binding of it exists; a
/// [`crate::gpu::DescriptorSet`] made from it keeps the buffer alive itself.
///
/// ```compile_fail
/// # use galerkin::gpu::{vk, Buffer, Gpu, GpuDesc, MemoryKind, Resource};
/// # fn f(gpu: &Gpu, pipeline: &galerkin::gpu::ComputePipeline) -> galerkin::gpu::GpuResult<()> {
/// let buffer = Buffer::<f32>::new(gpu, "x", 4, vk::BufferUsageFlags::STORAGE_BUFFER, MemoryKind::GpuOnly)?;
/// let binding = buffer.binding()?;
/// drop(buffer); // error[E0505]: cannot move out of `buffer` because it is borrowed
/// let set = pipeline.bind(gpu, &[Resource::Storage(binding)])?;
/// # Ok(()) }
/// ```
#[derive(Copy, Clone, Debug)]
pub struct BufferBinding<'a> {
    life: &'a Arc<Lifetime>,
    buffer: vk::Buffer,
    /// Offset in bytes (a multiple of `minStorageBufferOffsetAlignment`).
    pub offset: u64,
    /// Length in bytes (at most [`Gpu::max_binding_bytes`] for storage bindings).
    pub range: u64,
}

impl BufferBinding<'_> {
    /// The buffer's handle.
    pub fn raw(&self) -> vk::Buffer {
        self.buffer
    }

    pub(crate) fn lifetime(&self) -> &Arc<Lifetime> {
        self.life
    }
}

/// One chunk of an array bound as its own descriptor: elements `first .. first + len`.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct Chunk {
    /// Index of the first element.
    pub first: u64,
    /// Number of elements.
    pub len: u64,
}

/// A typed buffer of `len` elements of `T`. Its memory is freed when the buffer and every
/// recording and descriptor set that use it are gone (see [`crate::gpu::Recorder`]).
pub struct Buffer<T: Pod> {
    // `life` first: fields drop in order, and the lifetime must end while the device is alive.
    life: Arc<Lifetime>,
    shared: Arc<DeviceShared>,
    raw: vk::Buffer,
    /// The start of host-visible memory (mapped for the allocation's whole life).
    mapped: Option<NonNull<u8>>,
    len: u64,
    bytes: u64,
    kind: MemoryKind,
    name: String,
    _t: PhantomData<T>,
}

// SAFETY: the mapped pointer is only dereferenced through `&self`/`&mut self` accessors that
// check no pending GPU work uses the memory; everything else is handles and plain data.
unsafe impl<T: Pod> Send for Buffer<T> {}
// SAFETY: as above; shared access only reads.
unsafe impl<T: Pod> Sync for Buffer<T> {}

impl<T: Pod> Tracked for Buffer<T> {
    fn lifetime(&self) -> &Arc<Lifetime> {
        &self.life
    }
}

impl<T: Pod> std::fmt::Debug for Buffer<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Buffer")
            .field("name", &self.name)
            .field("len", &self.len)
            .field("kind", &self.kind)
            .finish()
    }
}

impl<T: Pod> Buffer<T> {
    /// Creates a buffer of `len` elements. Device-local buffers also get transfer usage (for
    /// staging). Sizes over `maxBufferSize` or `maxMemoryAllocationSize` are an error naming
    /// the buffer.
    pub fn new(
        gpu: &Gpu,
        name: &str,
        len: u64,
        usage: vk::BufferUsageFlags,
        kind: MemoryKind,
    ) -> GpuResult<Self> {
        let shared = gpu.shared.clone();
        let elem = std::mem::size_of::<T>() as u64;
        let bytes = len.checked_mul(elem).ok_or_else(|| GpuError::OverLimit {
            name: name.to_string(),
            requested: len,
            limit: u64::MAX / elem.max(1),
            limit_name: "address space",
            unit: "elements",
        })?;
        if bytes > shared.caps.max_buffer_size {
            return Err(GpuError::OverLimit {
                name: name.to_string(),
                requested: bytes,
                limit: shared.caps.max_buffer_size,
                limit_name: "maxBufferSize",
                unit: "bytes",
            });
        }
        let usage = usage | vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST;
        let info = vk::BufferCreateInfo::default()
            .size(bytes.max(4))
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: valid create info on this device.
        let raw = unsafe { shared.raw.create_buffer(&info, None) }.vk("vkCreateBuffer")?;
        // SAFETY: `raw` is a live buffer of this device.
        let requirements = unsafe { shared.raw.get_buffer_memory_requirements(raw) };
        let allocation = match shared.allocate(name, requirements, kind, true) {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: the buffer was never used.
                unsafe { shared.raw.destroy_buffer(raw, None) };
                return Err(e);
            }
        };
        // SAFETY: memory comes from a type allowed by `requirements`, at its offset.
        let bound = unsafe { shared.raw.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) };
        if let Err(e) = bound {
            // SAFETY: the buffer was never used.
            unsafe { shared.raw.destroy_buffer(raw, None) };
            shared.free(allocation);
            return Err(vk_error("vkBindBufferMemory", e));
        }
        shared.set_name(raw, name);
        let mapped = allocation.mapped_ptr().map(|p| p.cast::<u8>());
        let life = Lifetime::new(&shared, name, move |dev| {
            // SAFETY: the last reference is gone: no recording or set uses the buffer, and
            // the retirement waited for the engine's in-flight work.
            unsafe { dev.raw.destroy_buffer(raw, None) };
            dev.free(allocation);
        });
        Ok(Self { shared, life, raw, mapped, len, bytes, kind, name: name.to_string(), _t: PhantomData })
    }

    /// A device-local buffer holding a copy of `data` (an empty slice gets one unwritten
    /// element, so that it can still be bound).
    pub fn from_slice(gpu: &Gpu, name: &str, data: &[T], usage: vk::BufferUsageFlags) -> GpuResult<Self> {
        // An empty slice gets one (unwritten) element, so that it can still be bound.
        let b = Self::new(gpu, name, data.len().max(1) as u64, usage, MemoryKind::GpuOnly)?;
        if !data.is_empty() {
            b.upload(gpu, 0, data)?;
        }
        Ok(b)
    }

    /// The Vulkan handle.
    pub fn raw(&self) -> vk::Buffer {
        self.raw
    }

    /// Number of elements.
    pub fn len(&self) -> u64 {
        self.len
    }

    /// True if the buffer holds no elements.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Size in bytes.
    pub fn size_bytes(&self) -> u64 {
        self.bytes
    }

    /// The allocation's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Where the memory lives.
    pub fn kind(&self) -> MemoryKind {
        self.kind
    }

    /// The mapped elements of a host-visible buffer (`CpuToGpu`/`GpuToCpu`); `None` if its
    /// memory is not host-visible or recorded GPU work not yet known to be finished uses it.
    pub fn mapped(&self) -> Option<&[T]> {
        let p = self.mapped?;
        if self.life.pending() > 0 {
            return None;
        }
        // SAFETY: the mapping covers the allocation (at least `bytes`), lives as long as the
        // buffer, is aligned for `T` (allocations are at least 16-byte aligned; `T: Pod`), and
        // no pending GPU work writes it.
        Some(unsafe { std::slice::from_raw_parts(p.as_ptr().cast::<T>(), self.len as usize) })
    }

    /// True unless a recording that uses the buffer may still be running.
    pub(crate) fn is_idle(&self) -> bool {
        self.life.pending() == 0
    }

    /// Mutable mapped elements of a host-visible buffer. An error if the memory is not
    /// host-visible, or if recorded GPU work not yet known to be finished may read it (wait
    /// for the submission, or drop the host's [`crate::gpu::Recording`], first).
    pub fn mapped_mut(&mut self) -> GpuResult<&mut [T]> {
        let not = |reason| GpuError::NotMappable { name: self.name.clone(), reason };
        let p = self.mapped.ok_or_else(|| not("its memory is not host-visible"))?;
        if self.life.pending() > 0 {
            return Err(not("recorded GPU work that may use it has not been seen to finish"));
        }
        // SAFETY: as in `mapped`, and `&mut self` excludes other host access.
        Ok(unsafe { std::slice::from_raw_parts_mut(p.as_ptr().cast::<T>(), self.len as usize) })
    }

    /// True if `gpu` is the device this buffer was made on.
    pub fn is_on(&self, gpu: &Gpu) -> bool {
        Arc::ptr_eq(&self.shared, &gpu.shared)
    }

    fn check_device(&self, gpu: &Gpu) -> GpuResult<()> {
        if self.is_on(gpu) {
            Ok(())
        } else {
            Err(GpuError::WrongDevice { name: self.name.clone() })
        }
    }

    /// The whole buffer as one binding; an error if it exceeds one storage binding
    /// (use [`Buffer::binding_chunks`] for large arrays).
    pub fn binding(&self) -> GpuResult<BufferBinding<'_>> {
        let limit = self.shared.max_binding_bytes;
        if self.bytes > limit {
            return Err(GpuError::OverLimit {
                name: self.name.clone(),
                requested: self.bytes,
                limit,
                limit_name: "maxStorageBufferRange (bind it in chunks)",
                unit: "bytes",
            });
        }
        Ok(self.whole())
    }

    /// The whole buffer as a vertex, indirect or uniform binding (no storage-range check; a
    /// descriptor set still refuses a storage range over the limit).
    pub fn whole(&self) -> BufferBinding<'_> {
        BufferBinding { life: &self.life, buffer: self.raw, offset: 0, range: self.bytes.max(4) }
    }

    /// Elements `chunk.first .. chunk.first + chunk.len` as a binding.
    pub fn binding_range(&self, chunk: Chunk) -> BufferBinding<'_> {
        let elem = std::mem::size_of::<T>() as u64;
        assert!(
            chunk.first + chunk.len <= self.len,
            "chunk {chunk:?} outside `{}` of {} elements",
            self.name,
            self.len
        );
        BufferBinding {
            life: &self.life,
            buffer: self.raw,
            offset: chunk.first * elem,
            range: (chunk.len * elem).max(4),
        }
    }

    /// Splits the buffer into chunks of at most [`Gpu::max_binding_bytes`] each, starting on
    /// offsets aligned to `minStorageBufferOffsetAlignment`: how a kernel walks an array larger
    /// than one binding (`maxStorageBufferRange`, 128 MiB on lavapipe).
    pub fn binding_chunks(&self) -> Vec<Chunk> {
        chunk_elements(
            self.len,
            std::mem::size_of::<T>() as u64,
            self.shared.max_binding_bytes,
            self.shared.caps.min_storage_buffer_offset_alignment,
        )
    }

    /// Copies `data` into elements `first ..` through staging buffers (for device-local
    /// buffers), two chunks in flight; writes host-visible buffers directly. Waits until done.
    pub fn upload(&self, gpu: &Gpu, first: u64, data: &[T]) -> GpuResult<()> {
        self.check_device(gpu)?;
        let elem = std::mem::size_of::<T>() as u64;
        assert!(
            first + data.len() as u64 <= self.len,
            "upload of {} elements at {first} overflows `{}` ({} elements)",
            data.len(),
            self.name,
            self.len
        );
        let src: &[u8] = bytemuck::cast_slice(data);
        if src.is_empty() {
            return Ok(());
        }
        let chunk = STAGING_CHUNK_BYTES.min(src.len() as u64);
        let pool = &gpu.staging;
        let mut staging =
            [pool.take(gpu, MemoryKind::CpuToGpu, chunk)?, pool.take(gpu, MemoryKind::CpuToGpu, chunk)?];
        let mut in_flight: [Option<super::Submission>; 2] = [None, None];
        for (i, part) in src.chunks(chunk as usize).enumerate() {
            let k = i % 2;
            if let Some(s) = in_flight[k].take() {
                s.wait()?;
            }
            let stage = &mut staging[k];
            stage.mapped_mut()?[..part.len()].copy_from_slice(part);
            let dst_offset = first * elem + (i as u64) * chunk;
            let stage = &staging[k];
            let (s, ()) = gpu.submit(|rec| rec.copy_bytes(stage, 0, self, dst_offset, part.len() as u64))?;
            in_flight[k] = Some(s);
        }
        for s in in_flight.into_iter().flatten() {
            s.wait()?;
        }
        for b in staging {
            pool.give_back(b);
        }
        Ok(())
    }

    /// Reads the whole buffer back to the host.
    pub fn download(&self, gpu: &Gpu) -> GpuResult<Vec<T>> {
        self.download_range(gpu, Chunk { first: 0, len: self.len })
    }

    /// Reads elements `range.first .. range.first + range.len` back through staging buffers,
    /// two chunks in flight.
    pub fn download_range(&self, gpu: &Gpu, range: Chunk) -> GpuResult<Vec<T>> {
        let mut out = vec![T::zeroed(); range.len as usize];
        self.download_into(gpu, range.first, &mut out)?;
        Ok(out)
    }

    /// Reads elements `first .. first + out.len()` into `out` (reusing the caller's memory).
    pub fn download_into(&self, gpu: &Gpu, first: u64, out: &mut [T]) -> GpuResult<()> {
        self.check_device(gpu)?;
        let elem = std::mem::size_of::<T>() as u64;
        let range = Chunk { first, len: out.len() as u64 };
        assert!(range.first + range.len <= self.len, "download {range:?} outside `{}`", self.name);
        let dst: &mut [u8] = bytemuck::cast_slice_mut(out);
        if dst.is_empty() {
            return Ok(());
        }
        let chunk = STAGING_CHUNK_BYTES.min(dst.len() as u64);
        let pool = &gpu.staging;
        let staging =
            [pool.take(gpu, MemoryKind::GpuToCpu, chunk)?, pool.take(gpu, MemoryKind::GpuToCpu, chunk)?];
        let parts: Vec<&mut [u8]> = dst.chunks_mut(chunk as usize).collect();
        let mut in_flight: [Option<(super::Submission, usize)>; 2] = [None, None];
        let mut parts: Vec<Option<&mut [u8]>> = parts.into_iter().map(Some).collect();
        let n = parts.len();
        let drain = |slot: &mut Option<(super::Submission, usize)>,
                     parts: &mut Vec<Option<&mut [u8]>>,
                     k: usize|
         -> GpuResult<()> {
            if let Some((s, i)) = slot.take() {
                s.wait()?;
                let part = parts[i].take().expect("each part is read once");
                let len = part.len();
                let mapped = staging[k].mapped().ok_or_else(|| GpuError::NotMappable {
                    name: staging[k].name.clone(),
                    reason: "download staging is not host-visible",
                })?;
                part.copy_from_slice(&mapped[..len]);
            }
            Ok(())
        };
        for i in 0..n {
            let k = i % 2;
            drain(&mut in_flight[k], &mut parts, k)?;
            let size = parts[i].as_ref().map_or(0, |p| p.len()) as u64;
            let src_offset = range.first * elem + (i as u64) * chunk;
            let stage = &staging[k];
            let (s, ()) = gpu.submit(|rec| {
                rec.copy_bytes(self, src_offset, stage, 0, size);
                rec.access(stage, Access::HOST_READ);
            })?;
            in_flight[k] = Some((s, i));
        }
        for (k, slot) in in_flight.iter_mut().enumerate() {
            drain(slot, &mut parts, k)?;
        }
        for b in staging {
            pool.give_back(b);
        }
        Ok(())
    }
}

/// Splits `len` elements of `elem` bytes into chunks of at most `max_bytes` whose byte offsets
/// are multiples of `align`.
pub fn chunk_elements(len: u64, elem: u64, max_bytes: u64, align: u64) -> Vec<Chunk> {
    let lcm = {
        let (mut a, mut b) = (elem.max(1), align.max(1));
        while b != 0 {
            (a, b) = (b, a % b);
        }
        elem.max(1) / a * align.max(1)
    };
    let per_chunk = ((max_bytes / lcm).max(1) * lcm) / elem.max(1);
    let mut chunks = Vec::new();
    let mut first = 0;
    while first < len {
        let n = per_chunk.min(len - first);
        chunks.push(Chunk { first, len: n });
        first += n;
    }
    if chunks.is_empty() {
        chunks.push(Chunk { first: 0, len: 0 });
    }
    chunks
}
