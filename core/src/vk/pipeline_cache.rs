//! The device's `VkPipelineCache`, kept in the user's disk cache between runs
//! ([`crate::disk_cache`]): loaded when the device is created if it was made by the same
//! device and driver (checked against Vulkan's own cache header before Vulkan sees it), saved
//! when the device is destroyed.

use super::host_memory::core_callbacks as host_callbacks;
use ash::vk;

use crate::disk_cache::DiskCache;

/// The cache kind of pipeline caches.
const PIPELINE_CACHE: &str = "pipelines";
/// Bytes of Vulkan's pipeline cache header (version one).
const VULKAN_HEADER_BYTES: usize = 32;

/// A device's pipeline cache and where it is kept.
pub(super) struct PersistentPipelineCache {
    pub(super) handle: vk::PipelineCache,
    entry: Option<(DiskCache, String)>,
}

/// Whether `data` starts with the header Vulkan writes for this device and driver.
fn matches_device(data: &[u8], properties: &vk::PhysicalDeviceProperties) -> bool {
    let word = |index: usize| {
        data.get(index * 4..index * 4 + 4)
            .and_then(|b| b.try_into().ok())
            .map(u32::from_le_bytes)
    };
    data.len() >= VULKAN_HEADER_BYTES
        && word(0).is_some_and(|size| size as usize >= VULKAN_HEADER_BYTES)
        && word(1) == Some(vk::PipelineCacheHeaderVersion::ONE.as_raw() as u32)
        && word(2) == Some(properties.vendor_id)
        && word(3) == Some(properties.device_id)
        && data[16..32] == properties.pipeline_cache_uuid
}

impl PersistentPipelineCache {
    /// The pipeline cache of a new device: what the disk cache kept for this device and driver,
    /// or empty. Never fails: without a cache, pipelines are built without one.
    pub(super) fn load(device: &ash::Device, properties: &vk::PhysicalDeviceProperties) -> Self {
        let entry = DiskCache::user().map(|cache| {
            let uuid: String = properties
                .pipeline_cache_uuid
                .iter()
                .map(|b| format!("{b:02x}"))
                .collect();
            let name = format!(
                "{:04x}-{:04x}-{uuid}.bin",
                properties.vendor_id, properties.device_id
            );
            (cache, name)
        });
        let initial = entry
            .as_ref()
            .and_then(|(cache, name)| cache.read(PIPELINE_CACHE, name))
            .filter(|data| matches_device(data, properties))
            .unwrap_or_default();
        let create = |data: &[u8]| {
            let info = vk::PipelineCacheCreateInfo::default().initial_data(data);
            // SAFETY: the device is live; the data lives for the call.
            unsafe { device.create_pipeline_cache(&info, host_callbacks()) }
        };
        let handle = create(&initial)
            .or_else(|_| create(&[]))
            .unwrap_or_default();
        Self { handle, entry }
    }

    /// Writes the cache's data to the disk cache and destroys it; the device is idle.
    pub(super) fn save_and_destroy(&mut self, device: &ash::Device) {
        if self.handle == vk::PipelineCache::null() {
            return;
        }
        if let Some((cache, name)) = &self.entry {
            // SAFETY: the cache belongs to this device and no pipeline is being created.
            if let Ok(data) = unsafe { device.get_pipeline_cache_data(self.handle) } {
                cache.write(PIPELINE_CACHE, name, &data);
            }
        }
        // SAFETY: no pipeline creation uses it any more; destroyed once.
        unsafe { device.destroy_pipeline_cache(self.handle, host_callbacks()) };
        self.handle = vk::PipelineCache::null();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_this_devices_header_is_accepted() {
        let mut properties = vk::PhysicalDeviceProperties {
            vendor_id: 0x10de,
            device_id: 0x2330,
            ..Default::default()
        };
        properties.pipeline_cache_uuid = [7; 16];
        let mut data = Vec::new();
        for word in [32u32, 1, 0x10de, 0x2330] {
            data.extend_from_slice(&word.to_le_bytes());
        }
        data.extend_from_slice(&[7; 16]);
        data.extend_from_slice(b"driver data");
        assert!(matches_device(&data, &properties));
        let mut other_driver = data.clone();
        other_driver[20] = 8;
        assert!(!matches_device(&other_driver, &properties));
        let mut other_device = data.clone();
        other_device[12] ^= 1;
        assert!(!matches_device(&other_device, &properties));
        assert!(!matches_device(&data[..31], &properties));
    }
}
