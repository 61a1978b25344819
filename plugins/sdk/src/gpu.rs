//! The host's device as a plugin sees it: ash function tables loaded from the raw handles and
//! `vkGetInstanceProcAddr` the host passed, and buffers the host allocates.

use std::ffi::CString;
use std::sync::Arc;

use ash::vk;
use ash::vk::Handle;
use cadr_plugin_abi as abi;

use crate::message::MessageBuffer;

/// The device and the host services, shared by a plugin instance and its buffers.
pub struct Gpu {
    /// Instance-level functions.
    pub instance: ash::Instance,
    /// Device-level functions.
    pub device: ash::Device,
    /// The physical device the host's device was created on.
    pub physical_device: vk::PhysicalDevice,
    /// `VK_EXT_multi_draw` functions (present when the feature bit is).
    pub multi_draw: Option<ash::ext::multi_draw::Device>,
    /// `VK_EXT_mesh_shader` functions (present when `CADR_FEATURE_MESH_SHADER` is).
    pub mesh_shader: Option<ash::ext::mesh_shader::Device>,
    /// `VK_EXT_device_generated_commands` functions (present when
    /// `CADR_FEATURE_DEVICE_GENERATED_COMMANDS_EXT` is).
    pub generated_commands: Option<crate::dgc::Device>,
    /// `CADR_FEATURE_*` bits enabled on the device.
    pub features: abi::CadrFeatureBits,
    /// `minUniformBufferOffsetAlignment`.
    pub min_uniform_buffer_offset_alignment: u64,
    /// `maxDrawIndirectCount`: the most commands one indirect draw may run (at least 1).
    pub max_draw_indirect_count: u32,
    /// Colour and depth formats of the target.
    pub formats: (vk::Format, vk::Format),
    /// Worker threads the technique may use.
    pub worker_threads: u32,
    /// The host's pipeline cache (null from a host older than ABI 1.5): pass it when creating
    /// pipelines.
    pub pipeline_cache: vk::PipelineCache,
    allocation_callbacks: *const vk::AllocationCallbacks<'static>,
    host: *const abi::CadrHostApi,
}

// SAFETY: the host guarantees its API struct and allocation callbacks are thread-safe and
// outlive every instance; the ash tables are plain function pointers.
unsafe impl Send for Gpu {}
// SAFETY: as above.
unsafe impl Sync for Gpu {}

impl Gpu {
    /// The stages a vertex or parameter path's descriptor bindings are for: the vertex stage,
    /// and the mesh stage where the device has mesh shaders (the host's technique mesh shader
    /// runs the snippets of paths that announce `CADR_TRAIT_MESH_SHADING` there).
    pub fn path_stages(&self) -> vk::ShaderStageFlags {
        if self.features & abi::CADR_FEATURE_MESH_SHADER != 0 {
            vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::MESH_EXT
        } else {
            vk::ShaderStageFlags::VERTEX
        }
    }
}

impl std::fmt::Debug for Gpu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Gpu")
            .field("features", &self.features)
            .finish()
    }
}

/// How many elements (or bytes) a growing buffer should hold when `needed` no longer fits in
/// the `held` it has: exactly `needed` the first time (`held` 0), else at least half again as
/// many as it held, so that a scene growing one part at a time reallocates a logarithmic number
/// of times while a buffer made once wastes nothing (a power of two would waste up to half:
/// every view of a scene keeps its own command buffers).
pub fn grown_capacity(held: u64, needed: u64) -> u64 {
    if held == 0 {
        needed
    } else {
        needed.max(held.saturating_add(held / 2))
    }
}

impl Gpu {
    /// Loads the function tables from what `create` received.
    ///
    /// # Safety
    /// `info` must be the host's valid create info.
    pub unsafe fn from_create_info(info: &abi::CadrCreateInfo) -> Result<Arc<Self>, String> {
        // SAFETY: the host passes valid pointers for the life of the instance.
        let vulkan = unsafe { info.vulkan.as_ref() }.ok_or("the host passed no Vulkan handles")?;
        // SAFETY: same signature; VkInstance is a pointer-sized handle on both sides.
        let loader = unsafe {
            std::mem::transmute::<abi::CadrGetInstanceProcAddr, Option<vk::PFN_vkGetInstanceProcAddr>>(
                vulkan.get_instance_proc_addr,
            )
        };
        let static_fn = ash::StaticFn {
            get_instance_proc_addr: loader.ok_or("the host passed no vkGetInstanceProcAddr")?,
        };
        let instance_handle = vk::Instance::from_raw(vulkan.instance as u64);
        // SAFETY: the handle and loader are the host's live instance.
        let instance = unsafe { ash::Instance::load(&static_fn, instance_handle) };
        let device_handle = vk::Device::from_raw(vulkan.device as u64);
        // SAFETY: the device was created from that instance.
        let device = unsafe { ash::Device::load(instance.fp_v1_0(), device_handle) };
        let multi_draw = (vulkan.features & abi::CADR_FEATURE_MULTI_DRAW != 0)
            .then(|| ash::ext::multi_draw::Device::new(&instance, &device));
        let mesh_shader = (vulkan.features & abi::CADR_FEATURE_MESH_SHADER != 0)
            .then(|| ash::ext::mesh_shader::Device::new(&instance, &device));
        let generated_commands =
            if vulkan.features & abi::CADR_FEATURE_DEVICE_GENERATED_COMMANDS_EXT != 0 {
                Some(
                    crate::dgc::Device::new(&instance, &device).ok_or(
                        "the device lacks the commands of VK_EXT_device_generated_commands",
                    )?,
                )
            } else {
                None
            };
        let physical_device = vk::PhysicalDevice::from_raw(vulkan.physical_device as u64);
        // SAFETY: the host's physical device, of this instance.
        let limits = unsafe { instance.get_physical_device_properties(physical_device) }.limits;
        Ok(Arc::new(Self {
            max_draw_indirect_count: limits.max_draw_indirect_count.max(1),
            instance,
            device,
            physical_device,
            multi_draw,
            mesh_shader,
            generated_commands,
            features: vulkan.features,
            min_uniform_buffer_offset_alignment: vulkan.min_uniform_buffer_offset_alignment.max(1),
            formats: (
                vk::Format::from_raw(vulkan.color_format),
                vk::Format::from_raw(vulkan.depth_format),
            ),
            worker_threads: info.worker_threads.max(1),
            pipeline_cache: {
                let end = std::mem::offset_of!(abi::CadrVulkan, pipeline_cache)
                    + std::mem::size_of::<u64>();
                if vulkan.size as usize >= end {
                    vk::PipelineCache::from_raw(vulkan.pipeline_cache)
                } else {
                    vk::PipelineCache::null()
                }
            },
            allocation_callbacks: vulkan.allocation_callbacks.cast(),
            host: info.host,
        }))
    }

    /// The allocation callbacks to pass to every `vkCreate*` and `vkDestroy*`.
    pub fn allocator(&self) -> Option<&vk::AllocationCallbacks<'static>> {
        // SAFETY: the host keeps its callbacks alive for the life of the device.
        unsafe { self.allocation_callbacks.as_ref() }
    }

    /// Asks the host for a buffer.
    pub fn create_buffer(
        self: &Arc<Self>,
        name: &str,
        size_bytes: u64,
        usage: vk::BufferUsageFlags,
        location: abi::CadrMemoryLocation,
    ) -> Result<HostBuffer, String> {
        // SAFETY: the host API outlives the instance.
        let host = unsafe { self.host.as_ref() }.ok_or("the host passed no services")?;
        let create = host.create_buffer.ok_or("the host cannot create buffers")?;
        let name = CString::new(name).unwrap_or_default();
        let mut buffer = abi::CadrBuffer {
            buffer: 0,
            size_bytes: 0,
            address: 0,
            mapped: std::ptr::null_mut(),
            id: 0,
        };
        let mut message = MessageBuffer::new();
        // SAFETY: every pointer is valid for the call.
        let status = unsafe {
            create(
                host.user,
                size_bytes.max(4),
                usage.as_raw(),
                location,
                name.as_ptr(),
                &mut buffer,
                message.as_abi(),
            )
        };
        if status != abi::CADR_STATUS_OK {
            return Err(message.text());
        }
        Ok(HostBuffer {
            gpu: Arc::clone(self),
            raw: buffer,
        })
    }
}

impl Gpu {
    /// Asks the host (ABI 1.3) to compile GLSL `source` for `stage` into a shader module that
    /// the caller owns: destroy it with `device.destroy_shader_module(module, gpu.allocator())`.
    pub fn create_shader_module(
        &self,
        name: &str,
        stage: vk::ShaderStageFlags,
        source: &str,
    ) -> Result<vk::ShaderModule, String> {
        // SAFETY: the host API outlives the instance.
        let host = unsafe { self.host.as_ref() }.ok_or("the host passed no services")?;
        let end = std::mem::offset_of!(abi::CadrHostApi, create_shader_module)
            + std::mem::size_of::<usize>();
        let create = host
            .create_shader_module
            .filter(|_| host.size as usize >= end)
            .ok_or("the host cannot compile shaders (it speaks plugin ABI 1.2 or older)")?;
        let name_c = CString::new(name).map_err(|_| format!("shader name '{name}' holds a NUL"))?;
        let source = CString::new(source).map_err(|_| format!("shader '{name}' holds a NUL"))?;
        let mut module = 0u64;
        let mut message = MessageBuffer::new();
        // SAFETY: every pointer is valid for the call.
        let status = unsafe {
            create(
                host.user,
                stage.as_raw(),
                source.as_ptr(),
                name_c.as_ptr(),
                &mut module,
                message.as_abi(),
            )
        };
        if status != abi::CADR_STATUS_OK {
            return Err(message.text());
        }
        Ok(vk::ShaderModule::from_raw(module))
    }
}

/// A buffer the host allocated for a plugin; given back on drop (the owner makes sure the GPU
/// is done with it).
pub struct HostBuffer {
    gpu: Arc<Gpu>,
    raw: abi::CadrBuffer,
}

impl std::fmt::Debug for HostBuffer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HostBuffer")
            .field("size", &self.raw.size_bytes)
            .finish()
    }
}

// SAFETY: the mapped pointer is only written through &mut self.
unsafe impl Send for HostBuffer {}
// SAFETY: as above.
unsafe impl Sync for HostBuffer {}

impl HostBuffer {
    /// The `VkBuffer`.
    pub fn raw(&self) -> vk::Buffer {
        vk::Buffer::from_raw(self.raw.buffer)
    }

    /// Size in bytes.
    pub fn size(&self) -> u64 {
        self.raw.size_bytes
    }

    /// The host's id for it: never given to another buffer, unlike the `VkBuffer` handle, which
    /// a driver may hand out again for a buffer made after this one is destroyed. What a cache
    /// of descriptor writes should key on.
    pub fn id(&self) -> u64 {
        self.raw.id
    }

    /// Device address (0 without the usage).
    pub fn address(&self) -> u64 {
        self.raw.address
    }

    /// Copies `data` to byte `offset` of a host-visible buffer.
    pub fn write(&mut self, offset: u64, data: &[u8]) -> Result<(), String> {
        if self.raw.mapped.is_null() {
            return Err("the buffer is not host-visible".into());
        }
        if offset + data.len() as u64 > self.raw.size_bytes {
            return Err(format!(
                "writing {} bytes at {offset} overruns a {}-byte buffer",
                data.len(),
                self.raw.size_bytes
            ));
        }
        // SAFETY: the range lies inside the mapping (checked above); &mut self excludes
        // concurrent writers.
        unsafe {
            std::ptr::copy_nonoverlapping(
                data.as_ptr(),
                self.raw.mapped.cast::<u8>().add(offset as usize),
                data.len(),
            )
        };
        Ok(())
    }
}

impl HostBuffer {
    /// Reads `length` bytes at byte `offset` of a host-visible buffer (host-coherent memory:
    /// after the GPU work that wrote them has finished and been made visible to the host).
    pub fn read(&self, offset: u64, length: usize) -> Result<Vec<u8>, String> {
        if self.raw.mapped.is_null() {
            return Err("the buffer is not host-visible".into());
        }
        if offset + length as u64 > self.raw.size_bytes {
            return Err(format!(
                "reading {length} bytes at {offset} overruns a {}-byte buffer",
                self.raw.size_bytes
            ));
        }
        let mut bytes = vec![0u8; length];
        // SAFETY: the range lies inside the mapping (checked above).
        unsafe {
            std::ptr::copy_nonoverlapping(
                self.raw.mapped.cast::<u8>().add(offset as usize),
                bytes.as_mut_ptr(),
                length,
            )
        };
        Ok(bytes)
    }
}

impl Drop for HostBuffer {
    fn drop(&mut self) {
        // SAFETY: the host API outlives the instance; the buffer came from it.
        if let Some(host) = unsafe { self.gpu.host.as_ref() } {
            if let Some(destroy) = host.destroy_buffer {
                // SAFETY: as above.
                unsafe { destroy(host.user, &self.raw) };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::grown_capacity;

    #[test]
    fn a_buffer_made_once_fits_exactly_and_a_growing_one_grows_by_half() {
        assert_eq!(grown_capacity(0, 235_140), 235_140);
        assert_eq!(grown_capacity(1_000, 1_001), 1_500);
        assert_eq!(
            grown_capacity(1_000, 4_000),
            4_000,
            "never less than needed"
        );
        // Growing one element at a time from 1 reallocates a logarithmic number of times.
        let (mut held, mut reallocations) = (1_u64, 0);
        for needed in 2..=1_000_000 {
            if needed > held {
                held = grown_capacity(held, needed);
                reallocations += 1;
            }
        }
        assert!(reallocations < 40, "{reallocations} reallocations");
        assert_eq!(grown_capacity(u64::MAX - 1, u64::MAX), u64::MAX);
    }
}
