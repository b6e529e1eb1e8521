//! When a Vulkan object may be destroyed. Every engine object (buffer, image, view, sampler,
//! pipeline, descriptor set, render pass, framebuffer, query pool) keeps its destructor in one
//! [`Lifetime`] behind an `Arc`. The object holds one reference; a [`Recorder`] that records
//! the object holds another until the recording's work is known to be finished (its fence was
//! seen signalled, or the host released the [`Recording`]); a descriptor set holds one for
//! every resource it binds. The destructor runs when the last reference goes — after which
//! nothing recorded can still use the object — at once, through [`DeviceShared::retire`]. This
//! is the one retirement mechanism: nothing else defers a destructor.
//!
//! A lifetime also counts the recordings that are still pending (recorded, not yet known to be
//! finished): a buffer's mapped memory may be written from the host only when that count is
//! zero ([`crate::gpu::Buffer::mapped_mut`]).
//!
//! [`Recorder`]: super::Recorder
//! [`Recording`]: super::Recording

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, Weak};

use super::context::DeviceShared;
use super::retire::Retirement;

/// The destructor of one Vulkan object and the count of pending recordings that use it.
///
/// It holds its device weakly (the device's tracker holds uses of timed-out and orphaned
/// recordings, which must not keep the device alive); the object itself, a [`super::Gpu`], a
/// submission and a host's recording hold the device strongly, so it is alive whenever a
/// lifetime ends — except for those the device's own teardown releases, whose destructors
/// queue for that teardown to run.
pub struct Lifetime {
    shared: Weak<DeviceShared>,
    /// Where the destructor goes if the device is being torn down when the last reference
    /// goes ([`DeviceShared::graveyard`]).
    graveyard: Arc<Mutex<Vec<Retirement>>>,
    name: String,
    destroy: Mutex<Option<Retirement>>,
    pending: AtomicUsize,
}

impl std::fmt::Debug for Lifetime {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Lifetime").field("name", &self.name).field("pending", &self.pending()).finish()
    }
}

impl Lifetime {
    /// A lifetime that runs `destroy` (through the device's retirement) when its last
    /// reference is dropped.
    pub(crate) fn new(
        shared: &Arc<DeviceShared>,
        name: &str,
        destroy: impl FnOnce(&DeviceShared) + Send + 'static,
    ) -> Arc<Self> {
        Arc::new(Self {
            shared: Arc::downgrade(shared),
            graveyard: shared.graveyard.clone(),
            name: name.to_string(),
            destroy: Mutex::new(Some(Box::new(destroy))),
            pending: AtomicUsize::new(0),
        })
    }

    /// The object's name (for errors).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Recordings that use the object and are not yet known to be finished.
    pub fn pending(&self) -> usize {
        self.pending.load(Ordering::Acquire)
    }

    /// True if the object was made on the device of `shared`.
    pub(crate) fn is_on(&self, shared: &Arc<DeviceShared>) -> bool {
        std::ptr::eq(self.shared.as_ptr(), Arc::as_ptr(shared))
    }
}

impl Drop for Lifetime {
    fn drop(&mut self) {
        let destroy = self.destroy.get_mut().unwrap_or_else(|p| p.into_inner()).take();
        if let Some(destroy) = destroy {
            match self.shared.upgrade() {
                Some(shared) => shared.retire(destroy),
                // Only while the device itself is being torn down (see `DeviceShared::drop`).
                None => self.graveyard.lock().unwrap_or_else(|p| p.into_inner()).push(destroy),
            }
        }
    }
}

/// One pending recording's use of an object: holds the object alive and counts as pending
/// until dropped.
pub(crate) struct Use(Arc<Lifetime>);

impl Use {
    pub(crate) fn new(life: &Arc<Lifetime>) -> Self {
        life.pending.fetch_add(1, Ordering::AcqRel);
        Self(life.clone())
    }
}

impl Drop for Use {
    fn drop(&mut self) {
        self.0.pending.fetch_sub(1, Ordering::AcqRel);
    }
}

/// An engine object a recording can keep alive. Implemented by every object a pass records;
/// [`super::Recorder::keep`] takes any of them.
pub trait Tracked {
    /// The object's lifetime.
    fn lifetime(&self) -> &Arc<Lifetime>;
}
