//! Injected Vulkan failures, for testing what a host sees when memory runs out, a submission
//! fails or the device is lost (cargo feature `fault-injection`; off in normal builds, where
//! no call ever fails and the check costs nothing).
//!
//! `CADR_FAULT=KIND:N` makes the Nth call of KIND fail (counted from the process's start):
//! - `device-memory`: a device memory allocation returns `VK_ERROR_OUT_OF_DEVICE_MEMORY`;
//! - `host-memory`: a host allocation of a Vulkan object's memory, through cadr's allocation
//!   callbacks ([`super::host_memory`]), returns NULL, so the call that made it fails with
//!   `VK_ERROR_OUT_OF_HOST_MEMORY`. Mesa 22.3's lavapipe does not survive every such failure:
//!   it uses some allocations unchecked, in vkCreatePipelineLayout and while recording
//!   commands, and the validation layer does not either in some queries that return no
//!   result (and so could not report one). So cadr's own command pools (whose callbacks the
//!   driver allocates recorded commands with) get callbacks that count but never fail, and no
//!   host allocation fails inside cadr's vkCreatePipelineLayout, the physical-device queries,
//!   or the validation layer's set-up (instance creation and the first enumeration of
//!   physical devices with the layer, which goes on after a failure there and then crashes or
//!   deadlocks), or vkDeviceWaitIdle (where the driver leaks an allocation of its own after a
//!   failed one) (`without_host_memory_faults`); plugins load Vulkan through a
//!   `vkGetInstanceProcAddr` that wraps their vkCreatePipelineLayout the same way
//!   (`plugin_loader`). In vkCreateGraphicsPipelines and vkGetQueryPoolResults, which lavapipe
//!   survives a failure of the first allocation in but leaks after a later one, and in
//!   vkCreateDescriptorSetLayout, where Mesa 25's lavapipe does the same, only the first may
//!   fail (`with_first_host_memory_fault_only`);
//! - `submit`: a queue submission returns `VK_ERROR_OUT_OF_DEVICE_MEMORY`;
//! - `device-lost`: a queue submission returns `VK_ERROR_DEVICE_LOST`, and the device is lost
//!   from then on (every later submission, wait and allocation says so).
//!
//! Tests arm faults in-process with `arm` instead (with the feature). With `CADR_FAULT_TRACE`
//! set, each injected host-memory failure prints where it was raised: the way to find the
//! driver call behind a leak that a new driver brings (Mesa 25's lavapipe also leaks after a
//! failed later allocation in vkCreateDescriptorSetLayout).

/// The variable that prints where each injected host-memory failure was raised.
pub const TRACE_ENV: &str = "CADR_FAULT_TRACE";

/// What fails.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FaultKind {
    /// Device memory allocation.
    DeviceMemory,
    /// Host memory allocation through the Vulkan allocation callbacks.
    HostMemory,
    /// Queue submission.
    Submit,
    /// The device is lost at a queue submission.
    DeviceLost,
}

impl FaultKind {
    /// Every kind.
    pub const ALL: [FaultKind; 4] = [
        Self::DeviceMemory,
        Self::HostMemory,
        Self::Submit,
        Self::DeviceLost,
    ];

    /// The name `CADR_FAULT` uses.
    pub fn name(self) -> &'static str {
        match self {
            Self::DeviceMemory => "device-memory",
            Self::HostMemory => "host-memory",
            Self::Submit => "submit",
            Self::DeviceLost => "device-lost",
        }
    }

    /// The kind named `name`.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|kind| kind.name() == name)
    }

    #[cfg(feature = "fault-injection")]
    fn index(self) -> usize {
        self as usize
    }
}

/// Parses `CADR_FAULT`'s value, `KIND:N` with N ≥ 1.
pub fn parse_fault(text: &str) -> Result<(FaultKind, u64), String> {
    let names: Vec<&str> = FaultKind::ALL.iter().map(|k| k.name()).collect();
    let (kind, n) = text.split_once(':').ok_or_else(|| {
        format!(
            "CADR_FAULT={text}: expected KIND:N, KIND one of {}",
            names.join(", ")
        )
    })?;
    let kind = FaultKind::parse(kind).ok_or_else(|| {
        format!(
            "CADR_FAULT={text}: no fault kind '{kind}' (known: {})",
            names.join(", ")
        )
    })?;
    let n = n
        .parse::<u64>()
        .ok()
        .filter(|&n| n >= 1)
        .ok_or_else(|| format!("CADR_FAULT={text}: N must be a whole number from 1"))?;
    Ok((kind, n))
}

/// The real functions behind the `vkGetInstanceProcAddr` cadr hands plugins, for one instance
/// and its device (with the `fault-injection` feature they are wrapped; without it plugins get
/// the loader's own, and the others are not read).
#[derive(Clone, Copy)]
#[cfg_attr(not(feature = "fault-injection"), allow(dead_code))]
pub(crate) struct RealFunctions {
    /// The loader's (the Vulkan library may be unloaded and loaded again at another address
    /// between devices, so it is kept per device).
    pub get_instance_proc_addr: ash::vk::PFN_vkGetInstanceProcAddr,
    /// The instance's.
    pub get_device_proc_addr: ash::vk::PFN_vkGetDeviceProcAddr,
    /// The device's.
    pub create_pipeline_layout: ash::vk::PFN_vkCreatePipelineLayout,
}

#[cfg(feature = "fault-injection")]
mod armed {
    use std::ffi::{c_char, CStr};
    use std::sync::atomic::{AtomicU64, Ordering};
    use std::sync::{Mutex, OnceLock};

    use ash::vk;

    use super::{parse_fault, FaultKind, RealFunctions};

    /// Calls of each kind so far.
    static CALLS: [AtomicU64; FaultKind::ALL.len()] =
        [const { AtomicU64::new(0) }; FaultKind::ALL.len()];
    /// The fault armed: its kind and the call that fails.
    static ARMED: Mutex<Option<(FaultKind, u64)>> = Mutex::new(None);
    static FROM_ENVIRONMENT: OnceLock<()> = OnceLock::new();

    fn armed() -> std::sync::MutexGuard<'static, Option<(FaultKind, u64)>> {
        ARMED
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    fn read_environment() {
        FROM_ENVIRONMENT.get_or_init(|| {
            if let Ok(text) = std::env::var("CADR_FAULT") {
                match parse_fault(&text) {
                    Ok(fault) => *armed() = Some(fault),
                    Err(message) => eprintln!("cadr: {message}; no fault injected"),
                }
            }
        });
    }

    /// Makes call `n` (from 1) of `kind`, counted from now, fail; every count starts again.
    pub fn arm(kind: FaultKind, n: u64) {
        read_environment();
        reset_counts();
        *armed() = Some((kind, n));
    }

    /// Injects nothing from now on; every count starts again.
    pub fn disarm() {
        read_environment();
        reset_counts();
        *armed() = None;
    }

    /// Calls of `kind` counted since the last [`arm`] or [`disarm`].
    pub fn calls(kind: FaultKind) -> u64 {
        CALLS[kind.index()].load(Ordering::Relaxed)
    }

    fn reset_counts() {
        for count in &CALLS {
            count.store(0, Ordering::Relaxed);
        }
    }

    /// Which host allocations of this thread may fail.
    #[derive(Clone, Copy, PartialEq, Eq)]
    enum HostMemoryWindow {
        /// Every one.
        All,
        /// None ([`without_host_memory_faults`]).
        None,
        /// Only the first one from here on ([`with_first_host_memory_fault_only`]); `true`
        /// once that one was counted.
        FirstOnly(bool),
    }

    thread_local! {
        static HOST_MEMORY_WINDOW: std::cell::Cell<HostMemoryWindow> =
            const { std::cell::Cell::new(HostMemoryWindow::All) };
    }

    fn in_window<R>(window: HostMemoryWindow, work: impl FnOnce() -> R) -> R {
        let before = HOST_MEMORY_WINDOW.with(|current| current.replace(window));
        let result = work();
        HOST_MEMORY_WINDOW.with(|current| current.set(before));
        result
    }

    /// Runs `work` with no host-memory fault injected (nor counted) on this thread.
    pub(crate) fn without_host_memory_faults<R>(work: impl FnOnce() -> R) -> R {
        in_window(HostMemoryWindow::None, work)
    }

    /// Runs `work` with only its first host allocation on this thread able to fail (and
    /// counted): for driver calls that survive a failure of their first allocation but leak
    /// after a later one.
    pub(crate) fn with_first_host_memory_fault_only<R>(work: impl FnOnce() -> R) -> R {
        in_window(HostMemoryWindow::FirstOnly(false), work)
    }

    /// What [`plugin_loader`] was given, by instance and device handle (Vulkan passes the
    /// wrappers no user data). A handle may be reused once its object is gone: a new entry
    /// replaces any with the same instance or device, and no two live objects share one.
    static REAL_FUNCTIONS: Mutex<Vec<(vk::Instance, vk::Device, RealFunctions)>> =
        Mutex::new(Vec::new());

    fn real_functions(matches: impl Fn(vk::Instance, vk::Device) -> bool) -> Option<RealFunctions> {
        let table = REAL_FUNCTIONS
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        table
            .iter()
            .find(|&&(instance, device, _)| matches(instance, device))
            .map(|&(_, _, real)| real)
    }

    /// The `vkGetInstanceProcAddr` to hand plugins of `instance` and `device` in place of the
    /// loader's: the same functions, except that their `vkCreatePipelineLayout` runs with no
    /// host-memory fault injected, like cadr's own (lavapipe uses that allocation unchecked).
    pub(crate) fn plugin_loader(
        (instance, device): (vk::Instance, vk::Device),
        real: RealFunctions,
    ) -> vk::PFN_vkGetInstanceProcAddr {
        let mut table = REAL_FUNCTIONS
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        table.retain(|&(known_instance, known_device, _)| {
            known_instance != instance && known_device != device
        });
        table.push((instance, device, real));
        plugin_get_instance_proc_addr
    }

    const CREATE_PIPELINE_LAYOUT: &[u8] = b"vkCreatePipelineLayout";

    unsafe extern "system" fn plugin_get_instance_proc_addr(
        instance: vk::Instance,
        name: *const c_char,
    ) -> vk::PFN_vkVoidFunction {
        let real = real_functions(|known, _| known == instance)?;
        // SAFETY: Vulkan's contract: name is a NUL-terminated string.
        let wanted = unsafe { CStr::from_ptr(name) }.to_bytes();
        if wanted == CREATE_PIPELINE_LAYOUT {
            return plugin_create_pipeline_layout_fn();
        }
        if wanted == b"vkGetDeviceProcAddr" {
            // SAFETY: the wrapper has vkGetDeviceProcAddr's signature.
            return Some(unsafe {
                std::mem::transmute::<vk::PFN_vkGetDeviceProcAddr, unsafe extern "system" fn()>(
                    plugin_get_device_proc_addr,
                )
            });
        }
        // SAFETY: the caller's arguments, passed on.
        unsafe { (real.get_instance_proc_addr)(instance, name) }
    }

    fn plugin_create_pipeline_layout_fn() -> vk::PFN_vkVoidFunction {
        // SAFETY: the wrapper has vkCreatePipelineLayout's signature.
        Some(unsafe {
            std::mem::transmute::<vk::PFN_vkCreatePipelineLayout, unsafe extern "system" fn()>(
                plugin_create_pipeline_layout,
            )
        })
    }

    unsafe extern "system" fn plugin_get_device_proc_addr(
        device: vk::Device,
        name: *const c_char,
    ) -> vk::PFN_vkVoidFunction {
        let real = real_functions(|_, known| known == device)?;
        // SAFETY: Vulkan's contract: name is a NUL-terminated string.
        if unsafe { CStr::from_ptr(name) }.to_bytes() == CREATE_PIPELINE_LAYOUT {
            return plugin_create_pipeline_layout_fn();
        }
        // SAFETY: the caller's arguments, passed on.
        unsafe { (real.get_device_proc_addr)(device, name) }
    }

    unsafe extern "system" fn plugin_create_pipeline_layout(
        device: vk::Device,
        info: *const vk::PipelineLayoutCreateInfo<'_>,
        allocator: *const vk::AllocationCallbacks<'_>,
        layout: *mut vk::PipelineLayout,
    ) -> vk::Result {
        let Some(real) = real_functions(|_, known| known == device) else {
            return vk::Result::ERROR_INITIALIZATION_FAILED;
        };
        without_host_memory_faults(|| {
            // SAFETY: the caller's arguments, passed on.
            unsafe { (real.create_pipeline_layout)(device, info, allocator, layout) }
        })
    }

    /// Counts a call of `kind`; true when it is the one armed to fail.
    pub(crate) fn fails(kind: FaultKind) -> bool {
        if kind == FaultKind::HostMemory {
            let may_fail = HOST_MEMORY_WINDOW.with(|window| match window.get() {
                HostMemoryWindow::All => true,
                HostMemoryWindow::None | HostMemoryWindow::FirstOnly(true) => false,
                HostMemoryWindow::FirstOnly(false) => {
                    window.set(HostMemoryWindow::FirstOnly(true));
                    true
                }
            });
            if !may_fail {
                return false;
            }
        }
        read_environment();
        let call = CALLS[kind.index()].fetch_add(1, Ordering::Relaxed) + 1;
        *armed() == Some((kind, call))
    }
}

#[cfg(feature = "fault-injection")]
pub use armed::{arm, calls, disarm};

#[cfg(feature = "fault-injection")]
pub(crate) use armed::{
    fails, plugin_loader, with_first_host_memory_fault_only, without_host_memory_faults,
};

/// The `vkGetInstanceProcAddr` to hand plugins: without the feature, the loader's own.
#[cfg(not(feature = "fault-injection"))]
#[inline(always)]
pub(crate) fn plugin_loader(
    _handles: (ash::vk::Instance, ash::vk::Device),
    real: RealFunctions,
) -> ash::vk::PFN_vkGetInstanceProcAddr {
    real.get_instance_proc_addr
}

/// Runs `work` with no host-memory fault injected on this thread (for driver calls that do
/// not survive one); without the feature, just runs it.
#[cfg(not(feature = "fault-injection"))]
#[inline(always)]
pub(crate) fn without_host_memory_faults<R>(work: impl FnOnce() -> R) -> R {
    work()
}

/// Runs `work` with only its first host allocation able to fail; without the feature, just
/// runs it.
#[cfg(not(feature = "fault-injection"))]
#[inline(always)]
pub(crate) fn with_first_host_memory_fault_only<R>(work: impl FnOnce() -> R) -> R {
    work()
}

/// Without the feature nothing fails.
#[cfg(not(feature = "fault-injection"))]
#[inline(always)]
pub(crate) fn fails(_kind: FaultKind) -> bool {
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fault_specifications_are_checked() {
        assert_eq!(parse_fault("submit:3"), Ok((FaultKind::Submit, 3)));
        assert_eq!(parse_fault("device-lost:1"), Ok((FaultKind::DeviceLost, 1)));
        let refused = |text: &str, part: &str| parse_fault(text).is_err_and(|m| m.contains(part));
        assert!(refused("submit:0", "from 1"));
        assert!(refused("gpu-melt:2", "device-memory"));
        assert!(refused("submit", "KIND:N"));
    }
}
