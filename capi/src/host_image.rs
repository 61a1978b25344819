//! Frames into a host's own image: a renderer whose every frame is blitted into a `VkImage` the
//! host owns, with the host's semaphores (`cadr_renderer_create_for_image`,
//! `cadr_renderer_set_image`).

use cadr_core::vk::raw::{self as vk, Handle};
use cadr_core::vk::{BlitTarget, HostImage};

use crate::args::read_sized;
use crate::context::CadrContext;
use crate::error::{guard, CadrResult, Failure};
use crate::renderer::{new_renderer, with_renderer, CadrRenderer, Output};

/// A host's image that every frame of a renderer is blitted into, and how the blit
/// synchronises with the host (`cadr_renderer_create_for_image`). The image is the host's: a
/// 2D `VkImage` of one layer and level on the context's device (the host's own, lent with
/// `cadr_context_create_from_vulkan`), created with `VK_IMAGE_USAGE_TRANSFER_DST_BIT`, usable
/// on cadr's queue family (exclusive to it, or concurrent), in a format the device can blit
/// into with optimal tiling (for example `VK_FORMAT_R8G8B8A8_UNORM` or
/// `VK_FORMAT_B8G8R8A8_SRGB`, into which the frame's RGBA8 is converted). Its size is the
/// renderer's.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrHostImage {
    /// `sizeof(CadrHostImage)`.
    pub size: u32,
    /// The `VkImage`.
    pub image: u64,
    /// Its `VkFormat`.
    pub format: i32,
    /// Its width in pixels (1 to 16384).
    pub width: u32,
    /// Its height in pixels (1 to 16384).
    pub height: u32,
    /// The `VkImageLayout` the image is in when a frame's blit starts
    /// (`VK_IMAGE_LAYOUT_UNDEFINED` discards what it held).
    pub old_layout: i32,
    /// The `VkImageLayout` the blit leaves it in, for the host's next use (for example
    /// `VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL`).
    pub new_layout: i32,
    /// 0, or a binary `VkSemaphore` the host signals when the image may be written: each
    /// frame's blit waits for it (at the transfer stage), so the host signals it once per
    /// frame. With 0 the blit follows the host's earlier submissions to the queue only in
    /// submission order.
    pub wait_semaphore: u64,
    /// 0, or a binary `VkSemaphore` signalled when the image holds the frame (and its writes
    /// are available): the host's work that reads the image waits for it. With 0 the host's
    /// later submissions to the queue need a barrier from the transfer stage's writes.
    pub signal_semaphore: u64,
}

/// The host's image as the output takes it, checked.
///
/// # Safety
/// `image` is null or readable.
unsafe fn host_image(image: *const CadrHostImage) -> Result<HostImage, Failure> {
    // SAFETY: null or readable for its size (the caller's contract); zero bytes are a
    // CadrHostImage (numbers and null handles).
    let image = unsafe { read_sized(image, ("image", "CadrHostImage"), std::mem::zeroed()) }?;
    if image.image == 0 {
        return Err(Failure::invalid("image.image is VK_NULL_HANDLE"));
    }
    if image.width == 0 || image.height == 0 || image.width > 16384 || image.height > 16384 {
        return Err(Failure::invalid(format!(
            "image size {}x{}: each side must be 1 to 16384",
            image.width, image.height
        )));
    }
    let new_layout = vk::ImageLayout::from_raw(image.new_layout);
    if new_layout == vk::ImageLayout::UNDEFINED {
        return Err(Failure::invalid(
            "image.new_layout is VK_IMAGE_LAYOUT_UNDEFINED",
        ));
    }
    Ok(HostImage {
        target: BlitTarget {
            image: vk::Image::from_raw(image.image),
            extent: vk::Extent2D {
                width: image.width,
                height: image.height,
            },
            old_layout: vk::ImageLayout::from_raw(image.old_layout),
            new_layout,
        },
        format: vk::Format::from_raw(image.format),
        wait: vk::Semaphore::from_raw(image.wait_semaphore),
        signal: vk::Semaphore::from_raw(image.signal_semaphore),
    })
}

/// Creates a renderer whose every frame (`cadr_renderer_render`) is drawn at the size of the
/// host's image and then blitted into it, waiting for and signalling the host's semaphores
/// (see `CadrHostImage`), so that the host composites cadr's picture into its own passes. The
/// blit is submitted to cadr's queue before `cadr_renderer_render` returns; the renderer
/// starts with 2 frames in flight. `cadr_renderer_read_pixels` still reads the picture.
///
/// Returns as `cadr_renderer_create`, and `CADR_RESULT_INVALID_ARGUMENT` (a bad size, a null
/// image, an undefined final layout) or `CADR_RESULT_UNSUPPORTED` (a format the device cannot
/// blit into, named).
///
/// Ownership: the image and semaphores stay the host's, and must outlive the renderer (or
/// the next `cadr_renderer_set_image`) and every frame submitted into them; `image` is read
/// during the call. Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `image` is null or a valid `CadrHostImage` whose handles are live objects of the context's
/// device; `renderer` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_create_for_image(
    context: CadrContext,
    image: *const CadrHostImage,
    renderer: *mut CadrRenderer,
) -> CadrResult {
    guard(|| {
        // SAFETY: null or readable (the caller's contract).
        let image = unsafe { host_image(image) }?;
        let size = (image.target.extent.width, image.target.extent.height);
        new_renderer(context, size, Output::Image(image), renderer)
    })
}

/// Sends the next frames of a renderer made by `cadr_renderer_create_for_image` to another
/// image (the host rotates images, or its image was resized: the renderer takes the new
/// size), with its semaphores and layouts. Frames already submitted keep the image they had.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_INVALID_ARGUMENT` (as
/// `cadr_renderer_create_for_image`, or a renderer made otherwise), `CADR_RESULT_UNSUPPORTED`
/// (the format), `CADR_RESULT_VULKAN` or a handle error. Ownership and thread-safety: as
/// `cadr_renderer_create_for_image`.
///
/// # Safety
/// As `cadr_renderer_create_for_image`.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_set_image(
    renderer: CadrRenderer,
    image: *const CadrHostImage,
) -> CadrResult {
    guard(|| {
        // SAFETY: null or readable (the caller's contract).
        let image = unsafe { host_image(image) }?;
        with_renderer(renderer, |state| {
            let device = std::sync::Arc::clone(state.view.renderer().device());
            let Some(output) = state.image_output.as_mut() else {
                return Err(Failure::invalid(
                    "the renderer was not made for a host's image (cadr_renderer_create_for_image)",
                ));
            };
            output.set_image(&device, image)?;
            let extent = image.target.extent;
            state
                .view
                .renderer_mut()
                .resize(extent.width, extent.height)?;
            Ok(())
        })
    })
}
