//! Geometry from the host's arrays, and materials from parameters.

use std::ffi::c_char;

use cadr_core::scene::{Geometry, Material, Part, Vertex};

use crate::args::{deliver, optional_str, read_sized, slice};
use crate::bounds::CadrBounds;
use crate::error::{guard, Failure};
use crate::scene::{
    geometry_of, geometry_value, graph_failure, material_of, material_value, with_scene,
    CadrGeometry, CadrMaterial, CadrScene,
};

/// A range of a geometry's indices drawn with one material, and its range of edge indices.
///
/// Frozen: parts lie in an array the host indexes with its own `sizeof(CadrPart)`, so this
/// struct never changes within a major version.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CadrPart {
    /// First index in `indices`.
    pub first_index: u32,
    /// Number of indices (a multiple of 3).
    pub index_count: u32,
    /// First index in `wire_indices`.
    pub first_wire_index: u32,
    /// Number of wire indices (a multiple of 2; 0 when the part has no stored edges).
    pub wire_index_count: u32,
}

/// Geometry in the host's arrays. Everything is copied; the arrays can be freed after the
/// call.
///
/// The struct grows by appending fields: the host sets `size` to `sizeof(CadrGeometryDesc)`. A field an
/// older host does not know keeps its old behaviour (read as 0); a newer host's fields this
/// library does not know must be 0.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrGeometryDesc {
    /// `sizeof(CadrGeometryDesc)`, set by the host.
    pub size: u32,
    /// Name (NULL: empty).
    pub name: *const c_char,
    /// `vertex_count` × 3 floats: object-space positions.
    pub positions: *const f32,
    /// NULL, or `vertex_count` × 3 floats: unit normals. NULL computes smooth normals from the
    /// triangles (area-weighted).
    pub normals: *const f32,
    /// Number of vertices.
    pub vertex_count: u32,
    /// Triangle-list indices into the vertices.
    pub indices: *const u32,
    /// Number of indices (a multiple of 3).
    pub index_count: u32,
    /// NULL, or line-list indices: the edges drawn by the "edges" shade mode. Without them,
    /// edges are derived from the triangles by crease angle.
    pub wire_indices: *const u32,
    /// Number of wire indices (a multiple of 2).
    pub wire_index_count: u32,
    /// The parts; NULL with `part_count` 0 makes one part of all indices (and wire indices).
    pub parts: *const CadrPart,
    /// Number of parts.
    pub part_count: u32,
}

/// Material parameters (metallic-roughness, as glTF).
///
/// The struct grows by appending fields: the host sets `size` to `sizeof(CadrMaterialDesc)`. A field an
/// older host does not know keeps its old behaviour (read as 0); a newer host's fields this
/// library does not know must be 0.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrMaterialDesc {
    /// `sizeof(CadrMaterialDesc)`, set by the host.
    pub size: u32,
    /// Name (NULL: empty).
    pub name: *const c_char,
    /// Linear RGBA base color, each 0..1.
    pub base_color: [f32; 4],
    /// 0 = dielectric, 1 = metal.
    pub metallic: f32,
    /// 0 = mirror, 1 = fully rough.
    pub roughness: f32,
}

fn smooth_normals(positions: &[[f32; 3]], indices: &[u32]) -> Vec<[f32; 3]> {
    let mut sums = vec![glam::Vec3::ZERO; positions.len()];
    for triangle in indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| triangle[k] as usize);
        let (pa, pb, pc) = (
            glam::Vec3::from(positions[a]),
            glam::Vec3::from(positions[b]),
            glam::Vec3::from(positions[c]),
        );
        // The cross product's length is twice the area: bigger triangles weigh more.
        let normal = (pb - pa).cross(pc - pa);
        for v in [a, b, c] {
            sums[v] += normal;
        }
    }
    sums.into_iter()
        .map(|n| n.try_normalize().unwrap_or(glam::Vec3::Z).to_array())
        .collect()
}

/// Copies and checks a geometry description; errors name the field and the index.
///
/// # Safety
/// Every pointer in `desc` is null or valid for its count.
unsafe fn geometry_from(desc: *const CadrGeometryDesc) -> Result<Geometry, Failure> {
    // SAFETY: null or valid for its size (the caller's contract); zero bytes are a
    // CadrGeometryDesc (null arrays, zero counts).
    let desc = unsafe { read_sized(desc, ("desc", "CadrGeometryDesc"), std::mem::zeroed()) }?;
    let vertices = desc.vertex_count as usize;
    // SAFETY: the pointers are valid for their counts (the caller's contract).
    let (name, positions, normals, indices, wire_indices, parts) = unsafe {
        (
            optional_str(desc.name, "desc.name")?.unwrap_or(""),
            slice(desc.positions, vertices * 3, "desc.positions")?,
            if desc.normals.is_null() {
                None
            } else {
                Some(slice(desc.normals, vertices * 3, "desc.normals")?)
            },
            slice(desc.indices, desc.index_count as usize, "desc.indices")?,
            slice(
                desc.wire_indices,
                desc.wire_index_count as usize,
                "desc.wire_indices",
            )?,
            slice(desc.parts, desc.part_count as usize, "desc.parts")?,
        )
    };
    if let Some(i) = positions.iter().position(|v| !v.is_finite()) {
        return Err(Failure::invalid(format!(
            "desc.positions[{i}] (vertex {}) is not finite",
            i / 3
        )));
    }
    if let Some(i) = indices.iter().position(|&v| v as usize >= vertices) {
        return Err(Failure::invalid(format!(
            "desc.indices[{i}] = {} is not below vertex_count {vertices}",
            indices[i]
        )));
    }
    let points: Vec<[f32; 3]> = positions
        .chunks_exact(3)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    let normals: Vec<[f32; 3]> = match normals {
        Some(n) => n.chunks_exact(3).map(|n| [n[0], n[1], n[2]]).collect(),
        None => smooth_normals(&points, indices),
    };
    let parts: Vec<Part> = if parts.is_empty() {
        vec![Part {
            first_index: 0,
            index_count: desc.index_count,
            first_wire_index: 0,
            wire_index_count: desc.wire_index_count,
        }]
    } else {
        parts
            .iter()
            .map(|p| Part {
                first_index: p.first_index,
                index_count: p.index_count,
                first_wire_index: p.first_wire_index,
                wire_index_count: p.wire_index_count,
            })
            .collect()
    };
    let geometry = Geometry {
        name: name.to_owned(),
        vertices: points
            .into_iter()
            .zip(normals)
            .map(|(position, normal)| Vertex { position, normal })
            .collect(),
        indices: indices.to_vec(),
        wire_indices: wire_indices.to_vec(),
        parts,
        attributes: Vec::new(),
    };
    geometry
        .validate(0)
        .map_err(|e| Failure::invalid(format!("desc: {}", e.0)))?;
    Ok(geometry)
}

/// Copies and checks material parameters.
///
/// # Safety
/// `desc` is null or valid, its name null or a valid string.
unsafe fn material_from(desc: *const CadrMaterialDesc) -> Result<Material, Failure> {
    // SAFETY: null or valid for its size (the caller's contract); zero bytes are a
    // CadrMaterialDesc.
    let desc = unsafe { read_sized(desc, ("desc", "CadrMaterialDesc"), std::mem::zeroed()) }?;
    // SAFETY: the name is null or a valid string (the caller's contract).
    let name = unsafe { optional_str(desc.name, "desc.name") }?.unwrap_or("");
    let values = [
        ("base_color[0]", desc.base_color[0]),
        ("base_color[1]", desc.base_color[1]),
        ("base_color[2]", desc.base_color[2]),
        ("base_color[3]", desc.base_color[3]),
        ("metallic", desc.metallic),
        ("roughness", desc.roughness),
    ];
    if let Some((field, value)) = values.iter().find(|(_, v)| !(0.0..=1.0).contains(v)) {
        return Err(Failure::invalid(format!(
            "desc.{field} is {value}; it must lie in 0..1"
        )));
    }
    Ok(Material {
        name: name.to_owned(),
        base_color: desc.base_color,
        metallic: desc.metallic,
        roughness: desc.roughness,
        ..Material::default()
    })
}

/// Creates a geometry from the host's arrays (copied).
///
/// Returns `CADR_RESULT_OK` and writes `*geometry`, `CADR_RESULT_NULL_ARGUMENT`,
/// `CADR_RESULT_INVALID_ARGUMENT` (the message names the field and index: an index beyond the
/// vertices, a part beyond the indices, a count not a multiple of 3, a non-finite position) or
/// a handle error.
/// Ownership: the geometry belongs to the scene. Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// `desc` is null or valid with arrays valid for their counts; `geometry` null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_create_geometry(
    scene: CadrScene,
    desc: *const CadrGeometryDesc,
    geometry: *mut CadrGeometry,
) -> crate::CadrResult {
    guard(|| {
        // SAFETY: forwarded contract.
        let data = unsafe { geometry_from(desc) }?;
        let value = with_scene(scene, |s| {
            s.graph
                .create_geometry(data)
                .map(geometry_value)
                .map_err(graph_failure)
        })?;
        // SAFETY: geometry is null or writable (the caller's contract).
        unsafe { deliver(geometry, "geometry", value) }
    })
}

/// Replaces a geometry's data; Geo nodes that use it draw the new data. The part count must
/// stay the same (their part materials are kept).
///
/// Ownership: nothing changes hands; the arguments are read during the call only.
/// Returns as `cadr_scene_create_geometry`. Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// As `cadr_scene_create_geometry`.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_replace_geometry(
    scene: CadrScene,
    geometry: CadrGeometry,
    desc: *const CadrGeometryDesc,
) -> crate::CadrResult {
    guard(|| {
        // SAFETY: forwarded contract.
        let data = unsafe { geometry_from(desc) }?;
        with_scene(scene, |s| {
            let handle = geometry_of(&s.graph, geometry, "geometry")?;
            s.graph
                .replace_geometry(handle, data)
                .map_err(graph_failure)
        })
    })
}

/// Destroys a geometry that no Geo node uses.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_IN_USE` or a handle error.
/// Ownership: the handle (or item) is given back to cadr and invalid afterwards.
/// Thread-safety: as `cadr_scene_create`.
#[no_mangle]
pub extern "C" fn cadr_scene_destroy_geometry(
    scene: CadrScene,
    geometry: CadrGeometry,
) -> crate::CadrResult {
    guard(|| {
        with_scene(scene, |s| {
            let handle = geometry_of(&s.graph, geometry, "geometry")?;
            s.graph.destroy_geometry(handle).map_err(graph_failure)
        })
    })
}

/// Writes the object-space bounds of a geometry's vertices.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the outputs are the caller's; cadr keeps no pointer to them.
/// Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// `bounds` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_geometry_bounds(
    scene: CadrScene,
    geometry: CadrGeometry,
    bounds: *mut CadrBounds,
) -> crate::CadrResult {
    guard(|| {
        let value = with_scene(scene, |s| {
            let handle = geometry_of(&s.graph, geometry, "geometry")?;
            s.graph.geometry_bounds(handle).map_err(graph_failure)
        })?;
        // SAFETY: bounds is null or writable (the caller's contract).
        unsafe { deliver(bounds, "bounds", value.into()) }
    })
}

/// Sets how many bytes of geometry the scene keeps in host memory: geometries created or
/// replaced past it go to the scene's page file (`cadr-pages-PID-N.bin` in `CADR_PAGE_DIR`,
/// else `TMPDIR`, else `/var/tmp`; removed with the scene) and are read back when the GPU needs them, so that a
/// model larger than memory can be loaded. The default is half the memory budget
/// (`CADR_MEMORY_BUDGET`, else the machine's memory); 0 sends every geometry made from then on
/// to the file. Geometries already made stay where they are. `cadr_scene_statistics` reports
/// what is where.
///
/// Returns `CADR_RESULT_OK` or a handle error.
/// Ownership: nothing is kept. Thread-safety: as `cadr_scene_create`.
#[no_mangle]
pub extern "C" fn cadr_scene_set_geometry_memory_limit(
    scene: CadrScene,
    bytes: u64,
) -> crate::CadrResult {
    guard(|| {
        with_scene(scene, |s| {
            s.graph.set_geometry_memory_limit(bytes);
            Ok(())
        })
    })
}

/// Creates a material.
///
/// Returns `CADR_RESULT_OK` and writes `*material`, `CADR_RESULT_NULL_ARGUMENT`,
/// `CADR_RESULT_INVALID_ARGUMENT` (a value outside 0..1, named) or a handle error.
/// Ownership: the material belongs to the scene. Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// `desc` is null or valid; `material` null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_create_material(
    scene: CadrScene,
    desc: *const CadrMaterialDesc,
    material: *mut CadrMaterial,
) -> crate::CadrResult {
    guard(|| {
        // SAFETY: forwarded contract.
        let data = unsafe { material_from(desc) }?;
        let value = with_scene(scene, |s| {
            s.graph
                .create_material(data)
                .map(material_value)
                .map_err(graph_failure)
        })?;
        // SAFETY: material is null or writable (the caller's contract).
        unsafe { deliver(material, "material", value) }
    })
}

/// Changes a material's parameters; every part using it is drawn with them. A texture the
/// material has (from a loaded file or `cadr_scene_set_material_texture`) is kept, and so is
/// an alpha cutoff (glTF MASK); otherwise `base_color[3]` is the opacity, also for a material
/// a file or `cadr_scene_set_material_alpha_mode` made OPAQUE.
///
/// Ownership: nothing changes hands; the arguments are read during the call only.
/// Returns as `cadr_scene_create_material`. Thread-safety: as `cadr_scene_create`.
///
/// # Safety
/// `desc` is null or valid.
#[no_mangle]
pub unsafe extern "C" fn cadr_scene_set_material(
    scene: CadrScene,
    material: CadrMaterial,
    desc: *const CadrMaterialDesc,
) -> crate::CadrResult {
    guard(|| {
        // SAFETY: forwarded contract.
        let mut data = unsafe { material_from(desc) }?;
        with_scene(scene, |s| {
            let handle = material_of(&s.graph, material, "material")?;
            let current = s.graph.material(handle).map_err(graph_failure)?;
            data.base_color_texture = current.base_color_texture;
            // A mask keeps cutting; a file's OPAQUE mode must not hide the opacity a host sets.
            if let cadr_core::scene::AlphaMode::Mask { .. } = current.alpha_mode {
                data.alpha_mode = current.alpha_mode;
            }
            s.graph.set_material(handle, data).map_err(graph_failure)
        })
    })
}

/// Destroys a material that no part uses.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_IN_USE` or a handle error.
/// Ownership: the handle (or item) is given back to cadr and invalid afterwards.
/// Thread-safety: as `cadr_scene_create`.
#[no_mangle]
pub extern "C" fn cadr_scene_destroy_material(
    scene: CadrScene,
    material: CadrMaterial,
) -> crate::CadrResult {
    guard(|| {
        with_scene(scene, |s| {
            let handle = material_of(&s.graph, material, "material")?;
            s.graph.destroy_material(handle).map_err(graph_failure)
        })
    })
}
