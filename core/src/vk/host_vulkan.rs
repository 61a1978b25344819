//! A host's own Vulkan: what cadr needs of an instance and device a host made
//! ([`REQUIREMENTS`]), what the host enabled ([`HostDevice`], read from the `VkDeviceCreateInfo`
//! it created its device with) and the handles it lends ([`HostVulkan`]), which
//! `Device::from_host` uses without owning them.

use std::ffi::{c_void, CStr, CString};
use std::sync::Arc;

use ash::vk;
use cadr_vk_ext::device_generated_commands as dgc;

/// What cadr needs of a host's Vulkan, and what it uses where the host enabled it.
#[derive(Debug)]
pub struct Requirements {
    /// The lowest Vulkan version of the instance and the physical device.
    pub api_version: u32,
    /// Device extensions cadr uses where the host enabled them (faster paths, windows); none
    /// is required.
    pub optional_extensions: &'static [&'static CStr],
    /// Device features the host must enable, as `Struct::member`.
    pub required_features: &'static [&'static CStr],
    /// Device features cadr uses where the host enabled them (and the device has them).
    pub optional_features: &'static [&'static CStr],
}

/// Device features a host's device must have enabled for cadr.
pub const REQUIRED_FEATURES: &[&CStr] = &[
    c"VkPhysicalDeviceVulkan13Features::dynamicRendering",
    c"VkPhysicalDeviceVulkan13Features::synchronization2",
    c"VkPhysicalDeviceFeatures::shaderClipDistance",
    c"VkPhysicalDeviceFeatures::fillModeNonSolid",
    c"VkPhysicalDeviceFeatures::independentBlend",
];

/// What cadr needs of a host's Vulkan (see [`Requirements`]).
pub const REQUIREMENTS: Requirements = Requirements {
    api_version: vk::API_VERSION_1_3,
    optional_extensions: &[
        c"VK_EXT_multi_draw",
        c"VK_EXT_mesh_shader",
        c"VK_EXT_device_generated_commands",
        c"VK_KHR_maintenance5",
        c"VK_KHR_swapchain",
        c"VK_KHR_external_memory_fd",
        c"VK_KHR_external_semaphore_fd",
    ],
    required_features: REQUIRED_FEATURES,
    optional_features: &[
        c"VkPhysicalDeviceFeatures::multiDrawIndirect",
        c"VkPhysicalDeviceFeatures::drawIndirectFirstInstance",
        c"VkPhysicalDeviceFeatures::pipelineStatisticsQuery",
        c"VkPhysicalDeviceFeatures::fragmentStoresAndAtomics",
        c"VkPhysicalDeviceFeatures::geometryShader",
        c"VkPhysicalDeviceVulkan11Features::shaderDrawParameters",
        c"VkPhysicalDeviceVulkan12Features::bufferDeviceAddress",
        c"VkPhysicalDeviceVulkan12Features::drawIndirectCount",
        c"VkPhysicalDeviceVulkan12Features::hostQueryReset",
        c"VkPhysicalDeviceVulkan12Features::runtimeDescriptorArray",
        c"VkPhysicalDeviceVulkan12Features::shaderSampledImageArrayNonUniformIndexing",
        c"VkPhysicalDeviceVulkan12Features::descriptorBindingPartiallyBound",
        c"VkPhysicalDeviceVulkan12Features::descriptorBindingSampledImageUpdateAfterBind",
        c"VkPhysicalDeviceVulkan13Features::maintenance4",
        c"VkPhysicalDeviceMultiDrawFeaturesEXT::multiDraw",
        c"VkPhysicalDeviceMeshShaderFeaturesEXT::taskShader",
        c"VkPhysicalDeviceMeshShaderFeaturesEXT::meshShader",
        c"VkPhysicalDeviceDeviceGeneratedCommandsFeaturesEXT::deviceGeneratedCommands",
        c"VkPhysicalDeviceMaintenance5FeaturesKHR::maintenance5",
    ],
};

/// What a host enabled on its device: the features cadr reads (as the structs that hold them)
/// and the extensions.
#[derive(Clone, Debug, Default)]
pub struct HostDevice {
    /// `VkPhysicalDeviceFeatures`.
    pub core: vk::PhysicalDeviceFeatures,
    /// `VkPhysicalDeviceVulkan11Features::shaderDrawParameters`.
    pub shader_draw_parameters: bool,
    /// Of `VkPhysicalDeviceVulkan12Features`: bufferDeviceAddress, drawIndirectCount,
    /// hostQueryReset, and the four bindless texture features, all of them.
    pub buffer_device_address: bool,
    /// See `buffer_device_address`.
    pub draw_indirect_count: bool,
    /// See `buffer_device_address`.
    pub host_query_reset: bool,
    /// See `buffer_device_address`.
    pub bindless: bool,
    /// Of `VkPhysicalDeviceVulkan13Features` (or the structs of the extensions it took in).
    pub dynamic_rendering: bool,
    /// See `dynamic_rendering`.
    pub synchronization2: bool,
    /// See `dynamic_rendering`.
    pub maintenance4: bool,
    /// `VkPhysicalDeviceMultiDrawFeaturesEXT::multiDraw`.
    pub multi_draw: bool,
    /// `VkPhysicalDeviceMeshShaderFeaturesEXT`: taskShader and meshShader.
    pub mesh_shader: bool,
    /// `VkPhysicalDeviceDeviceGeneratedCommandsFeaturesEXT` and
    /// `VkPhysicalDeviceMaintenance5FeaturesKHR`.
    pub device_generated_commands: bool,
    /// The device extensions enabled.
    pub extensions: Vec<CString>,
    /// The queue families and how many queues of each the device was created with.
    pub queues: Vec<(u32, u32)>,
}

impl HostDevice {
    /// Reads what a host enabled from the `VkDeviceCreateInfo` it created its device with: the
    /// extensions, `pEnabledFeatures` or a `VkPhysicalDeviceFeatures2` in the chain, and the
    /// Vulkan 1.1–1.3, multi-draw, mesh-shader, generated-commands and maintenance5 feature
    /// structs of the chain.
    ///
    /// # Safety
    /// `info` points at a valid `VkDeviceCreateInfo` whose arrays and chain are valid for the
    /// call.
    pub unsafe fn from_create_info(info: *const c_void) -> Result<Self, String> {
        if info.is_null() {
            return Err("the device create info is null".into());
        }
        // SAFETY: the caller's contract.
        let info = unsafe { &*info.cast::<vk::DeviceCreateInfo>() };
        if info.s_type != vk::StructureType::DEVICE_CREATE_INFO {
            return Err(format!(
                "the device create info has sType {}, not VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO",
                info.s_type.as_raw()
            ));
        }
        let mut enabled = Self::default();
        for index in 0..info.enabled_extension_count as usize {
            // SAFETY: the array holds `enabled_extension_count` NUL-terminated names.
            let name = unsafe { CStr::from_ptr(*info.pp_enabled_extension_names.add(index)) };
            enabled.extensions.push(name.to_owned());
        }
        for index in 0..info.queue_create_info_count as usize {
            // SAFETY: the array holds `queue_create_info_count` entries.
            let queue = unsafe { &*info.p_queue_create_infos.add(index) };
            enabled
                .queues
                .push((queue.queue_family_index, queue.queue_count));
        }
        if !info.p_enabled_features.is_null() {
            // SAFETY: a valid VkPhysicalDeviceFeatures when not null.
            enabled.core = unsafe { *info.p_enabled_features };
        }
        let mut next = info.p_next.cast::<vk::BaseInStructure>();
        while !next.is_null() {
            // SAFETY: every struct of a valid chain starts with sType and pNext.
            let base = unsafe { &*next };
            // SAFETY: the struct's type is the one its sType names.
            unsafe { enabled.read_feature_struct(next.cast(), base.s_type) };
            next = base.p_next;
        }
        enabled.device_generated_commands &=
            enabled.has(c"VK_EXT_device_generated_commands") && enabled.has(c"VK_KHR_maintenance5");
        enabled.multi_draw &= enabled.has(c"VK_EXT_multi_draw");
        enabled.mesh_shader &= enabled.has(c"VK_EXT_mesh_shader");
        Ok(enabled)
    }

    /// Takes in the features of one struct of the chain, of type `s_type` (others are
    /// skipped).
    ///
    /// # Safety
    /// `feature` points at a valid struct of the type `s_type` names.
    unsafe fn read_feature_struct(&mut self, feature: *const c_void, s_type: vk::StructureType) {
        use vk::StructureType as S;
        let on = |value: vk::Bool32| value == vk::TRUE;
        match s_type {
            S::PHYSICAL_DEVICE_FEATURES_2 => {
                // SAFETY: the struct is of the type its sType names (the caller's contract).
                self.core = unsafe { &*feature.cast::<vk::PhysicalDeviceFeatures2>() }.features;
            }
            S::PHYSICAL_DEVICE_VULKAN_1_1_FEATURES => {
                // SAFETY: the struct is of the type its sType names (the caller's contract).
                let f = unsafe { &*feature.cast::<vk::PhysicalDeviceVulkan11Features>() };
                self.shader_draw_parameters = on(f.shader_draw_parameters);
            }
            S::PHYSICAL_DEVICE_VULKAN_1_2_FEATURES => {
                // SAFETY: the struct is of the type its sType names (the caller's contract).
                let f = unsafe { &*feature.cast::<vk::PhysicalDeviceVulkan12Features>() };
                self.buffer_device_address = on(f.buffer_device_address);
                self.draw_indirect_count = on(f.draw_indirect_count);
                self.host_query_reset = on(f.host_query_reset);
                self.bindless = on(f.runtime_descriptor_array)
                    && on(f.shader_sampled_image_array_non_uniform_indexing)
                    && on(f.descriptor_binding_partially_bound)
                    && on(f.descriptor_binding_sampled_image_update_after_bind);
            }
            S::PHYSICAL_DEVICE_VULKAN_1_3_FEATURES => {
                // SAFETY: the struct is of the type its sType names (the caller's contract).
                let f = unsafe { &*feature.cast::<vk::PhysicalDeviceVulkan13Features>() };
                self.dynamic_rendering = on(f.dynamic_rendering);
                self.synchronization2 = on(f.synchronization2);
                self.maintenance4 = on(f.maintenance4);
            }
            S::PHYSICAL_DEVICE_DYNAMIC_RENDERING_FEATURES => {
                // SAFETY: the struct is of the type its sType names (the caller's contract).
                let f = unsafe { &*feature.cast::<vk::PhysicalDeviceDynamicRenderingFeatures>() };
                self.dynamic_rendering = on(f.dynamic_rendering);
            }
            S::PHYSICAL_DEVICE_SYNCHRONIZATION_2_FEATURES => {
                // SAFETY: the struct is of the type its sType names (the caller's contract).
                let f = unsafe { &*feature.cast::<vk::PhysicalDeviceSynchronization2Features>() };
                self.synchronization2 = on(f.synchronization2);
            }
            S::PHYSICAL_DEVICE_MULTI_DRAW_FEATURES_EXT => {
                // SAFETY: the struct is of the type its sType names (the caller's contract).
                let f = unsafe { &*feature.cast::<vk::PhysicalDeviceMultiDrawFeaturesEXT>() };
                self.multi_draw = on(f.multi_draw);
            }
            S::PHYSICAL_DEVICE_MESH_SHADER_FEATURES_EXT => {
                // SAFETY: the struct is of the type its sType names (the caller's contract).
                let f = unsafe { &*feature.cast::<vk::PhysicalDeviceMeshShaderFeaturesEXT>() };
                self.mesh_shader = on(f.task_shader) && on(f.mesh_shader);
            }
            _ if s_type == dgc::STRUCTURE_TYPE_FEATURES => {
                // SAFETY: the struct is of the type its sType names (the caller's contract).
                let f = unsafe { &*feature.cast::<dgc::PhysicalDeviceFeatures>() };
                self.device_generated_commands = on(f.device_generated_commands);
            }
            _ => {}
        }
    }

    /// Whether the device extension `name` is enabled.
    pub fn has(&self, name: &CStr) -> bool {
        self.extensions.iter().any(|e| e.as_c_str() == name)
    }

    /// The first of [`REQUIRED_FEATURES`] the host did not enable, if any.
    pub fn missing_required(&self) -> Option<&'static CStr> {
        let core = &self.core;
        let enabled = [
            self.dynamic_rendering,
            self.synchronization2,
            core.shader_clip_distance == vk::TRUE,
            core.fill_mode_non_solid == vk::TRUE,
            core.independent_blend == vk::TRUE,
        ];
        REQUIRED_FEATURES
            .iter()
            .zip(enabled)
            .find(|(_, on)| !on)
            .map(|(name, _)| *name)
    }
}

/// Takes and gives back the host's lock on the queue it shares with cadr: called with `true`
/// before cadr uses the queue (submits, presents, waits for it) and `false` after, from any
/// thread that renders.
pub type QueueLock = Arc<dyn Fn(bool) + Send + Sync>;

/// Vulkan objects a host made and lends to cadr, which uses them without destroying them.
pub struct HostVulkan {
    /// The loader's `vkGetInstanceProcAddr` the host loaded Vulkan with.
    pub get_instance_proc_addr: vk::PFN_vkGetInstanceProcAddr,
    /// The host's instance.
    pub instance: vk::Instance,
    /// The instance extensions the host enabled (cadr logs validation messages through its
    /// own messenger where `VK_EXT_debug_utils` is among them).
    pub instance_extensions: Vec<CString>,
    /// The physical device of `device`.
    pub physical_device: vk::PhysicalDevice,
    /// The host's device.
    pub device: vk::Device,
    /// What the host enabled on `device`.
    pub enabled: HostDevice,
    /// The queue cadr submits to: its family and index.
    pub queue: (u32, u32),
    /// The host's lock on that queue, when the host uses it too.
    pub queue_lock: Option<QueueLock>,
}

impl HostVulkan {
    /// Whether the host enabled the instance extension `name`.
    pub fn has_instance_extension(&self, name: &CStr) -> bool {
        self.instance_extensions
            .iter()
            .any(|e| e.as_c_str() == name)
    }
}
