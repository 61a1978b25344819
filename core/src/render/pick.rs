//! The pick pass's target: instance ids (+1, 0 for nothing) in an R32_UINT image drawn with the
//! frame's depth, and the readback of a rectangle of ids and depths after the pass.

use std::sync::Arc;

use crate::error::RenderResult;
use crate::vk::raw as vk;

use super::frame_pipelines::PICK_FORMAT;
use crate::vk::{record_image_copy, Buffer, Device, Image, MemoryLocation};

/// A rectangle of pixels, x to the right and y down from the top-left corner.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelRect {
    /// Left column.
    pub x: u32,
    /// Top row.
    pub y: u32,
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
}

impl PixelRect {
    /// The rectangle of one pixel.
    pub fn pixel(x: u32, y: u32) -> Self {
        Self {
            x,
            y,
            width: 1,
            height: 1,
        }
    }

    /// The rectangle spanned by two corner pixels (both included), in any order.
    pub fn spanning((x1, y1): (u32, u32), (x2, y2): (u32, u32)) -> Self {
        Self {
            x: x1.min(x2),
            y: y1.min(y2),
            width: x1.abs_diff(x2) + 1,
            height: y1.abs_diff(y2) + 1,
        }
    }
}

impl std::fmt::Display for PixelRect {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.width == 0 || self.height == 0 {
            write!(f, "an empty rectangle at ({}, {})", self.x, self.y)
        } else if self.width == 1 && self.height == 1 {
            write!(f, "({}, {})", self.x, self.y)
        } else {
            write!(
                f,
                "({}, {})..({}, {})",
                self.x,
                self.y,
                u64::from(self.x) + u64::from(self.width) - 1,
                u64::from(self.y) + u64::from(self.height) - 1
            )
        }
    }
}

/// One pixel of the pick pass covered by a pickable instance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PickSample {
    /// Column.
    pub x: u32,
    /// Row.
    pub y: u32,
    /// The scene tree instance drawn there.
    pub instance: u32,
    /// Its depth (0 at the near plane, 1 at the far plane).
    pub depth: f32,
    /// Whether the pixel shows a section cap of the instance: the depth is then that of the
    /// far face the cap is painted on, not of the cut.
    pub cap: bool,
}

/// The pick pass's flag on the ids of pixels that show a cap (`CADR_PICK_CAP` in the shaders);
/// the other bits are the instance id + 1.
pub const PICK_CAP_BIT: u32 = 1 << 31;

/// The id image and the readback of one rectangle.
pub(crate) struct PickTarget {
    ids: Image,
    readback: Buffer,
    rect: PixelRect,
}

fn readback_buffer(device: &Arc<Device>, rect: PixelRect) -> RenderResult<Buffer> {
    // Ids, then depths: four bytes each per pixel.
    let pixels = u64::from(rect.width) * u64::from(rect.height);
    Ok(Buffer::new(
        device,
        "pick readback",
        pixels * 8,
        vk::BufferUsageFlags::TRANSFER_DST,
        MemoryLocation::GpuToCpu,
    )?)
}

impl PickTarget {
    /// An id image of `extent` and a readback for `rect`.
    pub(crate) fn new(
        device: &Arc<Device>,
        extent: vk::Extent2D,
        rect: PixelRect,
    ) -> RenderResult<Self> {
        let ids = Image::new(
            device,
            "pick ids",
            extent,
            PICK_FORMAT,
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC,
            vk::ImageAspectFlags::COLOR,
        )?;
        Ok(Self {
            ids,
            readback: readback_buffer(device, rect)?,
            rect,
        })
    }

    /// Reads `rect` back after the next pass (a larger readback buffer when needed).
    pub(crate) fn prepare(&mut self, rect: PixelRect) -> RenderResult<()> {
        let needed = u64::from(rect.width) * u64::from(rect.height) * 8;
        if self.readback.size() < needed {
            self.readback = readback_buffer(self.ids.device(), rect)?;
        }
        self.rect = rect;
        Ok(())
    }

    /// The id image (the pick pass's colour attachment).
    pub(crate) fn ids(&self) -> &Image {
        &self.ids
    }

    /// Records the copies of the rectangle's ids and depths; both images are in
    /// TRANSFER_SRC_OPTIMAL after the pass.
    pub(crate) fn record_readback(
        &self,
        device: &Device,
        command_buffer: vk::CommandBuffer,
        depth: &Image,
    ) {
        let rect = self.rect;
        let pixels = u64::from(rect.width) * u64::from(rect.height);
        let area = (rect.x, rect.y, rect.width, rect.height);
        record_image_copy(device, command_buffer, &self.ids, area, &self.readback, 0);
        record_image_copy(
            device,
            command_buffer,
            depth,
            area,
            &self.readback,
            pixels * 4,
        );
    }

    /// The covered pixels of the last readback.
    pub(crate) fn samples(&self) -> RenderResult<Vec<PickSample>> {
        let bytes = self.readback.mapped()?;
        let rect = self.rect;
        let pixels = rect.width as usize * rect.height as usize;
        let word = |i: usize| {
            let at = &bytes[i * 4..i * 4 + 4];
            u32::from_le_bytes([at[0], at[1], at[2], at[3]])
        };
        Ok((0..pixels)
            .filter_map(|i| {
                let id = word(i) & !PICK_CAP_BIT;
                (id != 0).then(|| PickSample {
                    x: rect.x + (i % rect.width as usize) as u32,
                    y: rect.y + (i / rect.width as usize) as u32,
                    instance: id - 1,
                    depth: f32::from_bits(word(pixels + i)),
                    cap: word(i) & PICK_CAP_BIT != 0,
                })
            })
            .collect())
    }
}
