//! The validation canary: a `VK_EXT_debug_utils` messenger that records every error the
//! Khronos validation layer reports, so a test can fail on any of them.
//!
//! The messenger is created with the instance (and also chained into `VkInstanceCreateInfo`,
//! so messages from instance creation and destruction — including leaked-object reports when
//! the device and instance are destroyed — are caught too). Like wgpu-hal, the callback does
//! nothing while the thread is panicking.

use std::ffi::{c_void, CStr};
use std::sync::{Arc, Mutex};

use ash::vk;

/// Every validation error seen by one [`crate::gpu::Gpu`], shared so that it can still be read
/// after the `Gpu` (and its instance) has been dropped — that is when leaks are reported.
#[derive(Debug, Default)]
pub struct ValidationLog {
    errors: Mutex<Vec<String>>,
    warnings: Mutex<usize>,
}

impl ValidationLog {
    /// The error messages recorded so far, in order.
    pub fn errors(&self) -> Vec<String> {
        self.errors.lock().map(|e| e.clone()).unwrap_or_default()
    }

    /// Number of warnings (logged through `tracing`, not failures).
    pub fn warning_count(&self) -> usize {
        self.warnings.lock().map(|w| *w).unwrap_or(0)
    }

    /// Panics with every recorded message if any validation error was recorded.
    /// The test harness calls this after dropping the `Gpu`.
    pub fn assert_clean(&self) {
        let errors = self.errors();
        assert!(
            errors.is_empty(),
            "{} Vulkan validation error(s):\n{}",
            errors.len(),
            errors.join("\n---\n")
        );
    }

    fn record(&self, severity: vk::DebugUtilsMessageSeverityFlagsEXT, message: String) {
        if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
            tracing::error!(target: "vulkan", "{message}");
            if let Ok(mut e) = self.errors.lock() {
                e.push(message);
            }
        } else if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING) {
            tracing::warn!(target: "vulkan", "{message}");
            if let Ok(mut w) = self.warnings.lock() {
                *w += 1;
            }
        } else {
            tracing::debug!(target: "vulkan", "{message}");
        }
    }
}

/// The messenger's create info, pointing at `log`. The caller keeps `log` alive for as long as
/// the messenger (or the instance it was chained into) exists.
pub(crate) fn messenger_info(log: &Arc<ValidationLog>) -> vk::DebugUtilsMessengerCreateInfoEXT<'static> {
    vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(
            vk::DebugUtilsMessageSeverityFlagsEXT::ERROR | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
        )
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(callback))
        .user_data(Arc::as_ptr(log) as *mut c_void)
}

unsafe extern "system" fn callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    if std::thread::panicking() || data.is_null() || user.is_null() {
        return vk::FALSE;
    }
    // SAFETY: `user` is the `Arc<ValidationLog>` pointer set in `messenger_info`, kept alive by
    // the owner of the messenger; `data` is valid for the duration of the callback per the spec.
    let (log, data) = unsafe { (&*(user as *const ValidationLog), &*data) };
    let text = |p: *const std::ffi::c_char| {
        if p.is_null() {
            String::new()
        } else {
            // SAFETY: the layer passes NUL-terminated strings valid during the callback.
            unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
        }
    };
    let message = format!("[{kind:?}] {}: {}", text(data.p_message_id_name), text(data.p_message));
    log.record(severity, message);
    vk::FALSE
}
