//! Writing glTF 2.0: one buffer, per geometry a position and a normal accessor (and, when it
//! has them, texture coordinates and colours) shared by its parts, one index accessor per
//! part; textures as PNG images in the buffer with their samplers, texture transforms as
//! `KHR_texture_transform`; a mesh per distinct (geometry, part materials, hidden
//! parts) combination; the node DAG unfolded into trees with matrices at full precision.

use std::collections::HashMap;

use glam::DMat4;
use serde_json::{json, Value};

use crate::scene::{Aabb, AlphaMode, NodeIndex, Scene, SceneError, UvTransform, Wrap};

/// A glTF document in memory: its JSON (without the buffer URI) and binary buffer.
pub struct GltfDocument {
    json: Value,
    /// The binary buffer.
    pub binary: Vec<u8>,
    /// Number of glTF nodes after unfolding shared subgraphs.
    pub unfolded_nodes: usize,
}

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;
const UNSIGNED_BYTE: u32 = 5121;

struct Builder<'a> {
    scene: &'a Scene,
    binary: Vec<u8>,
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
        while self.binary.len() % 4 != 0 {
            self.binary.push(0);
        }
        self.views.push(json!({"buffer": 0, "byteOffset": self.binary.len(), "byteLength": bytes.len(), "target": target}));
        self.binary.extend_from_slice(bytes);
        self.views.len() - 1
    }

    fn push_accessor(&mut self, accessor: Value) -> usize {
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    fn add_geometries(&mut self) {
        for geometry in &self.scene.geometries {
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
            while self.binary.len() % 4 != 0 {
                self.binary.push(0);
            }
            let png = png.into_inner();
            self.views.push(
                json!({"buffer": 0, "byteOffset": self.binary.len(), "byteLength": png.len()}),
            );
            self.binary.extend_from_slice(&png);
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

/// Builds the glTF document of a (validated) scene.
pub fn gltf_document(scene: &Scene) -> Result<GltfDocument, SceneError> {
    scene.validate()?;
    let mut builder = Builder {
        scene,
        binary: Vec::new(),
        views: Vec::new(),
        accessors: Vec::new(),
        meshes: Vec::new(),
        nodes: Vec::new(),
        geometry_accessors: Vec::new(),
        attribute_accessors: Vec::new(),
        mesh_cache: HashMap::new(),
    };
    builder.add_geometries();
    let [images, samplers, textures] = builder.add_textures()?;
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
    while builder.binary.len() % 4 != 0 {
        builder.binary.push(0);
    }
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

    /// The GLB container: JSON chunk and binary chunk.
    pub fn to_glb(&self) -> Vec<u8> {
        let mut json = self.json.to_string().into_bytes();
        while json.len() % 4 != 0 {
            json.push(b' ');
        }
        let has_binary = !self.binary.is_empty();
        let total = 12 + 8 + json.len() + if has_binary { 8 + self.binary.len() } else { 0 };
        let mut out = Vec::with_capacity(total);
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2_u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        out.extend_from_slice(&(json.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&json);
        if has_binary {
            out.extend_from_slice(&(self.binary.len() as u32).to_le_bytes());
            out.extend_from_slice(b"BIN\0");
            out.extend_from_slice(&self.binary);
        }
        out
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
