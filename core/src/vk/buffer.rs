//! Buffers with their memory, and uploads: written in place where the host can write the
//! buffer's memory, else streamed through staging buffers.

use super::host_memory::core_callbacks as host_callbacks;
use std::sync::Arc;

use ash::vk;
use gpu_allocator::vulkan::Allocation;
pub use gpu_allocator::MemoryLocation;

use super::command::{CommandContext, OneShot};
use super::device::Device;
use super::error::{VkError, VkResult, VkResultExt};

/// Bytes per staging buffer of a streamed upload ([`Buffer::upload_with`]).
const STAGING_CHUNK_BYTES: u64 = 16 << 20;
/// Staging buffers a streamed upload cycles through.
const STAGING_CHUNKS: usize = 3;

/// Bytes one thread fills at a time in an upload: large uploads are split into pieces this
/// big, spread over the cores.
const FILL_PIECE_BYTES: usize = 4 << 20;

/// Serials of buffers, counted process-wide (see [`Buffer::serial`]).
static NEXT_BUFFER_SERIAL: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

/// A buffer and its memory; freed on drop.
pub struct Buffer {
    device: Arc<Device>,
    raw: vk::Buffer,
    allocation: Option<Allocation>,
    size: u64,
    serial: u64,
}

impl Buffer {
    /// Creates a buffer of `size` bytes in `location`, named `name`.
    pub fn new(
        device: &Arc<Device>,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> VkResult<Self> {
        let info = vk::BufferCreateInfo::default()
            .size(size.max(4))
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: info is valid and lives until the call returns.
        let raw =
            unsafe { device.raw.create_buffer(&info, host_callbacks()) }.or_vk("vkCreateBuffer")?;
        // From here on, Drop cleans up the buffer if allocation fails.
        let mut buffer = Self {
            device: Arc::clone(device),
            raw,
            allocation: None,
            size,
            serial: NEXT_BUFFER_SERIAL.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
        };
        // SAFETY: raw is a live buffer of this device.
        let requirements = unsafe { device.raw.get_buffer_memory_requirements(raw) };
        let allocation = device.allocate(name, requirements, location, true)?;
        // SAFETY: the allocation satisfies the buffer's requirements and is not bound elsewhere.
        let bound = unsafe {
            device
                .raw
                .bind_buffer_memory(raw, allocation.memory(), allocation.offset())
        };
        buffer.allocation = Some(allocation);
        bound.or_vk("vkBindBufferMemory")?;
        device.set_name(raw, name);
        Ok(buffer)
    }

    /// The buffer's device address (it must have been created with `SHADER_DEVICE_ADDRESS`
    /// usage on a device with `bufferDeviceAddress`).
    pub fn device_address(&self) -> u64 {
        let info = vk::BufferDeviceAddressInfo::default().buffer(self.raw);
        // SAFETY: the buffer is live; callers only ask for buffers made with the usage.
        unsafe { self.device.raw.get_buffer_device_address(&info) }
    }

    /// The host pointer of a mapped (host-visible) buffer, or null.
    pub fn mapped_ptr(&self) -> *mut std::ffi::c_void {
        self.allocation
            .as_ref()
            .and_then(|a| a.mapped_ptr())
            .map_or(std::ptr::null_mut(), |p| p.as_ptr())
    }

    /// Creates a device-local buffer holding `data`, uploaded through a staging buffer.
    pub fn with_data(
        device: &Arc<Device>,
        name: &str,
        data: &[u8],
        usage: vk::BufferUsageFlags,
    ) -> VkResult<Self> {
        let mut buffer = Self::new(
            device,
            name,
            data.len() as u64,
            usage | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        buffer.upload_at(0, data)?;
        Ok(buffer)
    }

    /// Copies `data` to `offset` of this buffer (which needs TRANSFER_DST usage; see
    /// [`Buffer::upload_with`]). The caller makes sure the GPU is not using that range.
    pub fn upload_at(&mut self, offset: u64, data: &[u8]) -> VkResult<()> {
        self.upload_with(offset, data.len() as u64, |start, chunk| {
            let start = start as usize;
            chunk.copy_from_slice(&data[start..start + chunk.len()]);
        })
    }

    /// Uploads `size` bytes to `offset` of this buffer (which needs TRANSFER_DST usage):
    /// `fill(start, chunk)` writes bytes `start..start + chunk.len()` of the data, on up to a
    /// thread per core for large uploads, in any order. Where the buffer's memory is
    /// host-visible and coherent (a CPU device, a GPU sharing memory with the host) and
    /// [`Device::staged_uploads`] is off, `fill` writes it directly: no staging copy, no GPU
    /// work. Elsewhere the data streams through a ring of `STAGING_CHUNKS` staging buffers of
    /// `STAGING_CHUNK_BYTES`: the CPU fills one while the GPU copies the others, and only a
    /// buffer about to be refilled is waited for, so the data goes up at the speed of memory in
    /// bounded staging memory. Returns when the data is in the buffer. The caller makes sure
    /// the GPU is not using that range.
    pub fn upload_with(
        &mut self,
        offset: u64,
        size: u64,
        fill: impl Fn(u64, &mut [u8]) + Sync,
    ) -> VkResult<()> {
        if size == 0 {
            return Ok(());
        }
        if offset.checked_add(size).is_none_or(|end| end > self.size) {
            return Err(VkError::InvalidUse(format!(
                "uploading bytes {offset}..{} into a {}-byte buffer",
                offset.saturating_add(size),
                self.size
            )));
        }
        crate::timings::time(crate::timings::Phase::Upload, || {
            let direct = !self.device.staged_uploads()
                && self.allocation.as_ref().is_some_and(|a| {
                    a.memory_properties()
                        .contains(vk::MemoryPropertyFlags::HOST_COHERENT)
                });
            match self.mapped_mut() {
                Ok(bytes) if direct => {
                    let range = offset as usize..(offset + size) as usize;
                    fill_in_pieces(0, &mut bytes[range], &fill);
                    Ok(())
                }
                _ => self.upload_staged(offset, size, &fill),
            }
        })
    }

    /// [`Buffer::upload_with`] through the ring of staging buffers.
    fn upload_staged(
        &self,
        offset: u64,
        size: u64,
        fill: &(impl Fn(u64, &mut [u8]) + Sync),
    ) -> VkResult<()> {
        let device = &self.device;
        let chunk_bytes = size.min(STAGING_CHUNK_BYTES);
        let mut ring: Vec<(Buffer, CommandContext)> = Vec::new();
        let mut start = 0;
        while start < size {
            let length = (size - start).min(chunk_bytes);
            let slot = ring
                .len()
                .min((start / chunk_bytes) as usize % STAGING_CHUNKS);
            if slot == ring.len() {
                let staging = Self::new(
                    device,
                    "staging",
                    chunk_bytes,
                    vk::BufferUsageFlags::TRANSFER_SRC,
                    MemoryLocation::CpuToGpu,
                )?;
                ring.push((staging, CommandContext::new(device, "staging upload")?));
            }
            let (staging, commands) = &mut ring[slot];
            // Waits for this staging buffer's previous copy, then refills it.
            let command_buffer = commands.begin()?;
            fill_in_pieces(start, &mut staging.mapped_mut()?[..length as usize], fill);
            let region = [vk::BufferCopy::default()
                .dst_offset(offset + start)
                .size(length)];
            // SAFETY: both buffers live until the copy has completed (the ring is waited
            // for below); the region lies within both (checked by the caller).
            unsafe {
                device
                    .raw
                    .cmd_copy_buffer(command_buffer, staging.raw, self.raw, &region)
            };
            commands.submit()?;
            start += length;
        }
        for (_, commands) in &ring {
            commands.wait()?;
        }
        Ok(())
    }

    /// Copies `size` bytes from `offset` of this buffer (which needs TRANSFER_SRC usage) to the
    /// host through a readback buffer, and waits. The caller makes sure the GPU is done writing.
    pub fn download(&self, offset: u64, size: u64) -> VkResult<Vec<u8>> {
        if size == 0 {
            return Ok(Vec::new());
        }
        if offset + size > self.size {
            return Err(VkError::InvalidUse(format!(
                "reading bytes {offset}..{} of a {}-byte buffer",
                offset + size,
                self.size
            )));
        }
        let device = &self.device;
        let readback = Self::new(
            device,
            "readback",
            size,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?;
        let mut one_shot = OneShot::begin(device, "buffer readback")?;
        let region = [vk::BufferCopy::default().src_offset(offset).size(size)];
        // SAFETY: both buffers are alive until the submission below has completed; the region
        // lies within both (checked above).
        unsafe {
            device
                .raw
                .cmd_copy_buffer(one_shot.command_buffer(), self.raw, readback.raw, &region)
        };
        one_shot.submit_and_wait()?;
        Ok(readback.mapped()?.to_vec())
    }

    /// Writes `data` at `offset` into a host-visible buffer.
    pub fn write(&mut self, offset: u64, data: &[u8]) -> VkResult<()> {
        let size = self.size;
        let slice = self.mapped_mut()?;
        let start = offset as usize;
        let end = start + data.len();
        if end as u64 > size {
            return Err(VkError::InvalidUse(format!(
                "writing bytes {start}..{end} of a {size}-byte buffer"
            )));
        }
        slice[start..end].copy_from_slice(data);
        Ok(())
    }

    /// The mapped bytes of a host-visible buffer.
    pub fn mapped(&self) -> VkResult<&[u8]> {
        let size = self.size as usize;
        self.allocation
            .as_ref()
            .and_then(|a| a.mapped_slice())
            .map(|s| &s[..size])
            .ok_or_else(|| VkError::InvalidUse("mapping a buffer that is not host-visible".into()))
    }

    fn mapped_mut(&mut self) -> VkResult<&mut [u8]> {
        let size = self.size as usize;
        self.allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .map(|s| &mut s[..size])
            .ok_or_else(|| VkError::InvalidUse("writing a buffer that is not host-visible".into()))
    }

    /// The Vulkan handle.
    pub fn raw(&self) -> vk::Buffer {
        self.raw
    }

    /// A number no other buffer of the process has had: a driver may give a new buffer the
    /// handle of one destroyed before, so a descriptor written for the old one is known stale
    /// by its serial, not by its handle.
    pub fn serial(&self) -> u64 {
        self.serial
    }

    /// Size in bytes.
    pub fn size(&self) -> u64 {
        self.size
    }

    /// Records filling `size` bytes from `offset` (both multiples of 4; clamped to the buffer)
    /// with the word `value`.
    pub fn record_fill(
        &self,
        command_buffer: vk::CommandBuffer,
        offset: u64,
        size: u64,
        value: u32,
    ) {
        let offset = offset.min(self.size) & !3;
        let size = size.min(self.size - offset) & !3;
        if size == 0 {
            return;
        }
        // SAFETY: command_buffer is recording outside rendering; the buffer outlives the
        // submission (owners wait for their frames) and was created with TRANSFER_DST.
        unsafe {
            self.device
                .raw
                .cmd_fill_buffer(command_buffer, self.raw, offset, size, value)
        };
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        // SAFETY: users keep buffers alive until the GPU is done with them (renderers wait on
        // their frame fences before dropping); the handle is destroyed once.
        unsafe { self.device.raw.destroy_buffer(self.raw, host_callbacks()) };
        if let Some(allocation) = self.allocation.take() {
            self.device.free(allocation);
        }
    }
}

/// Calls `fill(start + offset, piece)` over `bytes` in pieces of `FILL_PIECE_BYTES`, on up to
/// a thread per core when there is more than one piece.
fn fill_in_pieces(start: u64, bytes: &mut [u8], fill: &(impl Fn(u64, &mut [u8]) + Sync)) {
    if bytes.len() <= FILL_PIECE_BYTES {
        fill(start, bytes);
        return;
    }
    let mut pieces: Vec<(u64, &mut [u8])> = bytes
        .chunks_mut(FILL_PIECE_BYTES)
        .enumerate()
        .map(|(index, piece)| (start + (index * FILL_PIECE_BYTES) as u64, piece))
        .collect();
    crate::parallel::for_each_mut(&mut pieces, |(piece_start, piece)| {
        fill(*piece_start, piece)
    });
}
