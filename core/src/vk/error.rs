//! Errors of the Vulkan layer.

use ash::vk;

/// What can go wrong below the renderer. Out-of-memory and device-lost are real run-time
/// conditions a host must handle; the rest mean the machine cannot run cadr as configured.
#[derive(Debug, thiserror::Error)]
pub enum VkError {
    /// The Vulkan loader library (`libvulkan.so.1`) could not be opened.
    #[error("cannot load the Vulkan loader library: {0} (install libvulkan1 and a driver such as mesa-vulkan-drivers)")]
    LoaderMissing(String),
    /// A Vulkan call returned an error code.
    #[error("{call} failed: {result}")]
    Call {
        /// The Vulkan entry point that failed.
        call: &'static str,
        /// The code it returned.
        result: vk::Result,
    },
    /// Host or device memory ran out.
    #[error("{call} ran out of memory ({result})")]
    OutOfMemory {
        /// The Vulkan entry point that failed.
        call: &'static str,
        /// `ERROR_OUT_OF_HOST_MEMORY` or `ERROR_OUT_OF_DEVICE_MEMORY`.
        result: vk::Result,
    },
    /// The device was lost (driver crash, GPU reset, hang).
    #[error("the Vulkan device was lost during {0}")]
    DeviceLost(&'static str),
    /// No physical device is usable.
    #[error("no Vulkan device found{0}")]
    NoDevice(String),
    /// Validation layers were requested but are not installed.
    #[error("the Vulkan validation layer VK_LAYER_KHRONOS_validation is not installed (Debian package vulkan-validationlayers)")]
    ValidationLayerMissing,
    /// The device lacks something cadr needs.
    #[error("device '{device}' is not supported: {reason}")]
    Unsupported {
        /// The device name.
        device: String,
        /// What is missing.
        reason: String,
    },
    /// The memory allocator refused an allocation.
    #[error("GPU memory allocation of {what} failed: {source}")]
    Allocation {
        /// What was being allocated (its debug name).
        what: String,
        /// The allocator's error.
        #[source]
        source: gpu_allocator::AllocationError,
    },
    /// The driver ran out of host memory while the memory allocator asked it for GPU memory
    /// (gpu-allocator reports that as an internal error).
    #[error("GPU memory allocation of {what} ran out of host memory (vkAllocateMemory: ERROR_OUT_OF_HOST_MEMORY)")]
    AllocationOutOfHostMemory {
        /// What was being allocated (its debug name).
        what: String,
    },
    /// A resource was used against its contract (a caller's bug, reported instead of panicking).
    #[error("invalid use: {0}")]
    InvalidUse(String),
}

/// Turns a `vk::Result` of the call `call` into the matching [`VkError`].
pub fn map_result(call: &'static str, result: vk::Result) -> VkError {
    match result {
        vk::Result::ERROR_OUT_OF_HOST_MEMORY | vk::Result::ERROR_OUT_OF_DEVICE_MEMORY => {
            VkError::OutOfMemory { call, result }
        }
        vk::Result::ERROR_DEVICE_LOST => VkError::DeviceLost(call),
        _ => VkError::Call { call, result },
    }
}

/// Turns an error of the memory allocator, allocating `what`, into a [`VkError`].
pub(crate) fn allocation_error(what: &str, source: gpu_allocator::AllocationError) -> VkError {
    match source {
        gpu_allocator::AllocationError::Internal(message)
            if message.contains("ERROR_OUT_OF_HOST_MEMORY") =>
        {
            VkError::AllocationOutOfHostMemory { what: what.into() }
        }
        source => VkError::Allocation {
            what: what.into(),
            source,
        },
    }
}

/// Extension to name the failing call when converting `VkResult`s.
pub trait VkResultExt<T> {
    /// Maps the error of a Vulkan call into a [`VkError`] that names `call`.
    fn or_vk(self, call: &'static str) -> Result<T, VkError>;
}

impl<T> VkResultExt<T> for Result<T, vk::Result> {
    fn or_vk(self, call: &'static str) -> Result<T, VkError> {
        self.map_err(|result| map_result(call, result))
    }
}

/// Result of the Vulkan layer.
pub type VkResult<T> = Result<T, VkError>;
