//! Writing glTF 2.0: one buffer, per geometry a position and a normal accessor (and, when it
//! has them, texture coordinates and colours) shared by its parts, one index accessor per
//! part; textures as PNG images in the buffer with their samplers, texture transforms as
//! `KHR_texture_transform`; a mesh per distinct (geometry, part materials, hidden
//! parts) combination; the node DAG unfolded into trees with matrices at full precision.

use std::collections::HashMap;
use std::io::Write as _;

use glam::DMat4;
use serde_json::{json, Value};

use crate::scene::{
    Aabb, AlphaMode, GeometryStore, NodeIndex, Scene, SceneError, UvTransform, Wrap,
};

/// A glTF document: its JSON (without the buffer URI) and binary buffer, in memory or in the
/// file it was written to as it was made.
pub struct GltfDocument {
    json: Value,
    /// The binary buffer.
    pub binary: Binary,
    /// Number of glTF nodes after unfolding shared subgraphs.
    pub unfolded_nodes: usize,
}

/// Where a document's binary buffer goes as it is made: memory, or a file, so that a scene
/// larger than memory is written a geometry at a time.
pub enum Binary {
    /// In memory.
    Memory(Vec<u8>),
    /// Written to a file (from its start) as it is made.
    File {
        /// The file, behind a buffer.
        writer: std::io::BufWriter<std::fs::File>,
        /// Bytes written so far.
        len: u64,
        /// The first write that failed: nothing is written after it.
        failed: Option<std::io::Error>,
    },
}

impl Binary {
    /// A buffer written to `file` as it is made.
    pub fn to_file(file: std::fs::File) -> Self {
        Self::File {
            writer: std::io::BufWriter::new(file),
            len: 0,
            failed: None,
        }
    }

    /// Its length so far.
    pub fn len(&self) -> u64 {
        match self {
            Self::Memory(bytes) => bytes.len() as u64,
            Self::File { len, .. } => *len,
        }
    }

    /// Whether nothing has been written.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn append(&mut self, data: &[u8]) {
        match self {
            Self::Memory(bytes) => bytes.extend_from_slice(data),
            Self::File {
                writer,
                len,
                failed,
            } => {
                if failed.is_none() {
                    *failed = writer.write_all(data).err();
                }
                *len += data.len() as u64;
            }
        }
    }

    /// Pads with zeros to a multiple of 4 bytes.
    fn pad(&mut self) {
        let padding = (4 - self.len() % 4) % 4;
        self.append(&[0; 3][..padding as usize]);
    }

    /// The file, everything written to it (or the first write that failed); none for a buffer
    /// in memory.
    pub fn finish(self) -> Option<std::io::Result<std::fs::File>> {
        match self {
            Self::Memory(_) => None,
            Self::File { writer, failed, .. } => Some(match failed {
                Some(error) => Err(error),
                None => writer
                    .into_inner()
                    .map_err(std::io::IntoInnerError::into_error),
            }),
        }
    }
}

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;
const UNSIGNED_BYTE: u32 = 5121;

struct Builder<'a> {
    scene: &'a Scene,
    /// Where the geometries' arrays are read, one at a time (the scene may be an outline).
    geometries: &'a dyn GeometryStore,
    binary: Binary,
    views: Vec<Value>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    nodes: Vec<Value>,
    /// Per geometry: (position accessor, normal accessor, first index accessor of its parts).
    geometry_accessors: Vec<(usize, usize, usize)>,
    /// Per geometry: its texture coordinate and colour accessors, when it has attributes.
    attribute_accessors: Vec<Option<(usize, usize)>>,
    mesh_cache: HashMap<(u32, Vec<u32>, Vec<u32>), usize>,
}

impl Builder<'_> {
    fn push_view(&mut self, bytes: &[u8], target: u32) -> usize {
        self.binary.pad();
        self.views.push(json!({"buffer": 0, "byteOffset": self.binary.len(), "byteLength": bytes.len(), "target": target}));
        self.binary.append(bytes);
        self.views.len() - 1
    }

    fn push_accessor(&mut self, accessor: Value) -> usize {
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    /// Every geometry's arrays, read one at a time; the error names a geometry that cannot be
    /// read back.
    fn add_geometries(&mut self) -> Result<(), String> {
        for index in 0..self.geometries.geometry_count() {
            let geometry = self.geometries.geometry(index)?;
            let positions: Vec<u8> = geometry
                .vertices
                .iter()
                .flat_map(|v| v.position)
                .flat_map(f32::to_le_bytes)
                .collect();
            let normals: Vec<u8> = geometry
                .vertices
                .iter()
                .flat_map(|v| v.normal)
                .flat_map(f32::to_le_bytes)
                .collect();
            let bounds = Aabb::from_points(geometry.vertices.iter().map(|v| v.position));
            let count = geometry.vertices.len();
            let (min, max) = if bounds.is_empty() {
                ([0.0; 3], [0.0; 3])
            } else {
                (
                    bounds.min.as_vec3().to_array(),
                    bounds.max.as_vec3().to_array(),
                )
            };
            let view = self.push_view(&positions, ARRAY_BUFFER);
            let position = self.push_accessor(
                json!({"bufferView": view, "componentType": FLOAT, "count": count, "type": "VEC3", "min": min, "max": max}),
            );
            let view = self.push_view(&normals, ARRAY_BUFFER);
            let normal = self.push_accessor(
                json!({"bufferView": view, "componentType": FLOAT, "count": count, "type": "VEC3"}),
            );
            let first_index_accessor = self.accessors.len();
            for part in &geometry.parts {
                let range =
                    part.first_index as usize..(part.first_index + part.index_count) as usize;
                let indices: Vec<u8> = geometry.indices[range]
                    .iter()
                    .flat_map(|i| i.to_le_bytes())
                    .collect();
                let view = self.push_view(&indices, ELEMENT_ARRAY_BUFFER);
                self.push_accessor(
                    json!({"bufferView": view, "componentType": UNSIGNED_INT, "count": part.index_count, "type": "SCALAR"}),
                );
            }
            self.geometry_accessors
                .push((position, normal, first_index_accessor));
            let attributes = (!geometry.attributes.is_empty()).then(|| {
                let uvs: Vec<u8> = geometry
                    .attributes
                    .iter()
                    .flat_map(|a| a.uv)
                    .flat_map(f32::to_le_bytes)
                    .collect();
                let colors: Vec<u8> = geometry.attributes.iter().flat_map(|a| a.color).collect();
                let view = self.push_view(&uvs, ARRAY_BUFFER);
                let uv = self.push_accessor(
                    json!({"bufferView": view, "componentType": FLOAT, "count": count, "type": "VEC2"}),
                );
                let view = self.push_view(&colors, ARRAY_BUFFER);
                let color = self.push_accessor(
                    json!({"bufferView": view, "componentType": UNSIGNED_BYTE, "normalized": true, "count": count, "type": "VEC4"}),
                );
                (uv, color)
            });
            self.attribute_accessors.push(attributes);
        }
        Ok(())
    }

    /// Every texture as a PNG image in the buffer, with its sampler: the `images`, `samplers`
    /// and `textures` arrays.
    fn add_textures(&mut self) -> Result<[Vec<Value>; 3], SceneError> {
        let wrap = |w: Wrap| match w {
            Wrap::Repeat => 10497,
            Wrap::ClampToEdge => 33071,
            Wrap::MirroredRepeat => 33648,
        };
        let (mut images, mut samplers, mut textures) = (Vec::new(), Vec::new(), Vec::new());
        for (t, texture) in self.scene.textures.iter().enumerate() {
            let image =
                image::RgbaImage::from_raw(texture.width, texture.height, texture.texels.to_vec())
                    .ok_or_else(|| {
                        SceneError(format!("texture {t} has the wrong number of texels"))
                    })?;
            let mut png = std::io::Cursor::new(Vec::new());
            image
                .write_to(&mut png, image::ImageFormat::Png)
                .map_err(|e| SceneError(format!("texture {t} ('{}'): {e}", texture.name)))?;
            self.binary.pad();
            let png = png.into_inner();
            self.views.push(
                json!({"buffer": 0, "byteOffset": self.binary.len(), "byteLength": png.len()}),
            );
            self.binary.append(&png);
            images.push(json!({"name": texture.name, "bufferView": self.views.len() - 1, "mimeType": "image/png"}));
            let sampler = texture.sampler;
            samplers.push(json!({
                "magFilter": if sampler.magnify_nearest { 9728 } else { 9729 },
                "minFilter": 9987,
                "wrapS": wrap(sampler.wrap_s),
                "wrapT": wrap(sampler.wrap_t)
            }));
            textures.push(json!({"source": t, "sampler": t}));
        }
        Ok([images, samplers, textures])
    }

    /// The mesh drawing `parts` of `geometry` with `materials` (one per listed part).
    fn mesh(&mut self, geometry: u32, parts: Vec<u32>, materials: Vec<u32>) -> usize {
        let key = (geometry, parts.clone(), materials.clone());
        if let Some(&mesh) = self.mesh_cache.get(&key) {
            return mesh;
        }
        let (position, normal, first) = self.geometry_accessors[geometry as usize];
        let mut attributes = json!({"POSITION": position, "NORMAL": normal});
        if let Some((uv, color)) = self.attribute_accessors[geometry as usize] {
            attributes["TEXCOORD_0"] = json!(uv);
            attributes["COLOR_0"] = json!(color);
        }
        let primitives: Vec<Value> = parts
            .iter()
            .zip(&materials)
            .map(|(&p, &m)| {
                json!({"attributes": attributes, "indices": first + p as usize, "material": m, "mode": 4})
            })
            .collect();
        let name = &self.scene.geometries[geometry as usize].name;
        self.meshes
            .push(json!({"name": name, "primitives": primitives}));
        self.mesh_cache.insert(key, self.meshes.len() - 1);
        self.meshes.len() - 1
    }

    /// Adds the subtree of `node` as new glTF nodes; returns the index of its root.
    fn add_node(&mut self, node: NodeIndex, local: DMat4) -> usize {
        let source = &self.scene.nodes[node as usize];
        let index = self.nodes.len();
        self.nodes.push(json!({"name": source.name}));
        if local != DMat4::IDENTITY {
            self.nodes[index]["matrix"] = json!(local.to_cols_array());
        }
        let mut children: Vec<usize> = Vec::new();
        if let Some(mesh) = &source.mesh {
            let parts_in_node: Vec<u32> = (0..mesh.part_materials.len() as u32)
                .filter(|&p| {
                    mesh.part_override(p)
                        .is_none_or(|o| o.visible && o.transform_child.is_none())
                })
                .collect();
            if !parts_in_node.is_empty() {
                let materials = parts_in_node
                    .iter()
                    .map(|&p| mesh.part_materials[p as usize])
                    .collect();
                let mesh_index = self.mesh(mesh.geometry, parts_in_node, materials);
                self.nodes[index]["mesh"] = json!(mesh_index);
            }
            // Parts placed by a child's matrix become nodes of their own with that matrix.
            for o in mesh.part_overrides.iter().filter(|o| o.visible) {
                if let Some(child) = o.transform_child {
                    let mesh_index = self.mesh(
                        mesh.geometry,
                        vec![o.part],
                        vec![mesh.part_materials[o.part as usize]],
                    );
                    let child_local = self.scene.nodes[child as usize].local;
                    self.nodes.push(json!({"name": format!("{} part {}", source.name, o.part), "mesh": mesh_index}));
                    let part_node = self.nodes.len() - 1;
                    if child_local != DMat4::IDENTITY {
                        self.nodes[part_node]["matrix"] = json!(child_local.to_cols_array());
                    }
                    children.push(part_node);
                }
            }
        }
        for &child in &source.children {
            let local = self.scene.nodes[child as usize].local;
            children.push(self.add_node(child, local));
        }
        if !children.is_empty() {
            self.nodes[index]["children"] = json!(children);
        }
        index
    }
}

/// Why a glTF document could not be made.
#[derive(Debug)]
pub enum GltfError {
    /// The scene is invalid (or a texture cannot be encoded).
    Scene(SceneError),
    /// A geometry could not be read back from its store (naming it).
    Geometry(String),
}

/// Builds the glTF document of a (validated) scene in memory.
pub fn gltf_document(scene: &Scene) -> Result<GltfDocument, SceneError> {
    scene.validate()?;
    gltf_document_from(scene, scene, Binary::Memory(Vec::new())).map_err(|error| match error {
        GltfError::Scene(error) => error,
        GltfError::Geometry(why) => SceneError(why),
    })
}

/// Builds the glTF document of the scene outlined by `scene` (whose references were checked;
/// its geometries may be stand-ins), its geometries read one at a time from `geometries` and
/// their arrays written to `binary` as they are read.
pub fn gltf_document_from(
    scene: &Scene,
    geometries: &dyn GeometryStore,
    binary: Binary,
) -> Result<GltfDocument, GltfError> {
    let mut builder = Builder {
        scene,
        geometries,
        binary,
        views: Vec::new(),
        accessors: Vec::new(),
        meshes: Vec::new(),
        nodes: Vec::new(),
        geometry_accessors: Vec::new(),
        attribute_accessors: Vec::new(),
        mesh_cache: HashMap::new(),
    };
    builder.add_geometries().map_err(GltfError::Geometry)?;
    let [images, samplers, textures] = builder.add_textures().map_err(GltfError::Scene)?;
    let mut transformed = false;
    let roots: Vec<usize> = scene
        .roots
        .iter()
        .map(|&r| builder.add_node(r, scene.nodes[r as usize].local))
        .collect();
    // Geometries no node draws are kept as meshes no node uses, so nothing is lost.
    for g in 0..scene.geometries.len() as u32 {
        if !builder
            .mesh_cache
            .keys()
            .any(|(geometry, _, _)| *geometry == g)
            && !scene.materials.is_empty()
        {
            let parts: Vec<u32> = (0..scene.geometries[g as usize].parts.len() as u32).collect();
            let materials = vec![0; parts.len()];
            builder.mesh(g, parts, materials);
        }
    }

    let texture_is_translucent = |t: u32| {
        scene
            .textures
            .get(t as usize)
            .is_some_and(|t| t.has_translucent_texels())
    };
    let materials: Vec<Value> = scene
        .materials
        .iter()
        .map(|m| {
            // A translucent material keeps its opacity (glTF's default mode ignores alpha).
            let mut material = json!({
                "name": m.name,
                "pbrMetallicRoughness": {"baseColorFactor": m.base_color, "metallicFactor": m.metallic, "roughnessFactor": m.roughness},
                "doubleSided": true
            });
            if let Some(reference) = &m.base_color_texture {
                let mut info = json!({"index": reference.texture});
                if reference.transform != UvTransform::IDENTITY {
                    transformed = true;
                    info["extensions"] =
                        json!({"KHR_texture_transform": texture_transform(&reference.transform)});
                }
                material["pbrMetallicRoughness"]["baseColorTexture"] = info;
            }
            match m.alpha_mode {
                AlphaMode::Mask { cutoff } => {
                    material["alphaMode"] = json!("MASK");
                    material["alphaCutoff"] = json!(cutoff);
                }
                AlphaMode::Blend if m.is_translucent(texture_is_translucent) => {
                    material["alphaMode"] = json!("BLEND");
                }
                AlphaMode::Blend | AlphaMode::Opaque => material["alphaMode"] = json!("OPAQUE"),
            }
            material
        })
        .collect();
    builder.binary.pad();
    let mut json = json!({
        "asset": {"version": "2.0", "generator": concat!("cadr ", env!("CARGO_PKG_VERSION"))},
        "scene": 0,
        "scenes": [{"name": scene.name, "nodes": roots}],
        "nodes": builder.nodes,
        "materials": materials,
        "buffers": [{"byteLength": builder.binary.len()}],
    });
    if transformed {
        json["extensionsUsed"] = json!(["KHR_texture_transform"]);
    }
    for (key, items) in [
        ("meshes", builder.meshes),
        ("images", images),
        ("samplers", samplers),
        ("textures", textures),
        ("bufferViews", builder.views),
        ("accessors", builder.accessors),
    ] {
        if !items.is_empty() {
            json[key] = Value::Array(items);
        }
    }
    if builder.binary.is_empty() {
        if let Some(object) = json.as_object_mut() {
            object.remove("buffers");
        }
    }
    let unfolded_nodes = json["nodes"].as_array().map_or(0, Vec::len);
    Ok(GltfDocument {
        json,
        binary: builder.binary,
        unfolded_nodes,
    })
}

impl GltfDocument {
    /// The JSON text with the buffer stored in the file `uri`.
    pub fn json_with_uri(&self, uri: &str) -> String {
        let mut json = self.json.clone();
        if let Some(buffer) = json["buffers"].get_mut(0) {
            buffer["uri"] = json!(uri);
        }
        json.to_string()
    }

    /// Writes the GLB container to `out`: the JSON chunk, then the binary chunk, copied from
    /// memory or from the file it was written to. Refuses a document GLB cannot hold: its
    /// lengths are 32-bit, so 4 GiB in all.
    pub fn write_glb(self, out: &mut impl std::io::Write) -> std::io::Result<()> {
        use std::io::Seek as _;
        let mut json = self.json.to_string().into_bytes();
        while json.len() % 4 != 0 {
            json.push(b' ');
        }
        let binary_len = self.binary.len();
        let has_binary = binary_len > 0;
        let total = 12 + 8 + json.len() as u64 + if has_binary { 8 + binary_len } else { 0 };
        let too_large = || {
            std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!(
                    "a GLB file holds at most 4 GiB, this scene needs {total} bytes: write .gltf (with its .bin) instead"
                ),
            )
        };
        let total = u32::try_from(total).map_err(|_| too_large())?;
        out.write_all(b"glTF")?;
        out.write_all(&2_u32.to_le_bytes())?;
        out.write_all(&total.to_le_bytes())?;
        out.write_all(&(json.len() as u32).to_le_bytes())?;
        out.write_all(b"JSON")?;
        out.write_all(&json)?;
        if !has_binary {
            return Ok(());
        }
        out.write_all(&(binary_len as u32).to_le_bytes())?;
        out.write_all(b"BIN\0")?;
        match self.binary {
            Binary::Memory(bytes) => out.write_all(&bytes),
            file @ Binary::File { .. } => {
                let Some(mut file) = file.finish().transpose()? else {
                    return Ok(());
                };
                file.rewind()?;
                std::io::copy(&mut std::io::BufReader::new(file), out).map(|_| ())
            }
        }
    }
}

/// `KHR_texture_transform`'s offset, rotation and scale of a transform made from them (what
/// the reader makes; a sheared transform, which no file gives, keeps its columns' lengths).
fn texture_transform(transform: &UvTransform) -> Value {
    let [a, b, offset_u] = transform.u_row;
    let [c, d, offset_v] = transform.v_row;
    // u_row = (cos·sx, sin·sy), v_row = (−sin·sx, cos·sy).
    let scale_x = a.hypot(c);
    let scale_y = b.hypot(d);
    let rotation = (-c).atan2(a);
    json!({"offset": [offset_u, offset_v], "rotation": rotation, "scale": [scale_x, scale_y]})
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.
    use super::*;

    #[test]
    fn a_glb_past_4_gib_is_refused_before_anything_is_written() {
        let document = GltfDocument {
            json: json!({"asset": {"version": "2.0"}}),
            binary: Binary::File {
                writer: std::io::BufWriter::new(tempfile_in_target()),
                len: 5 << 30,
                failed: None,
            },
            unfolded_nodes: 0,
        };
        let mut out = Vec::new();
        let error = document.write_glb(&mut out).unwrap_err().to_string();
        assert!(
            error.contains("at most 4 GiB") && error.contains(".gltf"),
            "{error}"
        );
        assert!(out.is_empty());
    }

    /// A scratch file (removed at once: only its handle is used).
    fn tempfile_in_target() -> std::fs::File {
        let (file, _guard) =
            crate::graph::temporary_file(&std::env::temp_dir(), "for a test").unwrap();
        file
    }
}
