//! Submitting work.
//!
//! Passes record through a [`Recorder`] they are handed and never submit. [`Gpu::run`] is the
//! convenience that records, submits to the engine's queue with its own fence, and waits on
//! that fence only (never `vkDeviceWaitIdle`, which would also wait on a host's work).
//! [`Gpu::submit`] returns a [`Submission`] to wait on later; it holds every object the
//! recording used (see [`super::lifetime`]) until its fence is seen signalled; what happens to
//! objects dropped meanwhile and to submissions that time out is [`super::retire`]'s.

use std::sync::Arc;
use std::time::Duration;

use ash::vk;

use super::context::{DeviceShared, Gpu};
use super::error::{vk_error, GpuError, GpuResult, VkContext};
use super::fault::{INJECTED_SUBMIT, INJECTED_WAIT};
use super::lifetime::Use;
use super::recorder::Recorder;
use super::slot::Slot;

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
        let r = match (r, self.shared.fault.lose_at_wait()) {
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
                if self.shared.fault.is_lost() {
                    return Err(GpuError::DeviceLost { during: INJECTED_WAIT });
                }
                Err(vk_error("vkWaitForFences (Gpu::run)", e))
            }
        }
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
        if shared.fault.is_lost() {
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
