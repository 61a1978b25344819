//! Sharing finished frames with another graphics API on the same device (an OpenGL host)
//! without a copy through the CPU: every frame is copied on the GPU into a buffer whose memory
//! is exported as a file descriptor (`VK_KHR_external_memory_fd`), which the host imports once
//! (`GL_EXT_memory_object_fd`) and reads as a pixel buffer. Its pixels are tightly packed RGBA8
//! rows, the top row first, as `Renderer::read_rgba8` gives them, followed where asked by the
//! frame's depth (32-bit floats in rows of the same order) for a host compositing its own
//! drawing with the frame.
//!
//! Two ways to hand a frame over:
//! - **Waited for** (the default, and where the device cannot share semaphores, as lavapipe
//!   cannot): the copy is waited for on the CPU before the frame is handed over, so the host
//!   needs no semaphore.
//! - **By semaphores** ([`FrameExport::share_semaphores`], `VK_KHR_external_semaphore_fd`):
//!   the copy signals `ready`, which the host's API waits for on its GPU timeline
//!   (`glWaitSemaphoreEXT`), and the host signals `released` once it has read the frame
//!   (`glSignalSemaphoreEXT`), which the next copy waits for before it overwrites the memory.
//!   Neither side waits on the CPU.

use std::os::fd::{FromRawFd, OwnedFd};
use std::sync::Arc;
use std::time::Duration;

use ash::vk;

use super::command::CommandContext;
use super::device::Device;
use super::error::{VkError, VkResult, VkResultExt};
use super::host_memory::core_callbacks as host_callbacks;
use super::image::{record_image_copy_into, Image, COLOR_FORMAT, DEPTH_FORMAT};

/// The handle type of the exported memory: a POSIX file descriptor of the driver's own kind,
/// which another API of the same driver family imports.
const HANDLE_TYPE: vk::ExternalMemoryHandleTypeFlags = vk::ExternalMemoryHandleTypeFlags::OPAQUE_FD;

/// Bytes the buffer has beyond the picture: an importer may want a buffer's memory to reach
/// past its end (llvmpipe reads buffers in blocks and wants 48 bytes more).
const IMPORTER_SLACK: u64 = 4096;

/// The handle type of the exported semaphores: a POSIX file descriptor (reference transference:
/// the host's imported semaphore and cadr's share one payload for as long as both live).
const SEMAPHORE_HANDLE_TYPE: vk::ExternalSemaphoreHandleTypeFlags =
    vk::ExternalSemaphoreHandleTypeFlags::OPAQUE_FD;

/// How long a frame waits on the CPU, before it is drawn, for the last copy, which waits for the
/// host's `released` signal: past it, the host is taken not to have released the frame (its
/// error, reported, not a hang).
const RELEASE_TIMEOUT: Duration = Duration::from_secs(10);

/// Where the depth starts after the colour: a multiple of this (a texel of every format, and
/// what pixel-buffer offsets of any API accept).
const DEPTH_ALIGNMENT: u64 = 256;

/// A buffer in memory of its own that can be exported, with the frame copied into it.
pub struct FrameExport {
    device: Arc<Device>,
    buffer: vk::Buffer,
    memory: vk::DeviceMemory,
    /// The memory's size (what an importer is told; at least the picture's bytes).
    allocation_size: u64,
    extent: vk::Extent2D,
    /// Where the depth starts, when the buffer holds it after the colour.
    depth_offset: Option<u64>,
    commands: CommandContext,
    /// The device's and the driver's UUIDs (`VkPhysicalDeviceIDProperties`): an importer
    /// shares memory only with a device and driver of the same UUIDs.
    uuids: ([u8; vk::UUID_SIZE], [u8; vk::UUID_SIZE]),
    /// The semaphores the copies synchronise with the host by, once it has asked for them;
    /// without, each copy is waited for on the CPU.
    semaphores: Option<ExportSemaphores>,
}

impl FrameExport {
    /// A buffer for frames of `extent`, with room for their depth after the colour when
    /// `with_depth`; refused where the device cannot export memory as a file descriptor.
    pub fn new(device: &Arc<Device>, extent: vk::Extent2D, with_depth: bool) -> VkResult<Self> {
        let unsupported = |reason: &str| VkError::Unsupported {
            device: device.adapter().name.clone(),
            reason: reason.to_owned(),
        };
        if device.external_fd.memory.is_none() {
            return Err(unsupported(
                "exporting frames needs VK_KHR_external_memory_fd, which this device lacks (or the host did not enable)",
            ));
        }
        let usage = vk::BufferUsageFlags::TRANSFER_DST;
        if !exportable(device, usage) {
            return Err(unsupported(
                "the driver cannot export a transfer buffer's memory as a file descriptor",
            ));
        }
        // Made first: nothing to undo when it fails.
        let commands = CommandContext::new(device, "frame export commands")?;
        let picture = u64::from(extent.width) * u64::from(extent.height) * 4;
        let depth_offset = with_depth.then(|| picture.next_multiple_of(DEPTH_ALIGNMENT));
        let size = depth_offset.map_or(picture, |offset| offset + picture) + IMPORTER_SLACK;
        let mut external = vk::ExternalMemoryBufferCreateInfo::default().handle_types(HANDLE_TYPE);
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .push_next(&mut external);
        // SAFETY: info and its chain are valid and live until the call returns.
        let buffer =
            unsafe { device.raw.create_buffer(&info, host_callbacks()) }.or_vk("vkCreateBuffer")?;
        let (memory, allocation_size) = match allocate_exportable(device, buffer) {
            Ok(allocated) => allocated,
            Err(error) => {
                // SAFETY: the buffer was just created, is unused and bound to nothing.
                unsafe { device.raw.destroy_buffer(buffer, host_callbacks()) };
                return Err(error);
            }
        };
        let export = Self {
            device: Arc::clone(device),
            buffer,
            memory,
            allocation_size,
            extent,
            depth_offset,
            commands,
            uuids: uuids(device),
            semaphores: None,
        };
        device.set_name(buffer, "exported frame");
        // SAFETY: the memory was allocated for this buffer (dedicated) and is bound to nothing.
        // On failure `export` is dropped, which frees both.
        unsafe { device.raw.bind_buffer_memory(buffer, memory, 0) }.or_vk("vkBindBufferMemory")?;
        Ok(export)
    }

    /// The size of the frames it holds.
    pub fn extent(&self) -> vk::Extent2D {
        self.extent
    }

    /// The device's UUID and the driver's, which an importer compares with its own
    /// (`GL_DEVICE_UUID_EXT`, `GL_DRIVER_UUID_EXT`) before importing.
    pub fn uuids(&self) -> ([u8; vk::UUID_SIZE], [u8; vk::UUID_SIZE]) {
        self.uuids
    }

    /// Where the depth starts in the buffer (rows of 32-bit floats, `width × 4` bytes each),
    /// when it holds the depth.
    pub fn depth_offset(&self) -> Option<u64> {
        self.depth_offset
    }

    /// The exported memory's size in bytes.
    pub fn allocation_size(&self) -> u64 {
        self.allocation_size
    }

    /// A new file descriptor of the exported memory, the caller's to import (which takes it)
    /// or close.
    pub fn file_descriptor(&self) -> VkResult<i32> {
        let Some(loader) = &self.device.external_fd.memory else {
            return Err(VkError::Unsupported {
                device: self.device.adapter().name.clone(),
                reason: "VK_KHR_external_memory_fd".into(),
            });
        };
        let info = vk::MemoryGetFdInfoKHR::default()
            .memory(self.memory)
            .handle_type(HANDLE_TYPE);
        // SAFETY: the memory was allocated exportable as this handle type.
        unsafe { loader.get_memory_fd(&info) }.or_vk("vkGetMemoryFdKHR")
    }

    /// Moves the semaphores of `earlier` (an export this one replaces, after a resize) to this
    /// one, so that the host keeps the semaphores it imported.
    pub fn take_semaphores_from(&mut self, earlier: &mut FrameExport) {
        self.semaphores = earlier.semaphores.take();
    }

    /// Hands the frames over by semaphores from the next copy on (made at the first call; the
    /// same semaphores after): new file descriptors of them, `(ready, released)`, the caller's
    /// to import or close. Refused where the device cannot export semaphores as file
    /// descriptors.
    pub fn share_semaphores(&mut self) -> VkResult<(OwnedFd, OwnedFd)> {
        let semaphores = match self.semaphores {
            Some(ref semaphores) => semaphores,
            None => self.semaphores.insert(ExportSemaphores::new(&self.device)?),
        };
        Ok((
            semaphores.file_descriptor(semaphores.ready)?,
            semaphores.file_descriptor(semaphores.released)?,
        ))
    }

    /// Waits (at most 10 s) for the last copy, which waits for the host's
    /// release of the frame before it when frames are handed over by semaphores: call it before
    /// drawing the next frame, which a driver's queue may otherwise hold behind that copy.
    /// Refused when the host has not released that frame by then.
    pub fn wait_for_release(&mut self) -> VkResult<()> {
        if self.semaphores.is_none() {
            return Ok(());
        }
        if !self.commands.wait_at_most(RELEASE_TIMEOUT)? {
            return Err(VkError::InvalidUse(format!(
                "the host has not signalled the `released` semaphore of the frame before the last one within {} s (signal it once for every frame it waits for `ready`, and flush)",
                RELEASE_TIMEOUT.as_secs()
            )));
        }
        Ok(())
    }

    /// Copies `frame` (in TRANSFER_SRC_OPTIMAL, of this export's extent and colour format) into
    /// the exported buffer, and its `depth` (the same, of the depth format) after it where the
    /// buffer has room for it. Without semaphores it waits for the copy: when it returns, the
    /// memory holds the frame. With them the copy waits for the host's release of the frame
    /// before (if one was handed over) and signals `ready`; it returns once it is submitted.
    pub fn copy(&mut self, frame: &Image, depth: Option<&Image>) -> VkResult<()> {
        debug_assert_eq!(frame.format(), COLOR_FORMAT);
        debug_assert_eq!(frame.extent(), self.extent);
        self.wait_for_release()?;
        let command_buffer = self.commands.begin()?;
        let mut images = vec![(frame, 0)];
        if let (Some(depth), Some(offset)) = (depth, self.depth_offset) {
            debug_assert_eq!(depth.format(), DEPTH_FORMAT);
            debug_assert_eq!(depth.extent(), self.extent);
            images.push((depth, offset));
        }
        for (image, offset) in images {
            // The image is in TRANSFER_SRC_OPTIMAL (made readable by the frame's own barrier,
            // earlier in submission order) and fits the buffer from `offset`; both outlive the
            // submission (the next frame's barrier orders its writes after this copy, and the
            // buffer is destroyed only after waiting for it).
            record_image_copy_into(
                &self.device,
                command_buffer,
                image,
                (0, 0, self.extent.width, self.extent.height),
                self.buffer,
                offset,
            );
        }
        // The writes made available to the host's API once the copy is waited for (or its
        // semaphore, whose signal makes them available too).
        let barrier = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::COPY)
            .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::HOST)
            .dst_access_mask(vk::AccessFlags2::HOST_READ)];
        let dependency = vk::DependencyInfo::default().memory_barriers(&barrier);
        // SAFETY: recording; the barrier is valid.
        unsafe {
            self.device
                .raw
                .cmd_pipeline_barrier2(command_buffer, &dependency)
        };
        match &mut self.semaphores {
            None => {
                self.commands.submit()?;
                self.commands.wait()
            }
            Some(semaphores) => {
                let released = [(semaphores.released, vk::PipelineStageFlags::TRANSFER)];
                let wait = &released[..usize::from(semaphores.handed_over)];
                self.commands
                    .submit_with_semaphores(wait, &[semaphores.ready])?;
                semaphores.handed_over = true;
                Ok(())
            }
        }
    }
}

impl Drop for FrameExport {
    fn drop(&mut self) {
        // The last copy may still run; after an error the buffer goes anyway. (A copy waiting
        // for a release the host never gives is waited for: the host's rule is to release
        // every frame it was handed before destroying the renderer.)
        let _ = self.commands.wait();
        // SAFETY: no submission uses the buffer any more (waited for above); an importer keeps
        // its own reference to the memory, which the driver frees when both let go.
        unsafe {
            self.device
                .raw
                .destroy_buffer(self.buffer, host_callbacks());
            self.device.raw.free_memory(self.memory, host_callbacks());
        }
        self.device.count_dedicated(self.allocation_size, false);
    }
}

/// The two binary semaphores frames are handed over by, exported as file descriptors
/// (`VK_KHR_external_semaphore_fd`): each copy signals `ready`, which the host waits for before
/// it reads the frame; the host signals `released` when it has read it, which the next copy
/// waits for before it overwrites the memory.
struct ExportSemaphores {
    device: Arc<Device>,
    /// Signalled by each copy when the memory holds its frame.
    ready: vk::Semaphore,
    /// Signalled by the host when it has read the frame it was handed.
    released: vk::Semaphore,
    /// Whether a frame was handed over (a `ready` signalled): the next copy waits for the
    /// host's `released` first.
    handed_over: bool,
}

impl ExportSemaphores {
    /// Creates both, refused where the device cannot export semaphores as file descriptors.
    fn new(device: &Arc<Device>) -> VkResult<Self> {
        let unsupported = |reason: &str| VkError::Unsupported {
            device: device.adapter().name.clone(),
            reason: reason.to_owned(),
        };
        if device.external_fd.semaphore.is_none() {
            return Err(unsupported(
                "sharing semaphores needs VK_KHR_external_semaphore_fd, which this device lacks (or the host did not enable): each frame's copy is waited for instead",
            ));
        }
        if !semaphore_exportable(device) {
            return Err(unsupported(
                "the driver cannot export a binary semaphore as a file descriptor",
            ));
        }
        let mut semaphores = Self {
            device: Arc::clone(device),
            ready: vk::Semaphore::null(),
            released: vk::Semaphore::null(),
            handed_over: false,
        };
        // Dropped on a failure below, destroying what was made (null handles are ignored).
        semaphores.ready = exportable_semaphore(device, "exported frame ready")?;
        semaphores.released = exportable_semaphore(device, "exported frame released")?;
        Ok(semaphores)
    }

    /// A new file descriptor of `semaphore` (one of this pair's).
    fn file_descriptor(&self, semaphore: vk::Semaphore) -> VkResult<OwnedFd> {
        let Some(loader) = &self.device.external_fd.semaphore else {
            return Err(VkError::Unsupported {
                device: self.device.adapter().name.clone(),
                reason: "VK_KHR_external_semaphore_fd".into(),
            });
        };
        let info = vk::SemaphoreGetFdInfoKHR::default()
            .semaphore(semaphore)
            .handle_type(SEMAPHORE_HANDLE_TYPE);
        // SAFETY: the semaphore was created exportable as this handle type.
        let fd = unsafe { loader.get_semaphore_fd(&info) }.or_vk("vkGetSemaphoreFdKHR")?;
        // SAFETY: the call made a new descriptor, owned by no one else.
        Ok(unsafe { OwnedFd::from_raw_fd(fd) })
    }
}

impl Drop for ExportSemaphores {
    fn drop(&mut self) {
        // SAFETY: the frame export that used them waited for its last copy before (it drops
        // them after its own drop); the host's imported semaphores keep their own references
        // to the payload.
        unsafe {
            self.device
                .raw
                .destroy_semaphore(self.ready, host_callbacks());
            self.device
                .raw
                .destroy_semaphore(self.released, host_callbacks());
        }
    }
}

/// A binary semaphore exportable as [`SEMAPHORE_HANDLE_TYPE`], named `name`.
fn exportable_semaphore(device: &Device, name: &str) -> VkResult<vk::Semaphore> {
    let mut export = vk::ExportSemaphoreCreateInfo::default().handle_types(SEMAPHORE_HANDLE_TYPE);
    let info = vk::SemaphoreCreateInfo::default().push_next(&mut export);
    // SAFETY: info and its chain are valid and live until the call returns.
    let semaphore = unsafe { device.raw.create_semaphore(&info, host_callbacks()) }
        .or_vk("vkCreateSemaphore")?;
    device.set_name(semaphore, name);
    Ok(semaphore)
}

/// Whether the driver can export a binary semaphore as [`SEMAPHORE_HANDLE_TYPE`].
fn semaphore_exportable(device: &Device) -> bool {
    let info =
        vk::PhysicalDeviceExternalSemaphoreInfo::default().handle_type(SEMAPHORE_HANDLE_TYPE);
    let mut properties = vk::ExternalSemaphoreProperties::default();
    // SAFETY: the physical device belongs to the device's instance; both structs are valid.
    unsafe {
        device
            .instance
            .raw
            .get_physical_device_external_semaphore_properties(
                device.adapter().physical,
                &info,
                &mut properties,
            )
    };
    properties
        .external_semaphore_features
        .contains(vk::ExternalSemaphoreFeatureFlags::EXPORTABLE)
}

/// The device's and the driver's UUIDs.
fn uuids(device: &Device) -> ([u8; vk::UUID_SIZE], [u8; vk::UUID_SIZE]) {
    let mut ids = vk::PhysicalDeviceIDProperties::default();
    let mut properties = vk::PhysicalDeviceProperties2::default().push_next(&mut ids);
    // SAFETY: the physical device belongs to the device's instance (Vulkan 1.3, where the query
    // is core); the chain lives on this stack frame.
    unsafe {
        device
            .instance
            .raw
            .get_physical_device_properties2(device.adapter().physical, &mut properties)
    };
    (ids.device_uuid, ids.driver_uuid)
}

/// Whether the driver can export the memory of a buffer of `usage` as [`HANDLE_TYPE`].
fn exportable(device: &Device, usage: vk::BufferUsageFlags) -> bool {
    let info = vk::PhysicalDeviceExternalBufferInfo::default()
        .usage(usage)
        .handle_type(HANDLE_TYPE);
    let mut properties = vk::ExternalBufferProperties::default();
    // SAFETY: the physical device belongs to the device's instance; both structs are valid.
    unsafe {
        device
            .instance
            .raw
            .get_physical_device_external_buffer_properties(
                device.adapter().physical,
                &info,
                &mut properties,
            )
    };
    properties
        .external_memory_properties
        .external_memory_features
        .contains(vk::ExternalMemoryFeatureFlags::EXPORTABLE)
}

/// Memory of its own for `buffer`, exportable as [`HANDLE_TYPE`], device-local where the
/// device has such a type; its size.
fn allocate_exportable(device: &Device, buffer: vk::Buffer) -> VkResult<(vk::DeviceMemory, u64)> {
    // SAFETY: the buffer belongs to this device.
    let requirements = unsafe { device.raw.get_buffer_memory_requirements(buffer) };
    // SAFETY: the physical device belongs to the device's instance.
    let types = unsafe {
        device
            .instance
            .raw
            .get_physical_device_memory_properties(device.adapter().physical)
    };
    let allowed = |index: usize| requirements.memory_type_bits & (1 << index) != 0;
    let candidates = types.memory_types_as_slice();
    let type_index = (0..candidates.len())
        .filter(|&i| allowed(i))
        .find(|&i| {
            candidates[i]
                .property_flags
                .contains(vk::MemoryPropertyFlags::DEVICE_LOCAL)
        })
        .or_else(|| (0..candidates.len()).find(|&i| allowed(i)))
        .ok_or_else(|| VkError::Unsupported {
            device: device.adapter().name.clone(),
            reason: "no memory type for an exported frame".into(),
        })?;
    let mut export = vk::ExportMemoryAllocateInfo::default().handle_types(HANDLE_TYPE);
    let mut dedicated = vk::MemoryDedicatedAllocateInfo::default().buffer(buffer);
    let info = vk::MemoryAllocateInfo::default()
        .allocation_size(requirements.size)
        .memory_type_index(type_index as u32)
        .push_next(&mut export)
        .push_next(&mut dedicated);
    // SAFETY: info and its chain are valid; the memory type exists and suits the buffer.
    let memory =
        unsafe { device.raw.allocate_memory(&info, host_callbacks()) }.or_vk("vkAllocateMemory")?;
    device.count_dedicated(requirements.size, true);
    Ok((memory, requirements.size))
}
