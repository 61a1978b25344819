//! The logical device: queue, memory allocator, debug names and capability flags.

use super::host_memory::core_callbacks as host_callbacks;
use std::ffi::CString;
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

use ash::vk;
use gpu_allocator::vulkan::{
    Allocation, AllocationCreateDesc, AllocationScheme, Allocator, AllocatorCreateDesc,
};
use gpu_allocator::MemoryLocation;

use super::adapter::{self, Adapter, DeviceChoice};
use super::error::{VkError, VkResult, VkResultExt};
use super::host_vulkan::{HostDevice, HostVulkan, QueueLock};
use super::instance::{Instance, InstanceOptions, ValidationLog};
use super::pipeline_cache::PersistentPipelineCache;

/// Optional device features cadr uses when present. Required ones (dynamic rendering,
/// synchronization2, shaderClipDistance, fillModeNonSolid) are not listed: a device without
/// them is refused.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Capabilities {
    /// `multiDrawIndirect`: many indirect draws in one call.
    pub multi_draw_indirect: bool,
    /// `drawIndirectFirstInstance`: per-draw indices through firstInstance.
    pub draw_indirect_first_instance: bool,
    /// `shaderDrawParameters`: gl_DrawID and gl_BaseInstance in shaders.
    pub shader_draw_parameters: bool,
    /// `bufferDeviceAddress`: GPU pointers to buffers.
    pub buffer_device_address: bool,
    /// `drawIndirectCount`: indirect draws whose count the GPU reads.
    pub draw_indirect_count: bool,
    /// `VK_EXT_multi_draw`: many index ranges in one call.
    pub multi_draw: bool,
    /// `pipelineStatisticsQuery`.
    pub pipeline_statistics_query: bool,
    /// Timestamps are supported on the render queue.
    pub timestamps: bool,
    /// `fragmentStoresAndAtomics`: fragment shaders write storage buffers (the exact
    /// transparency method's per-pixel lists, the outline highlight style's keys).
    pub fragment_stores_and_atomics: bool,
    /// How many textures the shaders can index in one runtime array of sampled images, each
    /// image its own size (descriptor indexing: `runtimeDescriptorArray`,
    /// `shaderSampledImageArrayNonUniformIndexing`, `descriptorBindingPartiallyBound`,
    /// `descriptorBindingSampledImageUpdateAfterBind`); 0 where the device lacks it (or
    /// [`DeviceOptions::texture_array_only`] said not to use it), and textures are layers of
    /// one array image instead.
    pub bindless_textures: u32,
    /// `geometryShader`: the hidden-line mode draws the silhouettes of hidden curved surfaces
    /// (`shaders/silhouette_lines.geom`).
    pub geometry_shader: bool,
    /// `VK_EXT_mesh_shader` with its task and mesh stages: pipelines made with
    /// [`super::Pipeline::mesh`] and drawn with [`super::draw_mesh_tasks_indirect_count`].
    pub mesh_shader: bool,
    /// `VK_EXT_device_generated_commands` (with `VK_KHR_maintenance5`): the GPU writes
    /// command sequences that a command buffer executes ([`super::dgc`]).
    pub device_generated_commands: bool,
    /// `VK_KHR_external_memory_fd`: frames can be shared with another API (OpenGL) through
    /// memory exported as a file descriptor ([`super::FrameExport`]).
    pub external_memory_fd: bool,
    /// `VK_KHR_external_semaphore_fd`: the copies of shared frames synchronise with the other
    /// API through semaphores exported as file descriptors ([`super::FrameExport::share_semaphores`]).
    pub external_semaphore_fd: bool,
}

/// How to create a [`Device`].
#[derive(Clone, Debug, Default)]
pub struct DeviceOptions {
    /// Instance options (validation layers, extra extensions).
    pub instance: InstanceOptions,
    /// Which physical device to use.
    pub choice: DeviceChoice,
    /// Extra device extensions (for example `VK_KHR_swapchain` for a host's window).
    pub extra_extensions: Vec<CString>,
    /// Keeps textures as layers of one array image even where the device could bind each
    /// texture at its own size (for comparing the two paths; off by default).
    pub texture_array_only: bool,
}

/// The raw handles of a device, for code that loads Vulkan itself (the technique plugins).
#[derive(Clone, Copy, Debug)]
pub struct RawHandles {
    /// The instance.
    pub instance: vk::Instance,
    /// The physical device.
    pub physical_device: vk::PhysicalDevice,
    /// The logical device.
    pub device: vk::Device,
    /// The loader's `vkGetInstanceProcAddr` (with the `fault-injection` feature, one that
    /// exempts what lavapipe cannot survive a host-memory fault in, as cadr's own calls are).
    pub get_instance_proc_addr: vk::PFN_vkGetInstanceProcAddr,
}

/// The commands of the extensions that share memory and semaphores with another API through
/// file descriptors, each where the device has it enabled.
pub(super) struct ExternalFdCommands {
    /// `VK_KHR_external_memory_fd`.
    pub(super) memory: Option<ash::khr::external_memory_fd::Device>,
    /// `VK_KHR_external_semaphore_fd`.
    pub(super) semaphore: Option<ash::khr::external_semaphore_fd::Device>,
}

/// The Vulkan device everything else is created on. Child objects hold an `Arc<Device>`.
pub struct Device {
    pub(crate) instance: Arc<Instance>,
    adapter: Adapter,
    pub(crate) raw: ash::Device,
    /// The render queue. Vulkan wants submissions, presents and device-wide waits on it
    /// externally synchronised: every use goes through [`Device::with_queue`], so renderers
    /// on several threads sharing this device take turns.
    queue: Mutex<vk::Queue>,
    allocator: Mutex<Option<Allocator>>,
    /// Set once the device reports (or a test injects) `VK_ERROR_DEVICE_LOST`: every later
    /// submission, wait and allocation is refused with [`VkError::DeviceLost`].
    lost: std::sync::atomic::AtomicBool,
    /// Bytes of device memory allocated now and at most (see [`Device::memory_in_use`]).
    memory_bytes: MemoryCounters,
    /// Set by [`Device::set_staged_uploads`]: uploads go through staging buffers even into
    /// host-visible memory.
    staged_uploads: std::sync::atomic::AtomicBool,
    debug_utils: Option<ash::ext::debug_utils::Device>,
    /// The commands of `VK_EXT_mesh_shader`, where [`Capabilities::mesh_shader`] is set.
    pub(super) mesh_shader: Option<ash::ext::mesh_shader::Device>,
    /// The commands of `VK_KHR_external_memory_fd` and `VK_KHR_external_semaphore_fd`, where
    /// the capabilities have them.
    pub(super) external_fd: ExternalFdCommands,
    capabilities: Capabilities,
    facts: DeviceFacts,
    /// Every pipeline is created through it; kept on disk between runs.
    pipeline_cache: PersistentPipelineCache,
    /// Whether cadr made the device (and destroys it) or a host lent it.
    owner: Owner,
}

/// Bytes of device memory cadr holds, counted as it allocates and frees.
#[derive(Default)]
struct MemoryCounters {
    /// Through the allocator, now.
    now: std::sync::atomic::AtomicU64,
    /// Through the allocator, at most so far.
    peak: std::sync::atomic::AtomicU64,
    /// In dedicated allocations outside the allocator (exported frames), now.
    dedicated: std::sync::atomic::AtomicU64,
}

/// What a device is, read once when it is made.
struct DeviceFacts {
    limits: vk::PhysicalDeviceLimits,
    /// How a multisampled depth is resolved into the one-sample depth that GPU cullers read
    /// between phases: the farthest sample where the device offers it (conservative for
    /// occlusion), else sample 0 (every Vulkan 1.2 device offers it).
    depth_resolve_mode: vk::ResolveModeFlags,
    /// Valid bits of the render queue's timestamps.
    queue_timestamp_bits: u32,
}

/// Who made a [`Device`].
enum Owner {
    /// cadr: it waits for the whole device and destroys it.
    Cadr,
    /// A host ([`Device::from_host`]): cadr waits only for its queue, takes the host's lock on
    /// it where there is one, and leaves the device (and instance) to the host.
    Host(Option<QueueLock>),
}

impl Device {
    /// Creates an instance and a device according to `options`.
    pub fn new(options: &DeviceOptions) -> VkResult<Arc<Self>> {
        crate::timings::time(crate::timings::Phase::Device, || {
            let instance = Arc::new(Instance::new(&options.instance)?);
            Self::on_instance(instance, options)
        })
    }

    /// Creates a device on an existing instance.
    pub fn with_instance(instance: Arc<Instance>, choice: &DeviceChoice) -> VkResult<Arc<Self>> {
        let options = DeviceOptions {
            choice: choice.clone(),
            ..DeviceOptions::default()
        };
        Self::on_instance(instance, &options)
    }

    /// Creates a device on an existing instance as `options` say (their instance options are
    /// not used); a missing extra extension is refused by name.
    fn on_instance(instance: Arc<Instance>, options: &DeviceOptions) -> VkResult<Arc<Self>> {
        let extra_extensions = &options.extra_extensions;
        let adapter = adapter::choose(&instance, &options.choice)?;
        let physical = adapter.physical;
        // SAFETY: physical comes from this instance.
        let properties = unsafe { instance.raw.get_physical_device_properties(physical) };

        let mut supported13 = vk::PhysicalDeviceVulkan13Features::default();
        let mut supported12 = vk::PhysicalDeviceVulkan12Features::default();
        let mut supported11 = vk::PhysicalDeviceVulkan11Features::default();
        let mut supported = vk::PhysicalDeviceFeatures2::default()
            .push_next(&mut supported13)
            .push_next(&mut supported12)
            .push_next(&mut supported11);
        // SAFETY: physical comes from this instance; the chain lives on this stack frame.
        unsafe {
            instance
                .raw
                .get_physical_device_features2(physical, &mut supported)
        };
        let core = supported.features;
        let depth_resolve_mode = depth_resolve_mode(&instance, physical);
        check_required_features(&adapter.name, &supported13, &core)?;
        // SAFETY: physical comes from this instance.
        let families = unsafe {
            instance
                .raw
                .get_physical_device_queue_family_properties(physical)
        };
        let queue_timestamp_bits = families[adapter.queue_family as usize].timestamp_valid_bits;
        // SAFETY: physical comes from this instance.
        let extensions = unsafe { instance.raw.enumerate_device_extension_properties(physical) }
            .or_vk("vkEnumerateDeviceExtensionProperties")?;
        check_extra_extensions(&adapter.name, &extensions, extra_extensions)?;
        let has_multi_draw = extensions
            .iter()
            .any(|e| e.extension_name_as_c_str() == Ok(ash::ext::multi_draw::NAME));
        let capabilities = Capabilities {
            multi_draw_indirect: core.multi_draw_indirect == vk::TRUE,
            draw_indirect_first_instance: core.draw_indirect_first_instance == vk::TRUE,
            shader_draw_parameters: supported11.shader_draw_parameters == vk::TRUE,
            buffer_device_address: supported12.buffer_device_address == vk::TRUE,
            draw_indirect_count: adapter.draw_indirect_count,
            multi_draw: has_multi_draw,
            pipeline_statistics_query: core.pipeline_statistics_query == vk::TRUE,
            timestamps: queue_timestamp_bits > 0 && properties.limits.timestamp_period > 0.0,
            fragment_stores_and_atomics: core.fragment_stores_and_atomics == vk::TRUE,
            bindless_textures: if options.texture_array_only {
                0
            } else {
                adapter.bindless_textures
            },
            geometry_shader: core.geometry_shader == vk::TRUE,
            mesh_shader: adapter.mesh_shader,
            device_generated_commands: adapter.device_generated_commands,
            external_memory_fd: adapter.external_memory_fd,
            external_semaphore_fd: adapter.external_semaphore_fd,
        };

        let raw = create_logical_device(
            &instance,
            (physical, adapter.queue_family),
            &capabilities,
            (&supported13, &supported12),
            extra_extensions,
        )?;
        let facts = DeviceFacts {
            limits: properties.limits,
            depth_resolve_mode,
            queue_timestamp_bits,
        };
        let queue = (adapter.queue_family, 0);
        Self::assemble(
            (instance, adapter),
            raw,
            queue,
            (capabilities, facts),
            Owner::Cadr,
        )
    }

    /// A device on a host's Vulkan objects, which cadr uses without destroying them: the
    /// host's instance, physical device, device and queue, with what the host enabled. Refused
    /// with the reason where the physical device lacks Vulkan 1.3, the queue family graphics
    /// and compute, or the host did not enable a feature cadr needs
    /// ([`super::host_vulkan::REQUIREMENTS`]).
    pub fn from_host(host: HostVulkan) -> VkResult<Arc<Self>> {
        let instance = Arc::new(Instance::from_host(&host)?);
        let physical = host.physical_device;
        let mut adapter = adapter::enumerate(&instance)?
            .into_iter()
            .find(|adapter| adapter.physical == physical)
            .ok_or_else(|| VkError::Unsupported {
                device: "the host's physical device".into(),
                reason: "it lacks Vulkan 1.3 or a queue family with graphics and compute".into(),
            })?;
        let unsupported = |reason: String| VkError::Unsupported {
            device: adapter.name.clone(),
            reason,
        };
        let (family, index) = host.queue;
        // SAFETY: physical comes from this instance.
        let families = unsafe {
            instance
                .raw
                .get_physical_device_queue_family_properties(physical)
        };
        let wanted = vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE;
        if !families
            .get(family as usize)
            .is_some_and(|f| f.queue_flags.contains(wanted))
        {
            return Err(unsupported(format!(
                "queue family {family} lacks graphics and compute"
            )));
        }
        if !host
            .enabled
            .queues
            .iter()
            .any(|&(f, count)| f == family && index < count)
        {
            return Err(unsupported(format!(
                "the host's device has no queue {index} of family {family}"
            )));
        }
        if let Some(missing) = host.enabled.missing_required() {
            return Err(unsupported(format!(
                "the host did not enable {}, which cadr needs (see cadr_vulkan_requirements)",
                missing.to_string_lossy()
            )));
        }
        adapter.queue_family = family;
        // SAFETY: physical comes from this instance.
        let properties = unsafe { instance.raw.get_physical_device_properties(physical) };
        let capabilities = host_capabilities(
            &host.enabled,
            &adapter,
            &families[family as usize],
            &properties,
        );
        let facts = DeviceFacts {
            limits: properties.limits,
            depth_resolve_mode: depth_resolve_mode(&instance, physical),
            queue_timestamp_bits: families[family as usize].timestamp_valid_bits,
        };
        // SAFETY: the host's live device, made on this instance's physical device.
        let raw = unsafe { ash::Device::load(instance.raw.fp_v1_0(), host.device) };
        let owner = Owner::Host(host.queue_lock);
        Self::assemble(
            (instance, adapter),
            raw,
            host.queue,
            (capabilities, facts),
            owner,
        )
    }

    /// The device around `raw`: its queue, allocator, debug names, mesh-shader commands and
    /// pipeline cache.
    fn assemble(
        (instance, adapter): (Arc<Instance>, Adapter),
        raw: ash::Device,
        (family, index): (u32, u32),
        (capabilities, facts): (Capabilities, DeviceFacts),
        owner: Owner,
    ) -> VkResult<Arc<Self>> {
        // SAFETY: the device was created with this queue.
        let queue = unsafe { raw.get_device_queue(family, index) };
        let physical = adapter.physical;
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.raw.clone(),
            device: raw.clone(),
            physical_device: physical,
            debug_settings: {
                let mut settings = gpu_allocator::AllocatorDebugSettings::default();
                settings.log_leaks_on_shutdown = true;
                settings
            },
            buffer_device_address: capabilities.buffer_device_address,
            allocation_sizes: gpu_allocator::AllocationSizes::default(),
        })
        .map_err(|source| super::error::allocation_error("the allocator itself", source))?;
        let debug_utils = instance
            .debug_utils
            .as_ref()
            .map(|_| ash::ext::debug_utils::Device::new(&instance.raw, &raw));
        let mesh_shader = capabilities
            .mesh_shader
            .then(|| ash::ext::mesh_shader::Device::new(&instance.raw, &raw));
        let external_fd = ExternalFdCommands {
            memory: capabilities
                .external_memory_fd
                .then(|| ash::khr::external_memory_fd::Device::new(&instance.raw, &raw)),
            semaphore: capabilities
                .external_semaphore_fd
                .then(|| ash::khr::external_semaphore_fd::Device::new(&instance.raw, &raw)),
        };

        // SAFETY: physical comes from this instance.
        let properties = unsafe { instance.raw.get_physical_device_properties(physical) };
        let pipeline_cache = PersistentPipelineCache::load(&raw, &properties);
        let device = Arc::new(Self {
            instance,
            adapter,
            raw,
            queue: Mutex::new(queue),
            allocator: Mutex::new(Some(allocator)),
            memory_bytes: Default::default(),
            staged_uploads: Default::default(),
            lost: Default::default(),
            debug_utils,
            mesh_shader,
            external_fd,
            capabilities,
            facts,
            pipeline_cache,
            owner,
        });
        device.set_name(queue, "cadr render queue");
        Ok(device)
    }

    /// The pipeline cache every pipeline is created with (null when none could be made).
    pub fn pipeline_cache(&self) -> vk::PipelineCache {
        self.pipeline_cache.handle
    }

    /// The instance the device was created on.
    pub fn instance(&self) -> &Arc<Instance> {
        &self.instance
    }

    /// The chosen physical device.
    pub fn adapter(&self) -> &Adapter {
        &self.adapter
    }

    /// Optional features that are enabled.
    pub fn capabilities(&self) -> Capabilities {
        self.capabilities
    }

    /// The sample counts a colour pass can have here (1 always; the MSAA levels 2, 4, 8, …
    /// the device offers for colour and depth attachments alike), smallest first.
    pub fn sample_counts(&self) -> Vec<u32> {
        self.adapter.sample_counts.clone()
    }

    /// How a multisampled depth attachment is resolved (see the field).
    pub fn depth_resolve_mode(&self) -> vk::ResolveModeFlags {
        self.facts.depth_resolve_mode
    }

    /// The device limits.
    pub fn limits(&self) -> &vk::PhysicalDeviceLimits {
        &self.facts.limits
    }

    /// Nanoseconds per timestamp tick, and the number of valid timestamp bits.
    pub fn timestamp_info(&self) -> (f64, u32) {
        (
            f64::from(self.facts.limits.timestamp_period),
            self.facts.queue_timestamp_bits,
        )
    }

    /// Validation messages recorded so far.
    pub fn validation_log(&self) -> &Arc<ValidationLog> {
        self.instance.validation_log()
    }

    /// The ash device, for code that needs raw Vulkan.
    pub fn raw(&self) -> &ash::Device {
        &self.raw
    }

    /// The queue family index of the render queue.
    pub fn queue_family(&self) -> u32 {
        self.adapter.queue_family
    }

    /// The device memory cadr holds now: through its allocator (plugins' buffers included:
    /// they allocate through the host) and in dedicated allocations (exported frames).
    pub fn memory_usage(&self) -> DeviceMemoryUsage {
        let dedicated = self
            .memory_bytes
            .dedicated
            .load(std::sync::atomic::Ordering::Relaxed);
        let (allocated_bytes, reserved_bytes) = match self.allocator().as_ref() {
            Some(allocator) => {
                let report = allocator.generate_report();
                (report.total_allocated_bytes, report.total_capacity_bytes)
            }
            None => (0, 0),
        };
        DeviceMemoryUsage {
            allocated_bytes: allocated_bytes + dedicated,
            reserved_bytes: reserved_bytes + dedicated,
        }
    }

    /// Counts `bytes` of a dedicated allocation made (`made`) or freed outside the allocator.
    pub(crate) fn count_dedicated(&self, bytes: u64, made: bool) {
        use std::sync::atomic::Ordering::Relaxed;
        if made {
            self.memory_bytes.dedicated.fetch_add(bytes, Relaxed);
        } else {
            self.memory_bytes.dedicated.fetch_sub(bytes, Relaxed);
        }
    }

    /// Locks the memory allocator.
    pub(crate) fn allocator(&self) -> MutexGuard<'_, Option<Allocator>> {
        self.allocator
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Allocates memory for `requirements` in `location`; `name` labels it in leak reports.
    pub(crate) fn allocate(
        &self,
        name: &str,
        requirements: vk::MemoryRequirements,
        location: MemoryLocation,
        linear: bool,
    ) -> VkResult<Allocation> {
        if self.is_lost() {
            return Err(VkError::DeviceLost("vkAllocateMemory"));
        }
        if super::fault::fails(super::fault::FaultKind::DeviceMemory) {
            return Err(super::error::map_result(
                "vkAllocateMemory (injected)",
                vk::Result::ERROR_OUT_OF_DEVICE_MEMORY,
            ));
        }
        let allocation = self
            .allocator()
            .as_mut()
            .ok_or(VkError::DeviceLost("memory allocation after shutdown"))?
            .allocate(&AllocationCreateDesc {
                name,
                requirements,
                location,
                linear,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|source| super::error::allocation_error(name, source))?;
        use std::sync::atomic::Ordering::Relaxed;
        let counters = &self.memory_bytes;
        let in_use = counters.now.fetch_add(allocation.size(), Relaxed) + allocation.size();
        counters.peak.fetch_max(in_use, Relaxed);
        Ok(allocation)
    }

    /// Returns memory to the allocator.
    pub(crate) fn free(&self, allocation: Allocation) {
        let size = allocation.size();
        if let Some(allocator) = self.allocator().as_mut() {
            if allocator.free(allocation).is_ok() {
                self.memory_bytes
                    .now
                    .fetch_sub(size, std::sync::atomic::Ordering::Relaxed);
            }
        }
    }

    /// Bytes of device memory the device's buffers and images hold now, and the most they
    /// held at once (a technique plugin's allocations included when made through the host).
    pub fn memory_in_use(&self) -> (u64, u64) {
        use std::sync::atomic::Ordering::Relaxed;
        (
            self.memory_bytes.now.load(Relaxed),
            self.memory_bytes.peak.load(Relaxed),
        )
    }

    /// Gives `handle` a debug name (shown by validation messages and capture tools).
    pub fn set_name<H: vk::Handle>(&self, handle: H, name: &str) {
        let Some(debug_utils) = &self.debug_utils else {
            return;
        };
        let Ok(name) = CString::new(name.replace('\0', " ")) else {
            return;
        };
        let info = vk::DebugUtilsObjectNameInfoEXT::default()
            .object_handle(handle)
            .object_name(&name);
        // SAFETY: handle is a live object of this device; info lives until the call returns.
        // A failure only loses a debug name, so it is ignored.
        let _ = unsafe { debug_utils.set_debug_utils_object_name(&info) };
    }

    /// The raw handles plugins load Vulkan from.
    pub fn raw_handles(&self) -> RawHandles {
        RawHandles {
            instance: self.instance.raw().handle(),
            physical_device: self.adapter.physical,
            device: self.raw.handle(),
            get_instance_proc_addr: super::fault::plugin_loader(
                (self.instance.raw().handle(), self.raw.handle()),
                super::fault::RealFunctions {
                    get_instance_proc_addr: self
                        .instance
                        .entry()
                        .static_fn()
                        .get_instance_proc_addr,
                    get_device_proc_addr: self.instance.raw().fp_v1_0().get_device_proc_addr,
                    create_pipeline_layout: self.raw.fp_v1_0().create_pipeline_layout,
                },
            ),
        }
    }

    /// Runs `use_queue` with the render queue reserved for it: no other thread submits,
    /// presents or waits for the device meanwhile.
    pub(crate) fn with_queue<R>(&self, use_queue: impl FnOnce(vk::Queue) -> R) -> R {
        let queue = self.queue.lock().unwrap_or_else(PoisonError::into_inner);
        match &self.owner {
            Owner::Host(Some(lock)) => {
                lock(true);
                let result = use_queue(*queue);
                lock(false);
                result
            }
            _ => use_queue(*queue),
        }
    }

    /// Submits `submits` to the render queue, signalling `fence` when they are done.
    pub(crate) fn submit(&self, submits: &[vk::SubmitInfo<'_>], fence: vk::Fence) -> VkResult<()> {
        use super::fault::{fails, without_host_memory_faults, FaultKind};
        if self.is_lost() {
            return Err(VkError::DeviceLost("vkQueueSubmit"));
        }
        if fails(FaultKind::Submit) {
            return Err(super::error::map_result(
                "vkQueueSubmit (injected)",
                vk::Result::ERROR_OUT_OF_DEVICE_MEMORY,
            ));
        }
        if fails(FaultKind::DeviceLost) {
            self.mark_lost();
            return Err(VkError::DeviceLost("vkQueueSubmit (injected)"));
        }
        let submitted = self.with_queue(|queue| {
            // SAFETY: the queue is reserved for this call; the caller passes executable
            // command buffers, semaphores and an unsignalled fence of this device.
            let submitted = unsafe { self.raw.queue_submit(queue, submits, fence) };
            if submitted.is_err() && submitted != Err(vk::Result::ERROR_DEVICE_LOST) {
                // A failed submission may have reached the queue in part (Mesa 22.3's lavapipe
                // queues the work before a later allocation fails): drain the queue, so that
                // nothing the caller frees after the error is still in use.
                // SAFETY: the queue is reserved for this call.
                let _ = without_host_memory_faults(|| unsafe { self.raw.queue_wait_idle(queue) });
            }
            submitted
        });
        if submitted == Err(vk::Result::ERROR_DEVICE_LOST) {
            self.mark_lost();
        }
        submitted.or_vk("vkQueueSubmit")
    }

    /// Makes uploads go through staging buffers and a GPU copy even into buffers whose memory
    /// the host can write (see [`super::Buffer::upload_with`]), as on a discrete GPU: for tests
    /// and measurements of that path on devices that would write directly. Any thread may
    /// call it; uploads started afterwards follow it.
    pub fn set_staged_uploads(&self, staged: bool) {
        self.staged_uploads
            .store(staged, std::sync::atomic::Ordering::Relaxed);
    }

    /// Whether uploads are made to go through staging buffers (see
    /// [`Device::set_staged_uploads`]).
    pub fn staged_uploads(&self) -> bool {
        self.staged_uploads
            .load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Whether the device was lost: nothing can be submitted to it any more; its objects can
    /// only be destroyed, and a new device created.
    pub fn is_lost(&self) -> bool {
        self.lost.load(std::sync::atomic::Ordering::Relaxed)
    }

    fn mark_lost(&self) {
        self.lost.store(true, std::sync::atomic::Ordering::Relaxed);
    }

    /// Waits until the device is idle (the queue reserved meanwhile, as Vulkan requires).
    pub fn wait_idle(&self) -> VkResult<()> {
        // Mesa 22.3's lavapipe does not free an allocation of its own when a later one fails
        // inside vkDeviceWaitIdle: no host-memory fault is injected there (a leak of the
        // driver's would hide one of cadr's).
        super::fault::without_host_memory_faults(|| {
            self.with_queue(|queue| match self.owner {
                // SAFETY: the device is alive and its only queue is reserved for the wait (a
                // lost device answers at once).
                Owner::Cadr => unsafe { self.raw.device_wait_idle() },
                // A host's device has the host's queues too, which cadr does not hold: it
                // waits for its own.
                // SAFETY: the queue is reserved for the wait.
                Owner::Host(_) => unsafe { self.raw.queue_wait_idle(queue) },
            })
        })
        .or_vk("vkDeviceWaitIdle")?;
        if self.is_lost() {
            return Err(VkError::DeviceLost("vkDeviceWaitIdle"));
        }
        Ok(())
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        // Every child object holds an Arc<Device>, so none is alive any more; waiting makes
        // sure the GPU is done before memory and the device go away.
        let _ = self.wait_idle();
        // The allocator frees its memory blocks through the device: drop it first.
        drop(self.allocator().take());
        self.pipeline_cache.save_and_destroy(&self.raw);
        if let Owner::Cadr = self.owner {
            // SAFETY: no child object remains (see above).
            unsafe { self.raw.destroy_device(host_callbacks()) };
        }
    }
}

/// Device memory held by cadr ([`Device::memory_usage`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DeviceMemoryUsage {
    /// Bytes in live allocations (buffers and images).
    pub allocated_bytes: u64,
    /// Bytes of the memory blocks the allocations are carved from: what the driver has given
    /// cadr, unused room included.
    pub reserved_bytes: u64,
}

/// How multisampled depth is resolved on `physical`: MAX (the farthest sample) where the
/// device offers it, else SAMPLE_ZERO, which every device offers.
fn depth_resolve_mode(instance: &Instance, physical: vk::PhysicalDevice) -> vk::ResolveModeFlags {
    let mut depth_resolve = vk::PhysicalDeviceDepthStencilResolveProperties::default();
    let mut properties2 = vk::PhysicalDeviceProperties2::default().push_next(&mut depth_resolve);
    // SAFETY: physical comes from this instance; the chain lives on this stack frame.
    unsafe {
        instance
            .raw
            .get_physical_device_properties2(physical, &mut properties2)
    };
    if depth_resolve
        .supported_depth_resolve_modes
        .contains(vk::ResolveModeFlags::MAX)
    {
        vk::ResolveModeFlags::MAX
    } else {
        vk::ResolveModeFlags::SAMPLE_ZERO
    }
}

/// Refuses a device that lacks what cadr cannot draw without: Vulkan 1.3's dynamic rendering
/// and synchronization2, clip distances (section planes), non-solid fill (the wireframe mode)
/// and independent blending (the transparency methods' targets).
fn check_required_features(
    device_name: &str,
    supported13: &vk::PhysicalDeviceVulkan13Features<'_>,
    core: &vk::PhysicalDeviceFeatures,
) -> VkResult<()> {
    let (dynamic_rendering, synchronization2) = (
        supported13.dynamic_rendering == vk::TRUE,
        supported13.synchronization2 == vk::TRUE,
    );
    if !dynamic_rendering || !synchronization2 {
        return Err(VkError::Unsupported {
            device: device_name.to_owned(),
            reason: "Vulkan 1.3 dynamicRendering and synchronization2 are required".into(),
        });
    }
    // Section planes clip in the vertex shader every technique shares; the wireframe
    // display mode draws triangles as lines; translucent surfaces blend into the
    // transparency method's targets, differently from the picture.
    for (supported, name) in [
        (
            core.shader_clip_distance,
            "shaderClipDistance (section planes)",
        ),
        (
            core.fill_mode_non_solid,
            "fillModeNonSolid (the wireframe display mode)",
        ),
        (
            core.independent_blend,
            "independentBlend (the transparency methods' targets)",
        ),
    ] {
        if supported != vk::TRUE {
            return Err(VkError::Unsupported {
                device: device_name.to_owned(),
                reason: format!("{name} is required"),
            });
        }
    }
    Ok(())
}

/// Refuses a device that lacks one of the host's `extra_extensions`, naming it.
fn check_extra_extensions(
    device_name: &str,
    extensions: &[vk::ExtensionProperties],
    extra_extensions: &[std::ffi::CString],
) -> VkResult<()> {
    for wanted in extra_extensions {
        let present = extensions
            .iter()
            .any(|e| e.extension_name_as_c_str() == Ok(wanted.as_c_str()));
        if !present {
            return Err(VkError::Unsupported {
                device: device_name.to_owned(),
                reason: format!(
                    "device extension {} is not supported",
                    wanted.to_string_lossy()
                ),
            });
        }
    }
    Ok(())
}

/// What cadr may use of a host's device: what the host enabled, where the device has it.
fn host_capabilities(
    enabled: &HostDevice,
    adapter: &Adapter,
    family: &vk::QueueFamilyProperties,
    properties: &vk::PhysicalDeviceProperties,
) -> Capabilities {
    let core = &enabled.core;
    let on = |value: vk::Bool32| value == vk::TRUE;
    Capabilities {
        multi_draw_indirect: on(core.multi_draw_indirect),
        draw_indirect_first_instance: on(core.draw_indirect_first_instance),
        shader_draw_parameters: enabled.shader_draw_parameters,
        buffer_device_address: enabled.buffer_device_address,
        draw_indirect_count: enabled.draw_indirect_count,
        multi_draw: enabled.multi_draw,
        pipeline_statistics_query: on(core.pipeline_statistics_query),
        timestamps: family.timestamp_valid_bits > 0 && properties.limits.timestamp_period > 0.0,
        fragment_stores_and_atomics: on(core.fragment_stores_and_atomics),
        bindless_textures: if enabled.bindless {
            adapter.bindless_textures
        } else {
            0
        },
        geometry_shader: on(core.geometry_shader),
        mesh_shader: enabled.mesh_shader && adapter.mesh_shader,
        device_generated_commands: enabled.device_generated_commands
            && enabled.buffer_device_address
            && adapter.device_generated_commands,
        external_memory_fd: enabled.has(c"VK_KHR_external_memory_fd") && adapter.external_memory_fd,
        external_semaphore_fd: enabled.has(c"VK_KHR_external_semaphore_fd")
            && adapter.external_semaphore_fd,
    }
}

/// Creates the logical device with one queue of `queue_family`, the features `capabilities`
/// say (and those cadr requires), and the extensions they need plus the host's extra ones.
fn create_logical_device(
    instance: &Instance,
    (physical, queue_family): (vk::PhysicalDevice, u32),
    capabilities: &Capabilities,
    (supported13, supported12): (
        &vk::PhysicalDeviceVulkan13Features<'_>,
        &vk::PhysicalDeviceVulkan12Features<'_>,
    ),
    extra_extensions: &[std::ffi::CString],
) -> VkResult<ash::Device> {
    let enabled_core = vk::PhysicalDeviceFeatures::default()
        .multi_draw_indirect(capabilities.multi_draw_indirect)
        .draw_indirect_first_instance(capabilities.draw_indirect_first_instance)
        .pipeline_statistics_query(capabilities.pipeline_statistics_query)
        .fragment_stores_and_atomics(capabilities.fragment_stores_and_atomics)
        .geometry_shader(capabilities.geometry_shader)
        .shader_clip_distance(true)
        .fill_mode_non_solid(true)
        .independent_blend(true);
    let mut enabled13 = vk::PhysicalDeviceVulkan13Features::default()
        .dynamic_rendering(true)
        .synchronization2(true)
        // Required by Vulkan 1.3; shaderc emits LocalSizeId for 1.3 targets, which needs it.
        .maintenance4(supported13.maintenance4 == vk::TRUE);

    let mut enabled12 = vk::PhysicalDeviceVulkan12Features::default()
        .buffer_device_address(capabilities.buffer_device_address)
        .draw_indirect_count(capabilities.draw_indirect_count)
        .host_query_reset(supported12.host_query_reset == vk::TRUE);
    if capabilities.bindless_textures > 0 {
        enabled12 = enabled12
            .runtime_descriptor_array(true)
            .shader_sampled_image_array_non_uniform_indexing(true)
            .descriptor_binding_partially_bound(true)
            .descriptor_binding_sampled_image_update_after_bind(true);
    }
    let mut enabled11 = vk::PhysicalDeviceVulkan11Features::default()
        .shader_draw_parameters(capabilities.shader_draw_parameters);
    let priorities = [1.0_f32];
    let queue_info = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(queue_family)
        .queue_priorities(&priorities)];
    let mut enabled = vk::PhysicalDeviceFeatures2::default()
        .features(enabled_core)
        .push_next(&mut enabled13)
        .push_next(&mut enabled12)
        .push_next(&mut enabled11);
    let mut multi_draw = vk::PhysicalDeviceMultiDrawFeaturesEXT::default().multi_draw(true);
    let mut mesh_shader_features = vk::PhysicalDeviceMeshShaderFeaturesEXT::default()
        .task_shader(true)
        .mesh_shader(true);
    let mut generated_commands_features =
        cadr_vk_ext::device_generated_commands::PhysicalDeviceFeatures {
            device_generated_commands: vk::TRUE,
            ..Default::default()
        };
    let mut maintenance5_features =
        vk::PhysicalDeviceMaintenance5FeaturesKHR::default().maintenance5(true);
    let mut enabled_extensions: Vec<&std::ffi::CStr> = Vec::new();
    if capabilities.device_generated_commands {
        enabled_extensions.push(cadr_vk_ext::device_generated_commands::NAME);
        enabled_extensions.push(ash::khr::maintenance5::NAME);
    }
    if capabilities.multi_draw {
        enabled_extensions.push(ash::ext::multi_draw::NAME);
    }
    if capabilities.mesh_shader {
        enabled_extensions.push(ash::ext::mesh_shader::NAME);
    }
    if capabilities.external_memory_fd {
        enabled_extensions.push(ash::khr::external_memory_fd::NAME);
    }
    if capabilities.external_semaphore_fd {
        enabled_extensions.push(ash::khr::external_semaphore_fd::NAME);
    }
    for wanted in extra_extensions {
        if !enabled_extensions.contains(&wanted.as_c_str()) {
            enabled_extensions.push(wanted);
        }
    }
    let extension_names: Vec<*const std::ffi::c_char> = enabled_extensions
        .iter()
        .map(|name| name.as_ptr())
        .collect();
    let mut create_info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queue_info)
        .enabled_extension_names(&extension_names)
        .push_next(&mut enabled);
    if capabilities.multi_draw {
        create_info = create_info.push_next(&mut multi_draw);
    }
    if capabilities.mesh_shader {
        create_info = create_info.push_next(&mut mesh_shader_features);
    }
    if capabilities.device_generated_commands {
        create_info = create_info
            .push_next(&mut generated_commands_features)
            .push_next(&mut maintenance5_features);
    }
    // SAFETY: create_info and its chain live until the call returns; only supported
    // features are enabled.
    unsafe {
        instance
            .raw
            .create_device(physical, &create_info, host_callbacks())
    }
    .or_vk("vkCreateDevice")
}
