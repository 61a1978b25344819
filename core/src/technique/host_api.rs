//! What the host offers plugin instances: buffers it allocates and frees for them, shader
//! modules compiled from their GLSL, and counting `VkAllocationCallbacks` for the objects they create, so that a test can prove that
//! swapping techniques leaks nothing.

use std::collections::HashMap;
use std::ffi::{c_char, c_void, CStr};
use std::sync::atomic::{AtomicI64, Ordering};
use std::sync::{Arc, Mutex};

use crate::vk::raw as vk;
use crate::vk::raw::Handle;
use cadr_plugin_abi as abi;

use crate::shaders::compile_glsl;
use crate::vk::host_memory::counting_callbacks;
use crate::vk::{create_unowned_shader_module, Buffer, Device, MemoryLocation, ShaderStage};

/// Live counts of what plugins hold.
#[derive(Debug, Default)]
pub struct PluginAllocations {
    /// Live host allocations made through the allocation callbacks (Vulkan objects' memory).
    pub object_allocations: AtomicI64,
    /// Live buffers created through the host API.
    pub buffers: AtomicI64,
    /// Bytes of those buffers.
    pub buffer_bytes: AtomicI64,
}

/// What plugins hold at one moment: a snapshot of the host's counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AllocationCounts {
    /// Live allocations of plugin-created Vulkan objects.
    pub object_allocations: i64,
    /// Live plugin buffers.
    pub buffers: i64,
    /// Their bytes.
    pub buffer_bytes: i64,
}

/// The host side of [`abi::CadrHostApi`]; boxed so that its address stays put.
pub(crate) struct HostServices {
    device: Arc<Device>,
    buffers: Mutex<HashMap<u64, Buffer>>,
    next_id: std::sync::atomic::AtomicU64,
    pub(crate) counts: Arc<PluginAllocations>,
    api: abi::CadrHostApi,
    callbacks: vk::AllocationCallbacks<'static>,
}

// SAFETY: the raw pointers in `api` and `callbacks` point at this struct itself; every field
// behind them is synchronised (mutex, atomics).
unsafe impl Send for HostServices {}
// SAFETY: as above.
unsafe impl Sync for HostServices {}

unsafe extern "C" fn create_buffer(
    user: *mut c_void,
    size_bytes: u64,
    usage: u32,
    location: abi::CadrMemoryLocation,
    name: *const c_char,
    out: *mut abi::CadrBuffer,
    message: *mut abi::CadrMessage,
) -> abi::CadrStatus {
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        // SAFETY: `user` is the HostServices this API belongs to.
        let services = unsafe { &*user.cast::<HostServices>() };
        let name = if name.is_null() {
            "plugin buffer".to_owned()
        } else {
            // SAFETY: the plugin passes a NUL-terminated string.
            unsafe { CStr::from_ptr(name) }
                .to_string_lossy()
                .into_owned()
        };
        services.create_buffer(size_bytes, usage, location, &name)
    }));
    match result {
        Ok(Ok(buffer)) if !out.is_null() => {
            // SAFETY: checked non-null; the plugin passes a writable struct.
            unsafe { *out = buffer };
            abi::CADR_STATUS_OK
        }
        Ok(Ok(_)) => abi::CADR_STATUS_ERROR,
        Ok(Err(text)) => {
            // SAFETY: the plugin passes a valid message buffer or null.
            unsafe { abi::CadrMessage::write(message, &text) };
            abi::CADR_STATUS_ERROR
        }
        Err(_) => abi::CADR_STATUS_PANICKED,
    }
}

unsafe extern "C" fn destroy_buffer(user: *mut c_void, buffer: *const abi::CadrBuffer) {
    let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        // SAFETY: `user` is the HostServices this API belongs to; `buffer` is the plugin's.
        let (services, buffer) = unsafe { (&*user.cast::<HostServices>(), buffer.as_ref()) };
        if let Some(buffer) = buffer {
            services.destroy_buffer(buffer.id);
        }
    }));
}

unsafe extern "C" fn create_shader_module(
    user: *mut c_void,
    stage: u32,
    source: *const c_char,
    name: *const c_char,
    module: *mut u64,
    message: *mut abi::CadrMessage,
) -> abi::CadrStatus {
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        // SAFETY: `user` is the HostServices this API belongs to.
        let services = unsafe { &*user.cast::<HostServices>() };
        // SAFETY: the plugin passes NUL-terminated strings (or null).
        let text = |pointer: *const c_char| {
            unsafe { pointer.as_ref() }.map(|_| {
                // SAFETY: as above, checked non-null.
                unsafe { CStr::from_ptr(pointer) }
                    .to_string_lossy()
                    .into_owned()
            })
        };
        let name = text(name).unwrap_or_else(|| "plugin shader".into());
        let source = text(source).ok_or_else(|| format!("shader '{name}' has no source"))?;
        services.create_shader_module(stage, &source, &name)
    }));
    match result {
        Ok(Ok(raw)) if !module.is_null() => {
            // SAFETY: checked non-null; the plugin passes a writable handle.
            unsafe { *module = raw };
            abi::CADR_STATUS_OK
        }
        Ok(Ok(_)) => abi::CADR_STATUS_ERROR,
        Ok(Err(text)) => {
            // SAFETY: the plugin passes a valid message buffer or null.
            unsafe { abi::CadrMessage::write(message, &text) };
            abi::CADR_STATUS_ERROR
        }
        Err(_) => abi::CADR_STATUS_PANICKED,
    }
}

impl HostServices {
    pub(crate) fn new(device: &Arc<Device>) -> Box<Self> {
        let counts = Arc::new(PluginAllocations::default());
        let mut services = Box::new(Self {
            device: Arc::clone(device),
            buffers: Mutex::new(HashMap::new()),
            next_id: std::sync::atomic::AtomicU64::new(1),
            counts,
            api: abi::CadrHostApi {
                size: std::mem::size_of::<abi::CadrHostApi>() as u32,
                user: std::ptr::null_mut(),
                create_buffer: Some(create_buffer),
                destroy_buffer: Some(destroy_buffer),
                create_shader_module: Some(create_shader_module),
            },
            callbacks: vk::AllocationCallbacks::default(),
        });
        let user: *mut HostServices = &mut *services;
        services.api.user = user.cast();
        services.callbacks = counting_callbacks(&services.counts.object_allocations);
        services
    }

    pub(crate) fn api(&self) -> *const abi::CadrHostApi {
        &self.api
    }

    pub(crate) fn callbacks(&self) -> *const vk::AllocationCallbacks<'static> {
        &self.callbacks
    }

    fn create_buffer(
        &self,
        size_bytes: u64,
        usage: u32,
        location: abi::CadrMemoryLocation,
        name: &str,
    ) -> Result<abi::CadrBuffer, String> {
        let mut usage = vk::BufferUsageFlags::from_raw(usage);
        if !self.device.capabilities().buffer_device_address {
            usage &= !vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS;
        }
        let memory = match location {
            abi::CADR_MEMORY_GPU_ONLY => MemoryLocation::GpuOnly,
            abi::CADR_MEMORY_CPU_TO_GPU => MemoryLocation::CpuToGpu,
            other => return Err(format!("unknown memory location {other}")),
        };
        let buffer = Buffer::new(&self.device, name, size_bytes, usage, memory)
            .map_err(|e| format!("cannot create buffer '{name}' of {size_bytes} bytes: {e}"))?;
        let address = if usage.contains(vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS) {
            buffer.device_address()
        } else {
            0
        };
        let id = self.next_id.fetch_add(1, Ordering::Relaxed);
        let described = abi::CadrBuffer {
            buffer: buffer.raw().as_raw(),
            size_bytes,
            address,
            mapped: buffer.mapped_ptr(),
            id,
        };
        self.counts.buffers.fetch_add(1, Ordering::Relaxed);
        self.counts
            .buffer_bytes
            .fetch_add(size_bytes as i64, Ordering::Relaxed);
        self.buffers
            .lock()
            .map_err(|_| "the host's buffer table is poisoned")?
            .insert(id, buffer);
        Ok(described)
    }

    /// Compiles `source` for `stage` and creates a module the plugin owns (made with the
    /// counting callbacks, which the plugin destroys it with).
    fn create_shader_module(&self, stage: u32, source: &str, name: &str) -> Result<u64, String> {
        let stage = match vk::ShaderStageFlags::from_raw(stage) {
            vk::ShaderStageFlags::VERTEX => ShaderStage::Vertex,
            vk::ShaderStageFlags::FRAGMENT => ShaderStage::Fragment,
            vk::ShaderStageFlags::COMPUTE => ShaderStage::Compute,
            other => return Err(format!("shader '{name}': unsupported stage {other:?}")),
        };
        let words = compile_glsl(name, source, stage, &[]).map_err(|e| e.to_string())?;
        let module = create_unowned_shader_module(&self.device, name, &words, &self.callbacks)
            .map_err(|e| format!("shader '{name}': {e}"))?;
        Ok(module.as_raw())
    }

    fn destroy_buffer(&self, id: u64) {
        let removed = self.buffers.lock().ok().and_then(|mut b| b.remove(&id));
        if let Some(buffer) = removed {
            self.counts.buffers.fetch_sub(1, Ordering::Relaxed);
            self.counts
                .buffer_bytes
                .fetch_sub(buffer.size() as i64, Ordering::Relaxed);
        }
    }

    pub(crate) fn snapshot(&self) -> AllocationCounts {
        AllocationCounts {
            object_allocations: self.counts.object_allocations.load(Ordering::Relaxed),
            buffers: self.counts.buffers.load(Ordering::Relaxed),
            buffer_bytes: self.counts.buffer_bytes.load(Ordering::Relaxed),
        }
    }
}
