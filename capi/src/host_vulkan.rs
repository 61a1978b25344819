//! The host's own Vulkan: what cadr needs of a device a host makes
//! (`cadr_vulkan_requirements`), and a context on the host's instance, device and queue
//! (`cadr_context_create_from_vulkan`).

use std::ffi::{c_char, c_void, CStr};
use std::sync::{Arc, OnceLock};

use cadr_core::vk::host_vulkan::{HostDevice, HostVulkan, QueueLock, REQUIREMENTS};
use cadr_core::vk::raw::{self as vk, Handle};
use cadr_core::vk::Device;

use crate::args::{deliver, deliver_sized, non_null, read_sized, string_list};
use crate::context::{
    c_strings, insert_context, options_or_default, plugin_dirs, CadrContext, CadrContextOptions,
};
use crate::error::{guard, CadrResult, Failure};

/// What cadr needs of a host's Vulkan instance and device, and what it uses where the host
/// enabled it (`cadr_vulkan_requirements`). Every string is cadr's, static, NUL-terminated;
/// features are named `Struct::member` as the Vulkan headers spell them (for example
/// `VkPhysicalDeviceVulkan13Features::dynamicRendering`).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrVulkanRequirements {
    /// `sizeof(CadrVulkanRequirements)`, set by the host: cadr fills the fields that fit and
    /// zeroes the ones a newer host knows and this library does not.
    pub size: u32,
    /// The lowest `VK_API_VERSION` of the instance and the physical device (1.3).
    pub api_version: u32,
    /// Device extensions cadr uses where the host enabled them (multi-draw, mesh shaders,
    /// device-generated commands, `VK_KHR_swapchain` for windows). None is required.
    pub optional_extensions: *const *const c_char,
    /// Number of `optional_extensions`.
    pub optional_extension_count: u32,
    /// Features the host must enable on its device.
    pub required_features: *const *const c_char,
    /// Number of `required_features`.
    pub required_feature_count: u32,
    /// Features cadr uses where the host enabled them; cadr falls back without them.
    pub optional_features: *const *const c_char,
    /// Number of `optional_features`.
    pub optional_feature_count: u32,
}

/// A list of cadr's static names as C pointers.
struct NameList(Vec<*const c_char>);

// SAFETY: the pointers point at `'static` string constants, never written.
unsafe impl Send for NameList {}
// SAFETY: as above.
unsafe impl Sync for NameList {}

/// The C pointers of `names`, made once per list.
fn name_list(
    list: &'static OnceLock<NameList>,
    names: &'static [&'static CStr],
) -> &'static [*const c_char] {
    &list
        .get_or_init(|| NameList(names.iter().map(|name| name.as_ptr()).collect()))
        .0
}

/// Writes what cadr needs of a host's Vulkan into `*requirements`, up to
/// `requirements->size` bytes (see `CadrVulkanRequirements`): the host enables the required
/// features (and the optional ones and extensions its device has) when it creates the device
/// it hands to `cadr_context_create_from_vulkan`.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or `CADR_RESULT_INVALID_ARGUMENT` (a
/// size too small to hold the size). Ownership: the struct is the caller's; the strings it
/// points at are cadr's, static. Thread-safety: callable from any thread.
///
/// # Safety
/// `requirements` is null or points at `requirements->size` writable bytes.
#[no_mangle]
pub unsafe extern "C" fn cadr_vulkan_requirements(
    requirements: *mut CadrVulkanRequirements,
) -> CadrResult {
    static EXTENSIONS: OnceLock<NameList> = OnceLock::new();
    static REQUIRED: OnceLock<NameList> = OnceLock::new();
    static OPTIONAL: OnceLock<NameList> = OnceLock::new();
    guard(|| {
        let extensions = name_list(&EXTENSIONS, REQUIREMENTS.optional_extensions);
        let required = name_list(&REQUIRED, REQUIREMENTS.required_features);
        let optional = name_list(&OPTIONAL, REQUIREMENTS.optional_features);
        let value = CadrVulkanRequirements {
            size: std::mem::size_of::<CadrVulkanRequirements>() as u32,
            api_version: REQUIREMENTS.api_version,
            optional_extensions: extensions.as_ptr(),
            optional_extension_count: extensions.len() as u32,
            required_features: required.as_ptr(),
            required_feature_count: required.len() as u32,
            optional_features: optional.as_ptr(),
            optional_feature_count: optional.len() as u32,
        };
        // SAFETY: requirements is null or holds its size in writable bytes (the contract).
        unsafe { deliver_sized(requirements, "requirements", value) }
    })
}

/// Vulkan's `vkGetInstanceProcAddr` as the host loaded it (a `PFN_vkGetInstanceProcAddr`,
/// cast to this type: `VkInstance` is a pointer).
pub type CadrGetInstanceProcAddr = Option<
    unsafe extern "C" fn(
        instance: *mut c_void,
        name: *const c_char,
    ) -> Option<unsafe extern "C" fn()>,
>;

/// Takes (or gives back) the host's lock on the queue it shares with cadr.
pub type CadrQueueLockFn = Option<unsafe extern "C" fn(user: *mut c_void)>;

/// A host's Vulkan objects that cadr uses without owning them
/// (`cadr_context_create_from_vulkan`). Dispatchable handles are pointers, as Vulkan's are.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrHostVulkan {
    /// `sizeof(CadrHostVulkan)`.
    pub size: u32,
    /// The `vkGetInstanceProcAddr` the host loaded Vulkan with.
    pub get_instance_proc_addr: CadrGetInstanceProcAddr,
    /// The host's `VkInstance`, created for Vulkan 1.3 or later.
    pub instance: *mut c_void,
    /// The instance extensions the host enabled: with `VK_EXT_debug_utils` cadr logs what the
    /// validation layer (if the host enabled it) reports, which
    /// `cadr_context_validation_error_count` counts; with `VK_KHR_surface` and the device's
    /// `VK_KHR_swapchain`, renderers can present to the host's windows.
    pub instance_extensions: *const *const c_char,
    /// Number of `instance_extensions`.
    pub instance_extension_count: u32,
    /// The `VkPhysicalDevice` of `device`.
    pub physical_device: *mut c_void,
    /// The host's `VkDevice`.
    pub device: *mut c_void,
    /// The `VkDeviceCreateInfo` the host created `device` with, read during the call only:
    /// its extensions, queues and features (`pEnabledFeatures`, or a
    /// `VkPhysicalDeviceFeatures2` and the Vulkan 1.1–1.3 feature structs in its chain) say
    /// what cadr may use.
    pub device_create_info: *const c_void,
    /// The queue family cadr submits to: graphics and compute.
    pub queue_family: u32,
    /// The queue's index in its family.
    pub queue_index: u32,
    /// NULL when cadr alone uses the queue; otherwise called (with `queue_user`) before cadr
    /// submits to, presents on or waits for the queue, from whichever thread renders, so that
    /// the host's own use of the queue waits meanwhile (Vulkan wants a queue's use externally
    /// synchronised).
    pub lock_queue: CadrQueueLockFn,
    /// Called after cadr's use of the queue; set with `lock_queue` or not at all.
    pub unlock_queue: CadrQueueLockFn,
    /// Passed to `lock_queue` and `unlock_queue`.
    pub queue_user: *mut c_void,
}

/// The host's lock functions and their argument, callable from any thread.
struct HostQueueLock {
    lock: unsafe extern "C" fn(*mut c_void),
    unlock: unsafe extern "C" fn(*mut c_void),
    user: *mut c_void,
}

// SAFETY: the host promises that its lock functions may be called from any thread with
// `queue_user` (the contract of `CadrHostVulkan::lock_queue`).
unsafe impl Send for HostQueueLock {}
// SAFETY: as above.
unsafe impl Sync for HostQueueLock {}

impl HostQueueLock {
    /// The lock as the device takes it: `true` takes it, `false` gives it back.
    fn into_queue_lock(self) -> QueueLock {
        Arc::new(move |take: bool| self.call(take))
    }

    /// Calls the host's lock (`take`) or unlock function.
    fn call(&self, take: bool) {
        let function = if take { self.lock } else { self.unlock };
        // SAFETY: the host's function, callable from any thread with its argument.
        unsafe { function(self.user) }
    }
}

/// Creates a context on a host's Vulkan instance, device and queue (see `CadrHostVulkan`),
/// which cadr uses without destroying them: the host keeps them alive, and its loader
/// loaded, until every renderer and the context are destroyed. cadr allocates its own memory,
/// pipelines and command pools on the device, and submits only to the queue given. `options`
/// may be NULL; of it only the plugin directories count (validation, device choice and
/// extensions are the host's, on its own objects).
///
/// Returns `CADR_RESULT_OK` and writes `*context`, or `CADR_RESULT_NULL_ARGUMENT`,
/// `CADR_RESULT_INVALID_ARGUMENT` (a bad size, null handles, a lock without an unlock, a
/// device create info that is not one), `CADR_RESULT_UNSUPPORTED` (the physical device lacks
/// Vulkan 1.3, the queue family graphics and compute, or the host did not enable a feature
/// cadr requires: the message names it; see `cadr_vulkan_requirements`) or
/// `CADR_RESULT_VULKAN`.
///
/// Ownership: `host`, its strings and the create info are read during the call only; the
/// Vulkan objects stay the host's; the context is the caller's until `cadr_context_destroy`.
/// Thread-safety: as `cadr_context_create`; with `lock_queue` set, cadr's renderers and the
/// host's own code may use the queue from any threads.
///
/// # Safety
/// `host` is null or a valid `CadrHostVulkan` whose handles are live objects of one instance
/// and device, made with the loader whose `vkGetInstanceProcAddr` it gives, and whose
/// pointers are null or valid for their counts; `options` is null or valid; `context` is null
/// or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_context_create_from_vulkan(
    host: *const CadrHostVulkan,
    options: *const CadrContextOptions,
    context: *mut CadrContext,
) -> CadrResult {
    guard(|| {
        non_null(context, "context")?;
        // SAFETY: null or valid for its size by the caller's contract; zero bytes are a
        // CadrHostVulkan (null pointers, no callbacks, numbers).
        let host = unsafe { read_sized(host, ("host", "CadrHostVulkan"), std::mem::zeroed()) }?;
        // SAFETY: valid by the caller's contract.
        let lent = unsafe { lent_vulkan(&host) }?;
        // SAFETY: null or valid by the caller's contract.
        let options = unsafe { options_or_default(options) }?;
        // SAFETY: its list is valid for its count (the caller's contract).
        let plugin_dirs = unsafe { plugin_dirs(&options) }?;
        let presentation =
            lent.has_instance_extension(c"VK_KHR_surface") && lent.enabled.has(c"VK_KHR_swapchain");
        let device = Device::from_host(lent)?;
        let handle = insert_context(device, plugin_dirs, presentation)?;
        // SAFETY: context is writable (the caller's contract).
        unsafe { deliver(context, "context", handle as CadrContext) }
    })
}

/// The host's objects as the device takes them, checked.
///
/// # Safety
/// As `cadr_context_create_from_vulkan`'s `host`.
unsafe fn lent_vulkan(host: &CadrHostVulkan) -> Result<HostVulkan, Failure> {
    let Some(get_instance_proc_addr) = host.get_instance_proc_addr else {
        return Err(Failure::invalid("host.get_instance_proc_addr is NULL"));
    };
    for (pointer, name) in [
        (host.instance.cast_const(), "host.instance"),
        (host.physical_device.cast_const(), "host.physical_device"),
        (host.device.cast_const(), "host.device"),
        (host.device_create_info, "host.device_create_info"),
    ] {
        if pointer.is_null() {
            return Err(Failure::invalid(format!("{name} is NULL")));
        }
    }
    // SAFETY: the host's `vkGetInstanceProcAddr` (the caller's contract), whose `VkInstance`
    // is a pointer and whose calling convention is C's on the platforms cadr builds for.
    let get_instance_proc_addr: vk::PFN_vkGetInstanceProcAddr =
        unsafe { std::mem::transmute(get_instance_proc_addr) };
    // SAFETY: valid for its count (the caller's contract).
    let instance_extensions = unsafe {
        string_list(
            host.instance_extensions,
            host.instance_extension_count as usize,
            "host.instance_extensions",
        )
    }?;
    let instance_extensions = c_strings(instance_extensions, "host.instance_extensions")?;
    // SAFETY: a valid VkDeviceCreateInfo (the caller's contract).
    let enabled = unsafe { HostDevice::from_create_info(host.device_create_info) }
        .map_err(|reason| Failure::invalid(format!("host.device_create_info: {reason}")))?;
    let queue_lock = match (host.lock_queue, host.unlock_queue) {
        (Some(lock), Some(unlock)) => Some(
            HostQueueLock {
                lock,
                unlock,
                user: host.queue_user,
            }
            .into_queue_lock(),
        ),
        (None, None) => None,
        _ => {
            return Err(Failure::invalid(
                "host.lock_queue and host.unlock_queue are set together or not at all",
            ))
        }
    };
    Ok(HostVulkan {
        get_instance_proc_addr,
        instance: vk::Instance::from_raw(host.instance as u64),
        instance_extensions,
        physical_device: vk::PhysicalDevice::from_raw(host.physical_device as u64),
        device: vk::Device::from_raw(host.device as u64),
        enabled,
        queue: (host.queue_family, host.queue_index),
        queue_lock,
    })
}
