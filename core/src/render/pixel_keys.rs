//! The per-pixel keys: a storage buffer of planes of one `uint` per pixel of the target (frame
//! set binding 7, `shaders/pixel_keys.glsl`), which the surface shaders fill with `atomicMin`
//! and the passes over the finished picture read: each key is the nearest surface's depth and
//! whether it is a highlighted part's. Plane 0 holds the highlight outline style's keys
//! (`shaders/outline.frag` draws the band from them); plane 1 the nearest surfaces, translucent
//! ones included, from which `shaders/silhouettes.frag` finds X-ray's silhouettes and draws
//! those of highlighted parts in the highlight's line colour; planes 2 and 3 the cap keys, the
//! nearest opaque fragments that show a section cap and that do not, from which
//! `shaders/cap_ties.frag` paints the caps that tie with another part's surface. Recording
//! needs the device's `fragmentStoresAndAtomics`.

use std::sync::Arc;

use crate::error::RenderResult;
use crate::vk::raw as vk;
use crate::vk::{Buffer, Device, MemoryLocation};

/// Bytes of one key (a `uint` per pixel).
const KEY_BYTES: u64 = 4;

/// The value a cleared key holds: no surface drawn there.
pub(crate) const NO_SURFACE: u32 = u32::MAX;

/// A plane of the keys (its index is the shaders' `CADR_*_PLANE`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum KeyPlane {
    /// The highlight outline style's keys.
    Outline = 0,
    /// The nearest surfaces (the silhouettes').
    NearestSurfaces = 1,
    /// The nearest fragments that show a section cap (the cap ties').
    Caps = 2,
    /// The nearest fragments that do not (the cap ties').
    Uncapped = 3,
}

/// The planes a frame uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct KeyUse {
    /// The outline keys (the outline highlight style).
    pub outline: bool,
    /// The nearest surfaces (the silhouettes').
    pub nearest_surfaces: bool,
    /// The cap keys, two planes (the cap ties').
    pub cap_keys: bool,
}

impl KeyUse {
    /// The first and the last plane used, if any.
    fn planes(self) -> Option<(u64, u64)> {
        let used = [
            (KeyPlane::Outline, self.outline),
            (KeyPlane::NearestSurfaces, self.nearest_surfaces),
            (KeyPlane::Caps, self.cap_keys),
            (KeyPlane::Uncapped, self.cap_keys),
        ];
        let mut planes = used
            .iter()
            .filter(|(_, on)| *on)
            .map(|&(plane, _)| plane as u64);
        let first = planes.next()?;
        Some((first, planes.next_back().unwrap_or(first)))
    }

    /// How many planes a buffer needs for this use (up to the last used), if any.
    pub fn plane_count(self) -> Option<u64> {
        self.planes().map(|(_, last)| last + 1)
    }
}

/// The keys of one target size, as many planes as the frames so far needed.
pub(crate) struct PixelKeys {
    /// The buffer the frame set names at binding 7.
    pub buffer: Buffer,
    /// The target size it was made for.
    pub extent: vk::Extent2D,
    /// The planes it holds.
    planes: u64,
}

impl PixelKeys {
    /// Keys of `planes` planes for a target of `extent`.
    pub fn new(device: &Arc<Device>, extent: vk::Extent2D, planes: u64) -> RenderResult<Self> {
        let buffer = Buffer::new(
            device,
            "pixel keys",
            (plane_bytes(extent) * planes).max(KEY_BYTES),
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        Ok(Self {
            buffer,
            extent,
            planes,
        })
    }

    /// The planes it holds.
    pub fn planes(&self) -> u64 {
        self.planes
    }

    /// Whether these keys serve a target of `extent` with `planes` planes.
    pub fn holds(&self, extent: vk::Extent2D, planes: u64) -> bool {
        self.extent == extent && self.planes >= planes
    }

    /// The bytes a frame of `key_use` clears, as (offset, size): from the first plane it uses
    /// to the last; none when it uses none.
    pub fn span(&self, key_use: KeyUse) -> Option<(u64, u64)> {
        let (first, last) = key_use.planes()?;
        let bytes = plane_bytes(self.extent);
        Some((first * bytes, (last + 1 - first) * bytes))
    }
}

/// Bytes of one plane: a key per pixel of `extent`.
fn plane_bytes(extent: vk::Extent2D) -> u64 {
    u64::from(extent.width) * u64::from(extent.height) * KEY_BYTES
}

#[cfg(test)]
mod tests {
    use super::KeyUse;

    #[test]
    fn a_buffer_holds_the_planes_up_to_the_last_used() {
        let outline = KeyUse {
            outline: true,
            ..KeyUse::default()
        };
        let nearest = KeyUse {
            nearest_surfaces: true,
            ..KeyUse::default()
        };
        let caps = KeyUse {
            cap_keys: true,
            ..KeyUse::default()
        };
        assert_eq!(KeyUse::default().plane_count(), None);
        assert_eq!(outline.plane_count(), Some(1));
        assert_eq!(nearest.plane_count(), Some(2));
        assert_eq!(caps.plane_count(), Some(4));
        assert_eq!(nearest.planes(), Some((1, 1)));
        assert_eq!(caps.planes(), Some((2, 3)));
        let both = KeyUse {
            outline: true,
            cap_keys: true,
            ..KeyUse::default()
        };
        assert_eq!(both.planes(), Some((0, 3)));
    }
}
