//! Copying finished frames into other images on the GPU: a ring of command buffers that blit
//! a frame into a target (a swapchain's image, a host's), each blit waiting for and signalling
//! semaphores, so that presenting or handing a frame over never waits for the GPU unless the
//! ring comes round to a blit still running.

use std::sync::Arc;

use ash::vk;

use super::command::CommandContext;
use super::device::Device;
use super::error::VkResult;
use super::image::{transition, Image};

/// How many blits may be on the GPU at once: as many as a renderer's frames in flight, so that
/// handing frames over never makes a frame wait for more than its frame slot does.
pub const BLITS_IN_FLIGHT: usize = 3;

/// An image a frame is blitted into, and its layouts before and after.
#[derive(Clone, Copy, Debug)]
pub struct BlitTarget {
    /// The image (2D, one layer and level, with transfer-destination usage).
    pub image: vk::Image,
    /// Its size; a frame of another size is scaled (linear filtering).
    pub extent: vk::Extent2D,
    /// The layout it is in when the blit starts (`UNDEFINED` discards its contents).
    pub old_layout: vk::ImageLayout,
    /// The layout the blit leaves it in.
    pub new_layout: vk::ImageLayout,
}

/// The command buffers of the last [`BLITS_IN_FLIGHT`] blits, used in turn.
pub struct BlitRing {
    device: Arc<Device>,
    contexts: Vec<CommandContext>,
    next: usize,
}

impl BlitRing {
    /// The ring's command buffers, named after `name`.
    pub fn new(device: &Arc<Device>, name: &str) -> VkResult<Self> {
        let contexts = (0..BLITS_IN_FLIGHT)
            .map(|index| CommandContext::new(device, &format!("{name} {index} commands")))
            .collect::<VkResult<Vec<_>>>()?;
        Ok(Self {
            device: Arc::clone(device),
            contexts,
            next: 0,
        })
    }

    /// Waits for the blit that last used the next slot and returns the slot: what a blit
    /// waits on and signals (semaphores) may be reused from then on.
    pub fn next_slot(&self) -> VkResult<usize> {
        self.contexts[self.next].wait()?;
        Ok(self.next)
    }

    /// Records and submits the blit of `frame` (in TRANSFER_SRC_OPTIMAL, left so) into
    /// `target` in the next slot, after each of `wait` (a semaphore and the stage that waits
    /// for it), signalling `signal` when done.
    pub fn blit(
        &mut self,
        frame: &Image,
        target: &BlitTarget,
        wait: &[(vk::Semaphore, vk::PipelineStageFlags)],
        signal: &[vk::Semaphore],
    ) -> VkResult<()> {
        let context = &mut self.contexts[self.next];
        let command_buffer = context.begin()?;
        record_blit(&self.device, command_buffer, frame, target);
        context.submit_with_semaphores(wait, signal)?;
        self.next = (self.next + 1) % BLITS_IN_FLIGHT;
        Ok(())
    }
}

/// Records the blit of `frame` (in TRANSFER_SRC_OPTIMAL) into `target`, scaled if their sizes
/// differ, leaving the target in its `new_layout`.
fn record_blit(
    device: &Device,
    command_buffer: vk::CommandBuffer,
    frame: &Image,
    target: &BlitTarget,
) {
    let (image, extent) = (target.image, target.extent);
    transition(
        device,
        command_buffer,
        image,
        vk::ImageAspectFlags::COLOR,
        (
            target.old_layout,
            vk::PipelineStageFlags2::BLIT,
            vk::AccessFlags2::NONE,
        ),
        (
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            vk::PipelineStageFlags2::BLIT,
            vk::AccessFlags2::TRANSFER_WRITE,
        ),
    );
    let source = frame.extent();
    let corner = |e: vk::Extent2D| vk::Offset3D {
        x: e.width as i32,
        y: e.height as i32,
        z: 1,
    };
    let layers = vk::ImageSubresourceLayers::default()
        .aspect_mask(vk::ImageAspectFlags::COLOR)
        .layer_count(1);
    let region = [vk::ImageBlit::default()
        .src_subresource(layers)
        .src_offsets([vk::Offset3D::default(), corner(source)])
        .dst_subresource(layers)
        .dst_offsets([vk::Offset3D::default(), corner(extent)])];
    let filter = if source == extent {
        vk::Filter::NEAREST
    } else {
        vk::Filter::LINEAR
    };
    // SAFETY: recording; the frame is in TRANSFER_SRC_OPTIMAL, the target was just moved to
    // TRANSFER_DST_OPTIMAL; both outlive the submission (the ring waits for it before reusing
    // its command buffer, and their owners wait for the queue before destroying them).
    unsafe {
        device.raw.cmd_blit_image(
            command_buffer,
            frame.raw(),
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            image,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            &region,
            filter,
        )
    };
    transition(
        device,
        command_buffer,
        image,
        vk::ImageAspectFlags::COLOR,
        (
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            vk::PipelineStageFlags2::BLIT,
            vk::AccessFlags2::TRANSFER_WRITE,
        ),
        (
            target.new_layout,
            vk::PipelineStageFlags2::BOTTOM_OF_PIPE,
            vk::AccessFlags2::NONE,
        ),
    );
}

/// A host's image that every frame is blitted into (`cadr_renderer_create_for_image`), with
/// the host's semaphores.
#[derive(Clone, Copy, Debug)]
pub struct HostImage {
    /// The image, its size and layouts.
    pub target: BlitTarget,
    /// Its format, which must be a blit destination with optimal tiling.
    pub format: vk::Format,
    /// Null, or a semaphore the host signals when the image may be written: the blit waits.
    pub wait: vk::Semaphore,
    /// Null, or a semaphore signalled when the image holds the frame.
    pub signal: vk::Semaphore,
}

/// Blits every frame into a host's image, after the host's semaphore, signalling the host's.
pub struct ImageOutput {
    ring: BlitRing,
    image: HostImage,
}

impl ImageOutput {
    /// An output into `image`, refused where its format cannot be blitted into.
    pub fn new(device: &Arc<Device>, image: HostImage) -> VkResult<Self> {
        check_blit_destination(device, image.format)?;
        Ok(Self {
            ring: BlitRing::new(device, "host image")?,
            image,
        })
    }

    /// The image the next frames go to.
    pub fn image(&self) -> &HostImage {
        &self.image
    }

    /// Sends the next frames to `image` instead, refused where its format cannot be blitted
    /// into.
    pub fn set_image(&mut self, device: &Device, image: HostImage) -> VkResult<()> {
        check_blit_destination(device, image.format)?;
        self.image = image;
        Ok(())
    }

    /// Blits `frame` (in TRANSFER_SRC_OPTIMAL) into the image, after the host's wait
    /// semaphore (at the transfer stage), signalling the host's semaphore when done; returns
    /// once it is submitted.
    pub fn copy(&mut self, frame: &Image) -> VkResult<()> {
        self.ring.next_slot()?;
        let image = self.image;
        let wait = [(image.wait, vk::PipelineStageFlags::TRANSFER)];
        let signal = [image.signal];
        // A null semaphore is none: an empty list (no allocation per frame).
        let given = |present: bool| usize::from(present);
        let wait = &wait[..given(image.wait != vk::Semaphore::null())];
        let signal = &signal[..given(image.signal != vk::Semaphore::null())];
        self.ring.blit(frame, &image.target, wait, signal)
    }
}

/// Refuses `format` where the device cannot blit into an image of it (optimal tiling).
fn check_blit_destination(device: &Device, format: vk::Format) -> VkResult<()> {
    // SAFETY: the physical device belongs to the device's instance.
    let properties = unsafe {
        device
            .instance
            .raw
            .get_physical_device_format_properties(device.adapter().physical, format)
    };
    if properties
        .optimal_tiling_features
        .contains(vk::FormatFeatureFlags::BLIT_DST)
    {
        Ok(())
    } else {
        Err(super::error::VkError::Unsupported {
            device: device.adapter().name.clone(),
            reason: format!("cannot blit frames into an image of format {format:?}"),
        })
    }
}
