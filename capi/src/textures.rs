//! Textures from the host's texels, the texture and alpha mode of a material, and the vertex
//! attributes (texture coordinates, colours) of a geometry: what a host with its own
//! tessellation needs to draw decals, wood grain or result colours (stresses, temperatures)
//! without writing a glTF file first.

use std::ffi::c_char;
use std::sync::Arc;

use cadr_core::graph::SceneGraph;
use cadr_core::scene::{
    AlphaMode, Material, Sampler, Texture, TextureRef, UvTransform, VertexAttributes, Wrap,
};

use crate::args::{deliver, optional_str, read_sized, slice};
use crate::error::{guard, CadrResult, Failure};
use crate::scene::{
    geometry_of, graph_failure, material_of, texture_of, texture_value, with_scene, CadrGeometry,
    CadrMaterial, CadrScene, CadrTexture,
};

/// Texture wrap: the image repeats (glTF REPEAT; the default).
pub const CADR_WRAP_REPEAT: u32 = 0;
/// Texture wrap: the edge texels extend outwards (glTF CLAMP_TO_EDGE).
pub const CADR_WRAP_CLAMP_TO_EDGE: u32 = 1;
/// Texture wrap: the image repeats, every other copy mirrored (glTF MIRRORED_REPEAT).
pub const CADR_WRAP_MIRRORED_REPEAT: u32 = 2;

/// Alpha mode: texture and vertex alpha are ignored and the material is drawn opaque
/// (glTF OPAQUE).
pub const CADR_ALPHA_OPAQUE: u32 = 0;
/// Alpha mode: a fragment whose alpha (texture × vertex colour × base colour) is under the
/// cutoff is cut away, the rest is opaque; picking goes through the holes too (glTF MASK).
pub const CADR_ALPHA_MASK: u32 = 1;
/// Alpha mode: alpha is opacity, drawn with the renderer's transparency method (glTF BLEND;
/// what a material has unless told otherwise).
pub const CADR_ALPHA_BLEND: u32 = 2;

/// An image in the host's memory. The texels are copied; the host may free them after the
/// call.
///
/// The struct grows by appending fields: the host sets `size` to `sizeof(CadrTextureDesc)`. A field an
/// older host does not know keeps its old behaviour (read as 0); a newer host's fields this
/// library does not know must be 0.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrTextureDesc {
    /// `sizeof(CadrTextureDesc)`, set by the host.
    pub size: u32,
    /// Name (NULL: empty); messages name the texture by it.
    pub name: *const c_char,
    /// Width in texels (at least 1).
    pub width: u32,
    /// Height in texels (at least 1).
    pub height: u32,
    /// `width × height × 4` bytes: RGBA, 8 bits each, colour sRGB-encoded and alpha linear
    /// (as PNG and glTF base-colour textures are), rows from the top of the image down.
    pub texels: *const u8,
    /// How the first texture coordinate wraps outside 0..1 (`CADR_WRAP_*`).
    pub wrap_s: u32,
    /// How the second texture coordinate wraps (`CADR_WRAP_*`).
    pub wrap_t: u32,
    /// Magnified texels show as blocks (nearest texel) instead of blended; minification
    /// always blends mip levels.
    pub magnify_nearest: bool,
}

fn wrap_from(code: u32, field: &str) -> Result<Wrap, Failure> {
    match code {
        CADR_WRAP_REPEAT => Ok(Wrap::Repeat),
        CADR_WRAP_CLAMP_TO_EDGE => Ok(Wrap::ClampToEdge),
        CADR_WRAP_MIRRORED_REPEAT => Ok(Wrap::MirroredRepeat),
        other => Err(Failure::invalid(format!(
            "desc.{field} is {other}; expected CADR_WRAP_REPEAT (0), CADR_WRAP_CLAMP_TO_EDGE (1) \
             or CADR_WRAP_MIRRORED_REPEAT (2)"
        ))),
    }
}

/// Copies and checks a texture description; errors name the field.
///
/// # Safety
/// `desc` is null or valid; its name null or a valid string; its texels null or valid for
/// `width × height × 4` bytes.
unsafe fn texture_from(desc: *const CadrTextureDesc) -> Result<Texture, Failure> {
    // SAFETY: null or valid for its size (the caller's contract); zero bytes are a
    // CadrTextureDesc (null name and texels, zero sizes).
    let desc = unsafe { read_sized(desc, ("desc", "CadrTextureDesc"), std::mem::zeroed()) }?;
    // SAFETY: the name is null or a valid string (the caller's contract).
    let name = unsafe { optional_str(desc.name, "desc.name") }?.unwrap_or("");
    if desc.width == 0 || desc.height == 0 {
        return Err(Failure::invalid(format!(
            "texture '{name}' is {}×{} texels; it needs at least 1×1",
            desc.width, desc.height
        )));
    }
    let bytes = u64::from(desc.width) * u64::from(desc.height) * 4;
    let budget = cadr_core::memory_budget::budget().map_err(Failure::invalid)?;
    if bytes > budget {
        return Err(Failure::new(
            CadrResult::InvalidArgument,
            cadr_core::memory_budget::over_budget(
                &format!("texture '{name}' of {}×{} texels", desc.width, desc.height),
                bytes,
                budget,
            ),
        ));
    }
    let sampler = Sampler {
        wrap_s: wrap_from(desc.wrap_s, "wrap_s")?,
        wrap_t: wrap_from(desc.wrap_t, "wrap_t")?,
        magnify_nearest: desc.magnify_nearest,
    };
    // SAFETY: the texels are valid for their count (the caller's contract); the count fits
    // the memory budget, hence the address space.
    let texels = unsafe { slice(desc.texels, bytes as usize, "desc.texels") }?;
    Ok(Texture {
        name: name.to_owned(),
        width: desc.width,
        height: desc.height,
        texels: Arc::new(texels.to_vec()),
        sampler,
    })
}

/// Creates a texture from the host's texels (copied). Materials use it through
/// `cadr_scene_set_material_texture`, with the texture coordinates of their geometry
/// (`cadr_scene_set_geometry_attributes`). The renderer mipmaps it, filtering in linear light.
///
/// Returns `CADR_RESULT_OK` and writes `*texture`, `CADR_RESULT_NULL_ARGUMENT` (the message
/// names the field), `CADR_RESULT_INVALID_ARGUMENT` (a size of 0, a wrap code unknown, texels
/// past the memory budget `CADR_MEMORY_BUDGET`) or a handle error.
/// Ownership: the texture belongs to the scene. Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// `desc` is null or valid with `texels` valid for `width × height × 4` bytes; `texture` null
/// or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_create_texture(
    scene: CadrScene,
    desc: *const CadrTextureDesc,
    texture: *mut CadrTexture,
) -> CadrResult {
    guard(|| {
        // SAFETY: forwarded contract.
        let data = unsafe { texture_from(desc) }?;
        let value = with_scene(scene, |s| {
            s.graph
                .create_texture(data)
                .map(texture_value)
                .map_err(graph_failure)
        })?;
        // SAFETY: texture is null or writable (the caller's contract).
        unsafe { deliver(texture, "texture", value) }
    })
}

/// Destroys a texture that no material uses.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_IN_USE` (materials still use it: set their texture
/// to 0 first) or a handle error.
/// Ownership: the handle is given back to cadr and invalid afterwards.
/// Thread-safety: as `cadr_scene_create`.
#[no_mangle]
pub extern "C" fn cadr_scene_destroy_texture(scene: CadrScene, texture: CadrTexture) -> CadrResult {
    guard(|| {
        with_scene(scene, |s| {
            let handle = texture_of(&s.graph, texture, "texture")?;
            s.graph.destroy_texture(handle).map_err(graph_failure)
        })
    })
}

/// Changes a material of `scene` by `edit` (which may read the graph), keeping the rest.
fn edit_material(
    scene: CadrScene,
    material: CadrMaterial,
    edit: impl FnOnce(&SceneGraph, &mut Material) -> Result<(), Failure>,
) -> Result<(), Failure> {
    with_scene(scene, |s| {
        let handle = material_of(&s.graph, material, "material")?;
        let mut data = s.graph.material(handle).map_err(graph_failure)?.clone();
        edit(&s.graph, &mut data)?;
        s.graph.set_material(handle, data).map_err(graph_failure)
    })
}

/// Gives a material a base-colour texture, which multiplies its base colour (and the vertex
/// colours), or takes it away (`texture` 0). `uv_transform` maps the geometry's texture
/// coordinates before sampling, as two rows of an affine map: `u' = t[0]·u + t[1]·v + t[2]`,
/// `v' = t[3]·u + t[4]·v + t[5]` (glTF `KHR_texture_transform` in one matrix); NULL keeps
/// them as they are. The material keeps its other parameters, and `cadr_scene_set_material`
/// keeps the texture.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_INVALID_ARGUMENT` (a transform entry not finite,
/// named) or a handle error (for the material or the texture).
/// Ownership: nothing changes hands; the arguments are read during the call only.
/// Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// `uv_transform` is null or points to 6 readable floats.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_set_material_texture(
    scene: CadrScene,
    material: CadrMaterial,
    texture: CadrTexture,
    uv_transform: *const f32,
) -> CadrResult {
    guard(|| {
        let transform = if uv_transform.is_null() {
            UvTransform::IDENTITY
        } else {
            // SAFETY: 6 readable floats (the caller's contract).
            let t = unsafe { slice(uv_transform, 6, "uv_transform") }?;
            if let Some(i) = t.iter().position(|v| !v.is_finite()) {
                return Err(Failure::invalid(format!(
                    "uv_transform[{i}] is {}; it must be finite",
                    t[i]
                )));
            }
            UvTransform {
                u_row: [t[0], t[1], t[2]],
                v_row: [t[3], t[4], t[5]],
            }
        };
        edit_material(scene, material, |graph, data| {
            data.base_color_texture = match texture {
                0 => None,
                value => Some(TextureRef {
                    texture: texture_of(graph, value, "texture")?.index(),
                    transform,
                }),
            };
            Ok(())
        })
    })
}

/// Sets how a material uses alpha: `CADR_ALPHA_BLEND` (the default; alpha is opacity),
/// `CADR_ALPHA_MASK` (fragments with alpha under `cutoff`, in 0..1, are cut away; the rest is
/// opaque) or `CADR_ALPHA_OPAQUE` (alpha is ignored). `cutoff` is read only for the mask.
/// `cadr_scene_set_material` later keeps a mask; it makes an opaque material blend again, so
/// that the opacity it sets shows.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_INVALID_ARGUMENT` (an unknown mode, a cutoff outside
/// 0..1) or a handle error.
/// Ownership: nothing changes hands. Thread-safety: as `cadr_scene_create`.
#[no_mangle]
pub extern "C" fn cadr_scene_set_material_alpha_mode(
    scene: CadrScene,
    material: CadrMaterial,
    mode: u32,
    cutoff: f32,
) -> CadrResult {
    guard(|| {
        let mode = match mode {
            CADR_ALPHA_OPAQUE => AlphaMode::Opaque,
            CADR_ALPHA_BLEND => AlphaMode::Blend,
            CADR_ALPHA_MASK if (0.0..=1.0).contains(&cutoff) => AlphaMode::Mask { cutoff },
            CADR_ALPHA_MASK => {
                return Err(Failure::invalid(format!(
                    "cutoff is {cutoff}; a mask's cutoff lies in 0..1"
                )))
            }
            other => {
                return Err(Failure::invalid(format!(
                    "mode is {other}; expected CADR_ALPHA_OPAQUE (0), CADR_ALPHA_MASK (1) or \
                     CADR_ALPHA_BLEND (2)"
                )))
            }
        };
        edit_material(scene, material, |_, data| {
            data.alpha_mode = mode;
            Ok(())
        })
    })
}

/// Gives a geometry's vertices texture coordinates and colours, or takes them away (both
/// NULL). `vertex_count` must be the geometry's. `uvs`: NULL (all (0, 0)) or `vertex_count`
/// × 2 floats, (0, 0) at the image's top left. `colors`: NULL (all white) or `vertex_count` × 4
/// floats, linear RGBA in 0..1 (kept in 8 bits each), multiplying the material's base colour (per-vertex results
/// such as stresses show this way, blended across each triangle). Geo nodes that use the
/// geometry draw with them from the next frame.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_INVALID_ARGUMENT` (a vertex count other than the
/// geometry's, a coordinate not finite or a colour outside 0..1, named with its index) or a
/// handle error.
/// Ownership: everything is copied; the arrays can be freed after the call.
/// Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// `uvs` and `colors` are null or valid for their counts.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_set_geometry_attributes(
    scene: CadrScene,
    geometry: CadrGeometry,
    vertex_count: u32,
    uvs: *const f32,
    colors: *const f32,
) -> CadrResult {
    guard(|| {
        let count = vertex_count as usize;
        // SAFETY: each array is null or valid for its count (the caller's contract); the
        // counts are checked against the geometry before the arrays are read.
        let read = |items: *const f32, per_vertex: usize, name: &str| unsafe {
            (!items.is_null())
                .then(|| slice(items, count * per_vertex, name))
                .transpose()
        };
        with_scene(scene, |s| {
            let handle = geometry_of(&s.graph, geometry, "geometry")?;
            let mut data = s
                .graph
                .geometry(handle)
                .map_err(graph_failure)?
                .into_owned();
            if data.vertices.len() != count {
                return Err(Failure::invalid(format!(
                    "vertex_count is {vertex_count}; geometry '{}' has {} vertices",
                    data.name,
                    data.vertices.len()
                )));
            }
            let (uvs, colors) = (read(uvs, 2, "uvs")?, read(colors, 4, "colors")?);
            if let Some(i) = uvs.and_then(|u| u.iter().position(|v| !v.is_finite())) {
                return Err(Failure::invalid(format!(
                    "uvs[{i}] (vertex {}) is not finite",
                    i / 2
                )));
            }
            if let Some(i) = colors.and_then(|c| c.iter().position(|v| !(0.0..=1.0).contains(v))) {
                return Err(Failure::invalid(format!(
                    "colors[{i}] (vertex {}) lies outside 0..1",
                    i / 4
                )));
            }
            data.attributes = if uvs.is_none() && colors.is_none() {
                Vec::new()
            } else {
                (0..count)
                    .map(|v| VertexAttributes {
                        uv: uvs.map_or([0.0; 2], |u| [u[2 * v], u[2 * v + 1]]),
                        color: colors.map_or([255; 4], |c| {
                            [0, 1, 2, 3].map(|k| (c[4 * v + k] * 255.0).round() as u8)
                        }),
                    })
                    .collect()
            };
            s.graph
                .replace_geometry(handle, data)
                .map_err(graph_failure)
        })
    })
}
