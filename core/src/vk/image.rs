//! Images: attachments, textures, their layout transitions and readback.

use super::host_memory::core_callbacks as host_callbacks;
use std::sync::Arc;

use ash::vk;
use gpu_allocator::vulkan::Allocation;
use gpu_allocator::MemoryLocation;

use super::buffer::Buffer;
use super::command::OneShot;
use super::device::Device;
use super::error::{VkError, VkResult, VkResultExt};

/// A 2D image with one view; freed on drop.
pub struct Image {
    device: Arc<Device>,
    raw: vk::Image,
    view: vk::ImageView,
    allocation: Option<Allocation>,
    format: vk::Format,
    extent: vk::Extent2D,
    samples: u32,
}

impl Image {
    /// Creates a device-local 2D image with one mip level and a view of it.
    pub fn new(
        device: &Arc<Device>,
        name: &str,
        extent: vk::Extent2D,
        format: vk::Format,
        usage: vk::ImageUsageFlags,
        aspect: vk::ImageAspectFlags,
    ) -> VkResult<Self> {
        Self::multisampled(device, name, (extent, 1), format, usage, aspect)
    }

    /// Creates a device-local 2D image of `samples` samples per pixel (1, or a count from
    /// [`Device::sample_counts`]: an attachment that is resolved into a one-sample image),
    /// with one mip level and a view of it.
    pub fn multisampled(
        device: &Arc<Device>,
        name: &str,
        (extent, samples): (vk::Extent2D, u32),
        format: vk::Format,
        usage: vk::ImageUsageFlags,
        aspect: vk::ImageAspectFlags,
    ) -> VkResult<Self> {
        let shape = ImageShape {
            extent,
            samples,
            layers: 1,
            mips: 1,
            array_view: false,
        };
        Self::create(device, name, shape, format, usage, aspect)
    }

    /// Creates a device-local 2D image of any [`ImageShape`] and a view of all of it (a 2D
    /// array view when it has several layers).
    fn create(
        device: &Arc<Device>,
        name: &str,
        shape: ImageShape,
        format: vk::Format,
        usage: vk::ImageUsageFlags,
        aspect: vk::ImageAspectFlags,
    ) -> VkResult<Self> {
        let ImageShape {
            extent,
            samples,
            layers,
            mips,
            ..
        } = shape;
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D {
                width: extent.width,
                height: extent.height,
                depth: 1,
            })
            .mip_levels(mips)
            .array_layers(layers)
            .samples(vk::SampleCountFlags::from_raw(samples))
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: info is valid and lives until the call returns.
        let raw =
            unsafe { device.raw.create_image(&info, host_callbacks()) }.or_vk("vkCreateImage")?;
        let mut image = Self {
            device: Arc::clone(device),
            raw,
            view: vk::ImageView::null(),
            allocation: None,
            format,
            extent,
            samples,
        };
        // SAFETY: raw is a live image of this device.
        let requirements = unsafe { device.raw.get_image_memory_requirements(raw) };
        let allocation = device.allocate(name, requirements, MemoryLocation::GpuOnly, false)?;
        // SAFETY: the allocation satisfies the image's requirements.
        let bound = unsafe {
            device
                .raw
                .bind_image_memory(raw, allocation.memory(), allocation.offset())
        };
        image.allocation = Some(allocation);
        bound.or_vk("vkBindImageMemory")?;
        let view_type = if shape.array_view || layers > 1 {
            vk::ImageViewType::TYPE_2D_ARRAY
        } else {
            vk::ImageViewType::TYPE_2D
        };
        let view_info = vk::ImageViewCreateInfo::default()
            .image(raw)
            .view_type(view_type)
            .format(format)
            .subresource_range(
                subresource_range(aspect)
                    .level_count(mips)
                    .layer_count(layers),
            );
        // SAFETY: the image is bound to memory; view_info matches it.
        image.view = unsafe { device.raw.create_image_view(&view_info, host_callbacks()) }
            .or_vk("vkCreateImageView")?;
        device.set_name(raw, name);
        device.set_name(image.view, &format!("{name} view"));
        Ok(image)
    }

    /// Creates an RGBA8 image holding `pixels` (tightly packed rows), uploaded through a
    /// staging buffer and left in `SHADER_READ_ONLY_OPTIMAL` for sampling.
    pub fn with_rgba8(
        device: &Arc<Device>,
        name: &str,
        extent: vk::Extent2D,
        pixels: &[u8],
        usage: vk::ImageUsageFlags,
    ) -> VkResult<Self> {
        let shape = ImageShape {
            extent,
            samples: 1,
            layers: 1,
            mips: 1,
            array_view: false,
        };
        Self::with_texels(
            device,
            name,
            (shape, vk::Format::R8G8B8A8_UNORM),
            pixels,
            usage,
        )
    }

    /// Creates a sampled image of a 4-byte-per-texel `format` holding `texels`, uploaded
    /// through a staging buffer and left in `SHADER_READ_ONLY_OPTIMAL`: layer by layer, each
    /// layer's mip levels from the largest, each level's rows tightly packed (level `m` is
    /// `max(1, width >> m)` × `max(1, height >> m)`).
    pub fn with_texels(
        device: &Arc<Device>,
        name: &str,
        (shape, format): (ImageShape, vk::Format),
        texels: &[u8],
        usage: vk::ImageUsageFlags,
    ) -> VkResult<Self> {
        let mut images = Self::many_with_texels(
            device,
            &[TexelImage {
                name,
                shape,
                format,
                texels,
            }],
            usage,
        )?;
        images
            .pop()
            .ok_or_else(|| VkError::InvalidUse(format!("image '{name}' was not made")))
    }

    /// Creates the sampled images `requests` describe, as [`Image::with_texels`] does one,
    /// through one staging buffer and one submission.
    pub fn many_with_texels(
        device: &Arc<Device>,
        requests: &[TexelImage<'_>],
        usage: vk::ImageUsageFlags,
    ) -> VkResult<Vec<Self>> {
        if requests.is_empty() {
            return Ok(Vec::new());
        }
        let mut images = Vec::with_capacity(requests.len());
        let mut regions = Vec::with_capacity(requests.len());
        let mut staged = 0u64;
        for request in requests {
            let shape = request.shape;
            let mut image_regions = shape.texel_regions();
            let expected = image_regions.last().map_or(0, |r| {
                r.buffer_offset
                    + u64::from(r.image_extent.width) * u64::from(r.image_extent.height) * 4
            });
            if request.texels.len() as u64 != expected {
                return Err(VkError::InvalidUse(format!(
                    "image '{}': {} bytes of texels for {}x{}, {} layers of {} mip levels at 4 bytes a texel (needs {expected})",
                    request.name,
                    request.texels.len(),
                    shape.extent.width,
                    shape.extent.height,
                    shape.layers,
                    shape.mips
                )));
            }
            for region in &mut image_regions {
                region.buffer_offset += staged;
            }
            staged += expected;
            regions.push(image_regions);
            images.push(Self::create(
                device,
                request.name,
                shape,
                request.format,
                usage | vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::SAMPLED,
                vk::ImageAspectFlags::COLOR,
            )?);
        }
        let name = requests[0].name;
        let mut staging = Buffer::new(
            device,
            &format!("{name} (staging)"),
            staged,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        let mut offset = 0u64;
        for request in requests {
            staging.write(offset, request.texels)?;
            offset += request.texels.len() as u64;
        }
        let mut one_shot = OneShot::begin(device, "image upload")?;
        let command_buffer = one_shot.command_buffer();
        for ((image, request), image_regions) in images.iter().zip(requests).zip(&regions) {
            let whole = subresource_range(vk::ImageAspectFlags::COLOR)
                .level_count(request.shape.mips)
                .layer_count(request.shape.layers);
            transition_range(
                device,
                command_buffer,
                (image.raw, whole),
                (
                    vk::ImageLayout::UNDEFINED,
                    vk::PipelineStageFlags2::TOP_OF_PIPE,
                    vk::AccessFlags2::NONE,
                ),
                (
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    vk::PipelineStageFlags2::COPY,
                    vk::AccessFlags2::TRANSFER_WRITE,
                ),
            );
            // SAFETY: the image is in TRANSFER_DST_OPTIMAL; the regions lie inside both
            // resources, which outlive the submission, waited for below.
            unsafe {
                device.raw.cmd_copy_buffer_to_image(
                    command_buffer,
                    staging.raw(),
                    image.raw,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    image_regions,
                )
            };
            transition_range(
                device,
                command_buffer,
                (image.raw, whole),
                (
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    vk::PipelineStageFlags2::COPY,
                    vk::AccessFlags2::TRANSFER_WRITE,
                ),
                (
                    vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                    vk::PipelineStageFlags2::VERTEX_SHADER
                        | vk::PipelineStageFlags2::FRAGMENT_SHADER,
                    vk::AccessFlags2::SHADER_SAMPLED_READ,
                ),
            );
        }
        one_shot.submit_and_wait()?;
        Ok(images)
    }

    /// The device that owns the image.
    pub fn device(&self) -> &Arc<Device> {
        &self.device
    }

    /// The Vulkan image.
    pub fn raw(&self) -> vk::Image {
        self.raw
    }

    /// The image view.
    pub fn view(&self) -> vk::ImageView {
        self.view
    }

    /// The pixel format.
    pub fn format(&self) -> vk::Format {
        self.format
    }

    /// Width and height.
    pub fn extent(&self) -> vk::Extent2D {
        self.extent
    }

    /// Samples per pixel (1 for an image that is not multisampled).
    pub fn samples(&self) -> u32 {
        self.samples
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        // SAFETY: owners wait for the GPU before dropping images; handles are destroyed once.
        unsafe {
            self.device
                .raw
                .destroy_image_view(self.view, host_callbacks());
            self.device.raw.destroy_image(self.raw, host_callbacks());
        }
        if let Some(allocation) = self.allocation.take() {
            self.device.free(allocation);
        }
    }
}

/// The whole of a single-mip, single-layer image.
pub fn subresource_range(aspect: vk::ImageAspectFlags) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange::default()
        .aspect_mask(aspect)
        .level_count(1)
        .layer_count(1)
}

/// Records a global memory barrier: writes of `src` (stages, accesses) before it become
/// visible to the accesses of `dst` after it.
pub fn memory_barrier(
    device: &Device,
    command_buffer: vk::CommandBuffer,
    (src_stage, src_access): (vk::PipelineStageFlags2, vk::AccessFlags2),
    (dst_stage, dst_access): (vk::PipelineStageFlags2, vk::AccessFlags2),
) {
    let memory = [vk::MemoryBarrier2::default()
        .src_stage_mask(src_stage)
        .src_access_mask(src_access)
        .dst_stage_mask(dst_stage)
        .dst_access_mask(dst_access)];
    let dependency = vk::DependencyInfo::default().memory_barriers(&memory);
    // SAFETY: command_buffer is recording, outside rendering.
    unsafe {
        device
            .raw
            .cmd_pipeline_barrier2(command_buffer, &dependency)
    };
}

/// An image layout transition with synchronization2 (of the first mip level and layer).
pub fn transition(
    device: &Device,
    command_buffer: vk::CommandBuffer,
    image: vk::Image,
    aspect: vk::ImageAspectFlags,
    old: (vk::ImageLayout, vk::PipelineStageFlags2, vk::AccessFlags2),
    new: (vk::ImageLayout, vk::PipelineStageFlags2, vk::AccessFlags2),
) {
    transition_range(
        device,
        command_buffer,
        (image, subresource_range(aspect)),
        old,
        new,
    );
}

/// A layout transition of `range` of an image with synchronization2.
pub fn transition_range(
    device: &Device,
    command_buffer: vk::CommandBuffer,
    (image, range): (vk::Image, vk::ImageSubresourceRange),
    (old_layout, src_stage, src_access): (
        vk::ImageLayout,
        vk::PipelineStageFlags2,
        vk::AccessFlags2,
    ),
    (new_layout, dst_stage, dst_access): (
        vk::ImageLayout,
        vk::PipelineStageFlags2,
        vk::AccessFlags2,
    ),
) {
    let barrier = [vk::ImageMemoryBarrier2::default()
        .src_stage_mask(src_stage)
        .src_access_mask(src_access)
        .dst_stage_mask(dst_stage)
        .dst_access_mask(dst_access)
        .old_layout(old_layout)
        .new_layout(new_layout)
        .image(image)
        .subresource_range(range)];
    let dependency = vk::DependencyInfo::default().image_memory_barriers(&barrier);
    // SAFETY: command_buffer is recording; image is alive for the command buffer's lifetime.
    unsafe {
        device
            .raw
            .cmd_pipeline_barrier2(command_buffer, &dependency)
    };
}

/// Records a copy of the pixels `(x, y, width, height)` of `image` (in TRANSFER_SRC_OPTIMAL,
/// one aspect: colour, or depth for a depth format) into `buffer` at `offset`, tightly packed.
pub fn record_image_copy(
    device: &Device,
    command_buffer: vk::CommandBuffer,
    image: &Image,
    (x, y, width, height): (u32, u32, u32, u32),
    buffer: &Buffer,
    offset: u64,
) {
    record_image_copy_into(
        device,
        command_buffer,
        image,
        (x, y, width, height),
        buffer.raw(),
        offset,
    );
}

/// [`record_image_copy`] into a buffer made outside cadr's allocator (an exported one).
pub(super) fn record_image_copy_into(
    device: &Device,
    command_buffer: vk::CommandBuffer,
    image: &Image,
    (x, y, width, height): (u32, u32, u32, u32),
    buffer: vk::Buffer,
    offset: u64,
) {
    let aspect = copied_aspect(image.format());
    let region = [vk::BufferImageCopy::default()
        .buffer_offset(offset)
        .image_subresource(
            vk::ImageSubresourceLayers::default()
                .aspect_mask(aspect)
                .layer_count(1),
        )
        .image_offset(vk::Offset3D {
            x: x as i32,
            y: y as i32,
            z: 0,
        })
        .image_extent(vk::Extent3D {
            width,
            height,
            depth: 1,
        })];
    // SAFETY: the caller records outside rendering with the image in TRANSFER_SRC_OPTIMAL; the
    // region lies inside the image and the buffer (the caller sized both), and both outlive
    // the submission.
    unsafe {
        device.raw().cmd_copy_image_to_buffer(
            command_buffer,
            image.raw(),
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            buffer,
            &region,
        )
    };
}

/// The color format of offscreen targets: 8-bit RGBA, read back as is.
pub const COLOR_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;
/// The depth format of offscreen targets.
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

/// One image for [`Image::many_with_texels`].
#[derive(Clone, Copy, Debug)]
pub struct TexelImage<'a> {
    /// Its debug name.
    pub name: &'a str,
    /// Its size, layers and mips.
    pub shape: ImageShape,
    /// A 4-byte-per-texel format.
    pub format: vk::Format,
    /// The texels, laid out as [`Image::with_texels`] takes them.
    pub texels: &'a [u8],
}

/// The size, samples, layers and mip levels of an image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageShape {
    /// Width and height of mip level 0.
    pub extent: vk::Extent2D,
    /// Samples per pixel (1 unless it is a multisampled attachment).
    pub samples: u32,
    /// Array layers.
    pub layers: u32,
    /// Mip levels.
    pub mips: u32,
    /// Whether its view is a 2D array (shaders sample it as `sampler2DArray`), whatever the
    /// layer count.
    pub array_view: bool,
}

impl ImageShape {
    /// The copy regions of texels laid out as [`Image::with_texels`] takes them, 4 bytes each.
    fn texel_regions(&self) -> Vec<vk::BufferImageCopy> {
        let mut offset = 0u64;
        let mut regions = Vec::new();
        for layer in 0..self.layers {
            for mip in 0..self.mips {
                let width = (self.extent.width >> mip).max(1);
                let height = (self.extent.height >> mip).max(1);
                regions.push(
                    vk::BufferImageCopy::default()
                        .buffer_offset(offset)
                        .image_subresource(
                            vk::ImageSubresourceLayers::default()
                                .aspect_mask(vk::ImageAspectFlags::COLOR)
                                .mip_level(mip)
                                .base_array_layer(layer)
                                .layer_count(1),
                        )
                        .image_extent(vk::Extent3D {
                            width,
                            height,
                            depth: 1,
                        }),
                );
                offset += u64::from(width) * u64::from(height) * 4;
            }
        }
        regions
    }
}

/// The aspect a copy of `format`'s texels reads: the depth of the depth format, else colour.
fn copied_aspect(format: vk::Format) -> vk::ImageAspectFlags {
    if format == DEPTH_FORMAT {
        vk::ImageAspectFlags::DEPTH
    } else {
        vk::ImageAspectFlags::COLOR
    }
}

fn full_copy_region(extent: vk::Extent2D, aspect: vk::ImageAspectFlags) -> vk::BufferImageCopy {
    vk::BufferImageCopy::default()
        .image_subresource(
            vk::ImageSubresourceLayers::default()
                .aspect_mask(aspect)
                .layer_count(1),
        )
        .image_extent(vk::Extent3D {
            width: extent.width,
            height: extent.height,
            depth: 1,
        })
}

/// Copies a one-sample `image` of 4 bytes per texel (RGBA8, or the depth format's 32-bit
/// floats) that is in `layout` (and has TRANSFER_SRC usage) to the host as tightly packed
/// rows; the image is back in `layout` afterwards.
pub fn read_image(
    device: &Arc<Device>,
    image: &Image,
    layout: vk::ImageLayout,
) -> VkResult<Vec<u8>> {
    let extent = image.extent();
    let aspect = copied_aspect(image.format());
    let size = u64::from(extent.width) * u64::from(extent.height) * 4;
    let readback = Buffer::new(
        device,
        "image readback",
        size,
        vk::BufferUsageFlags::TRANSFER_DST,
        MemoryLocation::GpuToCpu,
    )?;
    let mut one_shot = OneShot::begin(device, "image readback")?;
    let command_buffer = one_shot.command_buffer();
    let source_layout = vk::ImageLayout::TRANSFER_SRC_OPTIMAL;
    let all = (
        vk::PipelineStageFlags2::ALL_COMMANDS,
        vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE,
    );
    if layout != source_layout {
        transition(
            device,
            command_buffer,
            image.raw(),
            aspect,
            (layout, all.0, all.1),
            (
                source_layout,
                vk::PipelineStageFlags2::COPY,
                vk::AccessFlags2::TRANSFER_READ,
            ),
        );
    }
    let region = [full_copy_region(extent, aspect)];
    // SAFETY: the image is in TRANSFER_SRC_OPTIMAL; both resources outlive the submission,
    // which is waited for below.
    unsafe {
        device.raw.cmd_copy_image_to_buffer(
            command_buffer,
            image.raw(),
            source_layout,
            readback.raw(),
            &region,
        )
    };
    if layout != source_layout {
        transition(
            device,
            command_buffer,
            image.raw(),
            aspect,
            (
                source_layout,
                vk::PipelineStageFlags2::COPY,
                vk::AccessFlags2::TRANSFER_READ,
            ),
            (layout, all.0, all.1),
        );
    }
    one_shot.submit_and_wait()?;
    Ok(readback.mapped()?.to_vec())
}
