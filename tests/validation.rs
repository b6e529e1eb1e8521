//! The validation canary itself: it must catch real errors and leaks (so that "zero errors" in
//! every other test means something), and deferred destruction must keep resources alive
//! exactly as long as engine work uses them.

mod common;

use galerkin::gpu::{vk, Access, Buffer, Gpu, GpuDesc, MemoryKind};

fn validated() -> Gpu {
    Gpu::new(&GpuDesc { validation: true, ..GpuDesc::default() }).expect("gpu")
}

#[test]
fn the_canary_catches_a_misuse() {
    let gpu = validated();
    let log = gpu.validation_log().unwrap();
    // An access mask that the given stage cannot perform is invalid usage (and harmless to
    // the driver: a barrier is only a barrier).
    gpu.run(|rec| {
        rec.memory_barrier(
            (vk::PipelineStageFlags::TRANSFER, vk::AccessFlags::SHADER_WRITE),
            (vk::PipelineStageFlags::COMPUTE_SHADER, vk::AccessFlags::SHADER_READ),
        )
    })
    .unwrap();
    drop(gpu);
    assert!(!log.errors().is_empty(), "the validation layer reported nothing for an invalid barrier");
}

#[test]
fn synchronization_validation_catches_a_missing_barrier() {
    let gpu = validated();
    let log = gpu.validation_log().unwrap();
    let a =
        Buffer::<u32>::new(&gpu, "written", 1024, vk::BufferUsageFlags::STORAGE_BUFFER, MemoryKind::GpuOnly)
            .unwrap();
    let b = Buffer::<u32>::new(&gpu, "copy", 1024, vk::BufferUsageFlags::STORAGE_BUFFER, MemoryKind::GpuOnly)
        .unwrap();
    gpu.run(|rec| {
        rec.fill_buffer(&a, 1);
        // Read-after-write with no barrier between the fill and the copy: a hazard that only
        // synchronization validation reports.
        let region = vk::BufferCopy { src_offset: 0, dst_offset: 0, size: a.size_bytes() };
        // SAFETY: valid buffers, kept; the undeclared access (so no barrier) is the point of the
        // test.
        unsafe {
            rec.keep(&a);
            rec.keep(&b);
            gpu.device().cmd_copy_buffer(rec.raw(), a.raw(), b.raw(), &[region])
        };
    })
    .unwrap();
    drop((a, b, gpu));
    let errors = log.errors();
    assert!(
        errors.iter().any(|e| e.contains("SYNC-HAZARD")),
        "no synchronization hazard reported: {errors:?}"
    );
}

#[test]
fn the_canary_catches_a_leak_at_teardown() {
    let gpu = validated();
    let log = gpu.validation_log().unwrap();
    let info = vk::BufferCreateInfo::default().size(64).usage(vk::BufferUsageFlags::STORAGE_BUFFER);
    // SAFETY: a valid buffer, deliberately never destroyed.
    let _leaked = unsafe { gpu.device().create_buffer(&info, None) }.unwrap();
    assert!(log.errors().is_empty());
    drop(gpu);
    let errors = log.errors();
    assert!(!errors.is_empty(), "destroying a device with a live buffer must be reported");
    assert!(errors.iter().any(|e| e.contains("vkDestroyDevice") || e.contains("VkBuffer")), "{errors:?}");
}

#[test]
fn resources_dropped_while_recorded_live_until_the_fence() {
    let gpu = common::gpu();
    let keep =
        Buffer::<u32>::new(&gpu, "kept", 1024, vk::BufferUsageFlags::STORAGE_BUFFER, MemoryKind::GpuOnly)
            .unwrap();
    gpu.run(|rec| {
        // Used by the command buffer, then dropped before submission: destruction must wait.
        let temp = Buffer::<u32>::new(
            &gpu,
            "temporary",
            1024,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryKind::GpuOnly,
        )
        .unwrap();
        rec.fill_buffer(&temp, 7);
        rec.fill_buffer(&keep, 42);
    })
    .unwrap();
    assert!(keep.download(&gpu).unwrap().iter().all(|&v| v == 42));
}

#[test]
fn asynchronous_submission_keeps_dropped_resources_alive() {
    let gpu = common::gpu();
    let out =
        Buffer::<u32>::new(&gpu, "out", 1 << 20, vk::BufferUsageFlags::STORAGE_BUFFER, MemoryKind::GpuOnly)
            .unwrap();
    let src =
        Buffer::<u32>::from_slice(&gpu, "src", &vec![5u32; 1 << 20], vk::BufferUsageFlags::STORAGE_BUFFER)
            .unwrap();
    let (submission, ()) = gpu
        .submit(|rec| {
            let region = vk::BufferCopy { src_offset: 0, dst_offset: 0, size: src.size_bytes() };
            // A raw command keeps and declares what it names (Recorder::raw's contract): `src`
            // is dropped below while the copy may still run, and the recording's use of it
            // must keep it alive.
            rec.access(&src, Access::TRANSFER_READ);
            rec.access(&out, Access::TRANSFER_WRITE);
            // SAFETY: both buffers are kept and declared above.
            unsafe { gpu.device().cmd_copy_buffer(rec.raw(), src.raw(), out.raw(), &[region]) };
        })
        .unwrap();
    drop(src);
    submission.wait().unwrap();
    assert!(out.download(&gpu).unwrap().iter().all(|&v| v == 5));
}

#[test]
fn many_threads_share_one_gpu() {
    let gpu = common::gpu();
    std::thread::scope(|s| {
        for t in 0..4u32 {
            let gpu = &*gpu;
            s.spawn(move || {
                for k in 0..10u32 {
                    let b = Buffer::<u32>::new(
                        gpu,
                        "thread",
                        256,
                        vk::BufferUsageFlags::STORAGE_BUFFER,
                        MemoryKind::GpuOnly,
                    )
                    .unwrap();
                    gpu.run(|rec| rec.fill_buffer(&b, t * 100 + k)).unwrap();
                    assert!(b.download(gpu).unwrap().iter().all(|&v| v == t * 100 + k));
                }
            });
        }
    });
}
