//! The Vulkan instance, its validation layer and the debug messenger that collects validation
//! messages so that tests can fail on any error.

use super::host_memory::core_callbacks as host_callbacks;
use std::ffi::{c_void, CStr};
use std::sync::{Arc, Mutex};

use ash::vk;

use super::error::{VkError, VkResult, VkResultExt};
use super::host_vulkan::HostVulkan;

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// How to create the instance.
#[derive(Clone, Debug, Default)]
pub struct InstanceOptions {
    /// Enables `VK_LAYER_KHRONOS_validation` and a debug messenger. Tests always set it.
    pub validation: bool,
    /// With `validation`, also the layer's synchronization checks (missing barriers between
    /// commands, submissions and frames). Slow; the tests of the paths that synchronize
    /// most (transparency, windows with frames in flight) set it.
    pub synchronization_validation: bool,
    /// Extra instance extensions (for example the ones a host's window system needs).
    pub extra_extensions: Vec<std::ffi::CString>,
}

/// Validation messages seen so far, shared with the debug messenger callback.
#[derive(Debug, Default)]
pub struct ValidationLog {
    messages: Mutex<Vec<ValidationMessage>>,
}

/// One message from the validation layer.
#[derive(Clone, Debug)]
pub struct ValidationMessage {
    /// `true` for severity error, `false` for warning.
    pub is_error: bool,
    /// The message text, with its VUID.
    pub text: String,
}

impl ValidationLog {
    /// The messages of severity error recorded so far.
    pub fn errors(&self) -> Vec<String> {
        self.lock()
            .iter()
            .filter(|m| m.is_error)
            .map(|m| m.text.clone())
            .collect()
    }

    /// Number of warnings recorded so far.
    pub fn warning_count(&self) -> usize {
        self.lock().iter().filter(|m| !m.is_error).count()
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<ValidationMessage>> {
        // A panic while holding this lock cannot leave the Vec inconsistent: take it anyway.
        self.messages
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn record(&self, is_error: bool, text: String) {
        self.lock().push(ValidationMessage { is_error, text });
    }
}

/// The loaded Vulkan library, the instance and (with validation) the debug messenger.
pub struct Instance {
    pub(crate) entry: ash::Entry,
    pub(crate) raw: ash::Instance,
    pub(crate) debug_utils: Option<ash::ext::debug_utils::Instance>,
    messenger: vk::DebugUtilsMessengerEXT,
    validation_log: Arc<ValidationLog>,
    /// Keeps the callback's user data alive as long as the messenger exists.
    _callback_data: Option<Arc<ValidationLog>>,
    /// Whether cadr made the instance (and destroys it) rather than a host lending it.
    owned: bool,
}

impl Instance {
    /// Loads Vulkan and creates an instance for API version 1.3.
    pub fn new(options: &InstanceOptions) -> VkResult<Self> {
        // SAFETY: loading the system Vulkan loader runs its initialisers; it is the library
        // this process is meant to use, and the Entry keeps it loaded while in use.
        let entry =
            unsafe { ash::Entry::load() }.map_err(|e| VkError::LoaderMissing(e.to_string()))?;

        let mut layers = Vec::new();
        let mut extensions: Vec<*const i8> = options
            .extra_extensions
            .iter()
            .map(|e| e.as_ptr())
            .collect();
        let available_extensions =
            // SAFETY: entry is a loaded Vulkan entry; no layer name is passed.
            unsafe { entry.enumerate_instance_extension_properties(None) }
                .or_vk("vkEnumerateInstanceExtensionProperties")?;
        let has_debug_utils = available_extensions.iter().any(|e| {
            e.extension_name_as_c_str()
                .is_ok_and(|name| name == ash::ext::debug_utils::NAME)
        });
        if options.validation {
            // SAFETY: entry is a loaded Vulkan entry.
            let available = unsafe { entry.enumerate_instance_layer_properties() }
                .or_vk("vkEnumerateInstanceLayerProperties")?;
            let present = available.iter().any(|l| {
                l.layer_name_as_c_str()
                    .is_ok_and(|name| name == VALIDATION_LAYER)
            });
            if !present {
                return Err(VkError::ValidationLayerMissing);
            }
            layers.push(VALIDATION_LAYER.as_ptr());
        }
        if has_debug_utils {
            extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        }

        let app_info = vk::ApplicationInfo::default()
            .application_name(c"cadr")
            .application_version(vk::make_api_version(0, 0, 1, 0))
            .engine_name(c"cadr")
            .api_version(vk::API_VERSION_1_3);
        let synchronization = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        // The layer replaces the driver's handles by its own ("unique handles") and unwraps
        // them in the commands it knows. Commands of extensions newer than the layer
        // (`VK_EXT_device_generated_commands`) reach the driver without unwrapping, so the
        // layer keeps the driver's handles; every check stays on.
        let unique_handles = [vk::ValidationFeatureDisableEXT::UNIQUE_HANDLES];
        let mut validation_features =
            vk::ValidationFeaturesEXT::default().disabled_validation_features(&unique_handles);
        if options.synchronization_validation {
            validation_features = validation_features.enabled_validation_features(&synchronization);
        }
        if options.validation {
            // Offered by the validation layer itself.
            extensions.push(ash::ext::validation_features::NAME.as_ptr());
        }
        let mut create_info = vk::InstanceCreateInfo::default()
            .application_info(&app_info)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        if options.validation {
            create_info = create_info.push_next(&mut validation_features);
        }
        // SAFETY: create_info and everything it points to live until the call returns.
        let create = || unsafe { entry.create_instance(&create_info, host_callbacks()) };
        // The validation layer (tests only) does not survive a failed host allocation of its
        // own set-up: it goes on and crashes later. Injected host-memory failures test cadr,
        // so none is injected into an instance creation with the layer.
        let raw = if layers.is_empty() {
            create()
        } else {
            super::fault::without_host_memory_faults(create)
        }
        .or_vk("vkCreateInstance")?;

        let validation_log = Arc::new(ValidationLog::default());
        let debug_utils =
            has_debug_utils.then(|| ash::ext::debug_utils::Instance::new(&entry, &raw));
        // Built before the messenger, so that a failure to make it destroys the instance.
        let mut instance = Self {
            entry,
            raw,
            debug_utils,
            messenger: vk::DebugUtilsMessengerEXT::null(),
            validation_log,
            _callback_data: None,
            owned: true,
        };
        if options.validation {
            instance.log_validation()?;
        }
        Ok(instance)
    }

    /// A host's instance, which cadr uses without destroying it. Where the host enabled
    /// `VK_EXT_debug_utils`, cadr's own messenger records what the validation layer (if the
    /// host enabled it) reports into [`Instance::validation_log`].
    pub fn from_host(host: &HostVulkan) -> VkResult<Self> {
        let static_fn = ash::StaticFn {
            get_instance_proc_addr: host.get_instance_proc_addr,
        };
        // SAFETY: the host's `vkGetInstanceProcAddr`, valid as long as the host keeps its
        // loader (the host's contract: longer than cadr's context).
        let entry = unsafe { ash::Entry::from_static_fn(static_fn) };
        // SAFETY: the host's live instance, made through that loader.
        let raw = unsafe { ash::Instance::load(entry.static_fn(), host.instance) };
        let debug_utils = host
            .has_instance_extension(ash::ext::debug_utils::NAME)
            .then(|| ash::ext::debug_utils::Instance::new(&entry, &raw));
        let mut instance = Self {
            entry,
            raw,
            debug_utils,
            messenger: vk::DebugUtilsMessengerEXT::null(),
            validation_log: Arc::new(ValidationLog::default()),
            _callback_data: None,
            owned: false,
        };
        instance.log_validation()?;
        Ok(instance)
    }

    /// Records the validation layer's errors and warnings into the log through a messenger of
    /// cadr's own, where the instance has `VK_EXT_debug_utils`.
    fn log_validation(&mut self) -> VkResult<()> {
        if let Some(debug_utils) = &self.debug_utils {
            let validation_log = &self.validation_log;
            let user_data = Arc::clone(validation_log);
            let messenger_info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(
                    vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
                        | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
                )
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                        | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                        | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
                )
                .pfn_user_callback(Some(debug_callback))
                .user_data(Arc::as_ptr(&user_data) as *mut c_void);
            // SAFETY: the user data points to a ValidationLog kept alive by callback_data
            // until after the messenger is destroyed in Drop.
            let messenger = unsafe {
                debug_utils.create_debug_utils_messenger(&messenger_info, host_callbacks())
            }
            .or_vk("vkCreateDebugUtilsMessengerEXT")?;
            self.messenger = messenger;
            self._callback_data = Some(user_data);
        }
        Ok(())
    }

    /// Whether the validation layer reports into the log (validation was asked for).
    pub fn validation_enabled(&self) -> bool {
        self.messenger != vk::DebugUtilsMessengerEXT::null()
    }

    /// The validation messages recorded by the debug messenger (empty without validation).
    pub fn validation_log(&self) -> &Arc<ValidationLog> {
        &self.validation_log
    }

    /// The ash instance, for code that needs raw Vulkan (plugins, window systems).
    pub fn raw(&self) -> &ash::Instance {
        &self.raw
    }

    /// The ash entry (loader functions).
    pub fn entry(&self) -> &ash::Entry {
        &self.entry
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        if let Some(debug_utils) = &self.debug_utils {
            if self.messenger != vk::DebugUtilsMessengerEXT::null() {
                // SAFETY: the messenger was created from this instance and is destroyed once.
                unsafe {
                    debug_utils.destroy_debug_utils_messenger(self.messenger, host_callbacks())
                };
            }
        }
        if self.owned {
            // SAFETY: every child object (devices) is dropped before the instance: Device
            // holds an Arc<Instance>.
            unsafe { self.raw.destroy_instance(host_callbacks()) };
        }
    }
}

/// Structure types of extensions newer than Debian 12's validation layer (1.3.239) that cadr
/// chains where the driver has them: `VkPhysicalDeviceMaintenance5FeaturesKHR` (Vulkan
/// 1.3.268) and `VkPhysicalDeviceDeviceGeneratedCommandsFeaturesEXT` (1.3.296) into
/// `vkCreateDevice`, `VkBufferUsageFlags2CreateInfoKHR` (1.3.268) into the `dgc`
/// submission's `vkCreateBuffer` of preprocess memory, and `VkPipelineCreateFlags2CreateInfoKHR`
/// (1.3.268) into `vkCreateGraphicsPipelines` of the pipelines that `dgc` puts into an
/// execution set. The layer calls any structure it does not know an error
/// (`VUID-…-pNext-pNext`, "unknown VkStructureType"), though the driver knows it: for these
/// four structures, and that message alone, the message is a warning. A newer layer knows
/// them and validates them.
const STRUCTURES_NEWER_THAN_THE_LAYER: [i32; 4] =
    [1_000_470_000, 1_000_470_005, 1_000_470_006, 1_000_572_000];

/// Whether `text` is the layer's "unknown structure" message about one of
/// [`STRUCTURES_NEWER_THAN_THE_LAYER`].
fn is_unknown_newer_structure(text: &str) -> bool {
    text.contains("-pNext-pNext")
        && STRUCTURES_NEWER_THAN_THE_LAYER
            .iter()
            .any(|ty| text.contains(&format!("with unknown VkStructureType ({ty})")))
}

/// Whether `text` is about an extension newer than the layer that cadr enables: an unknown
/// structure of one ([`is_unknown_newer_structure`]), or the layer's warning that it does not
/// validate `VK_EXT_device_generated_commands` or `VK_KHR_maintenance5`. Logged at debug
/// level (still recorded), not printed on every run.
fn is_about_extensions_newer_than_the_layer(text: &str) -> bool {
    is_unknown_newer_structure(text)
        || ["VK_EXT_device_generated_commands", "VK_KHR_maintenance5"]
            .iter()
            .any(|name| text.contains(&format!("Extension {name} is not supported by this layer")))
}

/// Whether `text` is a validation message known to be wrong, recorded as a warning instead
/// of an error. There are two. The layer's "unknown structure" errors about structures of
/// extensions newer than it ([`is_unknown_newer_structure`]). And translucent fragments write the transparency method's storage
/// with atomics and at distinct places, unordered within a rendering by design; the
/// synchronization checks (layers 1.3.239 at least) accept that from the draws of one
/// command buffer but call it a write-after-write hazard between secondary command buffers
/// executed in one rendering, which the specification makes the same as recording them
/// inline. Only that shape matches: both accesses fragment-shader storage writes, found at
/// `vkCmdExecuteCommands`.
fn is_known_false_positive(text: &str) -> bool {
    is_unknown_newer_structure(text) || is_execute_commands_storage_hazard(text)
}

/// The write-after-write "hazard" between secondary command buffers described at
/// [`is_known_false_positive`].
fn is_execute_commands_storage_hazard(text: &str) -> bool {
    const FRAGMENT_STORAGE_WRITE: &str = "SYNC_FRAGMENT_SHADER_SHADER_STORAGE_WRITE";
    text.contains("SYNC-HAZARD-WRITE-AFTER-WRITE")
        && text.contains("vkCmdExecuteCommands: Hazard WRITE_AFTER_WRITE")
        && text.contains(&format!("recorded_usage: {FRAGMENT_STORAGE_WRITE}"))
        && text.contains(&format!("prior_usage: {FRAGMENT_STORAGE_WRITE}"))
}

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user_data: *mut c_void,
) -> vk::Bool32 {
    // Never unwind into the Vulkan loader.
    let _ = std::panic::catch_unwind(|| {
        if data.is_null() || user_data.is_null() {
            return;
        }
        // SAFETY: the layer passes a valid callback-data struct for the duration of the call.
        let data = unsafe { &*data };
        let text = if data.p_message.is_null() {
            String::from("(no message)")
        } else {
            // SAFETY: p_message is a NUL-terminated string owned by the layer during the call.
            unsafe { CStr::from_ptr(data.p_message) }
                .to_string_lossy()
                .into_owned()
        };
        // SAFETY: user_data is the ValidationLog that Instance keeps alive while the messenger exists.
        let log = unsafe { &*(user_data as *const ValidationLog) };
        let is_error = severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR)
            && !is_known_false_positive(&text);
        if is_error {
            log::error!("vulkan validation: {text}");
            eprintln!("[vulkan validation error] {text}");
        } else if is_about_extensions_newer_than_the_layer(&text) {
            log::debug!("vulkan validation (a structure newer than the layer): {text}");
        } else {
            log::warn!("vulkan validation: {text}");
        }
        log.record(is_error, text);
    });
    vk::FALSE
}

#[cfg(test)]
mod tests {
    use super::is_known_false_positive;

    const EXECUTE_COMMANDS_HAZARD: &str = "Validation Error: [ SYNC-HAZARD-WRITE-AFTER-WRITE ] \
        Object 0: name = frame commands | vkCmdExecuteCommands: Hazard WRITE_AFTER_WRITE for \
        entry 3, Recorded access info (recorded_usage: SYNC_FRAGMENT_SHADER_SHADER_STORAGE_WRITE, \
        command: vkCmdDrawIndexed). Access info (prior_usage: \
        SYNC_FRAGMENT_SHADER_SHADER_STORAGE_WRITE, write_barriers: 0, command: vkCmdDrawIndexed)";

    const UNKNOWN_STRUCTURE: &str = "Validation Error: [ VUID-VkDeviceCreateInfo-pNext-pNext ] \
        Object 0: VK_NULL_HANDLE, type = VK_OBJECT_TYPE_DEVICE; | MessageID = 0x901f59ec | \
        vkCreateDevice: pCreateInfo->pNext chain includes a structure with unknown \
        VkStructureType (1000572000); Allowed structures are [...]";

    #[test]
    fn only_the_unknown_structures_of_newer_extensions_cadr_chains_are_excused() {
        assert!(is_known_false_positive(UNKNOWN_STRUCTURE));
        for excused in ["(1000470000)", "(1000470005)", "(1000470006)"] {
            assert!(is_known_false_positive(
                &UNKNOWN_STRUCTURE.replace("(1000572000)", excused)
            ));
        }
        for (from, to) in [
            ("(1000572000)", "(1000572001)"),
            ("(1000572000)", "(1000328000)"),
            ("pNext-pNext", "sType-sType"),
        ] {
            let changed = UNKNOWN_STRUCTURE.replace(from, to);
            assert!(!is_known_false_positive(&changed), "{changed}");
        }
    }

    #[test]
    fn only_fragment_storage_writes_across_secondaries_are_excused() {
        assert!(is_known_false_positive(EXECUTE_COMMANDS_HAZARD));
        // Another stage, another hazard, or another command stays an error.
        for (from, to) in [
            (
                "prior_usage: SYNC_FRAGMENT_SHADER_SHADER_STORAGE_WRITE",
                "prior_usage: SYNC_COMPUTE_SHADER_SHADER_STORAGE_WRITE",
            ),
            (
                "recorded_usage: SYNC_FRAGMENT_SHADER_SHADER_STORAGE_WRITE",
                "recorded_usage: SYNC_FRAGMENT_SHADER_SHADER_STORAGE_READ",
            ),
            ("vkCmdExecuteCommands:", "vkCmdDrawIndexed:"),
            ("WRITE-AFTER-WRITE", "READ-AFTER-WRITE"),
        ] {
            let changed = EXECUTE_COMMANDS_HAZARD.replace(from, to);
            assert_ne!(changed, EXECUTE_COMMANDS_HAZARD);
            assert!(!is_known_false_positive(&changed), "{changed}");
        }
    }
}
