//! The scene's textures on the GPU and what each material slot says about its texture.
//!
//! Two paths, chosen by the device ([`crate::vk::Capabilities::bindless_textures`]):
//! - **Bindless** (descriptor indexing): each texture is an image of its own at its own size
//!   (its sides at most [`MAX_TABLE_SIDE`], all of them together within
//!   [`TABLE_BUDGET_BYTES`]), in a table of sampled images the shaders index by texture slot
//!   (frame set binding 9). A texture whose texels did not change keeps its image when the
//!   graph's textures change.
//! - **Array** (every device; lavapipe has no descriptor indexing): one 2D array image of
//!   square layers, layer `t` holding texture slot `t`, sampled through a `sampler2DArray`.
//!   Each texture is resampled to the layer size: the largest texture's side rounded up to a
//!   power of two, at most [`MAX_LAYER_SIZE`], halved while the array would pass
//!   [`ARRAY_BUDGET_BYTES`].
//!
//! Mip chains are made on the CPU with the `image` crate, in linear colour, a thread per core,
//! and uploaded in one submission; the textures are rebuilt when the graph's change.

use std::sync::Arc;

use image::imageops::FilterType;
use image::RgbaImage;

use crate::error::RenderResult;
use crate::graph::SceneGraph;
use crate::scene::{AlphaMode, Texture};
use crate::vk::raw as vk;
use crate::vk::{Device, Image, ImageShape, Sampler, TexelImage, VkError};

/// The largest layer side of the texture array, in texels.
pub const MAX_LAYER_SIZE: u32 = 1024;

/// The most device memory the texture array may take; layers shrink to fit.
pub const ARRAY_BUDGET_BYTES: u64 = 256 << 20;

/// The largest side of a bindless texture, in texels (larger ones are made smaller, keeping
/// their aspect).
pub const MAX_TABLE_SIDE: u32 = 8192;

/// The most device memory the bindless textures may take together; the largest shrink to fit.
pub const TABLE_BUDGET_BYTES: u64 = 1 << 30;

/// Bytes of one material slot's texture description on the GPU (`CadrMaterialTexture` in
/// `shaders/technique.vert`).
pub const MATERIAL_TEXTURE_BYTES: usize = 48;

/// `CadrMaterialTexture::info.y`: bits 0–1 wrap S, 2–3 wrap T ([`crate::scene::Wrap::code`]),
/// and these.
const SAMPLING_NEAREST: u32 = 16;
const SAMPLING_TRANSLUCENT: u32 = 32;

/// A material slot's texture as the vertex shader reads it: the UV transform's rows (xyz),
/// then texture slot + 1 (0: none; the array's layer or the table's element), sampling bits, alpha mode ([`AlphaMode::code`]) and the mask's
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

/// The scene's textures on the GPU, the two samplers the shaders choose between, and what
/// they were built from.
pub(super) struct SceneTextures {
    images: TextureImages,
    /// Trilinear.
    pub(super) linear: Sampler,
    /// Nearest texel when magnifying (glTF `magFilter` NEAREST).
    pub(super) nearest: Sampler,
    /// The graph's textures generation they were built from.
    pub(super) generation: u64,
    /// Whether the graph had any texture.
    pub(super) any: bool,
    /// With the table: each slot's view (null for an empty slot), as the frame set names them.
    table_views: Vec<vk::ImageView>,
}

/// The scene's textures as the frame set names them.
#[derive(Clone, Copy, Debug)]
pub enum TextureBindings<'a> {
    /// The texture array (bindings 5 and 6, with each sampler).
    Array(vk::ImageView),
    /// The bindless table (binding 9): each texture slot's view, null for an empty slot.
    Table(&'a [vk::ImageView]),
}

/// The images of one of the two paths (see the module).
enum TextureImages {
    /// Every texture slot a layer of this array.
    Array(Image),
    /// Per texture slot, its own image (none for an empty slot).
    Table(Vec<Option<TableTexture>>),
}

/// A texture of the bindless table and the texels it was made from.
struct TableTexture {
    image: Image,
    texels: Arc<Vec<u8>>,
}

impl SceneTextures {
    /// Builds the textures of `graph` on the path the device has. Returns them and the bytes
    /// uploaded.
    pub(super) fn new(device: &Arc<Device>, graph: &SceneGraph) -> RenderResult<(Self, u64)> {
        let mut textures = Self {
            images: TextureImages::Table(Vec::new()),
            table_views: Vec::new(),
            linear: Sampler::new(device, "scene textures (trilinear)", false)?,
            nearest: Sampler::new(device, "scene textures (nearest magnification)", true)?,
            generation: 0,
            any: false,
        };
        let bytes = textures.rebuild(device, graph)?;
        Ok((textures, bytes))
    }

    /// Builds them again from the graph's textures (the GPU is not using them); a bindless
    /// texture whose texels did not change keeps its image. On an error they stay as they
    /// were. Returns the bytes uploaded.
    pub(super) fn rebuild(
        &mut self,
        device: &Arc<Device>,
        graph: &SceneGraph,
    ) -> RenderResult<u64> {
        let slots: Vec<Option<&Texture>> = (0..graph.texture_capacity() as u32)
            .map(|t| graph.texture_at(t).map(|e| &e.texture))
            .collect();
        let capacity = device.capabilities().bindless_textures;
        let (images, bytes) = if capacity > 0 {
            let mut no_table = Vec::new();
            let previous = match &mut self.images {
                TextureImages::Table(table) => table,
                TextureImages::Array(_) => &mut no_table,
            };
            let (table, bytes) = build_table(device, &slots, capacity, previous)?;
            (TextureImages::Table(table), bytes)
        } else {
            build_array(device, &slots)?
        };
        self.table_views = match &images {
            TextureImages::Table(table) => table
                .iter()
                .map(|t| t.as_ref().map_or(vk::ImageView::null(), |t| t.image.view()))
                .collect(),
            TextureImages::Array(_) => Vec::new(),
        };
        self.images = images;
        self.generation = graph.textures_generation();
        self.any = slots.iter().any(Option::is_some);
        Ok(bytes)
    }
}

impl SceneTextures {
    /// How the frame set names them.
    pub(super) fn bindings(&self) -> TextureBindings<'_> {
        match &self.images {
            TextureImages::Array(image) => TextureBindings::Array(image.view()),
            TextureImages::Table(_) => TextureBindings::Table(&self.table_views),
        }
    }
}

/// The texture array of `slots` (one white texel when there is none), and the bytes uploaded.
fn build_array(
    device: &Arc<Device>,
    slots: &[Option<&Texture>],
) -> RenderResult<(TextureImages, u64)> {
    let any = slots.iter().any(Option::is_some);
    let layers = slots.len().max(1) as u32;
    let most_layers = device.limits().max_image_array_layers;
    if layers > most_layers {
        return Err(VkError::Unsupported {
            device: device.adapter().name.clone(),
            reason: format!(
                "the scene has {layers} texture slots, and the texture array of a device without descriptor indexing holds at most {most_layers} (maxImageArrayLayers)"
            ),
        }
        .into());
    }
    let size = if any { layer_size(slots, layers) } else { 1 };
    let mips = size.ilog2() + 1;
    let texels: Vec<u8> = if any {
        crate::parallel::map(slots, |slot| mip_chain(*slot, (size, size), mips)).concat()
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
    Ok((TextureImages::Array(image), texels.len() as u64))
}

/// The bindless table of `slots` at most `capacity` long, taking from `previous` the images
/// whose texels and size are the same (on an error, `previous` is left whole); returns it and
/// the bytes uploaded.
fn build_table(
    device: &Arc<Device>,
    slots: &[Option<&Texture>],
    capacity: u32,
    previous: &mut [Option<TableTexture>],
) -> RenderResult<(Vec<Option<TableTexture>>, u64)> {
    if slots.len() > capacity as usize {
        return Err(VkError::Unsupported {
            device: device.adapter().name.clone(),
            reason: format!(
                "the scene has {} texture slots, and the device binds at most {capacity} textures",
                slots.len()
            ),
        }
        .into());
    }
    let max_side = MAX_TABLE_SIDE.min(device.limits().max_image_dimension2_d);
    let sides: Vec<Option<(u32, u32)>> = slots
        .iter()
        .map(|slot| slot.map(|t| (t.width, t.height)))
        .collect();
    let sizes = table_sizes(&sides, max_side, TABLE_BUDGET_BYTES);
    // What can stay: the same texels at the same size.
    let keeps: Vec<bool> = slots
        .iter()
        .zip(&sizes)
        .enumerate()
        .map(|(t, (slot, size))| {
            let (Some(Some(old)), Some(texture)) = (previous.get(t), slot) else {
                return false;
            };
            let extent = old.image.extent();
            Arc::ptr_eq(&old.texels, &texture.texels)
                && Some((extent.width, extent.height)) == *size
        })
        .collect();
    let wanted: Vec<(usize, &Texture, (u32, u32))> = slots
        .iter()
        .zip(&sizes)
        .enumerate()
        .filter(|(t, _)| !keeps[*t])
        .filter_map(|(t, (slot, size))| Some((t, (*slot)?, (*size)?)))
        .collect();
    let chains: Vec<(Vec<u8>, u32)> = crate::parallel::map(&wanted, |&(_, texture, size)| {
        let mips = size.0.max(size.1).ilog2() + 1;
        (mip_chain(Some(texture), size, mips), mips)
    });
    let names: Vec<String> = wanted
        .iter()
        .map(|(t, texture, _)| format!("scene texture {t} '{}'", texture.name))
        .collect();
    let requests: Vec<TexelImage<'_>> = wanted
        .iter()
        .zip(&chains)
        .zip(&names)
        .map(
            |((&(_, _, (width, height)), (texels, mips)), name)| TexelImage {
                name,
                shape: ImageShape {
                    extent: vk::Extent2D { width, height },
                    samples: 1,
                    layers: 1,
                    mips: *mips,
                    array_view: false,
                },
                format: vk::Format::R8G8B8A8_SRGB,
                texels,
            },
        )
        .collect();
    let images = Image::many_with_texels(device, &requests, vk::ImageUsageFlags::SAMPLED)?;
    let bytes = chains.iter().map(|(texels, _)| texels.len() as u64).sum();
    let mut table: Vec<Option<TableTexture>> = keeps
        .iter()
        .enumerate()
        .map(|(t, &keep)| if keep { previous[t].take() } else { None })
        .collect();
    for ((t, texture, _), image) in wanted.iter().zip(images) {
        table[*t] = Some(TableTexture {
            image,
            texels: Arc::clone(&texture.texels),
        });
    }
    Ok((table, bytes))
}

/// The size of each bindless texture of `sides` (none for an empty slot): its own, made
/// smaller keeping its aspect while a side passes `max_side`, and the largest halved while all
/// of them with their mips would pass `budget` bytes (not below 16 texels a side).
fn table_sizes(
    sides: &[Option<(u32, u32)>],
    max_side: u32,
    budget: u64,
) -> Vec<Option<(u32, u32)>> {
    let fit = |(width, height): (u32, u32), limit: u32| -> (u32, u32) {
        let longest = width.max(height);
        if longest <= limit {
            return (width, height);
        }
        let scale = |side: u32| {
            ((u64::from(side) * u64::from(limit) + u64::from(longest) / 2) / u64::from(longest))
                .max(1) as u32
        };
        (scale(width), scale(height))
    };
    let bytes = |sizes: &[Option<(u32, u32)>]| -> u64 {
        sizes
            .iter()
            .flatten()
            .map(|&(w, h)| u64::from(w) * u64::from(h) * 4 * 4 / 3)
            .sum()
    };
    let mut limit = max_side.max(1);
    loop {
        let sizes: Vec<Option<(u32, u32)>> = sides
            .iter()
            .map(|side| side.map(|s| fit(s, limit)))
            .collect();
        if limit <= 16 || bytes(&sizes) <= budget {
            return sizes;
        }
        limit /= 2;
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

/// A texture resampled to `width` × `height` and its mip levels down to 1 × 1 (`mips` of
/// them), each level made from the one above it. Texels are filtered as light, in linear 16-bit colour (the sRGB
/// texels decoded first, each level encoded back to sRGB as it is stored), and weighted by
/// their alpha (premultiplied), so that the colour of transparent texels does not bleed into
/// the kept ones. A texture smaller than the layer and magnified to its nearest texel is
/// enlarged by repeating texels, which keeps them sharp (and exact).
fn mip_chain(texture: Option<&Texture>, (width, height): (u32, u32), mips: u32) -> Vec<u8> {
    let level_size = |m: u32| ((width >> m).max(1), (height >> m).max(1));
    let Some(texture) = texture else {
        let texels: u64 = (0..mips)
            .map(|m| {
                let (w, h) = level_size(m);
                u64::from(w) * u64::from(h)
            })
            .sum();
        return vec![0; texels as usize * 4];
    };
    let source = RgbaImage::from_raw(texture.width, texture.height, texture.texels.to_vec())
        .unwrap_or_else(|| RgbaImage::new(1, 1));
    let enlarged = texture.width <= width && texture.height <= height;
    let first_filter = if enlarged && texture.sampler.magnify_nearest {
        FilterType::Nearest
    } else {
        FilterType::Triangle
    };
    let mut level = linear_premultiplied(&source);
    if (texture.width, texture.height) != (width, height) {
        level = image::imageops::resize(&level, width, height, first_filter);
    }
    let mut texels = Vec::new();
    for m in 0..mips {
        texels.extend(level.pixels().flat_map(srgb_straight));
        if m + 1 < mips {
            let (next_width, next_height) = level_size(m + 1);
            level = image::imageops::resize(&level, next_width, next_height, FilterType::Triangle);
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
    fn table_textures_keep_their_size_within_the_side_and_the_budget() {
        let sides = [Some((300, 20)), None, Some((5000, 1000)), Some((1, 1))];
        // Their own sizes, the too-long one shrunk to the side keeping its aspect.
        assert_eq!(
            table_sizes(&sides, 4096, u64::MAX),
            [Some((300, 20)), None, Some((4096, 819)), Some((1, 1))]
        );
        // Over the budget, the largest shrink first, halving the side.
        let budget = 2048 * 410 * 4 * 4 / 3 + 300 * 20 * 6;
        assert_eq!(
            table_sizes(&sides, 4096, budget),
            [Some((300, 20)), None, Some((2048, 410)), Some((1, 1))]
        );
        // Never below 16 texels a side.
        assert_eq!(
            table_sizes(&sides, 4096, 0),
            [Some((16, 1)), None, Some((16, 3)), Some((1, 1))]
        );
    }

    #[test]
    fn non_square_mip_chains_halve_each_side_down_to_one() {
        let image = RgbaImage::from_pixel(8, 2, image::Rgba([10, 20, 30, 255]));
        let texels = mip_chain(Some(&texture_of(image)), (8, 2), 4);
        // 8 × 2, 4 × 1, 2 × 1, 1 × 1.
        assert_eq!(texels.len(), (16 + 4 + 2 + 1) * 4);
        assert_eq!(&texels[texels.len() - 4..], &[10, 20, 30, 255]);
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
        let texels = mip_chain(Some(&texture_of(checker)), (2, 2), 2);
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
        let texels = mip_chain(Some(&texture_of(mostly_blue)), (2, 2), 2);
        let last = &texels[16..20];
        assert_eq!(&last[..3], &[0, 0, 255], "{last:?}");
    }
}
