//! The rendered image, read back into host memory or written to a PNG file.

use std::path::Path;

use super::Renderer;
use crate::error::{RenderError, RenderResult};
use crate::timings::{self, Phase};

impl Renderer {
    /// Reads the last frame back as tightly packed RGBA8 rows.
    pub fn read_rgba8(&self) -> RenderResult<image::RgbaImage> {
        let (width, height) = self.size();
        self.finish()?;
        let pixels = timings::time(Phase::Readback, || self.target.read_rgba8(&self.device))?;
        image::RgbaImage::from_raw(width, height, pixels).ok_or_else(|| {
            RenderError::InvalidUse(format!("read back fewer pixels than {width}x{height}"))
        })
    }

    /// The depth of the last frame ([`Renderer::depth_for_host`]; a pick draws a frame too),
    /// row by row from the top, one value per pixel; refused unless frames keep it
    /// ([`Renderer::set_depth_to_host`]) and one was drawn since (and since the last resize).
    pub fn read_depth(&self) -> RenderResult<Vec<f32>> {
        let depth = self.depth_for_host().ok_or_else(|| {
            RenderError::InvalidUse("frames do not keep their depth for the host".into())
        })?;
        if !self.depth_readable {
            return Err(RenderError::InvalidUse(
                "no frame kept its depth since depth_to_host was turned on or the size changed"
                    .into(),
            ));
        }
        self.finish()?;
        let bytes = timings::time(Phase::Readback, || {
            crate::vk::read_image(
                &self.device,
                depth,
                crate::vk::raw::ImageLayout::TRANSFER_SRC_OPTIMAL,
            )
        })?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }

    /// Writes the last frame to a PNG file.
    pub fn save_png(&self, path: &Path) -> Result<(), SaveError> {
        let image = self.read_rgba8()?;
        timings::time(Phase::PngEncode, || {
            image.save_with_format(path, image::ImageFormat::Png)
        })
        .map_err(|source| SaveError::Write {
            path: path.to_owned(),
            source,
        })
    }
}

/// Why an image could not be saved.
#[derive(Debug, thiserror::Error)]
pub enum SaveError {
    /// Reading the image back failed.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// Writing the file failed.
    #[error("cannot write {}: {source}", path.display())]
    Write {
        /// The file.
        path: std::path::PathBuf,
        /// The encoder's or OS's error.
        #[source]
        source: image::ImageError,
    },
}
