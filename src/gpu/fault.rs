//! Fault injection for the tests, built only with the cargo feature `fault-injection` (which
//! `make test` turns on; a build without it has neither the [`crate::gpu::GpuDesc`] fields
//! nor the environment variables, and the checks compile to nothing). With it,
//! `GpuDesc::fail_allocation` and `GpuDesc::lose_device` (the CLI reads them from
//! `GALERKIN_FAIL_ALLOCATION` and `GALERKIN_LOSE_DEVICE`) make the N-th device allocation and
//! every later one fail as out of memory, or the wait for the N-th submission report the device
//! lost and every later submission fail as lost — so every command's error path can be driven
//! without a failing device (`tests/fault_injection.rs`, `tests/device_loss.rs`).

/// What an injected device loss reports from a wait.
pub(crate) const INJECTED_WAIT: &str =
    "vkWaitForFences (Gpu::run; lost by fault injection, GALERKIN_LOSE_DEVICE)";
/// What an injected device loss reports from a later submission.
pub(crate) const INJECTED_SUBMIT: &str =
    "vkQueueSubmit (the device was lost by fault injection, GALERKIN_LOSE_DEVICE)";

#[cfg(not(feature = "fault-injection"))]
pub(crate) use disabled::FaultInjection;
#[cfg(feature = "fault-injection")]
pub(crate) use enabled::FaultInjection;

/// Without the feature: no fault is ever injected.
#[cfg(not(feature = "fault-injection"))]
mod disabled {
    use super::super::context::GpuDesc;
    use super::super::error::GpuResult;

    /// No faults.
    #[derive(Debug, Default)]
    pub(crate) struct FaultInjection;

    impl FaultInjection {
        pub(crate) fn from_desc(_: &GpuDesc) -> Self {
            Self
        }
        #[inline(always)]
        pub(crate) fn allocation(&self, _: &str, _: u64) -> GpuResult<()> {
            Ok(())
        }
        #[inline(always)]
        pub(crate) fn lose_at_wait(&self) -> bool {
            false
        }
        #[inline(always)]
        pub(crate) fn is_lost(&self) -> bool {
            false
        }
    }
}

#[cfg(feature = "fault-injection")]
mod enabled {

    use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

    use super::super::context::GpuDesc;
    use super::super::error::{GpuError, GpuResult};

    /// One device's injected faults and the counts they are triggered by.
    #[derive(Debug, Default)]
    pub(crate) struct FaultInjection {
        /// The allocation that fails first (1-based), if any.
        fail_allocation: Option<u64>,
        allocations: AtomicU64,
        /// The submission wait that reports the device lost first (1-based), if any.
        lose_device: Option<u64>,
        waits: AtomicU64,
        lost: AtomicBool,
    }

    impl FaultInjection {
        /// Faults as `desc` asks for them.
        pub(crate) fn from_desc(desc: &GpuDesc) -> Self {
            Self::new(desc.fail_allocation, desc.lose_device)
        }

        /// Faults from these counts.
        pub(crate) fn new(fail_allocation: Option<u64>, lose_device: Option<u64>) -> Self {
            Self { fail_allocation, lose_device, ..Self::default() }
        }

        /// Counts an allocation of `bytes` for `name`; an error if it is one that must fail.
        pub(crate) fn allocation(&self, name: &str, bytes: u64) -> GpuResult<()> {
            let count = self.allocations.fetch_add(1, Ordering::Relaxed) + 1;
            if self.fail_allocation.is_some_and(|n| count >= n) {
                return Err(GpuError::OutOfMemory {
                    name: name.to_string(),
                    bytes,
                    detail: format!(
                        "allocation {count} failed by fault injection (GALERKIN_FAIL_ALLOCATION)"
                    ),
                });
            }
            Ok(())
        }

        /// Counts a wait for a submission; true if the device is lost from this one on (every
        /// later submission then fails as lost).
        pub(crate) fn lose_at_wait(&self) -> bool {
            let Some(n) = self.lose_device else { return false };
            let count = self.waits.fetch_add(1, Ordering::Relaxed) + 1;
            if count >= n {
                self.lost.store(true, Ordering::Relaxed);
            }
            count >= n
        }

        /// True once an injected loss has happened.
        pub(crate) fn is_lost(&self) -> bool {
            self.lost.load(Ordering::Relaxed)
        }
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        #[test]
        fn faults_start_at_their_count_and_stay() {
            let f = FaultInjection::new(Some(3), Some(2));
            assert!(f.allocation("a", 8).is_ok() && f.allocation("b", 8).is_ok());
            let e = f.allocation("c", 8).unwrap_err().to_string();
            assert!(e.contains("allocation 3") && e.contains("GALERKIN_FAIL_ALLOCATION"), "{e}");
            assert!(f.allocation("d", 8).is_err());
            assert!(!f.lose_at_wait() && !f.is_lost());
            assert!(f.lose_at_wait() && f.is_lost() && f.lose_at_wait());
            let none = FaultInjection::default();
            assert!((0..100).all(|_| none.allocation("x", 1).is_ok() && !none.lose_at_wait()));
        }
    }
}
