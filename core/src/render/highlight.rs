//! How highlighted parts (selection feedback) are shown: tinted towards the highlight colour,
//! or outlined by a band in that colour around them, their own colours kept. The outline
//! style's surfaces record per pixel the nearest surface's depth and whether it is highlighted
//! (the outline keys, binding 7 of the frame set, `shaders/outline.glsl`); after the rendering
//! `shaders/outline.frag` draws the band where a pixel not highlighted lies near one that is.

use std::sync::Arc;

use crate::error::RenderResult;
use crate::vk::raw as vk;
use crate::vk::{Buffer, Device, MemoryLocation};

/// How highlighted parts are drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum HighlightStyle {
    /// Their colour mixed towards the highlight colour (the default).
    #[default]
    Tint,
    /// Their own colours, with a band in the highlight colour around them. Needs the
    /// device's `fragmentStoresAndAtomics`.
    Outline,
}

impl HighlightStyle {
    /// Every style.
    pub const ALL: [HighlightStyle; 2] = [HighlightStyle::Tint, HighlightStyle::Outline];

    /// Its name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            HighlightStyle::Tint => "tint",
            HighlightStyle::Outline => "outline",
        }
    }

    /// Parses a command-line name.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|s| s.name() == name)
    }
}

/// Bytes of one outline key (a `uint` per pixel).
const KEY_BYTES: u64 = 4;

/// The value a cleared key holds: no surface drawn there.
pub(crate) const NO_SURFACE: u32 = u32::MAX;

/// The outline keys of one target size: a storage buffer of a key per pixel.
pub(crate) struct OutlineKeys {
    /// The buffer the frame set names at binding 7.
    pub buffer: Buffer,
    /// The target size it was made for.
    pub extent: vk::Extent2D,
}

impl OutlineKeys {
    /// Keys for a target of `extent`.
    pub fn new(device: &Arc<Device>, extent: vk::Extent2D) -> RenderResult<Self> {
        let pixels = u64::from(extent.width) * u64::from(extent.height);
        let buffer = Buffer::new(
            device,
            "outline keys",
            pixels.max(1) * KEY_BYTES,
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        Ok(Self { buffer, extent })
    }

    /// Bytes cleared every frame: every key.
    pub fn bytes(&self) -> u64 {
        u64::from(self.extent.width) * u64::from(self.extent.height) * KEY_BYTES
    }
}

#[cfg(test)]
mod tests {
    use super::HighlightStyle;

    #[test]
    fn styles_parse_by_name() {
        for style in HighlightStyle::ALL {
            assert_eq!(HighlightStyle::parse(style.name()), Some(style));
        }
        assert_eq!(HighlightStyle::parse("glow"), None);
        assert_eq!(HighlightStyle::default(), HighlightStyle::Tint);
    }
}
