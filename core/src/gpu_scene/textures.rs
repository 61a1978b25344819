//! The scene's textures on the GPU and what each material slot says about its texture.
//!
//! Textures live in one 2D array image of square, mipmapped sRGB layers, layer `t` holding
//! texture slot `t`, sampled through a `sampler2DArray` in the frame set: the path that works
//! on every device (lavapipe has no descriptor indexing, so no array of textures of their own
//! sizes). Each texture is resampled to the layer size: the largest texture's side rounded up
//! to a power of two, at most [`MAX_LAYER_SIZE`], halved while the array would pass
//! [`ARRAY_BUDGET_BYTES`]. Layers and their mip chains are made on the CPU with the `image`
//! crate, in linear colour, a thread per core, and uploaded once; the array is rebuilt when
//! the graph's textures change.

use std::sync::Arc;

use image::imageops::FilterType;
use image::RgbaImage;

use crate::error::RenderResult;
use crate::graph::SceneGraph;
use crate::scene::{AlphaMode, Texture};
use crate::vk::raw as vk;
use crate::vk::{Device, Image, ImageShape, Sampler};

/// The largest layer side, in texels.
pub const MAX_LAYER_SIZE: u32 = 1024;

/// The most device memory the array may take; layers shrink to fit.
pub const ARRAY_BUDGET_BYTES: u64 = 256 << 20;

/// Bytes of one material slot's texture description on the GPU (`CadrMaterialTexture` in
/// `shaders/technique.vert`).
pub const MATERIAL_TEXTURE_BYTES: usize = 48;

/// `CadrMaterialTexture::info.y`: bits 0–1 wrap S, 2–3 wrap T ([`crate::scene::Wrap::code`]),
/// and these.
const SAMPLING_NEAREST: u32 = 16;
const SAMPLING_TRANSLUCENT: u32 = 32;

/// A material slot's texture as the vertex shader reads it: the UV transform's rows (xyz),
/// then layer + 1 (0: none), sampling bits, alpha mode ([`AlphaMode::code`]) and the mask's
/// cutoff (f32 bits).
pub fn gpu_material_texture(graph: &SceneGraph, slot: u32) -> [u32; 12] {
    let Some(material) = graph.material_at(slot) else {
        return [0; 12];
    };
    let mut words = [0u32; 12];
    let cutoff = match material.alpha_mode {
        AlphaMode::Mask { cutoff } => cutoff,
        _ => 0.0,
    };
    words[8..12].copy_from_slice(&[0, 0, material.alpha_mode.code(), cutoff.to_bits()]);
    let reference = material
        .base_color_texture
        .and_then(|r| Some((r, graph.texture_at(r.texture)?)));
    match reference {
        Some((reference, entry)) => {
            let rows = [reference.transform.u_row, reference.transform.v_row];
            for (row, values) in rows.iter().enumerate() {
                for (column, value) in values.iter().enumerate() {
                    words[row * 4 + column] = value.to_bits();
                }
            }
            let sampler = entry.texture.sampler;
            let mut sampling = sampler.wrap_s.code() | sampler.wrap_t.code() << 2;
            if sampler.magnify_nearest {
                sampling |= SAMPLING_NEAREST;
            }
            if entry.translucent {
                sampling |= SAMPLING_TRANSLUCENT;
            }
            words[8] = reference.texture + 1;
            words[9] = sampling;
        }
        None => {
            words[0] = 1f32.to_bits();
            words[5] = 1f32.to_bits();
        }
    }
    words
}

/// Whether a material description differs from what the vertex shader assumes without one
/// (no texture, BLEND).
pub(super) fn is_described(words: &[u32; 12]) -> bool {
    words[8] != 0 || words[10] != AlphaMode::Blend.code()
}

/// The texture array, its view and the two samplers the shaders choose between.
pub(super) struct TextureArray {
    pub(super) image: Image,
    /// Trilinear.
    pub(super) linear: Sampler,
    /// Nearest texel when magnifying (glTF `magFilter` NEAREST).
    pub(super) nearest: Sampler,
    /// The graph's textures generation it was built from.
    pub(super) generation: u64,
    /// Whether the graph had any texture.
    pub(super) any: bool,
}

impl TextureArray {
    /// Builds the array from the graph's textures (one white texel when it has none); returns
    /// it and the bytes uploaded.
    pub(super) fn build(device: &Arc<Device>, graph: &SceneGraph) -> RenderResult<(Self, u64)> {
        let slots: Vec<Option<&Texture>> = (0..graph.texture_capacity() as u32)
            .map(|t| graph.texture_at(t).map(|e| &e.texture))
            .collect();
        let any = slots.iter().any(Option::is_some);
        let layers = slots.len().max(1) as u32;
        let size = if any { layer_size(&slots, layers) } else { 1 };
        let mips = size.ilog2() + 1;
        let texels: Vec<u8> = if any {
            crate::parallel::map(&slots, |slot| mip_chain(*slot, size, mips)).concat()
        } else {
            vec![255; 4]
        };
        let shape = ImageShape {
            extent: vk::Extent2D {
                width: size,
                height: size,
            },
            samples: 1,
            layers,
            mips,
            array_view: true,
        };
        let image = Image::with_texels(
            device,
            "scene textures",
            (shape, vk::Format::R8G8B8A8_SRGB),
            &texels,
            vk::ImageUsageFlags::SAMPLED,
        )?;
        let array = Self {
            image,
            linear: Sampler::new(device, "scene textures (trilinear)", false)?,
            nearest: Sampler::new(device, "scene textures (nearest magnification)", true)?,
            generation: graph.textures_generation(),
            any,
        };
        Ok((array, texels.len() as u64))
    }
}

/// The layer side: the largest texture's side as a power of two, at most
/// [`MAX_LAYER_SIZE`], halved until `layers` layers with their mips fit the budget.
fn layer_size(slots: &[Option<&Texture>], layers: u32) -> u32 {
    let largest = slots
        .iter()
        .flatten()
        .map(|t| t.width.max(t.height))
        .max()
        .unwrap_or(1);
    let mut size = largest.next_power_of_two().min(MAX_LAYER_SIZE);
    let bytes = |size: u32| u64::from(layers) * u64::from(size) * u64::from(size) * 4 * 4 / 3;
    while size > 16 && bytes(size) > ARRAY_BUDGET_BYTES {
        size /= 2;
    }
    size
}

/// A texture resampled to `size` × `size` and its mip levels down to 1 × 1, each level made
/// from the one above it. Texels are filtered as light, in linear 16-bit colour (the sRGB
/// texels decoded first, each level encoded back to sRGB as it is stored), and weighted by
/// their alpha (premultiplied), so that the colour of transparent texels does not bleed into
/// the kept ones. A texture smaller than the layer and magnified to its nearest texel is
/// enlarged by repeating texels, which keeps them sharp (and exact).
fn mip_chain(texture: Option<&Texture>, size: u32, mips: u32) -> Vec<u8> {
    let Some(texture) = texture else {
        let texels: u64 = (0..mips)
            .map(|m| u64::from((size >> m).max(1)).pow(2))
            .sum();
        return vec![0; texels as usize * 4];
    };
    let source = RgbaImage::from_raw(texture.width, texture.height, texture.texels.to_vec())
        .unwrap_or_else(|| RgbaImage::new(1, 1));
    let enlarged = texture.width <= size && texture.height <= size;
    let first_filter = if enlarged && texture.sampler.magnify_nearest {
        FilterType::Nearest
    } else {
        FilterType::Triangle
    };
    let mut level = linear_premultiplied(&source);
    if (texture.width, texture.height) != (size, size) {
        level = image::imageops::resize(&level, size, size, first_filter);
    }
    let mut texels = Vec::new();
    for m in 0..mips {
        texels.extend(level.pixels().flat_map(srgb_straight));
        if m + 1 < mips {
            let next = (size >> (m + 1)).max(1);
            level = image::imageops::resize(&level, next, next, FilterType::Triangle);
        }
    }
    texels
}

/// Linear colour with alpha, 16 bits a channel, the colour premultiplied by alpha.
type LinearImage = image::ImageBuffer<image::Rgba<u16>, Vec<u16>>;

/// `image`'s sRGB texels as linear colour premultiplied by alpha.
fn linear_premultiplied(image: &RgbaImage) -> LinearImage {
    let decode = srgb_decode_table();
    LinearImage::from_fn(image.width(), image.height(), |x, y| {
        let [r, g, b, a] = image.get_pixel(x, y).0;
        let alpha = u32::from(a);
        let premultiplied =
            |c: u8| ((u32::from(decode[usize::from(c)]) * alpha + 127) / 255) as u16;
        image::Rgba([
            premultiplied(r),
            premultiplied(g),
            premultiplied(b),
            u16::from(a) * 257,
        ])
    })
}

/// A linear premultiplied texel as sRGB bytes with straight alpha.
fn srgb_straight(texel: &image::Rgba<u16>) -> [u8; 4] {
    let [r, g, b, a] = texel.0;
    let alpha = f32::from(a) / 65535.0;
    let encode = |c: u16| {
        if a == 0 {
            return 0;
        }
        let linear = (f32::from(c) / 65535.0 / alpha).min(1.0);
        let srgb = if linear <= 0.003_130_8 {
            linear * 12.92
        } else {
            1.055 * linear.powf(1.0 / 2.4) - 0.055
        };
        (srgb * 255.0).round() as u8
    };
    [
        encode(r),
        encode(g),
        encode(b),
        ((u32::from(a) + 128) / 257) as u8,
    ]
}

/// Linear values of the 256 sRGB-encoded bytes, scaled to 16 bits.
fn srgb_decode_table() -> &'static [u16; 256] {
    static TABLE: std::sync::OnceLock<[u16; 256]> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        std::array::from_fn(|byte| {
            let srgb = byte as f32 / 255.0;
            let linear = if srgb <= 0.040_45 {
                srgb / 12.92
            } else {
                ((srgb + 0.055) / 1.055).powf(2.4)
            };
            (linear * 65535.0).round() as u16
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texture_of(image: RgbaImage) -> Texture {
        Texture {
            name: "test".into(),
            width: image.width(),
            height: image.height(),
            texels: Arc::new(image.into_raw()),
            sampler: Default::default(),
        }
    }

    #[test]
    fn opaque_srgb_bytes_survive_the_linear_round_trip() {
        for byte in 0..=255_u8 {
            let image = RgbaImage::from_pixel(1, 1, image::Rgba([byte, byte, byte, 255]));
            let texel = *linear_premultiplied(&image).get_pixel(0, 0);
            assert_eq!(
                srgb_straight(&texel),
                [byte, byte, byte, 255],
                "byte {byte}"
            );
        }
    }

    #[test]
    fn mips_average_light_not_srgb_bytes_and_ignore_transparent_colour() {
        // Black and white texels average to half the light: sRGB 188, not 128.
        let checker = RgbaImage::from_fn(2, 2, |x, y| {
            let white = (x + y) % 2 == 0;
            image::Rgba(if white { [255; 4] } else { [0, 0, 0, 255] })
        });
        let texels = mip_chain(Some(&texture_of(checker)), 2, 2);
        assert_eq!(texels.len(), (4 + 1) * 4);
        let last = &texels[16..20];
        assert!((187..=189).contains(&last[0]), "{last:?}");
        assert_eq!(last[3], 255);
        // A transparent red texel next to opaque blue ones adds no red to the mip.
        let mostly_blue = RgbaImage::from_fn(2, 2, |x, y| {
            image::Rgba(if (x, y) == (0, 0) {
                [255, 0, 0, 0]
            } else {
                [0, 0, 255, 255]
            })
        });
        let texels = mip_chain(Some(&texture_of(mostly_blue)), 2, 2);
        let last = &texels[16..20];
        assert_eq!(&last[..3], &[0, 0, 255], "{last:?}");
    }
}
