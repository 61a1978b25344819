//! Frames shared with an OpenGL host without a copy through the CPU: a renderer whose every
//! frame is copied on the GPU into memory exported as a file descriptor, which the host imports
//! (`GL_EXT_memory_object_fd`) and reads as a pixel buffer; with the frame's depth after it
//! when the host asks (`CadrRendererSettings::depth_to_host`), for compositing. Hosts that
//! cannot share memory read frames back (`cadr_renderer_read_pixels`, and the depth with
//! `cadr_renderer_read_depth`).

use cadr_core::vk::{raw, FrameExport, Image};

use std::os::fd::IntoRawFd;

use crate::args::{check_owning_size, deliver_sized};
use crate::context::CadrContext;
use crate::error::{guard, CadrResult, Failure};
use crate::renderer::{new_renderer, with_renderer, CadrRenderer, Output};

/// Where a renderer's frames are exported (`cadr_renderer_create_for_export`): the memory
/// exported, and a count that moves whenever it is replaced by memory of another size.
pub(crate) struct ExportOutput {
    export: FrameExport,
    generation: u64,
}

impl ExportOutput {
    /// An export of frames of `width` × `height` pixels (without their depth until a frame
    /// brings one).
    pub(crate) fn new(
        device: &std::sync::Arc<cadr_core::vk::Device>,
        (width, height): (u32, u32),
    ) -> Result<Self, Failure> {
        Ok(Self {
            export: FrameExport::new(device, raw::Extent2D { width, height }, false)?,
            generation: 1,
        })
    }

    /// Makes the exported memory hold frames of `extent`, with their depth or without: new
    /// memory, and a new generation, when either changed.
    pub(crate) fn reshape(
        &mut self,
        device: &std::sync::Arc<cadr_core::vk::Device>,
        extent: raw::Extent2D,
        with_depth: bool,
    ) -> Result<(), Failure> {
        if extent != self.export.extent() || with_depth != self.export.depth_offset().is_some() {
            let mut export = FrameExport::new(device, extent, with_depth)?;
            // The host keeps the semaphores it imported.
            export.take_semaphores_from(&mut self.export);
            self.export = export;
            self.generation += 1;
        }
        Ok(())
    }

    /// Waits until the host has released the frame before the last one, where frames are
    /// handed over by semaphores: the next frame's drawing must not queue behind a copy that
    /// waits for a release that never comes.
    pub(crate) fn wait_for_release(&mut self) -> Result<(), Failure> {
        self.export.wait_for_release().map_err(host_rule_broken)
    }

    /// Copies `frame`, and its `depth` when the renderer keeps it for the host, into the
    /// exported memory (reshaped first when the frame's size changed or the depth came or
    /// went) and waits for the copy, or, once the host has the semaphores, submits it between
    /// them.
    pub(crate) fn copy(
        &mut self,
        device: &std::sync::Arc<cadr_core::vk::Device>,
        frame: &Image,
        depth: Option<&Image>,
    ) -> Result<(), Failure> {
        self.reshape(device, frame.extent(), depth.is_some())?;
        self.export.copy(frame, depth).map_err(host_rule_broken)
    }
}

/// A failure of the export, `CADR_RESULT_INVALID_ARGUMENT` where the host broke the hand-over's
/// rule (a frame never released).
fn host_rule_broken(error: cadr_core::vk::VkError) -> Failure {
    match error {
        cadr_core::vk::VkError::InvalidUse(message) => Failure::invalid(message),
        error => error.into(),
    }
}

/// The memory a renderer's frames are exported into (`cadr_renderer_exported_frame`). After
/// each `cadr_renderer_render` it holds that frame: `height` rows of `row_bytes` bytes, the top
/// row first, 4 bytes per pixel (R, G, B, A, 8 bits each, as `cadr_renderer_read_pixels` gives
/// them), from offset 0; with `CadrRendererSettings::depth_to_host`, the frame's depth follows
/// from `depth_offset`.
///
/// The struct grows by appending fields: the host sets `size` to `sizeof(CadrExportedFrame)`;
/// cadr fills the fields within it and zeroes those of a newer header it does not know.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CadrExportedFrame {
    /// `sizeof(CadrExportedFrame)`, set by the host.
    pub size: u32,
    /// A new POSIX file descriptor of the memory (`VK_EXTERNAL_MEMORY_HANDLE_TYPE_OPAQUE_FD_BIT`),
    /// the host's: import it (`glImportMemoryFdEXT` with `GL_HANDLE_TYPE_OPAQUE_FD_EXT` takes
    /// it) or close it.
    pub fd: i32,
    /// The memory's size in bytes, as the importer is told it (at least
    /// `row_bytes × height`).
    pub allocation_size: u64,
    /// The frame's width in pixels.
    pub width: u32,
    /// The frame's height in pixels.
    pub height: u32,
    /// Bytes from one row to the next (`width × 4`).
    pub row_bytes: u32,
    /// Counts the memories exported so far: it moves when the renderer's size changed and its
    /// frames went to new memory, which the host then imports in place of the old one (whose
    /// frames no longer change).
    pub generation: u64,
    /// The Vulkan device's UUID (`VkPhysicalDeviceIDProperties::deviceUUID`): import only where
    /// the OpenGL driver's `GL_DEVICE_UUID_EXT` is the same.
    pub device_uuid: [u8; 16],
    /// The Vulkan driver's UUID (`driverUUID`): import only where `GL_DRIVER_UUID_EXT` is the
    /// same.
    pub driver_uuid: [u8; 16],
    /// Where the frame's depth starts in the memory, 0 when it holds none (the renderer's
    /// `depth_to_host` setting is off); after each `cadr_renderer_render` it holds that frame's
    /// depth: `height`
    /// rows of `depth_row_bytes` bytes, the top row first, one 32-bit float per pixel, 0 at the
    /// near plane and 1 at the far plane and where nothing is drawn (an OpenGL window depth
    /// with the default depth range; the projection is the camera's). It is the opaque
    /// surfaces' depth: translucent surfaces, and X-ray's, write none. Since 1.1.
    pub depth_offset: u64,
    /// Bytes from one row of the depth to the next (`width × 4`), 0 without depth. Since 1.1.
    pub depth_row_bytes: u32,
}

/// The two semaphores a renderer's exported frames are handed over by
/// (`cadr_renderer_export_semaphores`), as new POSIX file descriptors
/// (`VK_EXTERNAL_SEMAPHORE_HANDLE_TYPE_OPAQUE_FD_BIT`), the host's: import each once
/// (`glImportSemaphoreFdEXT` with `GL_HANDLE_TYPE_OPAQUE_FD_EXT` takes it) or close it. Both are
/// binary semaphores. For every frame, after `cadr_renderer_render`:
/// 1. the host waits for `ready` (`glWaitSemaphoreEXT`, naming the pixel buffer) before reading
///    the exported memory;
/// 2. having issued its reads of the frame, the host signals `released`
///    (`glSignalSemaphoreEXT`) and flushes (`glFlush`), before the next
///    `cadr_renderer_render`: that frame's copy waits for it before overwriting the memory.
///
/// Exactly once each per frame: a frame whose `ready` is not waited for leaves the semaphore
/// signalled, which the next frame's signal may not find. A host that does not release a frame
/// gets `CADR_RESULT_INVALID_ARGUMENT` from the render after next, which waits 10 s for the
/// release before it draws anything; the host then releases the frame, waits for `ready` of the
/// frame after it (whose copy was waiting), and goes on. Destroying the renderer waits for its
/// last copy: release every frame you were handed first. The semaphores stay the same across
/// resizes.
///
/// The struct grows by appending fields: the host sets `size` to
/// `sizeof(CadrExportedSemaphores)`; cadr fills the fields within it and zeroes those of a
/// newer header it does not know. Since 1.2.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CadrExportedSemaphores {
    /// `sizeof(CadrExportedSemaphores)`, set by the host.
    pub size: u32,
    /// Signalled by cadr when the exported memory holds the frame of the last
    /// `cadr_renderer_render` (and its writes are visible to the importer).
    pub ready_fd: i32,
    /// Signalled by the host when it has read the frame; the next frame's copy waits for it.
    pub released_fd: i32,
}

/// Creates an offscreen renderer of `width` × `height` pixels whose every frame
/// (`cadr_renderer_render`) is copied on the GPU into memory exported as a file descriptor
/// (`VK_KHR_external_memory_fd`), for an OpenGL host to import once and read as a pixel
/// buffer: no frame passes through the CPU. `cadr_renderer_render` returns once the copy is
/// done, so the host reads the frame after it without a semaphore, until the host asks for
/// semaphores (`cadr_renderer_export_semaphores`); the renderer starts with 1 frame in
/// flight. `cadr_renderer_exported_frame` gives the memory.
///
/// Returns as `cadr_renderer_create`, and `CADR_RESULT_UNSUPPORTED` where the device (or the
/// host that lent it) lacks `VK_KHR_external_memory_fd` or cannot export a buffer's memory:
/// read frames back with `cadr_renderer_read_pixels` instead.
/// Ownership: as `cadr_renderer_create`. Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `renderer` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_create_for_export(
    context: CadrContext,
    width: u32,
    height: u32,
    renderer: *mut CadrRenderer,
) -> CadrResult {
    guard(|| new_renderer(context, (width, height), Output::Export, renderer))
}

/// Writes the memory the renderer's frames are exported into, with a new file descriptor of
/// it, into `*frame` (up to the `frame->size` the host set). Call it once, import the memory,
/// and again when a frame's `generation` differs from the imported one (after a resize).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_INVALID_ARGUMENT` (a
/// renderer not made by `cadr_renderer_create_for_export`, or a `size` below 4),
/// `CADR_RESULT_VULKAN` or a handle error. Ownership: the file descriptor is the host's; the
/// memory stays cadr's until the renderer is destroyed or resized (an imported copy of it
/// stays valid for the importer). Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `frame` is null or writable for its `size`.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_exported_frame(
    renderer: CadrRenderer,
    frame: *mut CadrExportedFrame,
) -> CadrResult {
    guard(|| {
        crate::args::non_null(frame, "frame")?;
        let value = with_renderer(renderer, |state| {
            let Some(output) = &state.frame_export else {
                return Err(Failure::invalid(
                    "the renderer was not made to export its frames (cadr_renderer_create_for_export)",
                ));
            };
            let extent = output.export.extent();
            let (device_uuid, driver_uuid) = output.export.uuids();
            let depth_offset = output.export.depth_offset();
            Ok(CadrExportedFrame {
                size: std::mem::size_of::<CadrExportedFrame>() as u32,
                fd: output.export.file_descriptor()?,
                allocation_size: output.export.allocation_size(),
                width: extent.width,
                height: extent.height,
                row_bytes: extent.width * 4,
                generation: output.generation,
                device_uuid,
                driver_uuid,
                depth_offset: depth_offset.unwrap_or(0),
                depth_row_bytes: depth_offset.map_or(0, |_| extent.width * 4),
            })
        })?;
        // SAFETY: null or writable for its size (the caller's contract).
        let delivered = unsafe { deliver_sized(frame, "frame", value) };
        if delivered.is_err() {
            // The descriptor never reached the host: close it here.
            // SAFETY: the descriptor was just made for this call and is owned by no one else.
            drop(unsafe {
                <std::os::fd::OwnedFd as std::os::fd::FromRawFd>::from_raw_fd(value.fd)
            });
        }
        delivered
    })
}

/// Hands the renderer's exported frames over by two semaphores from the next
/// `cadr_renderer_render` on, instead of waiting for each frame's copy on the CPU, and writes
/// new file descriptors of them into `*semaphores` (see `CadrExportedSemaphores` for the
/// protocol). The first call makes them; a later call gives new descriptors of the same two.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_INVALID_ARGUMENT` (a
/// renderer not made by `cadr_renderer_create_for_export`, or a `size` below that of 1.2's
/// struct), `CADR_RESULT_UNSUPPORTED` where the device (or the host that lent it) lacks
/// `VK_KHR_external_semaphore_fd` or cannot export a binary semaphore (lavapipe): frames stay
/// waited for, as before the call; `CADR_RESULT_VULKAN` or a handle error.
/// Ownership: the file descriptors are the host's; the semaphores stay cadr's until the
/// renderer is destroyed (an imported copy stays valid for the importer). Thread-safety: as
/// `cadr_renderer_create`.
///
/// # Safety
/// `semaphores` is null or writable for its `size`.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_export_semaphores(
    renderer: CadrRenderer,
    semaphores: *mut CadrExportedSemaphores,
) -> CadrResult {
    guard(|| {
        // SAFETY: null or readable for its size (the caller's contract). Every field of 1.2's
        // struct carries a descriptor: a smaller one would leak them.
        unsafe {
            check_owning_size(
                semaphores,
                ("semaphores", "CadrExportedSemaphores"),
                std::mem::size_of::<CadrExportedSemaphores>(),
            )
        }?;
        let (ready, released) = with_renderer(renderer, |state| {
            let Some(output) = &mut state.frame_export else {
                return Err(Failure::invalid(
                    "the renderer was not made to export its frames (cadr_renderer_create_for_export)",
                ));
            };
            Ok(output.export.share_semaphores()?)
        })?;
        let value = CadrExportedSemaphores {
            size: std::mem::size_of::<CadrExportedSemaphores>() as u32,
            ready_fd: ready.into_raw_fd(),
            released_fd: released.into_raw_fd(),
        };
        // SAFETY: writable for its size (checked above, the caller's contract).
        unsafe { deliver_sized(semaphores, "semaphores", value) }
    })
}
