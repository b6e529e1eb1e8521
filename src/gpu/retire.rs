//! Retirement: when an object may be destroyed is decided by its [`super::Lifetime`] alone. A
//! recording holds a use of every object it records until its work is known to be finished
//! (its fence seen signalled, or the host's [`super::Recording`] dropped), so the last
//! reference to an object goes only when no recorded work can still use it, and it is
//! destroyed then, at once. The device counts its submissions in flight (serials, for
//! [`super::Gpu::pending_submissions`]) and keeps the slots they free for reuse.
//!
//! A submission that times out is not forgotten: dropping it hands its fence, serial and
//! objects to the device, which polls the fence at every later submission and retires them
//! when it signals (or at teardown). Objects of host recordings dropped without
//! [`super::Recorder::finish`] are kept until the device goes.

use std::collections::BTreeSet;

use ash::vk;

use super::context::DeviceShared;
use super::lifetime::Use;
use super::slot::Slot;

/// An object's destructor (run when its [`super::Lifetime`] ends).
pub(crate) type Retirement = Box<dyn FnOnce(&DeviceShared) + Send>;

/// Submission serials in flight, free slots, timed-out submissions and orphaned uses.
#[derive(Default)]
pub(crate) struct Tracker {
    pub(crate) next_serial: u64,
    pub(crate) in_flight: BTreeSet<u64>,
    /// Reusable slots, each with an unsignalled fence and a reset pool.
    pub(crate) free: Vec<Slot>,
    /// Timed-out submissions: their slot, serial and objects, until their fence signals.
    pub(crate) abandoned: Vec<(Slot, u64, Vec<Use>)>,
    /// Objects of host recordings dropped without [`Recorder::finish`], kept until teardown.
    pub(crate) orphans: Vec<Use>,
}

impl DeviceShared {
    /// Destroys an object whose last reference went: no recorded work can use it any more
    /// (every recording holds a use of what it records until its work has finished).
    pub(crate) fn retire(&self, destroy: impl FnOnce(&DeviceShared) + Send + 'static) {
        destroy(self);
    }

    /// Keeps a host recording's objects until the device goes.
    pub(crate) fn orphan(&self, uses: Vec<Use>) {
        let mut t = self.tracker.lock().unwrap_or_else(|p| p.into_inner());
        t.orphans.extend(uses);
    }

    /// Retires every timed-out submission whose fence has signalled since.
    pub(crate) fn poll_abandoned(&self) {
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

    /// Marks `serial` finished, returning `reuse` to the free slots.
    pub(crate) fn finish(&self, serial: u64, reuse: Option<Slot>) {
        let mut t = self.tracker.lock().unwrap_or_else(|p| p.into_inner());
        t.in_flight.remove(&serial);
        if let Some(slot) = reuse {
            t.free.push(slot);
        }
    }
}
