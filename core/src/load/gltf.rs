//! glTF 2.0 loading (`.gltf` with external or embedded buffers, `.glb`).
//!
//! Every byte range is checked before it is read, so a truncated or inconsistent file gives a
//! [`LoadError`] that names the buffer, view, accessor, mesh or node, never a panic. Meshes
//! become geometries (primitives are their parts), nodes keep their hierarchy and sharing, and
//! PBR factors become materials with their base-colour textures (`gltf_textures.rs`), texture
//! transforms (`KHR_texture_transform`) and alpha modes; primitives keep the texture
//! coordinates their material samples and their vertex colours.

use std::borrow::Cow;
use std::collections::hash_map::Entry;
use std::collections::HashMap;
use std::ops::Range;
use std::path::Path;

use base64::Engine as _;
use glam::{DMat4, DQuat, DVec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;

use super::gltf_buffers::{
    document_in, open_buffer_file, open_document, percent_decode, Document, GltfBuffers,
    SourceBytes, BYTES_BETWEEN_RELEASES,
};
use super::LoadError;
use crate::scene::{
    AlphaMode, Geometry, GeometrySink, Material, MeshRef, Node, Part, Scene, TextureRef,
    UvTransform, Vertex, VertexAttributes,
};

/// The glTF crate's validation reads each primitive's POSITION accessor before it checks that
/// the index exists, and panics on a file that names a missing one; this check runs first.
fn check_position_accessors(root: &gltf::json::Root) -> Result<(), String> {
    let accessors = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = gltf::json::validation::Checked::Valid(gltf::Semantic::Positions);
            if let Some(index) = primitive.attributes.get(&position) {
                if index.value() >= accessors {
                    return Err(format!(
                        "meshes[{m}].primitives[{p}].attributes.POSITION names accessor {}, but the file has {accessors} accessors",
                        index.value()
                    ));
                }
            }
        }
    }
    Ok(())
}

/// The glTF crate's `Image::source` unwraps a `mimeType` where the image has a `bufferView`,
/// and a `uri` where it has none, although its validation accepts an image without either; the
/// specification requires both, so such an image is refused first.
fn check_images(root: &gltf::json::Root) -> Result<(), String> {
    for (i, image) in root.images.iter().enumerate() {
        match (&image.buffer_view, &image.mime_type, &image.uri) {
            (Some(_), None, _) => {
                return Err(format!("images[{i}] has a bufferView but no mimeType"));
            }
            (None, _, None) => {
                return Err(format!("images[{i}] has neither a uri nor a bufferView"));
            }
            _ => {}
        }
    }
    Ok(())
}

/// Loads glTF from `bytes`; `path` names the file in errors and locates external buffers.
pub fn load_gltf_bytes(bytes: &[u8], path: &Path) -> Result<Scene, LoadError> {
    load_gltf_bytes_through(bytes, path, &mut crate::scene::KeepInScene)
}

/// [`load_gltf_bytes`], handing each geometry to `sink` as soon as it is made (see
/// [`GeometrySink`]).
pub(super) fn load_gltf_bytes_through(
    bytes: &[u8],
    path: &Path,
    sink: &mut dyn GeometrySink,
) -> Result<Scene, LoadError> {
    let document = document_in(bytes).map_err(|message| LoadError::Gltf {
        path: path.to_owned(),
        message,
    })?;
    load_gltf_through(document, path, sink)
}

/// Loads the glTF file at `path` (read a mesh at a time: see [`super::gltf_buffers`]), handing
/// each geometry to `sink` as soon as it is made (see [`GeometrySink`]).
pub(super) fn load_gltf_file_through(
    path: &Path,
    sink: &mut dyn GeometrySink,
) -> Result<Scene, LoadError> {
    load_gltf_through(open_document(path)?, path, sink)
}

/// Loads the glTF document or GLB in `source`, handing each geometry to `sink` as soon as it
/// is made (see [`GeometrySink`]); `path` names the file in errors and locates external
/// buffers.
fn load_gltf_through(
    source: Document<'_>,
    path: &Path,
    sink: &mut dyn GeometrySink,
) -> Result<Scene, LoadError> {
    let invalid = |message: String| LoadError::Invalid {
        path: path.to_owned(),
        message,
    };
    let gltf_error = |message: String| LoadError::Gltf {
        path: path.to_owned(),
        message,
    };
    let root = gltf::json::deserialize::from_slice(&source.json)
        .map_err(|e| gltf_error(gltf::Error::Deserialize(e).to_string()))?;
    let blob = source.bin;
    check_position_accessors(&root).map_err(invalid)?;
    check_images(&root).map_err(invalid)?;
    let document = gltf::Document::from_json(root).map_err(|e| gltf_error(e.to_string()))?;
    let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut buffers = resolve_buffers(&document, blob, &base_dir).map_err(invalid)?;
    check_views(&document, &buffers).map_err(invalid)?;

    let mut scene = Scene {
        name: path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        ..Scene::default()
    };
    read_image_views(&document, &mut buffers).map_err(invalid)?;
    let textures = super::gltf_textures::load_textures(&document, &buffers, path);
    buffers.release();
    // Scene textures are the glTF textures that decoded, in order.
    let mut texture_index = Vec::with_capacity(textures.len());
    for texture in textures {
        texture_index.push(texture.map(|texture| {
            scene.textures.push(texture);
            scene.textures.len() as u32 - 1
        }));
    }
    let (materials, uv_sets) = materials_of(&document, &texture_index);
    scene.materials = materials;
    let mut default_material = None;
    let mut mesh_refs: Vec<Option<MeshRef>> = Vec::new();
    // Meshes made of the same accessors (the same geometry under other materials, as cadr and
    // CSF exporters write them) share one geometry.
    let mut geometry_by_accessors: HashMap<Vec<[Option<usize>; 6]>, u32> = HashMap::new();
    let mut bytes_read_since_release = 0_u64;
    for mesh in document.meshes() {
        let key = accessor_key(&mesh, &uv_sets);
        read_accessors(&document, &mesh, &mut buffers).map_err(invalid)?;
        let (geometry, materials) = load_mesh(&mesh, &buffers, &uv_sets, path).map_err(invalid)?;
        // The geometry's bytes stand for the accessors it was read from.
        bytes_read_since_release += geometry.host_bytes();
        if bytes_read_since_release >= BYTES_BETWEEN_RELEASES {
            buffers.release();
            bytes_read_since_release = 0;
        }
        if geometry.parts.is_empty() {
            mesh_refs.push(None);
            continue;
        }
        let part_materials = materials
            .into_iter()
            .map(|m| {
                m.unwrap_or_else(|| {
                    *default_material.get_or_insert_with(|| {
                        scene.materials.push(Material::default());
                        scene.materials.len() as u32 - 1
                    })
                })
            })
            .collect();
        let geometry_index = match geometry_by_accessors.entry(key) {
            Entry::Occupied(entry) => *entry.get(),
            Entry::Vacant(entry) => *entry.insert(
                scene
                    .add_geometry(sink, geometry)
                    .map_err(|e| invalid(e.0))?,
            ),
        };
        mesh_refs.push(Some(MeshRef::new(geometry_index, part_materials)));
    }

    drop(buffers);
    for node in document.nodes() {
        let name = node
            .name()
            .map_or_else(|| format!("node {}", node.index()), str::to_owned);
        let local = node_matrix(&node);
        if !local.to_cols_array().iter().all(|c| c.is_finite()) {
            return Err(invalid(format!(
                "node {} ('{name}') has a non-finite transform",
                node.index()
            )));
        }
        scene.nodes.push(Node {
            name,
            local,
            children: node.children().map(|c| c.index() as u32).collect(),
            mesh: node.mesh().and_then(|m| mesh_refs[m.index()].clone()),
        });
    }
    scene.roots = roots_of(&document, &scene.nodes);
    scene.validate_outline().map_err(|e| invalid(e.0))?;
    Ok(scene)
}

/// The document's materials, and per material the texture-coordinate set its base-colour
/// texture samples; `texture_index` maps glTF textures to the scene's (none where one did not
/// decode).
fn materials_of(
    document: &gltf::Document,
    texture_index: &[Option<u32>],
) -> (Vec<Material>, Vec<Option<u32>>) {
    let mut uv_sets = Vec::new();
    let materials = document
        .materials()
        .enumerate()
        .map(|(i, m)| {
            let pbr = m.pbr_metallic_roughness();
            let (base_color_texture, uv_set) = base_color_texture(&pbr, texture_index);
            uv_sets.push(uv_set);
            let alpha_mode = alpha_mode(&m);
            let mut base_color = pbr.base_color_factor();
            if alpha_mode == AlphaMode::Opaque {
                // Fully opaque, wherever the colour goes (a CSF keeps it as opacity).
                base_color[3] = 1.0;
            }
            Material {
                name: m
                    .name()
                    .map_or_else(|| format!("material {i}"), str::to_owned),
                base_color,
                metallic: pbr.metallic_factor(),
                roughness: pbr.roughness_factor(),
                base_color_texture,
                alpha_mode,
            }
        })
        .collect();
    (materials, uv_sets)
}

/// The roots drawn: the default scene's nodes, or the first scene's; without a scene, every
/// node that is nobody's child.
fn roots_of(document: &gltf::Document, nodes: &[Node]) -> Vec<u32> {
    let chosen_scene = document
        .default_scene()
        .or_else(|| document.scenes().next());
    match chosen_scene {
        Some(s) => s.nodes().map(|n| n.index() as u32).collect(),
        None => {
            let mut is_child = vec![false; nodes.len()];
            for node in nodes {
                for &c in &node.children {
                    is_child[c as usize] = true;
                }
            }
            (0..nodes.len() as u32)
                .filter(|&n| !is_child[n as usize])
                .collect()
        }
    }
}

/// What a mesh's geometry is made of: per triangle primitive, its POSITION, NORMAL, index,
/// texture-coordinate (the set its material samples) and colour accessors and its mode.
fn accessor_key(mesh: &gltf::Mesh<'_>, uv_sets: &[Option<u32>]) -> Vec<[Option<usize>; 6]> {
    mesh.primitives()
        .filter(|p| {
            matches!(
                p.mode(),
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            )
        })
        .map(|p| {
            [
                p.get(&gltf::Semantic::Positions).map(|a| a.index()),
                p.get(&gltf::Semantic::Normals).map(|a| a.index()),
                p.indices().map(|a| a.index()),
                uv_set_of(&p, uv_sets)
                    .and_then(|set| p.get(&gltf::Semantic::TexCoords(set)))
                    .map(|a| a.index()),
                p.get(&gltf::Semantic::Colors(0)).map(|a| a.index()),
                Some(p.mode() as usize),
            ]
        })
        .collect()
}

fn node_matrix(node: &gltf::Node<'_>) -> DMat4 {
    match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => {
            DMat4::from_cols_array_2d(&matrix.map(|col| col.map(f64::from)))
        }
        gltf::scene::Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => {
            let [x, y, z, w] = rotation.map(f64::from);
            let rotation = DQuat::from_xyzw(x, y, z, w);
            // A non-unit quaternion from a file is normalised; a zero one stays non-finite.
            let rotation = if rotation.length_squared() > 0.0 {
                rotation.normalize()
            } else {
                rotation * f64::NAN
            };
            DMat4::from_scale_rotation_translation(
                DVec3::from(scale.map(f64::from)),
                rotation,
                DVec3::from(translation.map(f64::from)),
            )
        }
    }
}

/// Reads every buffer: the GLB binary chunk, a data URI or a file beside the glTF.
fn resolve_buffers<'a>(
    document: &gltf::Document,
    blob: Option<SourceBytes<'a>>,
    base_dir: &Path,
) -> Result<GltfBuffers<'a>, String> {
    let mut buffers = Vec::new();
    let mut blob = blob;
    // The last buffer that names the binary chunk takes it; any before it (glTF allows only
    // the first to) read it through a window of their own.
    let mut names_of_the_blob = document
        .buffers()
        .filter(|buffer| matches!(buffer.source(), gltf::buffer::Source::Bin))
        .count();
    for buffer in document.buffers() {
        let index = buffer.index();
        let (data, origin) = match buffer.source() {
            gltf::buffer::Source::Bin => {
                let missing = || {
                    format!("buffer {index} refers to the GLB binary chunk, but the file has none")
                };
                names_of_the_blob -= 1;
                let data = if names_of_the_blob == 0 {
                    blob.take().ok_or_else(missing)?
                } else {
                    blob.as_ref().ok_or_else(missing)?.duplicate().ok_or_else(|| {
                        format!("buffer {index}: no memory can be reserved for the GLB binary chunk")
                    })?
                };
                (data, "the GLB binary chunk".to_owned())
            }
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                let (_, payload) = uri
                    .split_once(";base64,")
                    .ok_or_else(|| format!("buffer {index} has a data URI that is not base64"))?;
                let data = base64::engine::general_purpose::STANDARD
                    .decode(payload)
                    .map_err(|e| format!("buffer {index} has invalid base64 data: {e}"))?;
                (
                    SourceBytes::Memory(Cow::Owned(data)),
                    "its data URI".to_owned(),
                )
            }
            gltf::buffer::Source::Uri(uri) => {
                let file = base_dir.join(percent_decode(uri));
                let data = open_buffer_file(&file, buffer.length()).map_err(|e| {
                    format!(
                        "buffer {index} refers to '{}', which cannot be read: {e}",
                        file.display()
                    )
                })?;
                (data, format!("'{}'", file.display()))
            }
        };
        let available = data.bytes().len();
        if available < buffer.length() {
            return Err(format!(
                "buffer {index} declares {} bytes, but {origin} holds only {available} (truncated?)",
                buffer.length(),
            ));
        }
        buffers.push(data);
    }
    Ok(GltfBuffers(buffers))
}

/// The bytes of `view` from `offset` within it, for `length` bytes at most: the buffer and
/// the range, in `u64` (a view's offset and length are each up to `u64::MAX` in the JSON; the
/// views were checked against their buffers before anything is read).
fn view_range(view: &gltf::buffer::View<'_>, offset: u128, length: u128) -> (usize, Range<u64>) {
    let view_start = view.offset() as u128;
    let view_end = view_start + view.length() as u128;
    let start = (view_start + offset).min(view_end);
    let end = start.saturating_add(length).min(view_end);
    (view.buffer().index(), start as u64..end as u64)
}

/// Reads from their files the bytes of every accessor `mesh`'s primitives name (attributes,
/// indices, sparse indices and values), each as far as its elements reach within its view.
fn read_accessors(
    document: &gltf::Document,
    mesh: &gltf::Mesh<'_>,
    buffers: &mut GltfBuffers<'_>,
) -> Result<(), String> {
    let Some(json) = document.as_json().meshes.get(mesh.index()) else {
        return Ok(());
    };
    let named = json.primitives.iter().flat_map(|primitive| {
        let attributes = primitive.attributes.values().map(|index| index.value());
        attributes.chain(primitive.indices.map(|index| index.value()))
    });
    // Validation has checked every accessor index.
    for accessor in named.filter_map(|index| document.accessors().nth(index)) {
        let element = accessor.size() as u128;
        let count = accessor.count() as u128;
        if let Some(view) = accessor.view() {
            let stride = view.stride().map_or(element, |s| s as u128);
            let (buffer, range) = view_range(&view, accessor.offset() as u128, stride * count);
            buffers.read(buffer, range)?;
        }
        if let Some(sparse) = accessor.sparse() {
            let sparse_count = sparse.count() as u128;
            for (_, view, offset, size) in sparse_parts(&sparse, element) {
                let (buffer, range) = view_range(&view, offset, size * sparse_count);
                buffers.read(buffer, range)?;
            }
        }
    }
    Ok(())
}

/// A sparse accessor's two arrays: what each is, its view, its offset in the view and the size
/// of one of its elements (`element`: the accessor's).
fn sparse_parts<'a>(
    sparse: &gltf::accessor::sparse::Sparse<'a>,
    element: u128,
) -> [(&'static str, gltf::buffer::View<'a>, u128, u128); 2] {
    let index_size = match sparse.indices().index_type() {
        gltf::accessor::sparse::IndexType::U8 => 1,
        gltf::accessor::sparse::IndexType::U16 => 2,
        gltf::accessor::sparse::IndexType::U32 => 4,
    };
    [
        (
            "indices",
            sparse.indices().view(),
            sparse.indices().offset() as u128,
            index_size,
        ),
        (
            "values",
            sparse.values().view(),
            sparse.values().offset() as u128,
            element,
        ),
    ]
}

/// Reads from their files the bytes of every image that lies in a buffer view.
fn read_image_views(
    document: &gltf::Document,
    buffers: &mut GltfBuffers<'_>,
) -> Result<(), String> {
    for image in document.images() {
        if let gltf::image::Source::View { view, .. } = image.source() {
            let (buffer, range) = view_range(&view, 0, view.length() as u128);
            buffers.read(buffer, range)?;
        }
    }
    Ok(())
}

/// Checks that every buffer view lies within its buffer (in `u128`: a view's offset and length
/// may each be up to `u64::MAX`, and the glTF crate adds them unchecked).
fn check_views(document: &gltf::Document, buffers: &GltfBuffers<'_>) -> Result<(), String> {
    for view in document.views() {
        let end = view.offset() as u128 + view.length() as u128;
        let available = buffers.get(view.buffer().index()).map_or(0, <[u8]>::len) as u128;
        if end > available {
            return Err(format!(
                "bufferView {} covers bytes {}..{end} of buffer {}, which has {available}",
                view.index(),
                view.offset(),
                view.buffer().index()
            ));
        }
    }
    Ok(())
}

/// Host bytes that loading holds for each element of an accessor that has no bufferView (all
/// zeros but for its sparse values): the element read, and the vertex, attribute and index
/// copies made from it, rounded up. Such an accessor's `count` is not bounded by any bytes in
/// the file, so it is checked against the memory budget before the glTF crate's reader
/// allocates `count` elements (an allocation that fails aborts the process).
const LOADED_BYTES_PER_VIEWLESS_ELEMENT: u64 = 64;

/// Checks that `accessor`'s elements lie within its view, and that it has the expected type.
/// Sizes are computed in `u128`, where a hostile `count` or offset cannot overflow them.
fn check_accessor(
    accessor: &gltf::Accessor<'_>,
    usage: &str,
    types: &[DataType],
    dimensions: Dimensions,
) -> Result<(), String> {
    let index = accessor.index();
    if !types.contains(&accessor.data_type()) || accessor.dimensions() != dimensions {
        return Err(format!(
            "accessor {index} used as {usage} is {:?} {:?}; expected {types:?} {dimensions:?}",
            accessor.data_type(),
            accessor.dimensions()
        ));
    }
    let element = accessor.size() as u128;
    let count = accessor.count() as u128;
    // The glTF crate's readers compute `count - 1` unchecked.
    if count == 0 {
        return Err(format!(
            "accessor {index} ({usage}) has count 0; glTF requires at least 1"
        ));
    }
    match accessor.view() {
        Some(view) => {
            // The glTF crate's reader takes each element from `stride` bytes, and indexes past
            // them (a panic) where the stride is shorter than an element.
            if let Some(stride) = view.stride().filter(|&s| (s as u128) < element) {
                return Err(format!(
                    "accessor {index} ({usage}) has {element}-byte elements, but bufferView {} has a byteStride of {stride}",
                    view.index()
                ));
            }
            let stride = view.stride().map_or(element, |s| s as u128);
            let needed = accessor.offset() as u128 + stride * (count - 1) + element;
            if needed > view.length() as u128 {
                return Err(format!(
                    "accessor {index} ({usage}, {count} elements) needs {needed} bytes of bufferView {}, which has {}",
                    view.index(),
                    view.length()
                ));
            }
        }
        None => {
            let budget = crate::memory_budget::budget()?;
            let needed = count.saturating_mul(LOADED_BYTES_PER_VIEWLESS_ELEMENT.into());
            if needed > budget.into() {
                return Err(format!(
                    "accessor {index} ({usage}) has no bufferView and {}",
                    crate::memory_budget::over_budget(
                        &format!("its {count} elements"),
                        u64::try_from(needed).unwrap_or(u64::MAX),
                        budget,
                    )
                ));
            }
        }
    }
    if let Some(sparse) = accessor.sparse() {
        let sparse_count = sparse.count() as u128;
        if sparse_count == 0 {
            return Err(format!(
                "accessor {index} ({usage}) has sparse.count 0; glTF requires at least 1"
            ));
        }
        for (what, view, offset, size) in sparse_parts(&sparse, element) {
            // glTF forbids a byteStride here; the glTF crate's reader would step by it (and
            // panic where it is shorter than an element).
            if let Some(stride) = view.stride() {
                return Err(format!(
                    "accessor {index} ({usage}) has sparse {what} in bufferView {}, which has a byteStride of {stride}; glTF forbids one there",
                    view.index()
                ));
            }
            if offset + size * sparse_count > view.length() as u128 {
                return Err(format!(
                    "accessor {index} ({usage}) has sparse {what} beyond the end of bufferView {}",
                    view.index()
                ));
            }
        }
    }
    Ok(())
}

/// One mesh as a geometry whose parts are its triangle primitives, with each part's material
/// (`None` = the glTF default material). `file` names the file in warnings.
fn load_mesh(
    mesh: &gltf::Mesh<'_>,
    buffers: &GltfBuffers<'_>,
    uv_sets: &[Option<u32>],
    file: &Path,
) -> Result<(Geometry, Vec<Option<u32>>), String> {
    let mesh_name = mesh
        .name()
        .map_or_else(|| format!("mesh {}", mesh.index()), str::to_owned);
    let mut geometry = Geometry {
        name: mesh_name.clone(),
        ..Geometry::default()
    };
    let mut materials = Vec::new();
    for primitive in mesh.primitives() {
        let at = format!(
            "mesh {} ('{mesh_name}') primitive {}",
            mesh.index(),
            primitive.index()
        );
        let mode = primitive.mode();
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            log::warn!(
                "{}: {at}: {mode:?} primitives are not drawn yet",
                file.display()
            );
            continue;
        }
        let positions_accessor = checked_accessors(&primitive, &at)?;
        let attributes = read_attributes(
            &primitive,
            &format!("{}: {at}", file.display()),
            buffers,
            uv_sets,
            positions_accessor.count(),
        )
        .map_err(|e| format!("{at}: {e}"))?;
        let reader = primitive.reader(|b| buffers.get(b.index()));
        let positions: Vec<[f32; 3]> = reader
            .read_positions()
            .ok_or_else(|| format!("{at}: POSITION cannot be read"))?
            .collect();
        if let Some((i, p)) = positions
            .iter()
            .enumerate()
            .find(|(_, p)| !p.iter().all(|c| c.is_finite()))
        {
            return Err(format!("{at}: POSITION {i} is not finite: {p:?}"));
        }
        let normals: Option<Vec<[f32; 3]>> = reader.read_normals().map(Iterator::collect);
        if let Some(normals) = &normals {
            if let Some((i, n)) = normals
                .iter()
                .enumerate()
                .find(|(_, n)| !n.iter().all(|c| c.is_finite()))
            {
                return Err(format!("{at}: NORMAL {i} is not finite: {n:?}"));
            }
        }
        let raw_indices: Vec<u32> = match reader.read_indices() {
            Some(indices) => indices.into_u32().collect(),
            None => (0..positions.len() as u32).collect(),
        };
        if let Some((i, &index)) = raw_indices
            .iter()
            .enumerate()
            .find(|(_, &x)| x as usize >= positions.len())
        {
            return Err(format!(
                "{at}: index {i} is {index}, but the primitive has {} vertices",
                positions.len()
            ));
        }
        let triangles = triangle_list(&raw_indices, mode);
        append_primitive(&mut geometry, &positions, normals, &triangles, attributes);
        materials.push(primitive.material().index().map(|m| m as u32));
    }
    Ok((geometry, materials))
}

/// Checks a primitive's POSITION, NORMAL and index accessors (their types, and that they lie
/// in their buffers), before the glTF crate reads them; returns the POSITION accessor. `at`
/// names the primitive in errors.
fn checked_accessors<'a>(
    primitive: &gltf::Primitive<'a>,
    at: &str,
) -> Result<gltf::Accessor<'a>, String> {
    let positions_accessor = primitive
        .get(&gltf::Semantic::Positions)
        .ok_or_else(|| format!("{at} has no POSITION"))?;
    check_accessor(
        &positions_accessor,
        "POSITION",
        &[DataType::F32],
        Dimensions::Vec3,
    )
    .map_err(|e| format!("{at}: {e}"))?;
    if let Some(normals) = primitive.get(&gltf::Semantic::Normals) {
        check_accessor(&normals, "NORMAL", &[DataType::F32], Dimensions::Vec3)
            .map_err(|e| format!("{at}: {e}"))?;
    }
    if let Some(indices) = primitive.indices() {
        check_accessor(
            &indices,
            "indices",
            &[DataType::U8, DataType::U16, DataType::U32],
            Dimensions::Scalar,
        )
        .map_err(|e| format!("{at}: {e}"))?;
    }
    Ok(positions_accessor)
}

/// Appends a primitive to `geometry` as one part: its vertices (with `normals`, or without
/// them flat-shaded, each triangle with vertices of its own), its `triangles`' indices, and its
/// vertex attributes (the geometry's other primitives get defaults where only some have them).
fn append_primitive(
    geometry: &mut Geometry,
    positions: &[[f32; 3]],
    normals: Option<Vec<[f32; 3]>>,
    triangles: &[u32],
    attributes: Option<Vec<VertexAttributes>>,
) {
    let base = geometry.vertices.len() as u32;
    if attributes.is_some() && geometry.attributes.is_empty() {
        geometry
            .attributes
            .resize(geometry.vertices.len(), VertexAttributes::default());
    }
    let first_index = geometry.indices.len() as u32;
    match normals {
        Some(normals) => {
            geometry.vertices.extend(
                positions
                    .iter()
                    .zip(&normals)
                    .map(|(&position, &normal)| Vertex { position, normal }),
            );
            geometry.indices.extend(triangles.iter().map(|&i| base + i));
            if let Some(attributes) = &attributes {
                geometry.attributes.extend_from_slice(attributes);
            }
        }
        None => {
            // glTF: without normals, flat shading. Each triangle gets its own vertices.
            for (t, triangle) in triangles.chunks_exact(3).enumerate() {
                let [a, b, c] =
                    [0, 1, 2].map(|k| DVec3::from(positions[triangle[k] as usize].map(f64::from)));
                let normal = (b - a)
                    .cross(c - a)
                    .normalize_or_zero()
                    .as_vec3()
                    .to_array();
                for &index in triangle {
                    geometry.vertices.push(Vertex {
                        position: positions[index as usize],
                        normal,
                    });
                    if let Some(attributes) = &attributes {
                        geometry.attributes.push(attributes[index as usize]);
                    }
                }
                geometry
                    .indices
                    .extend((0..3).map(|k| base + 3 * t as u32 + k));
            }
        }
    }
    if attributes.is_none() && !geometry.attributes.is_empty() {
        geometry
            .attributes
            .resize(geometry.vertices.len(), VertexAttributes::default());
    }
    let index_count = geometry.indices.len() as u32 - first_index;
    geometry.parts.push(Part {
        first_index,
        index_count,
        ..Part::default()
    });
}

/// The primitive's texture coordinates (the set its material samples) and vertex colours
/// (`COLOR_0`), one per vertex; `None` when it has neither. A material that samples a set the
/// primitive lacks gets a warning (saying it happened `at`: the file and primitive) and (0, 0).
fn read_attributes(
    primitive: &gltf::Primitive<'_>,
    at: &str,
    buffers: &GltfBuffers<'_>,
    uv_sets: &[Option<u32>],
    vertex_count: usize,
) -> Result<Option<Vec<VertexAttributes>>, String> {
    let check_count = |accessor: &gltf::Accessor<'_>, usage: &str| {
        if accessor.count() == vertex_count {
            Ok(())
        } else {
            Err(format!(
                "accessor {} ({usage}) has {} elements for {vertex_count} vertices",
                accessor.index(),
                accessor.count()
            ))
        }
    };
    let uv_set = uv_set_of(primitive, uv_sets);
    let uv_accessor = match uv_set {
        Some(set) => {
            let accessor = primitive.get(&gltf::Semantic::TexCoords(set));
            if accessor.is_none() {
                log::warn!(
                    "{at}: its material samples TEXCOORD_{set}, which the primitive does not have"
                );
            }
            accessor
        }
        None => None,
    };
    let uv_usage = format!("TEXCOORD_{}", uv_set.unwrap_or(0));
    if let Some(accessor) = &uv_accessor {
        check_accessor(
            accessor,
            &uv_usage,
            &[DataType::F32, DataType::U8, DataType::U16],
            Dimensions::Vec2,
        )?;
        check_count(accessor, &uv_usage)?;
    }
    let color_accessor = primitive.get(&gltf::Semantic::Colors(0));
    if let Some(accessor) = &color_accessor {
        let dimensions = if accessor.dimensions() == Dimensions::Vec3 {
            Dimensions::Vec3
        } else {
            Dimensions::Vec4
        };
        check_accessor(
            accessor,
            "COLOR_0",
            &[DataType::F32, DataType::U8, DataType::U16],
            dimensions,
        )?;
        check_count(accessor, "COLOR_0")?;
    }
    if uv_accessor.is_none() && color_accessor.is_none() {
        return Ok(None);
    }
    let reader = primitive.reader(|b| buffers.get(b.index()));
    let mut attributes = vec![VertexAttributes::default(); vertex_count];
    if let (Some(set), Some(_)) = (uv_set, &uv_accessor) {
        let uvs = reader
            .read_tex_coords(set)
            .ok_or_else(|| format!("{uv_usage} cannot be read"))?
            .into_f32();
        for (i, (attribute, uv)) in attributes.iter_mut().zip(uvs).enumerate() {
            if !uv.iter().all(|c| c.is_finite()) {
                return Err(format!("{uv_usage} {i} is not finite: {uv:?}"));
            }
            attribute.uv = uv;
        }
    }
    if color_accessor.is_some() {
        let colors = reader
            .read_colors(0)
            .ok_or("COLOR_0 cannot be read")?
            .into_rgba_u8();
        for (attribute, color) in attributes.iter_mut().zip(colors) {
            attribute.color = color;
        }
    }
    Ok(Some(attributes))
}

/// Converts strip and fan indices to a triangle list.
fn triangle_list(indices: &[u32], mode: Mode) -> Vec<u32> {
    match mode {
        Mode::TriangleStrip => (2..indices.len())
            .flat_map(|i| {
                if i % 2 == 0 {
                    [indices[i - 2], indices[i - 1], indices[i]]
                } else {
                    [indices[i - 1], indices[i - 2], indices[i]]
                }
            })
            .collect(),
        Mode::TriangleFan => (2..indices.len())
            .flat_map(|i| [indices[0], indices[i - 1], indices[i]])
            .collect(),
        _ => indices[..indices.len() / 3 * 3].to_vec(),
    }
}

/// How the material's `alphaMode` uses alpha: the factor's alpha is the opacity in BLEND, is
/// compared with the cutoff in MASK, and is made 1 in OPAQUE.
fn alpha_mode(material: &gltf::Material<'_>) -> AlphaMode {
    match material.alpha_mode() {
        gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
        gltf::material::AlphaMode::Mask => AlphaMode::Mask {
            cutoff: material.alpha_cutoff().unwrap_or(0.5),
        },
        gltf::material::AlphaMode::Blend => AlphaMode::Blend,
    }
}

/// The material's base-colour texture (with its `KHR_texture_transform`) and the
/// texture-coordinate set it samples; none when the material has no texture or its image
/// could not be decoded (`texture_index` maps glTF textures to the scene's).
fn base_color_texture(
    pbr: &gltf::material::PbrMetallicRoughness<'_>,
    texture_index: &[Option<u32>],
) -> (Option<TextureRef>, Option<u32>) {
    let Some(info) = pbr.base_color_texture() else {
        return (None, None);
    };
    let Some(texture) = texture_index.get(info.texture().index()).copied().flatten() else {
        return (None, None);
    };
    let (transform, set) = match info.texture_transform() {
        Some(t) => (
            UvTransform::from_offset_rotation_scale(t.offset(), t.rotation(), t.scale()),
            t.tex_coord().unwrap_or(info.tex_coord()),
        ),
        None => (UvTransform::IDENTITY, info.tex_coord()),
    };
    (Some(TextureRef { texture, transform }), Some(set))
}

/// The texture-coordinate set the primitive's material samples, if it samples one.
fn uv_set_of(primitive: &gltf::Primitive<'_>, uv_sets: &[Option<u32>]) -> Option<u32> {
    primitive
        .material()
        .index()
        .and_then(|m| uv_sets.get(m).copied().flatten())
}
