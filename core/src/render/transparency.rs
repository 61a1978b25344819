//! What a frame with translucent surfaces needs besides its picture: the transparency method's
//! colour targets at the frame's size, its storage buffer (part of the frame set, binding 1)
//! and the merge's descriptor set that reads the targets. Made when a method or size first
//! needs them, kept while both stay the same; the targets and storage are shared by the
//! renderers of one device that draw with the same method at the same size, as the depth is
//! (`vk/offscreen.rs`).

use std::sync::Arc;

use crate::error::RenderResult;
use crate::shaders;
use crate::vk::raw as vk;
use crate::vk::{
    Buffer, DescriptorSetLayout, DescriptorSets, Device, Image, MemoryLocation, Shared,
};
use cadr_plugin_abi as abi;

/// A transparency method as its technique described it (`CadrTransparencyMethod`), owned.
#[derive(Clone, Debug, PartialEq)]
pub struct TransparencyMethod {
    /// The technique's name (shaders are compiled once per method).
    pub name: String,
    /// Its colour targets.
    pub targets: Vec<abi::CadrTransparencyTarget>,
    /// Storage words at the start, zeroed every frame.
    pub storage_header_words: u32,
    /// Storage words per pixel.
    pub storage_words_per_pixel: u32,
    /// Of those, zeroed every frame.
    pub storage_cleared_words_per_pixel: u32,
    /// Defines `cadr_transparent_fragment`.
    pub fragment_snippet: String,
    /// Defines `cadr_merge`.
    pub merge_snippet: String,
}

impl TransparencyMethod {
    /// `template` with the method's declarations, the device's `defines` and `snippet`
    /// pasted in.
    pub(crate) fn assemble(
        &self,
        template: &shaders::ShaderSource,
        snippet: &str,
        defines: &str,
    ) -> String {
        let mut defines = format!(
            "{defines}#define CADR_TARGET_COUNT {}\n",
            self.targets.len()
        );
        if self.storage_words_per_pixel > 0 || self.storage_header_words > 0 {
            defines.push_str("#define CADR_STORAGE\n");
        }
        shaders::with_defines(template.source, &defines)
            .replace(shaders::TRANSPARENCY_MARKER, snippet)
    }

    /// Bytes of storage for `pixels`, and of those the bytes zeroed every frame.
    pub fn storage_bytes(&self, pixels: u64) -> (u64, u64) {
        let header = u64::from(self.storage_header_words);
        let total = header + u64::from(self.storage_words_per_pixel) * pixels;
        let cleared = header + u64::from(self.storage_cleared_words_per_pixel) * pixels;
        (total * 4, cleared.min(total) * 4)
    }

    /// The targets' formats.
    pub fn target_formats(&self) -> Vec<vk::Format> {
        self.targets
            .iter()
            .map(|t| vk::Format::from_raw(t.format))
            .collect()
    }
}

/// The smallest storage buffer: what binding 1 of the frame set holds when no method needs
/// storage (a binding must name a buffer).
pub(crate) const PLACEHOLDER_STORAGE_BYTES: u64 = 16;

/// The targets and storage of one transparency method at one size and sample count: what
/// the renderers of one device that draw with that method at that size share (a frame clears
/// the targets and zeroes the storage before it draws translucent surfaces, and is done with
/// them when it ends).
pub(crate) struct TransparencyAttachments {
    /// The device they are on.
    device: Arc<Device>,
    /// What they were made for: the method's name (a kind's names are unique, and a method
    /// describes itself once), the target size and its samples per pixel.
    made_for: (String, vk::Extent2D, u32),
    /// The method's colour targets (one sample: what the merge reads).
    pub images: Vec<Image>,
    /// With MSAA, the multisampled targets the translucent pass draws into, resolved into
    /// `images` at the end of the pass; empty otherwise.
    pub multisampled_images: Vec<Image>,
    /// Their clear values.
    pub clears: Vec<vk::ClearColorValue>,
    /// The storage buffer (at least [`PLACEHOLDER_STORAGE_BYTES`]).
    pub storage: Buffer,
    /// The bytes of it zeroed every frame.
    pub cleared_bytes: u64,
}

/// The shared attachments of every device.
static SHARED_ATTACHMENTS: Shared<TransparencyAttachments> = Shared::new();

impl TransparencyAttachments {
    /// Whether these were made for `method` at `extent` with `samples` per pixel.
    fn fit(&self, method: &TransparencyMethod, extent: vk::Extent2D, samples: u32) -> bool {
        self.made_for.0 == method.name && self.made_for.1 == extent && self.made_for.2 == samples
    }

    /// The device's attachments of `method` at `extent` with `samples` per pixel, made unless
    /// another renderer holds them.
    fn shared(
        device: &Arc<Device>,
        method: &TransparencyMethod,
        (extent, samples): (vk::Extent2D, u32),
    ) -> RenderResult<Arc<Self>> {
        SHARED_ATTACHMENTS.get_or_make(
            |held| Arc::ptr_eq(&held.device, device) && held.fit(method, extent, samples),
            || Self::new(device, method, (extent, samples)),
        )
    }

    /// Makes the targets and storage of `method` at `extent` with `samples` per pixel.
    fn new(
        device: &Arc<Device>,
        method: &TransparencyMethod,
        (extent, samples): (vk::Extent2D, u32),
    ) -> RenderResult<Self> {
        let images = method
            .target_formats()
            .into_iter()
            .enumerate()
            .map(|(i, format)| {
                Image::new(
                    device,
                    &format!("transparency target {i}"),
                    extent,
                    format,
                    vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED,
                    vk::ImageAspectFlags::COLOR,
                )
            })
            .collect::<Result<Vec<_>, _>>()?;
        let multisampled_images = if samples > 1 {
            method
                .target_formats()
                .into_iter()
                .enumerate()
                .map(|(i, format)| {
                    Image::multisampled(
                        device,
                        &format!("transparency target {i} (multisampled)"),
                        (extent, samples),
                        format,
                        vk::ImageUsageFlags::COLOR_ATTACHMENT,
                        vk::ImageAspectFlags::COLOR,
                    )
                })
                .collect::<Result<Vec<_>, _>>()?
        } else {
            Vec::new()
        };
        let clears = method
            .targets
            .iter()
            .map(|t| vk::ClearColorValue { float32: t.clear })
            .collect();
        let pixels = u64::from(extent.width) * u64::from(extent.height);
        let (bytes, cleared_bytes) = method.storage_bytes(pixels);
        Ok(Self {
            device: Arc::clone(device),
            made_for: (method.name.clone(), extent, samples),
            images,
            multisampled_images,
            clears,
            storage: storage_buffer(device, bytes)?,
            cleared_bytes,
        })
    }
}

/// What a renderer draws translucent surfaces with: the shared attachments of its method and
/// size, and its own merge set naming them.
pub(crate) struct TransparencyTargets {
    /// The targets and storage, shared with the device's other renderers of the same method,
    /// size and samples.
    pub attachments: Arc<TransparencyAttachments>,
    /// The merge's set 1: the targets.
    pub merge_set: DescriptorSets,
}

impl TransparencyTargets {
    /// Whether these were made for `method` at `extent` with `samples` per pixel.
    pub fn fit(&self, method: &TransparencyMethod, extent: vk::Extent2D, samples: u32) -> bool {
        self.attachments.fit(method, extent, samples)
    }

    /// The targets and storage of `method` at `extent` with `samples` per pixel (the device's
    /// shared ones) and a merge set naming them.
    pub fn new(
        device: &Arc<Device>,
        method: &TransparencyMethod,
        (extent, samples): (vk::Extent2D, u32),
        merge_set_layout: &DescriptorSetLayout,
    ) -> RenderResult<Self> {
        let attachments = TransparencyAttachments::shared(device, method, (extent, samples))?;
        let merge_set = DescriptorSets::new(device, "transparency merge", &[merge_set_layout])?;
        for (binding, image) in attachments.images.iter().enumerate() {
            merge_set.write_sampled_image(0, binding as u32, image.view());
        }
        Ok(Self {
            attachments,
            merge_set,
        })
    }
}

/// A storage buffer of `bytes` (at least the placeholder's), zeroed by transfers.
pub(crate) fn storage_buffer(device: &Arc<Device>, bytes: u64) -> RenderResult<Buffer> {
    Ok(Buffer::new(
        device,
        "transparency storage",
        bytes.max(PLACEHOLDER_STORAGE_BYTES),
        vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
        MemoryLocation::GpuOnly,
    )?)
}
