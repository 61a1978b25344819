//! Choosing the physical device: a discrete GPU first, overridable by `CADR_DEVICE`.

use ash::vk;

use super::error::{VkError, VkResult, VkResultExt};
use super::instance::Instance;

/// The environment variable that overrides the device choice: a device index (as listed by
/// `cadr devices`) or a case-insensitive substring of the device name.
pub const DEVICE_ENV: &str = "CADR_DEVICE";

/// A physical device that cadr can use, with the queue family it renders on.
#[derive(Clone, Debug)]
pub struct Adapter {
    pub(crate) physical: vk::PhysicalDevice,
    /// Index in the instance's device list.
    pub index: usize,
    /// The driver's device name.
    pub name: String,
    /// Discrete, integrated, virtual or CPU.
    pub device_type: vk::PhysicalDeviceType,
    /// The queue family with graphics and compute.
    pub queue_family: u32,
    /// The supported Vulkan version.
    pub api_version: u32,
    /// The samples per pixel a colour pass can have: 1 always, and the MSAA levels (2, 4, 8,
    /// …) the device offers for colour and depth attachments alike; smallest first.
    pub sample_counts: Vec<u32>,
    /// How many textures the bindless texture path can bind here (0: the device lacks
    /// descriptor indexing, or `CADR_TEXTURE_ARRAY=1` said not to use it, and textures are
    /// layers of one array); see
    /// [`super::Capabilities::bindless_textures`].
    pub bindless_textures: u32,
    /// Whether it has geometry shaders (`geometryShader`), which the hidden-line mode's
    /// dashed hidden silhouettes need; see [`super::Capabilities::geometry_shader`].
    pub geometry_shader: bool,
    /// Whether it has `VK_EXT_mesh_shader` with task and mesh shaders; see
    /// [`super::Capabilities::mesh_shader`].
    pub mesh_shader: bool,
    /// Whether it has `VK_EXT_device_generated_commands` (with `VK_KHR_maintenance5` and
    /// buffer device addresses, which it needs); see
    /// [`super::Capabilities::device_generated_commands`].
    pub device_generated_commands: bool,
    /// Whether it has `drawIndirectCount` (Vulkan 1.2), with which a GPU culler's commands are
    /// drawn as many as its count says; without it they are drawn by their capacity
    /// (`individual-mdi`). See [`super::Capabilities::draw_indirect_count`].
    pub draw_indirect_count: bool,
    /// Whether it has `VK_KHR_external_memory_fd`; see
    /// [`super::Capabilities::external_memory_fd`].
    pub external_memory_fd: bool,
    /// Whether it has `VK_KHR_external_semaphore_fd`; see
    /// [`super::Capabilities::external_semaphore_fd`].
    pub external_semaphore_fd: bool,
    /// Bytes of its largest device-local memory heap: its video memory (on a CPU device, or
    /// one sharing the host's memory, what the driver offers of that); 0 where it names none.
    pub video_memory: u64,
}

/// The most textures the bindless path binds, whatever the device allows (the frame set
/// holds a descriptor for each).
pub const MAX_BINDLESS_TEXTURES: u32 = 16_384;

/// How a device is chosen.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum DeviceChoice {
    /// `CADR_DEVICE` if set, else the best device by type.
    #[default]
    Auto,
    /// The device with this index.
    Index(usize),
    /// The first device whose name contains this text (case-insensitive).
    NameContains(String),
}

impl DeviceChoice {
    /// Parses a choice the way `CADR_DEVICE` is written: a number is an index, anything else a
    /// name substring.
    pub fn parse(text: &str) -> Self {
        match text.trim().parse::<usize>() {
            Ok(index) => Self::Index(index),
            Err(_) => Self::NameContains(text.trim().to_owned()),
        }
    }

    /// The choice from `CADR_DEVICE`, or `Auto` when it is unset or empty.
    pub fn from_env() -> Self {
        match std::env::var(DEVICE_ENV) {
            Ok(text) if !text.trim().is_empty() => Self::parse(&text),
            _ => Self::Auto,
        }
    }
}

fn type_rank(device_type: vk::PhysicalDeviceType) -> u32 {
    match device_type {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

/// Every physical device with a graphics+compute queue and Vulkan 1.3.
pub fn enumerate(instance: &Instance) -> VkResult<Vec<Adapter>> {
    // SAFETY: the instance is alive for the call.
    let enumerate_physical_devices = || unsafe { instance.raw.enumerate_physical_devices() };
    // The validation layer (tests only) sets itself up here and, after a failed host
    // allocation, leaves a lock held that the instance's destruction then waits for forever:
    // with the layer, no host-memory fault is injected (as in its instance creation).
    let physicals = if instance.validation_enabled() {
        super::fault::without_host_memory_faults(enumerate_physical_devices)
    } else {
        enumerate_physical_devices()
    }
    .or_vk("vkEnumeratePhysicalDevices")?;
    let mut adapters = Vec::new();
    for (index, physical) in physicals.into_iter().enumerate() {
        // These queries return no result, so they cannot report a failed host allocation (the
        // validation layer crashes on one): no host-memory fault is injected into them.
        let (properties, families, features, bindless_textures, mesh_shader, generated_commands) =
            super::fault::without_host_memory_faults(|| {
                // SAFETY: physical comes from this instance.
                let (properties, families, features) = unsafe {
                    (
                        instance.raw.get_physical_device_properties(physical),
                        instance
                            .raw
                            .get_physical_device_queue_family_properties(physical),
                        instance.raw.get_physical_device_features(physical),
                    )
                };
                (
                    properties,
                    families,
                    features,
                    bindless_textures(instance, physical),
                    has_mesh_shader(instance, physical),
                    has_device_generated_commands(instance, physical),
                )
            });
        let name = properties
            .device_name_as_c_str()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|_| format!("device {index}"));
        let wanted = vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE;
        let Some(queue_family) = families.iter().position(|f| f.queue_flags.contains(wanted))
        else {
            continue;
        };
        if properties.api_version < vk::API_VERSION_1_3 {
            continue;
        }
        adapters.push(Adapter {
            physical,
            index,
            name,
            device_type: properties.device_type,
            queue_family: queue_family as u32,
            api_version: properties.api_version,
            sample_counts: sample_counts(&properties.limits),
            bindless_textures,
            geometry_shader: features.geometry_shader == vk::TRUE,
            mesh_shader,
            device_generated_commands: generated_commands,
            draw_indirect_count: super::fault::without_host_memory_faults(|| {
                has_draw_indirect_count(instance, physical)
            }),
            external_memory_fd: super::fault::without_host_memory_faults(|| {
                has_extension(instance, physical, ash::khr::external_memory_fd::NAME)
            }),
            external_semaphore_fd: super::fault::without_host_memory_faults(|| {
                has_extension(instance, physical, ash::khr::external_semaphore_fd::NAME)
            }),
            video_memory: super::fault::without_host_memory_faults(|| {
                video_memory(instance, physical)
            }),
        });
    }
    Ok(adapters)
}

/// Whether `physical` has Vulkan 1.2's `drawIndirectCount`.
fn has_draw_indirect_count(instance: &Instance, physical: vk::PhysicalDevice) -> bool {
    let mut vulkan12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut features = vk::PhysicalDeviceFeatures2::default().push_next(&mut vulkan12);
    // SAFETY: physical comes from this instance, a Vulkan 1.3 one; the chain lives for the call.
    unsafe {
        instance
            .raw
            .get_physical_device_features2(physical, &mut features)
    };
    vulkan12.draw_indirect_count == vk::TRUE
}

/// Bytes of `physical`'s largest device-local memory heap (0 where it has none).
fn video_memory(instance: &Instance, physical: vk::PhysicalDevice) -> u64 {
    // SAFETY: physical comes from this instance.
    let properties = unsafe { instance.raw.get_physical_device_memory_properties(physical) };
    (properties.memory_heaps_as_slice().iter())
        .filter(|heap| heap.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
        .map(|heap| heap.size)
        .max()
        .unwrap_or(0)
}

/// Whether `physical` lists `extension`.
pub(super) fn has_extension(
    instance: &Instance,
    physical: vk::PhysicalDevice,
    extension: &std::ffi::CStr,
) -> bool {
    // SAFETY: physical comes from this instance.
    let extensions = unsafe { instance.raw.enumerate_device_extension_properties(physical) };
    extensions.is_ok_and(|extensions| {
        extensions
            .iter()
            .any(|e| e.extension_name_as_c_str() == Ok(extension))
    })
}

/// Whether `physical` has `VK_EXT_mesh_shader` with both its task and mesh stages.
fn has_mesh_shader(instance: &Instance, physical: vk::PhysicalDevice) -> bool {
    if !has_extension(instance, physical, ash::ext::mesh_shader::NAME) {
        return false;
    }
    let mut mesh = vk::PhysicalDeviceMeshShaderFeaturesEXT::default();
    let mut features = vk::PhysicalDeviceFeatures2::default().push_next(&mut mesh);
    // SAFETY: physical comes from this instance and has the extension; the chain lives on
    // this stack frame.
    unsafe {
        instance
            .raw
            .get_physical_device_features2(physical, &mut features)
    };
    mesh.task_shader == vk::TRUE && mesh.mesh_shader == vk::TRUE
}

/// Whether `physical` has `VK_EXT_device_generated_commands` and what it needs:
/// `VK_KHR_maintenance5` (its preprocess buffers' usage flag) and buffer device addresses
/// (the stream is read by address).
fn has_device_generated_commands(instance: &Instance, physical: vk::PhysicalDevice) -> bool {
    use cadr_vk_ext::device_generated_commands as dgc;
    if !has_extension(instance, physical, dgc::NAME)
        || !has_extension(instance, physical, ash::khr::maintenance5::NAME)
    {
        return false;
    }
    let mut generated = dgc::PhysicalDeviceFeatures::default();
    let mut maintenance5 = vk::PhysicalDeviceMaintenance5FeaturesKHR::default();
    let mut vulkan12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut features = vk::PhysicalDeviceFeatures2::default()
        .push_next(&mut generated)
        .push_next(&mut maintenance5)
        .push_next(&mut vulkan12);
    // SAFETY: physical comes from this instance and has both extensions; the chain lives on
    // this stack frame.
    unsafe {
        instance
            .raw
            .get_physical_device_features2(physical, &mut features)
    };
    generated.device_generated_commands == vk::TRUE
        && maintenance5.maintenance5 == vk::TRUE
        && vulkan12.buffer_device_address == vk::TRUE
}

/// How many textures the bindless path may bind on a device with these features and
/// properties (see [`Capabilities::bindless_textures`]): 0 without descriptor indexing.
fn bindless_texture_capacity(
    features: &vk::PhysicalDeviceVulkan12Features<'_>,
    properties: &vk::PhysicalDeviceVulkan12Properties<'_>,
) -> u32 {
    let has_all = [
        features.runtime_descriptor_array,
        features.shader_sampled_image_array_non_uniform_indexing,
        features.descriptor_binding_partially_bound,
        features.descriptor_binding_sampled_image_update_after_bind,
    ]
    .iter()
    .all(|&feature| feature == vk::TRUE);
    if !has_all {
        return 0;
    }
    // The frame set's other bindings count against the per-stage resources too.
    let room = properties
        .max_per_stage_descriptor_update_after_bind_sampled_images
        .min(properties.max_descriptor_set_update_after_bind_sampled_images)
        .min(
            properties
                .max_per_stage_update_after_bind_resources
                .saturating_sub(16),
        );
    let capacity = room.min(MAX_BINDLESS_TEXTURES);
    // A table this small is no better than the array's layers.
    if capacity < MIN_BINDLESS_TEXTURES {
        0
    } else {
        capacity
    }
}

/// Below this many, the bindless path is not used.
const MIN_BINDLESS_TEXTURES: u32 = 64;

/// The environment variable that keeps textures in one array even on a device with
/// descriptor indexing (`1`): a workaround for a driver whose descriptor indexing misbehaves.
pub const TEXTURE_ARRAY_ENV: &str = "CADR_TEXTURE_ARRAY";

/// How many textures the bindless path can bind on `physical` (see
/// [`bindless_texture_capacity`]); 0 when [`TEXTURE_ARRAY_ENV`] is `1`.
fn bindless_textures(instance: &Instance, physical: vk::PhysicalDevice) -> u32 {
    if std::env::var(TEXTURE_ARRAY_ENV).is_ok_and(|value| value.trim() == "1") {
        return 0;
    }
    let mut features12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut features = vk::PhysicalDeviceFeatures2::default().push_next(&mut features12);
    let mut properties12 = vk::PhysicalDeviceVulkan12Properties::default();
    let mut properties = vk::PhysicalDeviceProperties2::default().push_next(&mut properties12);
    // SAFETY: physical comes from this instance; the chains live on this stack frame.
    unsafe {
        instance
            .raw
            .get_physical_device_features2(physical, &mut features);
        instance
            .raw
            .get_physical_device_properties2(physical, &mut properties);
    }
    bindless_texture_capacity(&features12, &properties12)
}

/// The sample counts of a colour pass with a depth attachment under `limits`.
fn sample_counts(limits: &vk::PhysicalDeviceLimits) -> Vec<u32> {
    let offered = limits.framebuffer_color_sample_counts & limits.framebuffer_depth_sample_counts;
    (0..7)
        .map(|bit| 1u32 << bit)
        .filter(|&count| count == 1 || offered.contains(vk::SampleCountFlags::from_raw(count)))
        .collect()
}

/// Picks a device according to `choice`.
pub fn choose(instance: &Instance, choice: &DeviceChoice) -> VkResult<Adapter> {
    let adapters = enumerate(instance)?;
    let listing = || {
        adapters
            .iter()
            .map(|a| format!("{}: {}", a.index, a.name))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let choice = match choice {
        DeviceChoice::Auto => DeviceChoice::from_env(),
        other => other.clone(),
    };
    let chosen = match &choice {
        DeviceChoice::Auto => adapters
            .iter()
            .min_by_key(|a| (type_rank(a.device_type), a.index)),
        DeviceChoice::Index(index) => adapters.iter().find(|a| a.index == *index),
        DeviceChoice::NameContains(text) => {
            let text = text.to_lowercase();
            adapters
                .iter()
                .find(|a| a.name.to_lowercase().contains(&text))
        }
    };
    match chosen {
        Some(adapter) => Ok(adapter.clone()),
        None if adapters.is_empty() => Err(VkError::NoDevice(
            " with Vulkan 1.3 and a graphics queue (install mesa-vulkan-drivers for a CPU device)"
                .into(),
        )),
        None => Err(VkError::NoDevice(format!(
            " matching {choice:?} (from {DEVICE_ENV} or the options); available: {}",
            listing()
        ))),
    }
}
