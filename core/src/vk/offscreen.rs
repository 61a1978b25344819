//! The offscreen colour + depth target a renderer draws into, and the attachments that
//! targets of one device share.
//!
//! A frame clears its depth and uses it only until it ends (the pick pass, the GPU cullers'
//! phases, ambient occlusion and the edges read it inside the frame), and the same holds for
//! the multisampled colour and depth an MSAA colour pass draws into before it resolves them.
//! So the targets of one size (and samples) on one device share them: frames are submitted to
//! the device's one queue, and each frame's first use of an attachment waits for everything
//! earlier frames did with it (`rendering.rs`). Four views of one scene then hold one depth,
//! not four. A target whose depth outlives its frame (handed to the host,
//! `DepthSharing::Own`) keeps its own; only its colour, the picture, is always its own.

use std::sync::Arc;

use ash::vk;

use super::device::Device;
use super::error::{VkError, VkResult};
use super::image::{read_image, Image, COLOR_FORMAT, DEPTH_FORMAT};
use super::sharing::Shared;

/// Whether a target's depth is its own or shared with the other targets of its device and size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthSharing {
    /// Shared: what a frame draws into it lasts until the next frame of any target that
    /// shares it.
    Shared,
    /// Its own: it keeps a frame's depth until the target's next frame (for the host to read).
    Own,
}

/// The shared depth images of every device.
static SHARED_DEPTHS: Shared<Image> = Shared::new();

/// The shared multisampled attachments of every device.
static SHARED_MULTISAMPLED: Shared<MultisampledTarget> = Shared::new();

/// The one-sample depth image of `extent` that targets of `device` share, made when none
/// is held.
fn shared_depth(device: &Arc<Device>, extent: vk::Extent2D) -> VkResult<Arc<Image>> {
    SHARED_DEPTHS.get_or_make(
        |image| Arc::ptr_eq(image.device(), device) && image.extent() == extent,
        || depth_image(device, "offscreen depth (shared)", extent),
    )
}

/// The multisampled attachments of `extent` and `samples` that targets of `device` share,
/// made when none are held.
fn shared_multisampled(
    device: &Arc<Device>,
    extent: vk::Extent2D,
    samples: u32,
) -> VkResult<Arc<MultisampledTarget>> {
    let fits = |target: &MultisampledTarget| {
        Arc::ptr_eq(target.color.device(), device)
            && target.color.extent() == extent
            && target.color.samples() == samples
    };
    SHARED_MULTISAMPLED.get_or_make(fits, || {
        Ok(MultisampledTarget {
            color: Image::multisampled(
                device,
                "offscreen color (multisampled, shared)",
                (extent, samples),
                COLOR_FORMAT,
                vk::ImageUsageFlags::COLOR_ATTACHMENT,
                vk::ImageAspectFlags::COLOR,
            )?,
            depth: Image::multisampled(
                device,
                "offscreen depth (multisampled, shared)",
                (extent, samples),
                DEPTH_FORMAT,
                vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
                vk::ImageAspectFlags::DEPTH,
            )?,
        })
    })
}

/// A one-sample depth attachment of `extent` as targets use it.
fn depth_image(device: &Arc<Device>, name: &str, extent: vk::Extent2D) -> VkResult<Image> {
    Image::new(
        device,
        name,
        extent,
        DEPTH_FORMAT,
        // Read back under the cursor by the pick pass; sampled by GPU occlusion culling
        // between the phases of a frame.
        vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT
            | vk::ImageUsageFlags::TRANSFER_SRC
            | vk::ImageUsageFlags::SAMPLED,
        vk::ImageAspectFlags::DEPTH,
    )
}

/// The depth of `extent` a target with `sharing` draws into.
fn target_depth(
    device: &Arc<Device>,
    extent: vk::Extent2D,
    sharing: DepthSharing,
) -> VkResult<Arc<Image>> {
    match sharing {
        DepthSharing::Shared => shared_depth(device, extent),
        DepthSharing::Own => Ok(Arc::new(depth_image(device, "offscreen depth", extent)?)),
    }
}

/// An offscreen color + depth target that can be read back.
pub struct OffscreenTarget {
    /// The color attachment (left in TRANSFER_SRC_OPTIMAL after a frame): the picture, into
    /// which a multisampled colour pass resolves.
    pub color: Image,
    /// The depth attachment: the pick pass's, and what a multisampled colour pass resolves
    /// its depth into for GPU cullers to read between phases; shared with the device's other
    /// targets of its size unless made with [`DepthSharing::Own`].
    pub depth: Arc<Image>,
    /// With MSAA, what the colour pass draws into before it is resolved; shared with the
    /// device's other targets of its size and samples.
    pub multisampled: Option<Arc<MultisampledTarget>>,
}

/// The multisampled colour and depth attachments of an MSAA colour pass.
pub struct MultisampledTarget {
    /// Resolved (averaged) into [`OffscreenTarget::color`].
    pub color: Image,
    /// Resolved into [`OffscreenTarget::depth`] with [`Device::depth_resolve_mode`].
    pub depth: Image,
}

impl OffscreenTarget {
    /// Creates a target of `width` × `height` pixels whose colour pass draws `samples` samples
    /// per pixel (1: no multisampling; others must be in [`Device::sample_counts`]), with its
    /// depth shared or its own as `sharing` says.
    pub fn new(
        device: &Arc<Device>,
        (width, height): (u32, u32),
        samples: u32,
        sharing: DepthSharing,
    ) -> VkResult<Self> {
        let limit = device.limits().max_image_dimension2_d;
        if width == 0 || height == 0 || width > limit || height > limit {
            return Err(VkError::Unsupported {
                device: device.adapter().name.clone(),
                reason: format!("a {width}x{height} target (each side must be 1 to {limit})"),
            });
        }
        let offered = device.sample_counts();
        if !offered.contains(&samples) {
            return Err(VkError::Unsupported {
                device: device.adapter().name.clone(),
                reason: format!("{samples} samples per pixel (this device offers {offered:?})"),
            });
        }
        let extent = vk::Extent2D { width, height };
        let color = Image::new(
            device,
            "offscreen color",
            extent,
            COLOR_FORMAT,
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC,
            vk::ImageAspectFlags::COLOR,
        )?;
        let depth = target_depth(device, extent, sharing)?;
        let multisampled = if samples > 1 {
            Some(shared_multisampled(device, extent, samples)?)
        } else {
            None
        };
        Ok(Self {
            color,
            depth,
            multisampled,
        })
    }

    /// Gives the target a depth shared or its own, as `sharing` says (the caller waited for
    /// the target's frames; what the old depth held is not kept).
    pub fn set_depth_sharing(&mut self, sharing: DepthSharing) -> VkResult<()> {
        self.depth = target_depth(self.color.device(), self.extent(), sharing)?;
        Ok(())
    }

    /// Samples per pixel of the colour pass.
    pub fn samples(&self) -> u32 {
        self.multisampled.as_ref().map_or(1, |m| m.color.samples())
    }

    /// Width and height in pixels.
    pub fn extent(&self) -> vk::Extent2D {
        self.color.extent()
    }

    /// Copies the color image (in TRANSFER_SRC_OPTIMAL) to the host as tightly packed RGBA8 rows.
    pub fn read_rgba8(&self, device: &Arc<Device>) -> VkResult<Vec<u8>> {
        read_image(device, &self.color, vk::ImageLayout::TRANSFER_SRC_OPTIMAL)
    }
}
