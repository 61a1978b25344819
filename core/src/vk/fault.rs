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
//!   failed one) (`without_host_memory_faults`); plugins' calls are not exempt;
//! - `submit`: a queue submission returns `VK_ERROR_OUT_OF_DEVICE_MEMORY`;
//! - `device-lost`: a queue submission returns `VK_ERROR_DEVICE_LOST`, and the device is lost
//!   from then on (every later submission, wait and allocation says so).
//!
//! Tests arm faults in-process with `arm` instead (with the feature).

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

#[cfg(feature = "fault-injection")]
mod armed {
    use std::sync::atomic::{AtomicU64, Ordering};
    use std::sync::{Mutex, OnceLock};

    use super::{parse_fault, FaultKind};

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

    thread_local! {
        /// Set while this thread runs [`without_host_memory_faults`].
        static HOST_MEMORY_EXEMPT: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    }

    /// Runs `work` with no host-memory fault injected (nor counted) on this thread.
    pub(crate) fn without_host_memory_faults<R>(work: impl FnOnce() -> R) -> R {
        let before = HOST_MEMORY_EXEMPT.with(|exempt| exempt.replace(true));
        let result = work();
        HOST_MEMORY_EXEMPT.with(|exempt| exempt.set(before));
        result
    }

    /// Counts a call of `kind`; true when it is the one armed to fail.
    pub(crate) fn fails(kind: FaultKind) -> bool {
        if kind == FaultKind::HostMemory && HOST_MEMORY_EXEMPT.with(std::cell::Cell::get) {
            return false;
        }
        read_environment();
        let call = CALLS[kind.index()].fetch_add(1, Ordering::Relaxed) + 1;
        *armed() == Some((kind, call))
    }
}

#[cfg(feature = "fault-injection")]
pub use armed::{arm, calls, disarm};

#[cfg(feature = "fault-injection")]
pub(crate) use armed::{fails, without_host_memory_faults};

/// Runs `work` with no host-memory fault injected on this thread (for driver calls that do
/// not survive one); without the feature, just runs it.
#[cfg(not(feature = "fault-injection"))]
#[inline(always)]
pub(crate) fn without_host_memory_faults<R>(work: impl FnOnce() -> R) -> R {
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
