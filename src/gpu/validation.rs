//! Validation messenger: collects every warning and error the Khronos
//! validation layer (with synchronization validation) reports, so tests and
//! `--validate` runs can fail on any of them instead of scrolling past logs.

use ash::vk;
use std::ffi::{c_void, CStr};
use std::fmt;
use std::sync::{Arc, Mutex};

pub const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// One message reported by the validation layer.
#[derive(Clone, Debug)]
pub struct ValidationMessage {
    pub severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    /// The VUID or hazard name, e.g. `SYNC-HAZARD-READ-AFTER-WRITE`.
    pub id: String,
    pub text: String,
}

impl fmt::Display for ValidationMessage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let sev = if self.severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
            "error"
        } else {
            "warning"
        };
        write!(f, "[{sev}] {}: {}", self.id, self.text)
    }
}

/// Messages kept until taken. A host that never takes them (validation
/// left on in a long-running engine) holds at most `MAX_KEPT`; the rest are
/// counted, and a last message says how many were dropped.
#[derive(Default)]
pub(crate) struct Messages {
    kept: Vec<ValidationMessage>,
    dropped: u64,
    /// Whether an error was among the dropped.
    dropped_error: bool,
}

/// How many messages are kept until taken.
pub const MAX_KEPT: usize = 1024;

impl Messages {
    fn push(&mut self, message: ValidationMessage) {
        match self.kept.len() < MAX_KEPT {
            true => self.kept.push(message),
            false => {
                self.dropped += 1;
                self.dropped_error |= message.severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR);
            }
        }
    }

    /// The kept messages, and one more naming how many were dropped.
    pub(crate) fn list(&self) -> Vec<ValidationMessage> {
        let mut list = self.kept.clone();
        if self.dropped > 0 {
            list.push(ValidationMessage {
                severity: match self.dropped_error {
                    true => vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
                    false => vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
                },
                id: "lacuna-messages-dropped".into(),
                text: format!(
                    "{} more validation messages were dropped: lacuna keeps the first {MAX_KEPT} until they are taken",
                    self.dropped
                ),
            });
        }
        list
    }

    pub(crate) fn take(&mut self) -> Vec<ValidationMessage> {
        let list = self.list();
        *self = Messages::default();
        list
    }
}

pub(crate) type MessageStore = Arc<Mutex<Messages>>;

/// Owns the debug-utils messenger; the store outlives it through the `Arc`.
pub(crate) struct Messenger {
    loader: ash::ext::debug_utils::Instance,
    handle: vk::DebugUtilsMessengerEXT,
    // Boxed so the pointer handed to Vulkan stays put.
    _user: Box<MessageStore>,
    pub store: MessageStore,
}

unsafe extern "system" fn on_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    if data.is_null() || user.is_null() {
        return vk::FALSE;
    }
    let data = &*data;
    let text = data
        .message_as_c_str()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let id = data
        .message_id_name_as_c_str()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let store = &*(user as *const MessageStore);
    if let Ok(mut v) = store.lock() {
        v.push(ValidationMessage { severity, id, text });
    }
    vk::FALSE
}

impl Messenger {
    pub(crate) fn new(entry: &ash::Entry, instance: &ash::Instance) -> crate::Result<Self> {
        use crate::error::VkContext;
        let loader = ash::ext::debug_utils::Instance::new(entry, instance);
        let store: MessageStore = Arc::new(Mutex::new(Messages::default()));
        let user = Box::new(store.clone());
        let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
            .message_severity(
                vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
            )
            .message_type(
                vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                    | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                    | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
            )
            .pfn_user_callback(Some(on_message))
            .user_data(&*user as *const MessageStore as *mut c_void);
        let handle =
            unsafe { loader.create_debug_utils_messenger(&info, None) }.vk("vkCreateDebugUtilsMessengerEXT")?;
        Ok(Messenger {
            loader,
            handle,
            _user: user,
            store,
        })
    }
}

impl Drop for Messenger {
    fn drop(&mut self) {
        unsafe { self.loader.destroy_debug_utils_messenger(self.handle, None) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn message(i: usize) -> ValidationMessage {
        ValidationMessage {
            severity: vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
            id: format!("VUID-{i}"),
            text: String::new(),
        }
    }

    #[test]
    fn messages_past_the_cap_are_counted_and_named_until_taken() {
        let mut store = Messages::default();
        for i in 0..MAX_KEPT + 5 {
            store.push(message(i));
        }
        let list = store.list();
        assert_eq!(list.len(), MAX_KEPT + 1);
        assert_eq!(list[MAX_KEPT - 1].id, format!("VUID-{}", MAX_KEPT - 1));
        assert!(
            list[MAX_KEPT].text.starts_with("5 more validation messages"),
            "{}",
            list[MAX_KEPT]
        );
        // The dropped were errors: so is the message that counts them.
        assert!(list[MAX_KEPT].to_string().starts_with("[error]"), "{}", list[MAX_KEPT]);
        assert_eq!(store.take().len(), MAX_KEPT + 1);
        assert!(store.take().is_empty());
        store.push(message(7));
        assert_eq!(
            store.take().iter().map(|m| m.id.as_str()).collect::<Vec<_>>(),
            ["VUID-7"]
        );
    }
}
