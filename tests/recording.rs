//! The recording layer's guarantees (`galerkin::gpu::Recorder`): everything a recording uses
//! stays alive until its work is known to be finished — on a host's command buffer until the
//! host releases the `Recording`, on the engine's until its fence — so objects dropped right
//! after recording are still valid when the work runs (the validation layer, on in every test,
//! reports any destroyed object a submitted command buffer uses); host access to mapped memory
//! is refused while a recording that uses it is pending; objects remember their device; and a
//! submission that timed out is retired once it finishes.

mod common;

use common::host::HostCommands;

use std::time::{Duration, Instant};

use galerkin::bench::kernels::FmaKernel;
use galerkin::demo::axpy::{axpy_error_ratio, Axpy};
use galerkin::gpu::{vk, Buffer, GpuError, MemoryKind, Recorder, Resource};

#[test]
fn objects_dropped_after_recording_into_a_host_buffer_live_until_the_host_releases_it() {
    let gpu = common::gpu();
    let n = 50_000;
    let (x, y) = (common::random_f32(n, 11), common::random_f32(n, 12));
    let xb = Buffer::from_slice(&gpu, "x", &x, vk::BufferUsageFlags::STORAGE_BUFFER).unwrap();
    let yb = Buffer::from_slice(&gpu, "y", &y, vk::BufferUsageFlags::STORAGE_BUFFER).unwrap();
    let axpy = Axpy::new(&gpu).unwrap();
    let binding = axpy.bind(&gpu, &xb, &yb).unwrap();
    let host = HostCommands::new(&gpu);
    // SAFETY: the host's buffer is recording on this device, used by this thread only, and
    // the Recording is kept until its fence was waited for.
    let mut rec = unsafe { Recorder::from_host(&gpu, host.cmd) };
    axpy.record(&gpu, &mut rec, &binding, 0.5);
    let recording = rec.finish();
    assert!(recording.objects() >= 2, "the pipeline and its set are kept: {recording:?}");
    // The pipeline, its descriptor set and x go before the work is even submitted.
    drop((binding, axpy, xb));
    host.submit_and_wait();
    drop(recording);
    let out = yb.download(&gpu).unwrap();
    // Tolerance: fma(a, x, y) in f32 is within two roundings of the exact value.
    let (ratio, at) = axpy_error_ratio(0.5, &x, &y, &out);
    assert!(ratio <= 1.0, "element {at}: {ratio} times the f32 bound");
}

#[test]
fn mapped_memory_is_refused_while_a_recording_that_uses_it_is_pending() {
    let gpu = common::gpu();
    let mut b = Buffer::<u32>::new(
        &gpu,
        "host-visible",
        256,
        vk::BufferUsageFlags::STORAGE_BUFFER,
        MemoryKind::CpuToGpu,
    )
    .unwrap();
    b.mapped_mut().unwrap().fill(7);
    let host = HostCommands::new(&gpu);
    // SAFETY: as above.
    let mut rec = unsafe { Recorder::from_host(&gpu, host.cmd) };
    rec.fill_buffer(&b, 3);
    let recording = rec.finish();
    match b.mapped_mut() {
        Err(GpuError::NotMappable { name, .. }) => assert_eq!(name, "host-visible"),
        other => panic!("mapped while pending: {:?}", other.map(|s| s.len())),
    }
    assert!(b.mapped().is_none(), "reading while the device may write is refused too");
    host.submit_and_wait();
    drop(recording);
    assert!(b.mapped().unwrap().iter().all(|&v| v == 3), "the device's fill is visible after the fence");
    b.mapped_mut().unwrap()[0] = 9;
}

#[test]
fn engine_submissions_keep_what_they_recorded_until_their_fence() {
    let gpu = common::gpu();
    let n = 10_000;
    let (x, y) = (common::random_f32(n, 21), common::random_f32(n, 22));
    let yb = Buffer::from_slice(&gpu, "y", &y, vk::BufferUsageFlags::STORAGE_BUFFER).unwrap();
    let (submission, ()) = {
        let xb = Buffer::from_slice(&gpu, "x", &x, vk::BufferUsageFlags::STORAGE_BUFFER).unwrap();
        let axpy = Axpy::new(&gpu).unwrap();
        let binding = axpy.bind(&gpu, &xb, &yb).unwrap();
        gpu.submit(|rec| axpy.record(&gpu, rec, &binding, -2.0)).unwrap()
        // x, the pipeline and its set are dropped here, before the work is waited for.
    };
    submission.wait().unwrap();
    let out = yb.download(&gpu).unwrap();
    let (ratio, at) = axpy_error_ratio(-2.0, &x, &y, &out);
    assert!(ratio <= 1.0, "element {at}: {ratio} times the f32 bound");
}

#[test]
fn objects_remember_their_device() {
    let a = common::gpu();
    let b = common::gpu();
    let on_a =
        Buffer::from_slice(&a, "buffer of device A", &[1.0f32; 64], vk::BufferUsageFlags::STORAGE_BUFFER)
            .unwrap();
    assert!(on_a.is_on(&a) && !on_a.is_on(&b));
    let wrong = |e: GpuError| matches!(e, GpuError::WrongDevice { ref name } if name == "buffer of device A");
    assert!(wrong(on_a.upload(&b, 0, &[2.0; 4]).unwrap_err()), "upload through another device");
    assert!(wrong(on_a.download(&b).unwrap_err()), "download through another device");
    let axpy_b = Axpy::new(&b).unwrap();
    let on_b = Buffer::from_slice(&b, "y on B", &[0.0f32; 64], vk::BufferUsageFlags::STORAGE_BUFFER).unwrap();
    let err = axpy_b.bind(&b, &on_a, &on_b).err().expect("a set on B binding A's buffer is refused");
    assert!(wrong(err), "a set on B binding A's buffer");
    let _ = Resource::Storage(on_a.binding().unwrap());
    // Recording A's buffer into B's command buffer is a bug: a panic naming it, before
    // anything reaches the device.
    let panicked = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let _ = b.run(|rec| rec.fill_buffer(&on_a, 0));
    }));
    let message = panicked.expect_err("recording another device's buffer panics");
    let text = message.downcast_ref::<String>().cloned().unwrap_or_default();
    assert!(text.contains("buffer of device A"), "{text}");
    // Both devices still work and tear down cleanly (validation is checked at drop).
    assert_eq!(on_a.download(&a).unwrap()[0], 1.0);
    b.run(|rec| rec.fill_buffer(&on_b, 0)).unwrap();
}

#[test]
fn a_timed_out_submission_is_retired_once_it_finishes() {
    let gpu = common::gpu();
    // About a quarter of a second of FMA chains on lavapipe: far longer than the 1 µs waited.
    let fma = FmaKernel::new(&gpu, 64).unwrap();
    let (submission, ()) = gpu.submit(|rec| fma.record(rec, 200_000, 0.999, 1e-4)).unwrap();
    let waited = submission.wait_for(Duration::from_micros(1));
    assert!(matches!(waited, Err(GpuError::Timeout { .. })), "{waited:?}");
    assert!(gpu.pending_submissions() >= 1, "the timed-out work is still tracked");
    // Dropping the kernel now must not destroy what the running work uses (validation would
    // report it); its objects are released when the work is seen finished.
    drop(fma);
    let start = Instant::now();
    while gpu.pending_submissions() > 0 {
        assert!(start.elapsed() < Duration::from_secs(120), "the submission was never retired");
        std::thread::sleep(Duration::from_millis(5));
        gpu.poll();
    }
    // Later work runs and its resources are freed at once again.
    let y = Buffer::from_slice(&gpu, "after", &[1u32; 16], vk::BufferUsageFlags::STORAGE_BUFFER).unwrap();
    gpu.run(|rec| rec.fill_buffer(&y, 5)).unwrap();
    assert_eq!(y.download(&gpu).unwrap(), vec![5; 16]);
}
