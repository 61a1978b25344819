//! The context: the Vulkan instance and device, and the technique plugins found for them.

use std::ffi::{c_char, c_void, CString};
use std::path::PathBuf;
use std::sync::Arc;

use cadr_core::technique::{default_plugin_dirs, feature_bits, PluginRegistry, TechniqueKind};
use cadr_core::vk::{raw::Handle, Device, DeviceChoice, DeviceOptions, InstanceOptions};

use crate::args::{deliver, deliver_sized, non_null, optional_str, read_sized, string_list};
use crate::error::{guard, CadrResult, Failure};
use crate::handles::{lock, Registry};

/// Opaque type behind [`CadrContext`]; never dereferenced by the host or by cadr.
pub struct CadrContextObject {
    _private: (),
}

/// A context: one Vulkan instance and device, and the technique plugins found for them.
/// Created by `cadr_context_create`, released by `cadr_context_destroy`.
pub type CadrContext = *mut CadrContextObject;

/// How to create a context. Set `size`, fill it with `cadr_context_options_default`, then
/// change what you need.
///
/// The struct grows by appending fields: an older host's options take the defaults of the
/// fields it does not know; a newer host's fields this library does not know must be 0.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrContextOptions {
    /// `sizeof(CadrContextOptions)`, set by the host.
    pub size: u32,
    /// Enables the Vulkan validation layer (`VK_LAYER_KHRONOS_validation`); its error messages
    /// are counted by `cadr_context_validation_error_count`. Default: false.
    pub validation: bool,
    /// The physical device's index as `cadr devices` lists it, or -1 (default) to choose by
    /// `device_name`, then by the `CADR_DEVICE` variable, then a discrete GPU first.
    pub device_index: i32,
    /// NULL (default), or a case-insensitive part of the device's name.
    pub device_name: *const c_char,
    /// Extra instance extensions, e.g. what `glfwGetRequiredInstanceExtensions` returns. When
    /// `VK_KHR_surface` is among them, the device gets `VK_KHR_swapchain` so that renderers can
    /// present to the host's windows.
    pub instance_extensions: *const *const c_char,
    /// Number of `instance_extensions`.
    pub instance_extension_count: u32,
    /// Extra device extensions.
    pub device_extensions: *const *const c_char,
    /// Number of `device_extensions`.
    pub device_extension_count: u32,
    /// Directories searched for technique plugins (`*cadr_plugin_*.so`) before the defaults.
    pub plugin_dirs: *const *const c_char,
    /// Number of `plugin_dirs`.
    pub plugin_dir_count: u32,
    /// Also search the default directories: beside `libcadr.so` (and its `cadr/plugins/`),
    /// beside the executable, and `CADR_PLUGIN_PATH`. Default: true.
    pub default_plugin_dirs: bool,
}

/// The kind of a physical device.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CadrDeviceType {
    /// Something else.
    Other = 0,
    /// A GPU sharing memory with the CPU.
    IntegratedGpu = 1,
    /// A GPU of its own.
    DiscreteGpu = 2,
    /// A virtualised GPU.
    VirtualGpu = 3,
    /// A CPU implementation such as lavapipe.
    Cpu = 4,
}

/// Device feature: many indirect draws in one call (`multiDrawIndirect`).
pub const CADR_DEVICE_FEATURE_MULTI_DRAW_INDIRECT: u64 = 1;
/// Device feature: per-draw indices through firstInstance in indirect draws.
pub const CADR_DEVICE_FEATURE_DRAW_INDIRECT_FIRST_INSTANCE: u64 = 1 << 1;
/// Device feature: `gl_DrawID` and `gl_BaseInstance` in shaders.
pub const CADR_DEVICE_FEATURE_SHADER_DRAW_PARAMETERS: u64 = 1 << 2;
/// Device feature: GPU pointers to buffers.
pub const CADR_DEVICE_FEATURE_BUFFER_DEVICE_ADDRESS: u64 = 1 << 3;
/// Device feature: indirect draws whose count the GPU reads.
pub const CADR_DEVICE_FEATURE_DRAW_INDIRECT_COUNT: u64 = 1 << 4;
/// Device feature: `VK_EXT_multi_draw`.
pub const CADR_DEVICE_FEATURE_MULTI_DRAW: u64 = 1 << 5;
/// Device feature: GPU timestamps on the render queue (frame GPU times).
pub const CADR_DEVICE_FEATURE_TIMESTAMPS: u64 = 1 << 6;
/// Device feature: renderers can present to windows (`VK_KHR_swapchain` enabled).
pub const CADR_DEVICE_FEATURE_PRESENTATION: u64 = 1 << 7;

/// The device a context renders with.
///
/// The struct grows by appending fields: the host sets `size` to `sizeof(CadrDeviceInfo)`; cadr fills
/// the fields within it and zeroes those of a newer header it does not know.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrDeviceInfo {
    /// `sizeof(CadrDeviceInfo)`, set by the host.
    pub size: u32,
    /// The driver's device name, NUL-terminated (cut to fit).
    pub name: [c_char; 256],
    /// Its kind.
    pub device_type: CadrDeviceType,
    /// Its Vulkan version (`VK_MAKE_API_VERSION` packing).
    pub api_version: u32,
    /// Index in the instance's device list.
    pub index: u32,
    /// The queue family cadr renders and presents on.
    pub queue_family: u32,
    /// Optional features: `CADR_DEVICE_FEATURE_*` bits (later versions add bits).
    pub features: u64,
    /// Whether the validation layer is on.
    pub validation: bool,
    /// Bytes of its largest device-local memory heap: its video memory (on a CPU device, what
    /// the driver offers of the host's). A scene whose full detail needs more than half of it
    /// streams (as past `CADR_MEMORY_BUDGET`).
    pub video_memory_bytes: u64,
}

/// A technique kind.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CadrTechniqueKind {
    /// How vertices reach the shader.
    Vertex = 0,
    /// How matrices and materials reach the shader.
    Parameters = 1,
    /// Which draws are issued and how.
    Submission = 2,
    /// Which instances are drawn.
    Culling = 3,
    /// How translucent surfaces are blended (`weighted-blended`, the default, or the exact
    /// `per-pixel-lists`).
    Transparency = 4,
}

impl CadrTechniqueKind {
    pub(crate) fn core(self) -> TechniqueKind {
        match self {
            Self::Vertex => TechniqueKind::Vertex,
            Self::Parameters => TechniqueKind::Parameters,
            Self::Submission => TechniqueKind::Submission,
            Self::Culling => TechniqueKind::Culling,
            Self::Transparency => TechniqueKind::Transparency,
        }
    }

    fn from_core(kind: TechniqueKind) -> Self {
        match kind {
            TechniqueKind::Vertex => Self::Vertex,
            TechniqueKind::Parameters => Self::Parameters,
            TechniqueKind::Submission => Self::Submission,
            TechniqueKind::Culling => Self::Culling,
            TechniqueKind::Transparency => Self::Transparency,
        }
    }

    /// Reads a kind from its raw value (C callers can pass any integer).
    pub(crate) fn from_raw(value: u32) -> Result<Self, Failure> {
        Ok(match value {
            0 => Self::Vertex,
            1 => Self::Parameters,
            2 => Self::Submission,
            3 => Self::Culling,
            4 => Self::Transparency,
            _ => {
                return Err(Failure::invalid(format!(
                    "technique kind {value} is not 0..4"
                )))
            }
        })
    }
}

/// One technique offered by the plugins. The strings belong to the context and stay valid
/// until it is destroyed.
///
/// The struct grows by appending fields: the host sets `size` to `sizeof(CadrTechniqueInfo)`; cadr fills
/// the fields within it and zeroes those of a newer header it does not know.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrTechniqueInfo {
    /// `sizeof(CadrTechniqueInfo)`, set by the host.
    pub size: u32,
    /// Its kind.
    pub kind: CadrTechniqueKind,
    /// Its name, unique within the kind (e.g. "groups-mdi-replay").
    pub name: *const c_char,
    /// What it does.
    pub description: *const c_char,
    /// The plugin library it comes from, or "built-in" for the built-in techniques (listed
    /// first; they need no library).
    pub library: *const c_char,
    /// Whether this device can run it.
    pub supported: bool,
    /// Why not, when `supported` is false (empty otherwise).
    pub unsupported_reason: *const c_char,
}

/// A plugin library (or one of its techniques) that was refused. The strings belong to the
/// context.
///
/// The struct grows by appending fields: the host sets `size` to `sizeof(CadrPluginRefusal)`; cadr fills
/// the fields within it and zeroes those of a newer header it does not know.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrPluginRefusal {
    /// `sizeof(CadrPluginRefusal)`, set by the host.
    pub size: u32,
    /// The library.
    pub library: *const c_char,
    /// Why (another ABI version, a missing symbol, a panic, …), with the technique's name when
    /// only one technique was refused.
    pub reason: *const c_char,
}

/// The strings of one technique, kept NUL-terminated for the host.
pub(crate) struct TechniqueText {
    pub(crate) kind: TechniqueKind,
    pub(crate) name: CString,
    description: CString,
    library: CString,
    supported: bool,
    reason: CString,
}

/// What a context holds. Renderers keep it alive after the context handle is destroyed.
pub(crate) struct ContextState {
    pub(crate) device: Arc<Device>,
    pub(crate) registry: Arc<PluginRegistry>,
    pub(crate) techniques: Vec<TechniqueText>,
    refusals: Vec<(CString, CString)>,
    pub(crate) presentation: bool,
}

impl ContextState {
    /// The context-owned name of a technique, for handing out to the host.
    pub(crate) fn technique_name(&self, kind: TechniqueKind, name: &str) -> *const c_char {
        self.techniques
            .iter()
            .find(|t| t.kind == kind && t.name.to_bytes() == name.as_bytes())
            .map_or(c"".as_ptr(), |t| t.name.as_ptr())
    }
}

pub(crate) static CONTEXTS: Registry<Arc<ContextState>> = Registry::new(0xC1, "context");

/// The state behind a context handle.
pub(crate) fn context_state(context: CadrContext) -> Result<Arc<ContextState>, Failure> {
    let object = CONTEXTS.get(context as u64, "context")?;
    let state = Arc::clone(&lock(&object));
    Ok(state)
}

/// Item `index` of a list the host walks by count and index; out of range is
/// `CADR_RESULT_NOT_FOUND`.
fn list_item<'a, T>(items: &'a [T], index: u32, what: &str) -> Result<&'a T, Failure> {
    items.get(index as usize).ok_or_else(|| {
        Failure::new(
            CadrResult::NotFound,
            format!("{what} index {index} is out of range (0..{})", items.len()),
        )
    })
}

fn c_string(text: &str) -> CString {
    CString::new(text.replace('\0', " ")).unwrap_or_default()
}

/// The default options: no validation, automatic device choice, no extra extensions, default
/// plugin directories.
fn default_options() -> CadrContextOptions {
    CadrContextOptions {
        size: std::mem::size_of::<CadrContextOptions>() as u32,
        validation: false,
        device_index: -1,
        device_name: std::ptr::null(),
        instance_extensions: std::ptr::null(),
        instance_extension_count: 0,
        device_extensions: std::ptr::null(),
        device_extension_count: 0,
        plugin_dirs: std::ptr::null(),
        plugin_dir_count: 0,
        default_plugin_dirs: true,
    }
}

/// Fills `*options` with the defaults, up to the `options->size` the host set
/// (`sizeof(CadrContextOptions)`): no validation, automatic device choice, no extra
/// extensions, default plugin directories.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or `CADR_RESULT_INVALID_ARGUMENT` (a
/// `size` below 4). Ownership: `options` is the caller's. Thread-safety: callable from any
/// thread.
///
/// # Safety
/// `options` is null or writable for its `size`.
#[no_mangle]
pub unsafe extern "C" fn cadr_context_options_default(
    options: *mut CadrContextOptions,
) -> CadrResult {
    // SAFETY: options is null or writable for its size (the caller's contract).
    guard(|| unsafe { deliver_sized(options, "options", default_options()) })
}

pub(crate) fn c_strings(names: Vec<String>, what: &str) -> Result<Vec<CString>, Failure> {
    names
        .into_iter()
        .enumerate()
        .map(|(i, n)| {
            CString::new(n).map_err(|_| Failure::invalid(format!("{what}[{i}] contains NUL")))
        })
        .collect()
}

/// Creates a context: the Vulkan instance (with the host's extensions), the device, and the
/// technique plugins found for it. `options` may be NULL for the defaults.
///
/// Returns `CADR_RESULT_OK` and writes `*context`, or `CADR_RESULT_NULL_ARGUMENT`,
/// `CADR_RESULT_INVALID_ARGUMENT` (bad `size`, bad strings), `CADR_RESULT_UNSUPPORTED` (no
/// device with Vulkan 1.3, a missing extension) or `CADR_RESULT_VULKAN`.
///
/// Ownership: the options and their strings are read during the call only; the context is
/// the caller's until `cadr_context_destroy`. Thread-safety: callable from any thread; a
/// context may be used from several threads (its renderers take turns on the device's queue,
/// which the device guards itself).
///
/// # Safety
/// `options` is null or a valid options struct whose pointers are null or valid for their
/// counts; `context` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_context_create(
    options: *const CadrContextOptions,
    context: *mut CadrContext,
) -> CadrResult {
    guard(|| {
        non_null(context, "context")?;
        // SAFETY: null or valid (the caller's contract).
        let options = unsafe { options_or_default(options) }?;
        // SAFETY: the pointers are valid for their counts (the caller's contract).
        let (instance_extensions, device_extensions, plugin_dirs, device_name) = unsafe {
            (
                string_list(
                    options.instance_extensions,
                    options.instance_extension_count as usize,
                    "options.instance_extensions",
                )?,
                string_list(
                    options.device_extensions,
                    options.device_extension_count as usize,
                    "options.device_extensions",
                )?,
                plugin_dirs(&options)?,
                optional_str(options.device_name, "options.device_name")?,
            )
        };
        let presentation = instance_extensions.iter().any(|e| e == "VK_KHR_surface");
        let mut device_extensions = c_strings(device_extensions, "options.device_extensions")?;
        if presentation
            && !device_extensions
                .iter()
                .any(|e| e.as_bytes() == b"VK_KHR_swapchain")
        {
            device_extensions.push(c"VK_KHR_swapchain".to_owned());
        }
        let choice = match (options.device_index, device_name) {
            (index, _) if index >= 0 => DeviceChoice::Index(index as usize),
            (_, Some(name)) => DeviceChoice::NameContains(name.to_owned()),
            _ => DeviceChoice::from_env(),
        };
        let device = Device::new(&DeviceOptions {
            instance: InstanceOptions {
                validation: options.validation,
                extra_extensions: c_strings(instance_extensions, "options.instance_extensions")?,
                ..InstanceOptions::default()
            },
            choice,
            extra_extensions: device_extensions,
            ..DeviceOptions::default()
        })?;
        let handle = insert_context(device, plugin_dirs, presentation)?;
        // SAFETY: context is null or writable (the caller's contract).
        unsafe { deliver(context, "context", handle as CadrContext) }
    })
}

/// The host's options, or the defaults for null; an older host's options take the defaults
/// of the fields it does not know.
///
/// # Safety
/// `options` is null or a valid options struct.
pub(crate) unsafe fn options_or_default(
    options: *const CadrContextOptions,
) -> Result<CadrContextOptions, Failure> {
    let defaults = default_options();
    if options.is_null() {
        return Ok(defaults);
    }
    // SAFETY: non-null and valid for its size by contract.
    unsafe { read_sized(options, ("options", "CadrContextOptions"), defaults) }
}

/// The plugin directories `options` names, and whether the default ones are searched too.
///
/// # Safety
/// The options' plugin directory list is null or valid for its count.
pub(crate) unsafe fn plugin_dirs(
    options: &CadrContextOptions,
) -> Result<(Vec<String>, bool), Failure> {
    // SAFETY: valid for its count (the caller's contract).
    let dirs = unsafe {
        string_list(
            options.plugin_dirs,
            options.plugin_dir_count as usize,
            "options.plugin_dirs",
        )
    }?;
    Ok((dirs, options.default_plugin_dirs))
}

/// Registers a context of `device` with the technique plugins found in `plugin_dirs` (and the
/// default directories when asked); returns its handle.
pub(crate) fn insert_context(
    device: Arc<Device>,
    (plugin_dirs, default_dirs): (Vec<String>, bool),
    presentation: bool,
) -> Result<u64, Failure> {
    let mut dirs: Vec<PathBuf> = plugin_dirs.into_iter().map(PathBuf::from).collect();
    if default_dirs {
        dirs.extend(default_plugin_dirs());
    }
    let registry = PluginRegistry::discover(&dirs, feature_bits(device.capabilities()));
    let techniques = registry
        .techniques()
        .iter()
        .map(|t| TechniqueText {
            kind: t.kind,
            name: c_string(&t.name),
            description: c_string(&t.description),
            library: c_string(&t.library.display().to_string()),
            supported: t.support.is_ok(),
            reason: c_string(t.support.as_ref().err().map_or("", String::as_str)),
        })
        .collect();
    let refusals = registry
        .refusals()
        .iter()
        .map(|r| {
            let reason = match &r.technique {
                Some(name) => format!("{name}: {}", r.reason),
                None => r.reason.clone(),
            };
            (
                c_string(&r.library.display().to_string()),
                c_string(&reason),
            )
        })
        .collect();
    let state = ContextState {
        device,
        registry: Arc::new(registry),
        techniques,
        refusals,
        presentation,
    };
    CONTEXTS.insert(Arc::new(state))
}

/// Destroys a context handle. Renderers made from it keep the device alive until they are
/// destroyed too. NULL is a no-op.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_DESTROYED_HANDLE` or `CADR_RESULT_FOREIGN_HANDLE`.
/// Ownership: the handle is invalid afterwards. Thread-safety: callable from any thread, but
/// not while another thread still uses this handle.
#[no_mangle]
pub extern "C" fn cadr_context_destroy(context: CadrContext) -> CadrResult {
    guard(|| {
        let removed = CONTEXTS.remove(context as u64, "context")?;
        drop(removed);
        Ok(())
    })
}

fn device_type(raw: cadr_core::vk::raw::PhysicalDeviceType) -> CadrDeviceType {
    use cadr_core::vk::raw::PhysicalDeviceType as T;
    match raw {
        T::INTEGRATED_GPU => CadrDeviceType::IntegratedGpu,
        T::DISCRETE_GPU => CadrDeviceType::DiscreteGpu,
        T::VIRTUAL_GPU => CadrDeviceType::VirtualGpu,
        T::CPU => CadrDeviceType::Cpu,
        _ => CadrDeviceType::Other,
    }
}

/// Describes the context's device: name, type, Vulkan version and optional features.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: `*info` is the caller's. Thread-safety: callable from any thread.
///
/// # Safety
/// `info` is null or writable for its `size`.
#[no_mangle]
pub unsafe extern "C" fn cadr_context_device_info(
    context: CadrContext,
    info: *mut CadrDeviceInfo,
) -> CadrResult {
    guard(|| {
        let state = context_state(context)?;
        let adapter = state.device.adapter();
        let capabilities = state.device.capabilities();
        let mut name = [0 as c_char; 256];
        for (slot, byte) in name.iter_mut().zip(adapter.name.bytes().take(255)) {
            *slot = byte as c_char;
        }
        let value = CadrDeviceInfo {
            size: std::mem::size_of::<CadrDeviceInfo>() as u32,
            name,
            device_type: device_type(adapter.device_type),
            api_version: adapter.api_version,
            index: adapter.index as u32,
            queue_family: adapter.queue_family,
            features: [
                (
                    capabilities.multi_draw_indirect,
                    CADR_DEVICE_FEATURE_MULTI_DRAW_INDIRECT,
                ),
                (
                    capabilities.draw_indirect_first_instance,
                    CADR_DEVICE_FEATURE_DRAW_INDIRECT_FIRST_INSTANCE,
                ),
                (
                    capabilities.shader_draw_parameters,
                    CADR_DEVICE_FEATURE_SHADER_DRAW_PARAMETERS,
                ),
                (
                    capabilities.buffer_device_address,
                    CADR_DEVICE_FEATURE_BUFFER_DEVICE_ADDRESS,
                ),
                (
                    capabilities.draw_indirect_count,
                    CADR_DEVICE_FEATURE_DRAW_INDIRECT_COUNT,
                ),
                (capabilities.multi_draw, CADR_DEVICE_FEATURE_MULTI_DRAW),
                (capabilities.timestamps, CADR_DEVICE_FEATURE_TIMESTAMPS),
                (state.presentation, CADR_DEVICE_FEATURE_PRESENTATION),
            ]
            .into_iter()
            .filter(|(has, _)| *has)
            .fold(0, |mask, (_, bit)| mask | bit),
            validation: state.device.instance().validation_enabled(),
            video_memory_bytes: adapter.video_memory,
        };
        // SAFETY: info is null or writable for its size (the caller's contract).
        unsafe { deliver_sized(info, "info", value) }
    })
}

/// Writes the context's `VkInstance` into `*instance`, for creating a window surface on it
/// (e.g. `glfwCreateWindowSurface`). Cast it to `VkInstance`.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the instance belongs to cadr and lives as long as the context or any of its
/// renderers; do not destroy it. Thread-safety: callable from any thread.
///
/// # Safety
/// `instance` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_context_vulkan_instance(
    context: CadrContext,
    instance: *mut *mut c_void,
) -> CadrResult {
    guard(|| {
        let state = context_state(context)?;
        let raw = state.device.instance().raw().handle().as_raw() as *mut c_void;
        // SAFETY: instance is null or writable (the caller's contract).
        unsafe { deliver(instance, "instance", raw) }
    })
}

/// Writes how many validation messages of severity error the context's device has reported
/// so far (0 when validation is off).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the outputs are the caller's; cadr keeps no pointer to them.
/// Thread-safety: callable from any thread.
///
/// # Safety
/// `count` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_context_validation_error_count(
    context: CadrContext,
    count: *mut u64,
) -> CadrResult {
    guard(|| {
        let state = context_state(context)?;
        let errors = state.device.validation_log().errors().len() as u64;
        // SAFETY: count is null or writable (the caller's contract).
        unsafe { deliver(count, "count", errors) }
    })
}

/// The device memory a context's cadr holds, and the host memory libcadr holds, filled by
/// `cadr_context_memory_usage`. Hosts watch them over a session (a CAD tool stays open for
/// days) to see that cadr's share of the GPU and of the host does not grow.
///
/// The struct grows by appending fields: set `size` to `sizeof(CadrMemoryUsage)` before the
/// call. cadr writes only the fields that lie within `size` bytes, so a host compiled against
/// an older header keeps working with a newer library; a host compiled against a newer header
/// gets the fields this library does not know zeroed.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CadrMemoryUsage {
    /// `sizeof(CadrMemoryUsage)`, set by the host.
    pub size: u32,
    /// Bytes of device memory in cadr's live buffers and images (all renderers and scenes of
    /// the context, and the technique plugins' buffers).
    pub device_allocated_bytes: u64,
    /// Bytes of device memory cadr has taken from the driver: the blocks its buffers and
    /// images are carved from, unused room included (at least `device_allocated_bytes`).
    pub device_reserved_bytes: u64,
    /// Bytes of host memory libcadr holds in the whole process (every context): its own heap
    /// allocations and the host memory of the Vulkan objects it creates, which drivers
    /// allocate through cadr's allocation callbacks (with validation on, the validation
    /// layer's records of them too). Not the driver's memory allocated without
    /// them (on a CPU driver such as lavapipe, its "device" memory, compiled shaders and
    /// rasterizer memory live in the process's heap too), nor the technique plugins' own
    /// heaps, nor the host's: the measure of what cadr itself keeps on the host, where the
    /// process's heap or resident size mixes in the driver's. Since 1.2.
    pub host_allocated_bytes: u64,
}

/// Writes the device memory the context's cadr holds now, and the host memory libcadr holds,
/// into `*usage`, up to `usage->size` bytes (see `CadrMemoryUsage`). The process's resident
/// size is the host's to measure; `scripts/soak.sh` watches it beside these.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_INVALID_ARGUMENT`
/// (`usage->size` smaller than its own field) or a handle error.
/// Ownership: `*usage` is the caller's; cadr keeps no pointer to it. Thread-safety: callable
/// from any thread.
///
/// # Safety
/// `usage` is null, or writable for `usage->size` bytes (at least 4).
#[no_mangle]
pub unsafe extern "C" fn cadr_context_memory_usage(
    context: CadrContext,
    usage: *mut CadrMemoryUsage,
) -> CadrResult {
    guard(|| {
        let state = context_state(context)?;
        let memory = state.device.memory_usage();
        let value = CadrMemoryUsage {
            size: std::mem::size_of::<CadrMemoryUsage>() as u32,
            device_allocated_bytes: memory.allocated_bytes,
            device_reserved_bytes: memory.reserved_bytes,
            host_allocated_bytes: cadr_core::host_heap::bytes_in_use(),
        };
        // SAFETY: usage is null or holds `usage->size` writable bytes (the caller's contract).
        unsafe { deliver_sized(usage, "usage", value) }
    })
}

/// Writes the number of techniques the plugins offer (supported or not).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the outputs are the caller's; cadr keeps no pointer to them.
/// Thread-safety: callable from any thread.
///
/// # Safety
/// `count` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_context_technique_count(
    context: CadrContext,
    count: *mut u32,
) -> CadrResult {
    guard(|| {
        let state = context_state(context)?;
        // SAFETY: count is null or writable (the caller's contract).
        unsafe { deliver(count, "count", state.techniques.len() as u32) }
    })
}

/// Describes technique `index` (0 to count - 1).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NOT_FOUND` (index out of range),
/// `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the strings in `*info` belong to the context and live until it and its
/// renderers are destroyed. Thread-safety: callable from any thread.
///
/// # Safety
/// `info` is null or writable for its `size`.
#[no_mangle]
pub unsafe extern "C" fn cadr_context_technique(
    context: CadrContext,
    index: u32,
    info: *mut CadrTechniqueInfo,
) -> CadrResult {
    guard(|| {
        let state = context_state(context)?;
        let technique = list_item(&state.techniques, index, "technique")?;
        let value = CadrTechniqueInfo {
            size: std::mem::size_of::<CadrTechniqueInfo>() as u32,
            kind: CadrTechniqueKind::from_core(technique.kind),
            name: technique.name.as_ptr(),
            description: technique.description.as_ptr(),
            library: technique.library.as_ptr(),
            supported: technique.supported,
            unsupported_reason: technique.reason.as_ptr(),
        };
        // SAFETY: info is null or writable for its size (the caller's contract).
        unsafe { deliver_sized(info, "info", value) }
    })
}

/// Writes the number of refused plugin libraries and techniques.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the outputs are the caller's; cadr keeps no pointer to them.
/// Thread-safety: callable from any thread.
///
/// # Safety
/// `count` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_context_refusal_count(
    context: CadrContext,
    count: *mut u32,
) -> CadrResult {
    guard(|| {
        let state = context_state(context)?;
        // SAFETY: count is null or writable (the caller's contract).
        unsafe { deliver(count, "count", state.refusals.len() as u32) }
    })
}

/// Describes refusal `index` (0 to count - 1).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NOT_FOUND` (index out of range),
/// `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the strings belong to the context. Thread-safety: callable from any thread.
///
/// # Safety
/// `refusal` is null or writable for its `size`.
#[no_mangle]
pub unsafe extern "C" fn cadr_context_refusal(
    context: CadrContext,
    index: u32,
    refusal: *mut CadrPluginRefusal,
) -> CadrResult {
    guard(|| {
        let state = context_state(context)?;
        let (library, reason) = list_item(&state.refusals, index, "refusal")?;
        let value = CadrPluginRefusal {
            size: std::mem::size_of::<CadrPluginRefusal>() as u32,
            library: library.as_ptr(),
            reason: reason.as_ptr(),
        };
        // SAFETY: refusal is null or writable for its size (the caller's contract).
        unsafe { deliver_sized(refusal, "refusal", value) }
    })
}
