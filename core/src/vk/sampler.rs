//! Samplers: how shaders filter the images they sample.

use std::sync::Arc;

use ash::vk;

use super::device::Device;
use super::error::{VkResult, VkResultExt};
use super::host_memory::core_callbacks as host_callbacks;

/// A sampler that blends mip levels when minifying and clamps to the edge (shaders that repeat
/// or mirror wrap the coordinates themselves, which keeps one sampler for every wrap mode);
/// destroyed on drop.
pub struct Sampler {
    device: Arc<Device>,
    raw: vk::Sampler,
}

impl Sampler {
    /// A trilinear sampler; with `magnify_nearest`, magnification picks the nearest texel.
    pub fn new(device: &Arc<Device>, name: &str, magnify_nearest: bool) -> VkResult<Self> {
        let magnify = if magnify_nearest {
            vk::Filter::NEAREST
        } else {
            vk::Filter::LINEAR
        };
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(magnify)
            .min_filter(vk::Filter::LINEAR)
            .mipmap_mode(vk::SamplerMipmapMode::LINEAR)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .max_lod(vk::LOD_CLAMP_NONE);
        // SAFETY: the info lives for the call.
        let raw = unsafe { device.raw().create_sampler(&info, host_callbacks()) }
            .or_vk("vkCreateSampler")?;
        device.set_name(raw, name);
        Ok(Self {
            device: Arc::clone(device),
            raw,
        })
    }

    /// The Vulkan sampler.
    pub fn raw(&self) -> vk::Sampler {
        self.raw
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        // SAFETY: owners drop samplers after the GPU is done with the sets naming them.
        unsafe {
            self.device
                .raw()
                .destroy_sampler(self.raw, host_callbacks())
        };
    }
}
