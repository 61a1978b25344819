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

/// How many planes the buffer holds.
const PLANES: u64 = 4;

/// The keys of one target size.
pub(crate) struct PixelKeys {
    /// The buffer the frame set names at binding 7.
    pub buffer: Buffer,
    /// The target size it was made for.
    pub extent: vk::Extent2D,
}

impl PixelKeys {
    /// Keys for a target of `extent`.
    pub fn new(device: &Arc<Device>, extent: vk::Extent2D) -> RenderResult<Self> {
        let buffer = Buffer::new(
            device,
            "pixel keys",
            (plane_bytes(extent) * PLANES).max(KEY_BYTES),
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        Ok(Self { buffer, extent })
    }

    /// The bytes a frame that uses the outline keys (`outline`), the nearest surfaces
    /// (`nearest_surfaces`) and the cap keys (`cap_keys`) clears, as (offset, size): from the
    /// first plane it uses to the last; none when it uses none.
    pub fn span(
        &self,
        outline: bool,
        nearest_surfaces: bool,
        cap_keys: bool,
    ) -> Option<(u64, u64)> {
        let used = [
            (KeyPlane::Outline, outline),
            (KeyPlane::NearestSurfaces, nearest_surfaces),
            (KeyPlane::Caps, cap_keys),
            (KeyPlane::Uncapped, cap_keys),
        ];
        let mut planes = used
            .iter()
            .filter(|(_, on)| *on)
            .map(|&(plane, _)| plane as u64);
        let first = planes.next()?;
        let last = planes.next_back().unwrap_or(first);
        let bytes = plane_bytes(self.extent);
        Some((first * bytes, (last + 1 - first) * bytes))
    }
}

/// Bytes of one plane: a key per pixel of `extent`.
fn plane_bytes(extent: vk::Extent2D) -> u64 {
    u64::from(extent.width) * u64::from(extent.height) * KEY_BYTES
}
