//! glTF images and textures: each image read (from a buffer view, a data URI or a file beside
//! the glTF) and decoded once with the `image` crate, the images on a thread each up to the
//! machine's cores; each texture is an image with its sampler.
//!
//! An image that cannot be read or decoded is not fatal: the textures made from it are left
//! out with a warning that names the image and why, and their materials draw untextured.

use std::borrow::Cow;
use std::path::Path;
use std::sync::Arc;

use base64::Engine as _;

use super::gltf_buffers::{GltfBuffers, SourceBytes};
use crate::scene::{Sampler, Texture, Wrap};

/// A decoded image: width, height and RGBA texels.
type Decoded = (u32, u32, Arc<Vec<u8>>);

/// The scene's textures, one per glTF texture (`None` for those whose image failed, with a
/// warning naming the glTF `file`, whose folder holds external images).
pub(super) fn load_textures(
    document: &gltf::Document,
    buffers: &GltfBuffers<'_>,
    file: &Path,
) -> Vec<Option<Texture>> {
    let base_dir = file.parent().unwrap_or(Path::new(""));
    let images: Vec<gltf::Image<'_>> = document.images().collect();
    let encoded = crate::parallel::map(&images, |image| {
        let bytes = encoded_bytes(image, buffers, base_dir)?;
        let (width, height) = dimensions(bytes.bytes())?;
        Ok((bytes, u64::from(width) * u64::from(height) * 4))
    });
    let admitted = within_memory_budget(encoded);
    let decoded = crate::parallel::map(&admitted, |bytes| decode(bytes.as_ref()?.bytes()));
    let decoded: Vec<Option<Decoded>> = decoded
        .into_iter()
        .zip(&images)
        .map(|(result, image)| {
            result
                .map_err(|why| {
                    log::warn!(
                        "{}: image {} ({}) is left out: {why}",
                        file.display(),
                        image.index(),
                        image_name(image)
                    )
                })
                .ok()
        })
        .collect();
    document
        .textures()
        .map(|texture| {
            let image = texture.source();
            let (width, height, texels) = decoded[image.index()].clone()?;
            Some(Texture {
                name: texture
                    .name()
                    .map_or_else(|| image_name(&image), str::to_owned),
                width,
                height,
                texels,
                sampler: sampler(&texture.sampler()),
            })
        })
        .collect()
}

fn image_name(image: &gltf::Image<'_>) -> String {
    match (image.name(), image.source()) {
        (Some(name), _) => name.to_owned(),
        (None, gltf::image::Source::Uri { uri, .. }) if !uri.starts_with("data:") => uri.to_owned(),
        (None, _) => format!("image {}", image.index()),
    }
}

fn sampler(sampler: &gltf::texture::Sampler<'_>) -> Sampler {
    let wrap = |mode: gltf::texture::WrappingMode| match mode {
        gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
        gltf::texture::WrappingMode::ClampToEdge => Wrap::ClampToEdge,
        gltf::texture::WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
    };
    Sampler {
        wrap_s: wrap(sampler.wrap_s()),
        wrap_t: wrap(sampler.wrap_t()),
        magnify_nearest: sampler.mag_filter() == Some(gltf::texture::MagFilter::Nearest),
    }
}

/// An image's encoded bytes and the bytes of its decoded texels, or why it cannot be read.
type Encoded<'b> = Result<(SourceBytes<'b>, u64), String>;

/// The images that fit the memory budget decoded together (in the file's order; each takes
/// 4 bytes a texel), the others refused saying so.
fn within_memory_budget(encoded: Vec<Encoded<'_>>) -> Vec<Result<SourceBytes<'_>, String>> {
    let budget = crate::memory_budget::budget();
    let mut taken = 0_u64;
    encoded
        .into_iter()
        .map(|image| {
            let (bytes, decoded_bytes) = image?;
            let budget = budget.clone()?;
            let needed = taken.saturating_add(decoded_bytes);
            if needed > budget {
                return Err(crate::memory_budget::over_budget(
                    "its texels with those of the images before it",
                    needed,
                    budget,
                ));
            }
            taken = needed;
            Ok(bytes)
        })
        .collect()
}

/// One image's encoded bytes: from its buffer view, its data URI or its file.
fn encoded_bytes<'b>(
    image: &gltf::Image<'_>,
    buffers: &'b GltfBuffers<'_>,
    base_dir: &Path,
) -> Result<SourceBytes<'b>, String> {
    Ok(match image.source() {
        gltf::image::Source::View { view, .. } => {
            // The views were checked against their buffers before any image is read.
            let buffer = buffers.get(view.buffer().index()).unwrap_or_default();
            SourceBytes::Memory(Cow::Borrowed(
                &buffer[view.offset()..view.offset() + view.length()],
            ))
        }
        gltf::image::Source::Uri { uri, .. } if uri.starts_with("data:") => {
            let (_, payload) = uri
                .split_once(";base64,")
                .ok_or("its data URI is not base64")?;
            SourceBytes::Memory(Cow::Owned(
                base64::engine::general_purpose::STANDARD
                    .decode(payload)
                    .map_err(|e| format!("its data URI has invalid base64 data: {e}"))?,
            ))
        }
        gltf::image::Source::Uri { uri, .. } => {
            let file = base_dir.join(super::gltf_buffers::percent_decode(uri));
            SourceBytes::Memory(Cow::Owned(
                super::gltf_buffers::read_image_file(&file)
                    .map_err(|e| format!("'{}' cannot be read: {e}", file.display()))?,
            ))
        }
    })
}

/// A reader of an image's encoded bytes.
type BytesReader<'b> = image::ImageReader<std::io::Cursor<&'b [u8]>>;

/// A reader of an image's bytes in the format they are in, and that format.
fn reader(bytes: &[u8]) -> Result<(BytesReader<'_>, image::ImageFormat), String> {
    let reader = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| e.to_string())?;
    let format = reader
        .format()
        .ok_or("its format is not one cadr decodes (PNG or JPEG)")?;
    Ok((reader, format))
}

/// The width and height an image's header declares.
fn dimensions(bytes: &[u8]) -> Result<(u32, u32), String> {
    let (reader, format) = reader(bytes)?;
    reader
        .into_dimensions()
        .map_err(|e| format!("it is not a valid {format:?} image: {e}"))
}

/// Decodes one image (within the `image` crate's default allocation limit, 512 MiB).
fn decode(bytes: &[u8]) -> Result<Decoded, String> {
    let (reader, format) = reader(bytes)?;
    let decoded = reader
        .decode()
        .map_err(|e| format!("it is not a valid {format:?} image: {e}"))?
        .into_rgba8();
    let (width, height) = decoded.dimensions();
    if width == 0 || height == 0 {
        return Err("it has no texels".into());
    }
    Ok((width, height, Arc::new(decoded.into_raw())))
}
