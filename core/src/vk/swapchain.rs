//! Presenting to a host's window: a swapchain on a `VkSurfaceKHR` that the host created on
//! cadr's instance. Each frame is rendered offscreen as usual and then blitted into the acquired
//! swapchain image, so every technique renders the same way for files, tests and windows.
//!
//! The swapchain is recreated when the window's size changes, when the driver reports it out of
//! date or suboptimal, and it pauses (presents nothing) while the window has no area
//! (minimized). Frames reach the window in the chosen present mode (FIFO by default), and a
//! present does not wait for the GPU.

use super::host_memory::core_callbacks as host_callbacks;
use std::sync::Arc;

use ash::vk;

use super::device::Device;
use super::error::{VkError, VkResult, VkResultExt};
use super::frame_blit::{BlitRing, BlitTarget, BLITS_IN_FLIGHT};
use super::image::Image;

/// What happened to a frame handed to [`Swapchain::present`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PresentOutcome {
    /// The frame is on its way to the window.
    Presented,
    /// Nothing was shown: the window has no area, or the swapchain was out of date and has been
    /// recreated (the next frame is shown).
    Skipped,
}

/// How presented frames reach the window.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PresentMode {
    /// Paced to the display, never torn (every device offers it; the default).
    Fifo,
    /// The newest frame replaces a waiting one: not torn, not paced (low latency).
    Mailbox,
    /// Shown at once, possibly torn: frames as fast as they are drawn.
    Immediate,
}

impl PresentMode {
    /// Every mode.
    pub const ALL: [PresentMode; 3] = [Self::Fifo, Self::Mailbox, Self::Immediate];

    /// Its name in messages.
    pub fn name(self) -> &'static str {
        match self {
            Self::Fifo => "fifo",
            Self::Mailbox => "mailbox",
            Self::Immediate => "immediate",
        }
    }

    fn raw(self) -> vk::PresentModeKHR {
        match self {
            Self::Fifo => vk::PresentModeKHR::FIFO,
            Self::Mailbox => vk::PresentModeKHR::MAILBOX,
            Self::Immediate => vk::PresentModeKHR::IMMEDIATE,
        }
    }
}

/// A swapchain that owns its surface.
pub struct Swapchain {
    device: Arc<Device>,
    surface_fn: ash::khr::surface::Instance,
    swapchain_fn: ash::khr::swapchain::Device,
    surface: vk::SurfaceKHR,
    raw: vk::SwapchainKHR,
    images: Vec<vk::Image>,
    format: vk::Format,
    extent: vk::Extent2D,
    /// The size the host last asked for (used where the surface does not dictate one).
    wanted: vk::Extent2D,
    /// Set when the driver reported the swapchain suboptimal or out of date.
    stale: bool,
    /// How frames reach the window.
    present_mode: PresentMode,
    /// One per swapchain image: signalled by the blit, waited for by the presentation.
    ready_to_present: Vec<vk::Semaphore>,
    /// The blits of the last presents.
    blits: BlitRing,
    /// Per slot of the ring: the semaphore the acquisition of that blit's image signals.
    image_acquired: Vec<vk::Semaphore>,
}

fn create_semaphore(device: &Device, name: &str) -> VkResult<vk::Semaphore> {
    // SAFETY: a default semaphore create info is valid.
    let semaphore = unsafe {
        device
            .raw
            .create_semaphore(&vk::SemaphoreCreateInfo::default(), host_callbacks())
    }
    .or_vk("vkCreateSemaphore")?;
    device.set_name(semaphore, name);
    Ok(semaphore)
}

impl Swapchain {
    /// Creates a swapchain of about `width` × `height` pixels on `surface` (created on
    /// `device`'s instance). On success the swapchain owns the surface and destroys it when
    /// dropped; on failure the surface stays the caller's. The device must have
    /// `VK_KHR_swapchain` and its queue must be able to present to the surface.
    pub fn new(
        device: &Arc<Device>,
        surface: vk::SurfaceKHR,
        width: u32,
        height: u32,
    ) -> VkResult<Self> {
        let instance = device.instance();
        let surface_fn = ash::khr::surface::Instance::new(instance.entry(), instance.raw());
        // SAFETY: physical device, queue family and surface belong to this instance.
        let supported = unsafe {
            surface_fn.get_physical_device_surface_support(
                device.adapter().physical,
                device.queue_family(),
                surface,
            )
        }
        .or_vk("vkGetPhysicalDeviceSurfaceSupportKHR")?;
        if !supported {
            return Err(VkError::Unsupported {
                device: device.adapter().name.clone(),
                reason: "its render queue cannot present to this surface".into(),
            });
        }
        let swapchain_fn = ash::khr::swapchain::Device::new(instance.raw(), device.raw());
        let blits = BlitRing::new(device, "present")?;
        let mut swapchain = Self {
            device: Arc::clone(device),
            surface_fn,
            swapchain_fn,
            surface,
            raw: vk::SwapchainKHR::null(),
            images: Vec::new(),
            format: vk::Format::UNDEFINED,
            extent: vk::Extent2D::default(),
            wanted: vk::Extent2D { width, height },
            stale: false,
            present_mode: PresentMode::Fifo,
            ready_to_present: Vec::new(),
            blits,
            image_acquired: Vec::new(),
        };
        for index in 0..BLITS_IN_FLIGHT {
            // Dropped with the swapchain on a failure.
            let semaphore = create_semaphore(device, &format!("present {index} image acquired"))?;
            swapchain.image_acquired.push(semaphore);
        }
        if let Err(error) = swapchain.recreate() {
            // The caller keeps the surface: Drop must not destroy it.
            swapchain.surface = vk::SurfaceKHR::null();
            return Err(error);
        }
        Ok(swapchain)
    }

    /// The size of the swapchain images; zero while the window has no area.
    pub fn extent(&self) -> vk::Extent2D {
        self.extent
    }

    /// The swapchain images' format.
    pub fn format(&self) -> vk::Format {
        self.format
    }

    /// The present modes the surface offers (FIFO always).
    pub fn present_modes(&self) -> VkResult<Vec<PresentMode>> {
        // SAFETY: physical device and surface belong to this instance.
        let offered = unsafe {
            self.surface_fn.get_physical_device_surface_present_modes(
                self.device.adapter().physical,
                self.surface,
            )
        }
        .or_vk("vkGetPhysicalDeviceSurfacePresentModesKHR")?;
        Ok(PresentMode::ALL
            .into_iter()
            .filter(|mode| *mode == PresentMode::Fifo || offered.contains(&mode.raw()))
            .collect())
    }

    /// How frames reach the window now.
    pub fn present_mode(&self) -> PresentMode {
        self.present_mode
    }

    /// Presents with `mode` from the next frame on (the swapchain is recreated); a mode the
    /// surface does not offer is refused with the ones it does.
    pub fn set_present_mode(&mut self, mode: PresentMode) -> VkResult<()> {
        if mode == self.present_mode {
            return Ok(());
        }
        let offered = self.present_modes()?;
        if !offered.contains(&mode) {
            let names: Vec<&str> = offered.iter().map(|m| m.name()).collect();
            return Err(VkError::Unsupported {
                device: self.device.adapter().name.clone(),
                reason: format!(
                    "the window's surface does not offer the {} present mode (it offers {})",
                    mode.name(),
                    names.join(", ")
                ),
            });
        }
        let previous = self.present_mode;
        self.present_mode = mode;
        if let Err(error) = self.recreate() {
            self.present_mode = previous;
            return Err(error);
        }
        Ok(())
    }

    /// Records the window's new size and recreates the swapchain for it.
    pub fn resize(&mut self, width: u32, height: u32) -> VkResult<()> {
        self.wanted = vk::Extent2D { width, height };
        self.recreate()
    }

    /// Recreates the swapchain for the surface's current size (or the size the host asked for
    /// where the surface leaves it open).
    pub fn recreate(&mut self) -> VkResult<()> {
        let device = &*self.device;
        device.wait_idle()?;
        let physical = device.adapter().physical;
        // SAFETY: physical device and surface belong to this instance.
        let capabilities = unsafe {
            self.surface_fn
                .get_physical_device_surface_capabilities(physical, self.surface)
        }
        .or_vk("vkGetPhysicalDeviceSurfaceCapabilitiesKHR")?;
        let extent = if capabilities.current_extent.width == u32::MAX {
            vk::Extent2D {
                width: self.wanted.width.clamp(
                    capabilities.min_image_extent.width,
                    capabilities.max_image_extent.width,
                ),
                height: self.wanted.height.clamp(
                    capabilities.min_image_extent.height,
                    capabilities.max_image_extent.height,
                ),
            }
        } else {
            capabilities.current_extent
        };
        self.stale = false;
        if extent.width == 0 || extent.height == 0 {
            // Minimized: keep the old swapchain (if any) and present nothing until it has area.
            self.extent = vk::Extent2D::default();
            return Ok(());
        }
        if !capabilities
            .supported_usage_flags
            .contains(vk::ImageUsageFlags::TRANSFER_DST)
        {
            return Err(VkError::Unsupported {
                device: device.adapter().name.clone(),
                reason: "the surface's images cannot be blitted into (no TRANSFER_DST usage)"
                    .into(),
            });
        }
        // SAFETY: as above.
        let formats = unsafe {
            self.surface_fn
                .get_physical_device_surface_formats(physical, self.surface)
        }
        .or_vk("vkGetPhysicalDeviceSurfaceFormatsKHR")?;
        // Offscreen frames are UNORM; a UNORM swapchain shows them with the same values.
        let preferred = [vk::Format::B8G8R8A8_UNORM, vk::Format::R8G8B8A8_UNORM];
        let chosen = preferred
            .iter()
            .find_map(|f| formats.iter().find(|s| s.format == *f))
            .or_else(|| formats.first())
            .copied()
            .ok_or_else(|| VkError::Unsupported {
                device: device.adapter().name.clone(),
                reason: "the surface offers no image format".into(),
            })?;
        let mut image_count = capabilities.min_image_count + 1;
        if capabilities.max_image_count > 0 {
            image_count = image_count.min(capabilities.max_image_count);
        }
        let composite = [
            vk::CompositeAlphaFlagsKHR::OPAQUE,
            vk::CompositeAlphaFlagsKHR::INHERIT,
            vk::CompositeAlphaFlagsKHR::PRE_MULTIPLIED,
            vk::CompositeAlphaFlagsKHR::POST_MULTIPLIED,
        ]
        .into_iter()
        .find(|c| capabilities.supported_composite_alpha.contains(*c))
        .unwrap_or(vk::CompositeAlphaFlagsKHR::OPAQUE);
        let old = self.raw;
        let create_info = vk::SwapchainCreateInfoKHR::default()
            .surface(self.surface)
            .min_image_count(image_count)
            .image_format(chosen.format)
            .image_color_space(chosen.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(vk::ImageUsageFlags::TRANSFER_DST)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(capabilities.current_transform)
            .composite_alpha(composite)
            // FIFO by default: always offered, and paced to the display as a CAD window wants.
            .present_mode(self.present_mode.raw())
            .clipped(true)
            .old_swapchain(old);
        // SAFETY: the create info is valid for this surface (values come from its
        // capabilities); the old swapchain is retired by this call and destroyed below after
        // the device went idle.
        let raw = unsafe {
            self.swapchain_fn
                .create_swapchain(&create_info, host_callbacks())
        }
        .or_vk("vkCreateSwapchainKHR")?;
        // SAFETY: the device is idle, so nothing uses the old swapchain or its images.
        unsafe { self.swapchain_fn.destroy_swapchain(old, host_callbacks()) };
        self.raw = raw;
        // SAFETY: raw is a live swapchain.
        self.images = unsafe { self.swapchain_fn.get_swapchain_images(raw) }
            .or_vk("vkGetSwapchainImagesKHR")?;
        self.format = chosen.format;
        self.extent = extent;
        while self.ready_to_present.len() < self.images.len() {
            let semaphore = create_semaphore(device, "swapchain image ready to present")?;
            self.ready_to_present.push(semaphore);
        }
        Ok(())
    }

    /// Blits `frame` (a color image in TRANSFER_SRC_OPTIMAL, as a frame leaves it) into the
    /// next swapchain image and presents it, without waiting for the GPU: the blit follows the
    /// frame on the queue, and the next frame's drawing into `frame` waits for the blit there.
    /// Only the blit of the present three presents ago is waited for, as its
    /// command buffer and semaphore are reused.
    pub fn present(&mut self, frame: &Image) -> VkResult<PresentOutcome> {
        let slot = self.blits.next_slot()?;
        if self.stale {
            self.recreate()?;
        }
        if self.extent.width == 0 || self.extent.height == 0 {
            // The window may have regained its area: ask the surface again.
            self.recreate()?;
            if self.extent.width == 0 {
                return Ok(PresentOutcome::Skipped);
            }
        }
        let image_acquired = self.image_acquired[slot];
        // SAFETY: the swapchain is live; the semaphore is unsignalled (its last wait, the
        // slot's last blit, completed: it was waited for above).
        let acquired = unsafe {
            self.swapchain_fn.acquire_next_image(
                self.raw,
                u64::MAX,
                image_acquired,
                vk::Fence::null(),
            )
        };
        let index = match acquired {
            Ok((index, suboptimal)) => {
                self.stale |= suboptimal;
                index
            }
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
                self.recreate()?;
                return Ok(PresentOutcome::Skipped);
            }
            Err(error) => return Err(super::error::map_result("vkAcquireNextImageKHR", error)),
        };
        let image = self.images[index as usize];
        let ready = self.ready_to_present[index as usize];
        let target = BlitTarget {
            image,
            extent: self.extent,
            old_layout: vk::ImageLayout::UNDEFINED,
            new_layout: vk::ImageLayout::PRESENT_SRC_KHR,
        };
        self.blits.blit(
            frame,
            &target,
            &[(image_acquired, vk::PipelineStageFlags::TRANSFER)],
            &[ready],
        )?;
        let device = &*self.device;
        let swapchains = [self.raw];
        let indices = [index];
        let waits = [ready];
        let present_info = vk::PresentInfoKHR::default()
            .wait_semaphores(&waits)
            .swapchains(&swapchains)
            .image_indices(&indices);
        let presented = device.with_queue(|queue| {
            // SAFETY: the image was acquired and its blit submitted with `ready` signalled;
            // the queue is reserved for the call.
            unsafe { self.swapchain_fn.queue_present(queue, &present_info) }
        });
        let outcome = match presented {
            Ok(suboptimal) => {
                self.stale |= suboptimal;
                PresentOutcome::Presented
            }
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
                self.stale = true;
                PresentOutcome::Skipped
            }
            Err(error) => return Err(super::error::map_result("vkQueuePresentKHR", error)),
        };
        Ok(outcome)
    }
}

impl Drop for Swapchain {
    fn drop(&mut self) {
        let _ = self.device.wait_idle();
        // SAFETY: the device is idle; every handle is destroyed once, the surface last (after
        // the swapchain made on it).
        unsafe {
            for semaphore in self
                .ready_to_present
                .drain(..)
                .chain(self.image_acquired.drain(..))
            {
                self.device
                    .raw
                    .destroy_semaphore(semaphore, host_callbacks());
            }
            self.swapchain_fn
                .destroy_swapchain(self.raw, host_callbacks());
            // The host created the surface without allocation callbacks (glfwCreateWindowSurface
            // with NULL), so it is destroyed without them.
            self.surface_fn.destroy_surface(self.surface, None);
        }
    }
}
