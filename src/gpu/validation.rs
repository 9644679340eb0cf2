//! Validation-layer hookup: a debug-utils messenger that counts every message it receives.
//!
//! Tests run with the Khronos validation layer and synchronization validation on, and a single
//! warning or error fails them: [`ValidationLog::count`] must stay 0.

use ash::vk;
use std::ffi::{c_void, CStr};
use std::sync::{Arc, Mutex};

/// Messages the validation layer (or the driver) reported through `VK_EXT_debug_utils`.
///
/// Shared between the context and the messenger callback; cheap to clone.
#[derive(Clone, Default, Debug)]
pub struct ValidationLog {
    inner: Arc<Mutex<Vec<String>>>,
}

impl ValidationLog {
    /// Number of warnings and errors received so far.
    pub fn count(&self) -> usize {
        self.lock().len()
    }

    /// The messages received so far, oldest first.
    pub fn messages(&self) -> Vec<String> {
        self.lock().clone()
    }

    /// A messenger description whose callback appends to this log, for hosts that create their
    /// own instance (chain it into `VkInstanceCreateInfo` and/or pass it to
    /// `vkCreateDebugUtilsMessengerEXT`).
    ///
    /// The log must stay at the same address (e.g. in a `Box`) until the messenger is destroyed.
    pub fn messenger_create_info(&self) -> vk::DebugUtilsMessengerCreateInfoEXT<'static> {
        messenger_info(self)
    }

    fn push(&self, message: String) {
        self.lock().push(message);
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<String>> {
        // A panic while holding the lock only loses the Vec's consistency, which a list of strings keeps.
        self.inner.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }
}

/// Severities that count as a validation failure.
pub(crate) const COUNTED_SEVERITIES: vk::DebugUtilsMessageSeverityFlagsEXT =
    vk::DebugUtilsMessageSeverityFlagsEXT::from_raw(
        vk::DebugUtilsMessageSeverityFlagsEXT::WARNING.as_raw() | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR.as_raw(),
    );

/// Builds the messenger description whose callback appends to `log`.
///
/// `log` must outlive the messenger: the context keeps a boxed clone alive for exactly that long.
pub(crate) fn messenger_info(log: &ValidationLog) -> vk::DebugUtilsMessengerCreateInfoEXT<'static> {
    vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(COUNTED_SEVERITIES | vk::DebugUtilsMessageSeverityFlagsEXT::INFO)
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(debug_callback))
        .user_data(log as *const ValidationLog as *mut c_void)
}

/// Whether a message fails a validated run: every warning or error of the validation layer,
/// its performance warnings included (`UNASSIGNED-CoreValidation-Shader-OutputNotConsumed`
/// says a pipeline fetches or passes data no stage reads), every synchronization hazard, and
/// errors from anywhere. Drivers' own GENERAL warnings (e.g. Mesa 22.3's SPIR-V front end
/// warning about a valid `invariant gl_Position`) are logged, not counted: they are not about
/// the application's use of Vulkan.
fn is_counted(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    id: &str,
) -> bool {
    let from_layer =
        kind.intersects(vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE);
    (from_layer && severity.intersects(COUNTED_SEVERITIES))
        || severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR)
        || id.starts_with("SYNC-HAZARD")
}

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user_data: *mut c_void,
) -> vk::Bool32 {
    if data.is_null() || user_data.is_null() {
        return vk::FALSE;
    }
    // SAFETY: the layer passes a valid callback-data struct; user_data is the ValidationLog the
    // context keeps alive for the messenger's lifetime.
    let (data, log) = unsafe { (&*data, &*(user_data as *const ValidationLog)) };
    let text = |p: *const std::ffi::c_char| {
        if p.is_null() {
            String::new()
        } else {
            // SAFETY: non-null strings from the layer are NUL-terminated.
            unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
        }
    };
    let id = text(data.p_message_id_name);
    let message = text(data.p_message);
    let counted = is_counted(severity, kind, &id);
    if counted {
        tracing::error!(target: "vulkan", ?kind, id = %id, "{message}");
        log.push(format!("[{id}] {message}"));
    } else if severity.intersects(COUNTED_SEVERITIES) {
        tracing::warn!(target: "vulkan", ?kind, id = %id, "{message}");
    } else {
        tracing::trace!(target: "vulkan", ?kind, id = %id, "{message}");
    }
    vk::FALSE
}

#[cfg(test)]
mod tests {
    use super::*;
    use vk::DebugUtilsMessageSeverityFlagsEXT as Severity;
    use vk::DebugUtilsMessageTypeFlagsEXT as Kind;

    #[test]
    fn warnings_and_errors_of_the_layer_count_and_driver_warnings_do_not() {
        let id = "UNASSIGNED-CoreValidation-Shader-OutputNotConsumed";
        assert!(is_counted(Severity::WARNING, Kind::PERFORMANCE, id));
        assert!(is_counted(Severity::WARNING, Kind::VALIDATION, "VUID-x"));
        assert!(is_counted(Severity::ERROR, Kind::VALIDATION, "VUID-x"));
        assert!(is_counted(Severity::ERROR, Kind::GENERAL, "driver"));
        assert!(is_counted(Severity::INFO, Kind::VALIDATION, "SYNC-HAZARD-WRITE-AFTER-READ"));
        assert!(!is_counted(Severity::WARNING, Kind::GENERAL, "../src/vulkan/runtime/vk_nir.c:56"));
        assert!(!is_counted(Severity::INFO, Kind::PERFORMANCE, id));
        assert!(!is_counted(Severity::INFO, Kind::VALIDATION, "VUID-x"));
    }
}
