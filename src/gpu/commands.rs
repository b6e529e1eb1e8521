//! Submitting work and retiring resources.
//!
//! Passes record through a [`Recorder`] they are handed and never submit. [`Gpu::run`] is the
//! convenience that records, submits to the engine's queue with its own fence, and waits on
//! that fence only (never `vkDeviceWaitIdle`, which would also wait on a host's work).
//! [`Gpu::submit`] returns a [`Submission`] to wait on later; it holds every object the
//! recording used (see [`super::lifetime`]) until its fence is seen signalled.
//!
//! Deferred destruction: every engine submission also gets a serial that is "in flight" from
//! the moment its recording begins until its fence is seen signalled. A resource whose last
//! reference goes while any serial is in flight is not destroyed at once: its destructor is
//! queued with the newest serial and runs when no serial at or below it is in flight.
//!
//! A submission that times out is not forgotten: dropping it hands its fence, serial and
//! objects to the device, which polls the fence at every later submission and retires them
//! when it signals (or at teardown).

use std::collections::BTreeSet;
use std::sync::Arc;
use std::time::Duration;

use ash::vk;

use super::context::{DeviceShared, Gpu};
use super::error::{vk_error, GpuError, GpuResult, VkContext};
use super::lifetime::Use;
use super::recorder::Recorder;

/// One submission's command pool (its own, so recording on several threads needs no lock),
/// its one command buffer and its fence.
#[derive(Clone, Copy)]
pub(crate) struct Slot {
    pub pool: vk::CommandPool,
    pub cmd: vk::CommandBuffer,
    pub fence: vk::Fence,
}

impl Slot {
    fn new(shared: &DeviceShared) -> GpuResult<Self> {
        let info = vk::CommandPoolCreateInfo::default().queue_family_index(shared.queue_family);
        // SAFETY: plain object creation on this device.
        let pool = unsafe { shared.raw.create_command_pool(&info, None) }.vk("vkCreateCommandPool")?;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: `pool` is new and used by this thread only.
        let cmd = match unsafe { shared.raw.allocate_command_buffers(&alloc) } {
            Ok(c) => c[0],
            Err(e) => {
                // SAFETY: nothing else uses the new pool.
                unsafe { shared.raw.destroy_command_pool(pool, None) };
                return Err(vk_error("vkAllocateCommandBuffers", e));
            }
        };
        // SAFETY: plain object creation.
        match unsafe { shared.raw.create_fence(&vk::FenceCreateInfo::default(), None) } {
            Ok(fence) => Ok(Self { pool, cmd, fence }),
            Err(e) => {
                // SAFETY: the pool (and its buffer) were never submitted.
                unsafe { shared.raw.destroy_command_pool(pool, None) };
                Err(vk_error("vkCreateFence", e))
            }
        }
    }

    /// Resets the pool (and so the buffer) for reuse; the fence must already be unsignalled.
    fn reset(&self, shared: &DeviceShared) -> bool {
        // SAFETY: the slot's work is finished or was never submitted.
        unsafe { shared.raw.reset_command_pool(self.pool, vk::CommandPoolResetFlags::empty()) }.is_ok()
    }

    /// Destroys the slot's objects.
    pub(crate) fn destroy(self, shared: &DeviceShared) {
        // SAFETY: the slot's work is finished or was never submitted.
        unsafe {
            shared.raw.destroy_fence(self.fence, None);
            shared.raw.destroy_command_pool(self.pool, None);
        }
    }
}

/// A destructor waiting for in-flight work.
pub(crate) type Retirement = Box<dyn FnOnce(&DeviceShared) + Send>;

/// Submission serials in flight and the destructors waiting for them.
#[derive(Default)]
pub(crate) struct Tracker {
    next_serial: u64,
    in_flight: BTreeSet<u64>,
    retired: Vec<(u64, Retirement)>,
    /// Reusable slots, each with an unsignalled fence and a reset pool.
    pub(crate) free: Vec<Slot>,
    /// Timed-out submissions: their slot, serial and objects, until their fence signals.
    pub(crate) abandoned: Vec<(Slot, u64, Vec<Use>)>,
    /// Objects of host recordings dropped without [`Recorder::finish`], kept until teardown.
    pub(crate) orphans: Vec<Use>,
}

impl Tracker {
    /// Everything still waiting (used at teardown, when nothing can be in flight).
    pub(crate) fn take_all(&mut self) -> Vec<Retirement> {
        self.retired.drain(..).map(|(_, f)| f).collect()
    }

    /// Marks `serial` finished and returns the destructors that may now run.
    fn complete(&mut self, serial: u64) -> Vec<Retirement> {
        self.in_flight.remove(&serial);
        let oldest = self.in_flight.first().copied().unwrap_or(u64::MAX);
        let (ready, keep): (Vec<_>, Vec<_>) = self.retired.drain(..).partition(|(s, _)| *s < oldest);
        self.retired = keep;
        ready.into_iter().map(|(_, f)| f).collect()
    }
}

impl DeviceShared {
    /// Destroys an object now, or after the engine's in-flight work if there is any.
    pub(crate) fn retire(&self, destroy: impl FnOnce(&DeviceShared) + Send + 'static) {
        let mut t = self.tracker.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(&newest) = t.in_flight.last() {
            t.retired.push((newest, Box::new(destroy)));
        } else {
            drop(t);
            destroy(self);
        }
    }

    /// Keeps a host recording's objects until the device goes.
    pub(crate) fn orphan(&self, uses: Vec<Use>) {
        let mut t = self.tracker.lock().unwrap_or_else(|p| p.into_inner());
        t.orphans.extend(uses);
    }

    /// Retires every timed-out submission whose fence has signalled since.
    fn poll_abandoned(&self) {
        let done: Vec<(Slot, u64, Vec<Use>)> = {
            let mut t = self.tracker.lock().unwrap_or_else(|p| p.into_inner());
            if t.abandoned.is_empty() {
                return;
            }
            let (done, waiting): (Vec<_>, Vec<_>) = t
                .abandoned
                .drain(..)
                // SAFETY: the fence belongs to this device and was submitted.
                .partition(|(slot, _, _)| unsafe { self.raw.get_fence_status(slot.fence) }.unwrap_or(true));
            t.abandoned = waiting;
            done
        };
        for (slot, serial, uses) in done {
            // SAFETY: the fence is signalled (or the device is lost): the queue no longer uses it.
            let fence_reset = unsafe { self.raw.reset_fences(&[slot.fence]) }.is_ok();
            let reuse = (fence_reset && slot.reset(self)).then_some(slot);
            if reuse.is_none() {
                slot.destroy(self);
            }
            drop(uses);
            self.finish(serial, reuse);
        }
    }

    /// At teardown: waits (up to the fence timeout each) for timed-out submissions and returns
    /// their slots and objects; a fence that never signals leaves its slot undestroyed.
    pub(crate) fn drain_abandoned(&mut self) -> (Vec<Slot>, Vec<Use>) {
        let nanos = u64::try_from(self.fence_timeout.as_nanos()).unwrap_or(u64::MAX);
        let abandoned = self.tracker.get_mut().map(|t| std::mem::take(&mut t.abandoned)).unwrap_or_default();
        let (mut slots, mut released) = (Vec::new(), Vec::new());
        for (slot, _, uses) in abandoned {
            // SAFETY: the fence belongs to this device.
            match unsafe { self.raw.wait_for_fences(&[slot.fence], true, nanos) } {
                Ok(()) | Err(vk::Result::ERROR_DEVICE_LOST) => {
                    slots.push(slot);
                    released.extend(uses);
                }
                Err(e) => {
                    tracing::error!("a timed-out submission is still running at teardown ({e}); leaking it");
                    std::mem::forget(uses);
                }
            }
        }
        (slots, released)
    }

    fn finish(&self, serial: u64, reuse: Option<Slot>) {
        let ready = {
            let mut t = self.tracker.lock().unwrap_or_else(|p| p.into_inner());
            if let Some(pair) = reuse {
                t.free.push(pair);
            }
            t.complete(serial)
        };
        for f in ready {
            f(self);
        }
    }
}

/// Work submitted with [`Gpu::submit`]. Waiting (or dropping) it waits on its own fence.
#[must_use = "a submission is waited on when dropped; call wait() to see its errors"]
pub struct Submission {
    /// Every object the recording used, released when the fence is seen signalled (first:
    /// fields drop in order, and these must go while the device is alive).
    uses: Vec<Use>,
    shared: Arc<DeviceShared>,
    slot: Slot,
    serial: u64,
    done: bool,
    /// A wait already timed out: dropping it abandons it rather than waiting again.
    timed_out: bool,
}

impl Submission {
    /// Waits until the work has finished. Device loss and timeouts are errors, not panics.
    pub fn wait(mut self) -> GpuResult<()> {
        let timeout = self.shared.fence_timeout;
        self.wait_inner(timeout)
    }

    /// Waits at most `timeout` (instead of [`crate::gpu::GpuDesc::fence_timeout`]). On a
    /// timeout the work is handed to the device, which retires it once its fence signals
    /// (see [`Gpu::pending_submissions`]).
    pub fn wait_for(mut self, timeout: Duration) -> GpuResult<()> {
        self.wait_inner(timeout)
    }

    /// True if the work has finished (does not block).
    pub fn is_done(&self) -> bool {
        // SAFETY: the fence belongs to this device and is alive until this submission drops.
        self.done || unsafe { self.shared.raw.get_fence_status(self.slot.fence) }.unwrap_or(false)
    }

    fn wait_inner(&mut self, timeout: Duration) -> GpuResult<()> {
        if self.done {
            return Ok(());
        }
        let nanos = u64::try_from(timeout.as_nanos()).unwrap_or(u64::MAX);
        // SAFETY: the fence was submitted with this work and is owned by the engine.
        let r = unsafe { self.shared.raw.wait_for_fences(&[self.slot.fence], true, nanos) };
        let r = match (r, self.shared.inject_loss()) {
            // Injected (GpuDesc::lose_device): the work has finished, so the lost path below
            // may destroy what it used, as after a real loss.
            (Ok(()), true) => Err(vk::Result::ERROR_DEVICE_LOST),
            (r, _) => r,
        };
        match r {
            Ok(()) => {
                self.done = true;
                // SAFETY: the fence is signalled and the queue no longer uses it.
                let fence_reset = unsafe { self.shared.raw.reset_fences(&[self.slot.fence]) }.is_ok();
                let reuse = (fence_reset && self.slot.reset(&self.shared)).then_some(self.slot);
                if reuse.is_none() {
                    self.slot.destroy(&self.shared);
                }
                self.uses.clear();
                self.shared.finish(self.serial, reuse);
                Ok(())
            }
            Err(vk::Result::TIMEOUT) => {
                self.timed_out = true;
                Err(GpuError::Timeout { during: "Gpu::run", seconds: timeout.as_secs_f64() })
            }
            Err(e) => {
                // Device lost: nothing will signal again. Retire the serial so drops proceed,
                // and destroy the slot's fence and command buffer (allowed on a lost device).
                self.done = true;
                self.uses.clear();
                self.slot.destroy(&self.shared);
                self.shared.finish(self.serial, None);
                if self.shared.lost.load(std::sync::atomic::Ordering::Relaxed) {
                    return Err(GpuError::DeviceLost { during: INJECTED_WAIT });
                }
                Err(vk_error("vkWaitForFences (Gpu::run)", e))
            }
        }
    }
}

/// What an injected device loss ([`crate::gpu::GpuDesc::lose_device`]) reports.
const INJECTED_WAIT: &str = "vkWaitForFences (Gpu::run; lost by fault injection, GALERKIN_LOSE_DEVICE)";
const INJECTED_SUBMIT: &str = "vkQueueSubmit (the device was lost by fault injection, GALERKIN_LOSE_DEVICE)";

impl DeviceShared {
    /// Counts a wait for a submission; true if [`crate::gpu::GpuDesc::lose_device`] says the
    /// device is lost from this one on (the flag then fails every later submission).
    fn inject_loss(&self) -> bool {
        let Some(n) = self.lose_device else { return false };
        let count = self.waits.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        if count >= n {
            self.lost.store(true, std::sync::atomic::Ordering::Relaxed);
        }
        count >= n
    }
}

impl Drop for Submission {
    fn drop(&mut self) {
        if !self.done && !self.timed_out {
            let timeout = self.shared.fence_timeout;
            if let Err(e) = self.wait_inner(timeout) {
                tracing::error!("dropping an unfinished submission: {e}");
            }
        }
        if !self.done {
            // Timed out: the device polls its fence from now on and retires its serial and
            // objects when it signals, rather than destroying anything still running.
            let mut t = self.shared.tracker.lock().unwrap_or_else(|p| p.into_inner());
            t.abandoned.push((self.slot, self.serial, std::mem::take(&mut self.uses)));
        }
    }
}

impl Gpu {
    /// Records `record` into a fresh command buffer, submits it to the engine's queue and waits
    /// for it. Returns what `record` returned.
    pub fn run<R>(&self, record: impl FnOnce(&mut Recorder<'_>) -> R) -> GpuResult<R> {
        let (submission, r) = self.submit(record)?;
        submission.wait()?;
        Ok(r)
    }

    /// Records and submits without waiting; wait on the returned [`Submission`].
    pub fn submit<R>(&self, record: impl FnOnce(&mut Recorder<'_>) -> R) -> GpuResult<(Submission, R)> {
        // SAFETY: no semaphores.
        unsafe { self.submit_with_semaphores(&[], &[], record) }
    }

    /// Like [`Gpu::submit`], waiting on `wait` semaphores (each at its stage) before the work
    /// and signalling `signal` after it — how a frame waits for a swapchain image and tells
    /// presentation it is done.
    ///
    /// # Safety
    /// Every semaphore is a live binary semaphore of this device that stays alive until the
    /// submission has finished; each `wait` semaphore has a signal operation submitted (or a
    /// presentation-engine acquire pending) and each `signal` semaphore has no pending signal.
    pub unsafe fn submit_with_semaphores<R>(
        &self,
        wait: &[(vk::Semaphore, vk::PipelineStageFlags)],
        signal: &[vk::Semaphore],
        record: impl FnOnce(&mut Recorder<'_>) -> R,
    ) -> GpuResult<(Submission, R)> {
        let shared = &self.shared;
        shared.poll_abandoned();
        let (slot, serial) = {
            let mut t = shared.tracker.lock().unwrap_or_else(|p| p.into_inner());
            let serial = t.next_serial;
            t.next_serial += 1;
            t.in_flight.insert(serial);
            (t.free.pop(), serial)
        };
        // Anything failing before the queue owns the work must release the serial and the slot.
        struct Pending<'a> {
            shared: &'a DeviceShared,
            serial: u64,
            slot: Option<Slot>,
            armed: bool,
        }
        impl Drop for Pending<'_> {
            fn drop(&mut self) {
                if self.armed {
                    let reuse = self.slot.filter(|s| s.reset(self.shared));
                    if let (Some(s), None) = (self.slot, reuse) {
                        s.destroy(self.shared);
                    }
                    self.shared.finish(self.serial, reuse);
                }
            }
        }
        let mut pending = Pending { shared, serial, slot, armed: true };
        let slot = match pending.slot {
            Some(s) => s,
            None => {
                let s = Slot::new(shared)?;
                pending.slot = Some(s);
                s
            }
        };
        let (cmd, fence) = (slot.cmd, slot.fence);
        let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: `cmd` is in the initial state (fresh or reset).
        unsafe { shared.raw.begin_command_buffer(cmd, &begin) }.vk("vkBeginCommandBuffer")?;
        let mut recorder = Recorder::engine(self, cmd);
        let r = record(&mut recorder);
        let uses = recorder.into_uses();
        // SAFETY: `cmd` is recording.
        unsafe { shared.raw.end_command_buffer(cmd) }.vk("vkEndCommandBuffer")?;
        let cmds = [cmd];
        let wait_semaphores: Vec<_> = wait.iter().map(|w| w.0).collect();
        let wait_stages: Vec<_> = wait.iter().map(|w| w.1).collect();
        let submit = vk::SubmitInfo::default()
            .command_buffers(&cmds)
            .wait_semaphores(&wait_semaphores)
            .wait_dst_stage_mask(&wait_stages)
            .signal_semaphores(signal);
        if shared.lost.load(std::sync::atomic::Ordering::Relaxed) {
            return Err(GpuError::DeviceLost { during: INJECTED_SUBMIT });
        }
        {
            let queue = shared.queue.lock().unwrap_or_else(|p| p.into_inner());
            // SAFETY: the queue is externally synchronised by its mutex; `fence` is unsignalled.
            unsafe { shared.raw.queue_submit(*queue, &[submit], fence) }.vk("vkQueueSubmit")?;
        }
        pending.armed = false;
        Ok((Submission { shared: shared.clone(), slot, serial, done: false, timed_out: false, uses }, r))
    }

    /// Engine submissions not yet seen finished (including timed-out ones the device is still
    /// polling): resources dropped meanwhile wait for them.
    pub fn pending_submissions(&self) -> usize {
        let t = self.shared.tracker.lock().unwrap_or_else(|p| p.into_inner());
        t.in_flight.len()
    }

    /// Retires timed-out submissions that have finished since (every submission does this
    /// too); for a host loop that submits nothing through the engine for a while.
    pub fn poll(&self) {
        self.shared.poll_abandoned();
    }

    /// The default timeout of [`Gpu::run`].
    pub fn fence_timeout(&self) -> Duration {
        self.shared.fence_timeout
    }
}
