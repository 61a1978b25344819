//! A small valid glTF scene (two cube instances with two materials) in every container
//! (.gltf + .bin, embedded data URI, .glb), and ways to break it.

use std::path::{Path, PathBuf};

use base64::Engine as _;
use cadr_core::csf::{
    CsfFile, CsfGeometry, CsfGeometryPart, CsfMaterial, CsfMeta, CsfNode, CsfNodePart,
    FLAG_UNIQUE_NODES,
};
use cadr_core::scene::{Geometry, Part, Vertex};

/// Byte offsets in the cube's binary buffer.
pub const POSITIONS_OFFSET: usize = 0;
/// Start of the normals.
pub const NORMALS_OFFSET: usize = 288;
/// Start of the 36 u32 indices.
pub const INDICES_OFFSET: usize = 576;
/// Length of the buffer.
pub const BUFFER_LENGTH: usize = 720;

/// The default node list: a root with two instances of the cube mesh.
pub const TWO_INSTANCES: &str = r#"[
    {"name": "root", "children": [1, 2]},
    {"name": "left", "mesh": 0, "translation": [-1.0, 0.0, 0.0]},
    {"name": "right", "mesh": 0, "translation": [1.2, 0.3, 0.0], "rotation": [0.0, 0.3826834, 0.0, 0.9238795]}
]"#;

/// A cube mesh (24 vertices, 36 indices split into two primitives) as glTF JSON and binary.
#[derive(Clone, Debug)]
pub struct CubeGltf {
    /// The binary buffer.
    pub bin: Vec<u8>,
    /// The `nodes` array (JSON).
    pub nodes: String,
    /// Extra top-level JSON members (each ending in a comma).
    pub extra: String,
}

impl Default for CubeGltf {
    fn default() -> Self {
        Self::new()
    }
}

impl CubeGltf {
    /// The valid cube scene.
    pub fn new() -> Self {
        let mut positions = Vec::new();
        let mut normals = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        for axis in 0..3 {
            for sign in [-1.0_f32, 1.0] {
                let mut normal = [0.0_f32; 3];
                normal[axis] = sign;
                let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                let base = positions.len() as u32;
                for (du, dv) in [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)] {
                    let mut p = [0.0_f32; 3];
                    p[axis] = 0.5 * sign;
                    p[u] = du;
                    p[v] = dv;
                    positions.push(p);
                    normals.push(normal);
                }
                indices.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
            }
        }
        let mut bin = Vec::with_capacity(BUFFER_LENGTH);
        for p in positions.iter().chain(&normals) {
            for c in p {
                bin.extend_from_slice(&c.to_le_bytes());
            }
        }
        for i in indices {
            bin.extend_from_slice(&i.to_le_bytes());
        }
        assert_eq!(bin.len(), BUFFER_LENGTH);
        Self {
            bin,
            nodes: TWO_INSTANCES.to_owned(),
            extra: String::new(),
        }
    }

    /// Writes `value` as the f32 at byte `offset` of the buffer.
    pub fn set_f32(&mut self, offset: usize, value: f32) {
        self.bin[offset..offset + 4].copy_from_slice(&value.to_le_bytes());
    }

    /// Writes `value` as the u32 at byte `offset` of the buffer.
    pub fn set_u32(&mut self, offset: usize, value: u32) {
        self.bin[offset..offset + 4].copy_from_slice(&value.to_le_bytes());
    }

    /// The glTF JSON; `buffer_uri` is None for a GLB binary chunk.
    pub fn json(&self, buffer_uri: Option<&str>) -> String {
        let uri = buffer_uri
            .map(|u| format!(r#""uri": "{u}", "#))
            .unwrap_or_default();
        format!(
            r#"{{
  "asset": {{"version": "2.0", "generator": "cadr tests"}},
  {extra}
  "scene": 0,
  "scenes": [{{"nodes": [0]}}],
  "nodes": {nodes},
  "meshes": [{{"name": "cube", "primitives": [
      {{"attributes": {{"POSITION": 0, "NORMAL": 1}}, "indices": 2, "material": 0}},
      {{"attributes": {{"POSITION": 0, "NORMAL": 1}}, "indices": 3, "material": 1}}]}}],
  "materials": [
      {{"name": "red", "pbrMetallicRoughness": {{"baseColorFactor": [0.8, 0.1, 0.1, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.5}}}},
      {{"name": "blue", "pbrMetallicRoughness": {{"baseColorFactor": [0.1, 0.2, 0.8, 1.0], "metallicFactor": 0.5, "roughnessFactor": 0.3}}}}],
  "buffers": [{{{uri}"byteLength": {BUFFER_LENGTH}}}],
  "bufferViews": [
      {{"buffer": 0, "byteOffset": {POSITIONS_OFFSET}, "byteLength": 288}},
      {{"buffer": 0, "byteOffset": {NORMALS_OFFSET}, "byteLength": 288}},
      {{"buffer": 0, "byteOffset": {INDICES_OFFSET}, "byteLength": 144}}],
  "accessors": [
      {{"bufferView": 0, "componentType": 5126, "count": 24, "type": "VEC3", "min": [-0.5, -0.5, -0.5], "max": [0.5, 0.5, 0.5]}},
      {{"bufferView": 1, "componentType": 5126, "count": 24, "type": "VEC3"}},
      {{"bufferView": 2, "byteOffset": 0, "componentType": 5125, "count": 18, "type": "SCALAR"}},
      {{"bufferView": 2, "byteOffset": 72, "componentType": 5125, "count": 18, "type": "SCALAR"}}]
}}"#,
            extra = self.extra,
            nodes = self.nodes
        )
    }

    /// Writes `NAME.gltf` and `NAME.bin` into `dir`; returns the .gltf path.
    pub fn write_separate(&self, dir: &Path, name: &str) -> PathBuf {
        let bin_name = format!("{name}.bin");
        std::fs::write(dir.join(&bin_name), &self.bin).expect("write .bin");
        let path = dir.join(format!("{name}.gltf"));
        std::fs::write(&path, self.json(Some(&bin_name))).expect("write .gltf");
        path
    }

    /// Writes `NAME.gltf` with the buffer embedded as a base64 data URI.
    pub fn write_embedded(&self, dir: &Path, name: &str) -> PathBuf {
        let uri = format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&self.bin)
        );
        let path = dir.join(format!("{name}.gltf"));
        std::fs::write(&path, self.json(Some(&uri))).expect("write .gltf");
        path
    }

    /// The scene as GLB bytes.
    pub fn glb(&self) -> Vec<u8> {
        self.glb_with_json(&self.json(None))
    }

    /// GLB bytes of `json` (for example [`CubeGltf::json`] with a change) and the binary.
    pub fn glb_with_json(&self, json: &str) -> Vec<u8> {
        let mut json = json.as_bytes().to_vec();
        while !json.len().is_multiple_of(4) {
            json.push(b' ');
        }
        let mut bin = self.bin.clone();
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let total = 12 + 8 + json.len() + 8 + bin.len();
        let mut out = Vec::with_capacity(total);
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2_u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        out.extend_from_slice(&(json.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&json);
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
        out
    }

    /// Writes `NAME.glb` into `dir`.
    pub fn write_glb(&self, dir: &Path, name: &str) -> PathBuf {
        let path = dir.join(format!("{name}.glb"));
        std::fs::write(&path, self.glb()).expect("write .glb");
        path
    }
}

/// A fresh empty directory for one test's files, removed when the test passes (one kind of
/// scratch directory for every test: [`crate::c_programs::ScratchDir`]).
pub use crate::c_programs::scratch_dir;

/// A file using what cadr does not draw: texture, aux and per-part channels, metas, payloads,
/// a hidden part, a part placed by a child's matrix, a geometry without normals.
pub fn rich_csf_file() -> CsfFile {
    let vertices = vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0];
    let mut perpart = Vec::new();
    for p in 0..2_u32 {
        for v in [0.0_f32, 0.0, 0.0, 1.0, 1.0, 0.0] {
            perpart.extend_from_slice(&(v + p as f32).to_le_bytes());
        }
    }
    for (begin, count) in [(0_u32, 4_u32), (0, 4)] {
        perpart.extend_from_slice(&begin.to_le_bytes());
        perpart.extend_from_slice(&count.to_le_bytes());
    }
    let geometry = CsfGeometry {
        vertices,
        normals: [0.0, 0.0, 1.0].repeat(4),
        normal_channels: 1,
        tex: vec![0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 1.0],
        tex_channels: 1,
        aux: vec![0.5; 16],
        aux_storage_order: vec![1],
        perpart,
        perpart_storage_order: vec![0, 1],
        index_solid: vec![0, 1, 2, 1, 3, 2],
        index_wire: vec![0, 1, 1, 3, 3, 2, 2, 0],
        parts: vec![
            CsfGeometryPart {
                deprecated: 0,
                num_index_solid: 3,
                num_index_wire: 4,
            },
            CsfGeometryPart {
                deprecated: 0,
                num_index_solid: 3,
                num_index_wire: 4,
            },
        ],
    };
    let bare = CsfGeometry {
        vertices: vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0],
        index_solid: vec![0, 1, 2],
        parts: vec![CsfGeometryPart {
            deprecated: 0,
            num_index_solid: 3,
            num_index_wire: 0,
        }],
        ..CsfGeometry::default()
    };
    let translate = |x: f32| {
        let mut m = [0.0_f32; 16];
        m[0] = 1.0;
        m[5] = 1.0;
        m[10] = 1.0;
        m[15] = 1.0;
        m[12] = x;
        m
    };
    let packet = {
        let mut p = vec![0_u8; 28];
        p[0..4].copy_from_slice(&7_u32.to_le_bytes());
        p[16..20].copy_from_slice(&28_u32.to_le_bytes());
        p
    };
    CsfFile {
        version: 6,
        file_flags: FLAG_UNIQUE_NODES,
        root: 0,
        geometries: vec![geometry, bare],
        materials: vec![
            CsfMaterial {
                name: "plain".into(),
                color: [0.2, 0.4, 0.6, 1.0],
                kind: 3,
                bytes: packet.clone(),
            },
            CsfMaterial {
                name: "other".into(),
                color: [0.9, 0.1, 0.1, 1.0],
                kind: 0,
                bytes: Vec::new(),
            },
        ],
        nodes: vec![
            CsfNode {
                object_tm: translate(0.0),
                world_tm: translate(0.0),
                geometry: 0,
                parts: vec![
                    CsfNodePart {
                        active: 1,
                        material: 0,
                        node: 1,
                    },
                    CsfNodePart {
                        active: 0,
                        material: 1,
                        node: -1,
                    },
                ],
                children: vec![1, 2],
            },
            CsfNode {
                object_tm: translate(5.0),
                world_tm: translate(5.0),
                geometry: -1,
                parts: vec![],
                children: vec![],
            },
            CsfNode {
                object_tm: translate(-3.0),
                world_tm: translate(-3.0),
                geometry: 1,
                parts: vec![CsfNodePart {
                    active: 1,
                    material: 1,
                    node: -1,
                }],
                children: vec![],
            },
        ],
        node_metas: vec![
            CsfMeta {
                name: "assembly".into(),
                flags: 1,
                bytes: packet.clone(),
            },
            CsfMeta::default(),
            CsfMeta::default(),
        ],
        geometry_metas: Vec::new(),
        file_meta: Some(CsfMeta {
            name: "file".into(),
            flags: 0,
            bytes: packet,
        }),
    }
}

/// Where the quads of [`textured_gltf`] lie: centres (x, y) in the plane z = 0, each
/// [`QUAD_SIZE`](textured::QUAD_SIZE) across, in front of a red backdrop at z = -0.5.
pub mod textured {
    /// The checker texture (8 × 8 texels, NEAREST), repeated twice each way by
    /// `KHR_texture_transform`: 16 × 16 cells.
    pub const CHECKER: (f64, f64) = (-1.0, 1.0);
    /// The alpha-masked texture (MASK, cutoff 0.5): its left half is cut away.
    pub const MASKED: (f64, f64) = (1.0, 1.0);
    /// Vertex colours (no texture): red top left, green top right, blue bottom right, white
    /// bottom left.
    pub const VERTEX_COLORS: (f64, f64) = (-1.0, -1.0);
    /// A BLEND texture of blue at half opacity: the backdrop shows through.
    pub const BLENDED: (f64, f64) = (1.0, -1.0);
    /// Side of each quad.
    pub const QUAD_SIZE: f64 = 1.6;
    /// The checker's dark and light texels (sRGB).
    pub const CHECKER_COLORS: [[u8; 4]; 2] = [[20, 20, 20, 255], [250, 210, 30, 255]];
    /// The masked texture's kept half (sRGB).
    pub const MASK_KEPT: [u8; 4] = [255, 140, 0, 255];
    /// The blended texture's one texel (sRGB, alpha 128).
    pub const BLEND_TEXEL: [u8; 4] = [30, 80, 230, 128];
}

/// A PNG data URI of `width` × `height` RGBA `texels`.
pub fn png_data_uri(width: u32, height: u32, texels: Vec<u8>) -> String {
    let image = image::RgbaImage::from_raw(width, height, texels).expect("texels for the size");
    let mut png = std::io::Cursor::new(Vec::new());
    image
        .write_to(&mut png, image::ImageFormat::Png)
        .expect("encode PNG");
    format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(png.into_inner())
    )
}

/// Writes `textured.gltf` (buffer and PNG images embedded as data URIs) into `dir`: four quads
/// facing +Z over a red backdrop, showing a repeated checker texture with a texture transform,
/// an alpha mask, vertex colours and a translucent texture (see [`textured`]).
pub fn textured_gltf(dir: &Path) -> PathBuf {
    use textured::*;
    let mut buffer: Vec<u8> = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut push = |bytes: Vec<u8>, accessor: String| {
        while !buffer.len().is_multiple_of(4) {
            buffer.push(0);
        }
        views.push(format!(
            r#"{{"buffer": 0, "byteOffset": {}, "byteLength": {}}}"#,
            buffer.len(),
            bytes.len()
        ));
        buffer.extend_from_slice(&bytes);
        accessors.push(accessor.replace("VIEW", &(views.len() - 1).to_string()));
        accessors.len() - 1
    };
    let f32s = |values: &[f32]| values.iter().flat_map(|v| v.to_le_bytes()).collect();
    // Quads: (centre, z, half size, material, with uv, with colours).
    let quads = [
        ((0.0, 0.0), -0.5, 2.2, 0, false, false),
        (CHECKER, 0.0, QUAD_SIZE / 2.0, 1, true, false),
        (MASKED, 0.0, QUAD_SIZE / 2.0, 2, true, false),
        (VERTEX_COLORS, 0.0, QUAD_SIZE / 2.0, 3, false, true),
        (BLENDED, 0.0, QUAD_SIZE / 2.0, 4, true, false),
    ];
    let mut meshes = Vec::new();
    for ((cx, cy), z, half, material, uv, colors) in quads {
        let (x0, x1, y0, y1) = (cx - half, cx + half, cy - half, cy + half);
        // Top left, top right, bottom right, bottom left.
        let corners = [[x0, y1], [x1, y1], [x1, y0], [x0, y0]];
        let positions: Vec<f32> = corners
            .iter()
            .flat_map(|[x, y]| [*x as f32, *y as f32, z as f32])
            .collect();
        let (min, max) = (
            [x0 as f32, y0 as f32, z as f32],
            [x1 as f32, y1 as f32, z as f32],
        );
        let position = push(
            f32s(&positions),
            format!(
                r#"{{"bufferView": VIEW, "componentType": 5126, "count": 4, "type": "VEC3", "min": {min:?}, "max": {max:?}}}"#
            ),
        );
        let normal = push(
            f32s(&[0.0, 0.0, 1.0].repeat(4)),
            r#"{"bufferView": VIEW, "componentType": 5126, "count": 4, "type": "VEC3"}"#.into(),
        );
        let indices = push(
            [0u16, 3, 2, 0, 2, 1]
                .iter()
                .flat_map(|i| i.to_le_bytes())
                .collect(),
            r#"{"bufferView": VIEW, "componentType": 5123, "count": 6, "type": "SCALAR"}"#.into(),
        );
        let mut attributes = format!(r#""POSITION": {position}, "NORMAL": {normal}"#);
        if uv {
            let coordinates = push(
                f32s(&[0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0]),
                r#"{"bufferView": VIEW, "componentType": 5126, "count": 4, "type": "VEC2"}"#.into(),
            );
            attributes.push_str(&format!(r#", "TEXCOORD_0": {coordinates}"#));
        }
        if colors {
            let rgba = [
                [255u8, 0, 0, 255],
                [0, 255, 0, 255],
                [0, 0, 255, 255],
                [255, 255, 255, 255],
            ];
            let colors = push(
                rgba.concat(),
                r#"{"bufferView": VIEW, "componentType": 5121, "normalized": true, "count": 4, "type": "VEC4"}"#
                    .into(),
            );
            attributes.push_str(&format!(r#", "COLOR_0": {colors}"#));
        }
        meshes.push(format!(
            r#"{{"primitives": [{{"attributes": {{{attributes}}}, "indices": {indices}, "material": {material}}}]}}"#
        ));
    }
    let checker: Vec<u8> = (0..64)
        .flat_map(|i| CHECKER_COLORS[(i % 8 + i / 8) % 2])
        .collect();
    let images = [
        png_data_uri(8, 8, checker),
        png_data_uri(2, 1, [[0, 0, 0, 0], MASK_KEPT].concat()),
        png_data_uri(1, 1, BLEND_TEXEL.to_vec()),
    ]
    .map(|uri| format!(r#"{{"uri": "{uri}"}}"#))
    .join(", ");
    let nodes: Vec<String> = (0..quads.len())
        .map(|m| format!(r#"{{"mesh": {m}}}"#))
        .collect();
    let json = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["KHR_texture_transform"],
  "scene": 0,
  "scenes": [{{"nodes": [0, 1, 2, 3, 4]}}],
  "nodes": [{nodes}],
  "meshes": [{meshes}],
  "materials": [
    {{"name": "backdrop", "pbrMetallicRoughness": {{"baseColorFactor": [0.8, 0.05, 0.05, 1.0], "roughnessFactor": 1.0, "metallicFactor": 0.0}}}},
    {{"name": "checker", "pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0, "extensions": {{"KHR_texture_transform": {{"scale": [2.0, 2.0]}}}}}}, "roughnessFactor": 1.0, "metallicFactor": 0.0}}}},
    {{"name": "masked", "alphaMode": "MASK", "alphaCutoff": 0.5, "pbrMetallicRoughness": {{"baseColorTexture": {{"index": 1}}, "roughnessFactor": 1.0, "metallicFactor": 0.0}}}},
    {{"name": "vertex colours", "pbrMetallicRoughness": {{"roughnessFactor": 1.0, "metallicFactor": 0.0}}}},
    {{"name": "blended", "alphaMode": "BLEND", "pbrMetallicRoughness": {{"baseColorTexture": {{"index": 2}}, "roughnessFactor": 1.0, "metallicFactor": 0.0}}}}
  ],
  "samplers": [{{"magFilter": 9728, "minFilter": 9987, "wrapS": 10497, "wrapT": 10497}}],
  "images": [{images}],
  "textures": [{{"source": 0, "sampler": 0}}, {{"source": 1, "sampler": 0}}, {{"source": 2, "sampler": 0}}],
  "buffers": [{{"byteLength": {length}, "uri": "data:application/octet-stream;base64,{data}"}}],
  "bufferViews": [{views}],
  "accessors": [{accessors}]
}}"#,
        nodes = nodes.join(", "),
        meshes = meshes.join(", "),
        length = buffer.len(),
        data = base64::engine::general_purpose::STANDARD.encode(&buffer),
        views = views.join(", "),
        accessors = accessors.join(", "),
    );
    let path = dir.join("textured.gltf");
    std::fs::write(&path, json).expect("write textured.gltf");
    path
}

/// A scene of one 2 × 2 quad in the plane z = 0, facing +z, drawn with `material` (the
/// scene's only one), with `textures`: its texture coordinates run from 0 to `u_across` left
/// to right and from 0 to 1 top to bottom.
pub fn quad_scene(
    material: cadr_core::scene::Material,
    textures: Vec<cadr_core::scene::Texture>,
    u_across: f32,
) -> cadr_core::scene::Scene {
    use cadr_core::scene::{Geometry, MeshRef, Node, Part, Scene, Vertex, VertexAttributes};
    let corners = [[-1.0f32, 1.0], [1.0, 1.0], [1.0, -1.0], [-1.0, -1.0]];
    let quad = Geometry {
        name: "quad".into(),
        vertices: corners
            .iter()
            .map(|&[x, y]| Vertex {
                position: [x, y, 0.0],
                normal: [0.0, 0.0, 1.0],
            })
            .collect(),
        indices: vec![0, 3, 2, 0, 2, 1],
        parts: vec![Part {
            first_index: 0,
            index_count: 6,
            ..Part::default()
        }],
        attributes: corners
            .iter()
            .map(|&[x, y]| VertexAttributes {
                uv: [(x + 1.0) / 2.0 * u_across, (1.0 - y) / 2.0],
                ..VertexAttributes::default()
            })
            .collect(),
        ..Geometry::default()
    };
    let mut node = Node::new("quad");
    node.mesh = Some(MeshRef::new(0, vec![0]));
    Scene {
        geometries: vec![quad],
        materials: vec![material],
        textures,
        nodes: vec![node],
        roots: vec![0],
        ..Scene::default()
    }
}

/// Gives material slot `slot` of `graph` the base-colour texture `texture`, untransformed.
pub fn give_texture(
    graph: &mut cadr_core::graph::SceneGraph,
    slot: u32,
    texture: cadr_core::graph::TextureHandle,
) {
    let material = graph.material_handle_at(slot).expect("the material slot");
    let mut textured = graph.material(material).expect("the material").clone();
    textured.base_color_texture = Some(cadr_core::scene::TextureRef {
        texture: texture.index(),
        transform: cadr_core::scene::UvTransform::IDENTITY,
    });
    graph
        .set_material(material, textured)
        .expect("set the material");
}

/// A box from -1 to 1 on each axis, wound counter-clockwise seen from outside; without its top
/// (+z) face when `open`.
pub fn unit_box(open: bool) -> Geometry {
    let vertices: Vec<Vertex> = (0..8)
        .map(|i| {
            let p = [i & 1, i >> 1 & 1, i >> 2 & 1].map(|b| if b == 1 { 1.0 } else { -1.0 });
            Vertex {
                position: p,
                normal: p.map(|c| c / 3f32.sqrt()),
            }
        })
        .collect();
    // Faces as quads (a, b, c, d), counter-clockwise from outside.
    let faces: [[u32; 4]; 6] = [
        [0, 2, 3, 1], // -z
        [0, 1, 5, 4], // -y
        [0, 4, 6, 2], // -x
        [1, 3, 7, 5], // +x
        [2, 6, 7, 3], // +y
        [4, 5, 7, 6], // +z
    ];
    let kept = if open { &faces[..5] } else { &faces[..] };
    let indices: Vec<u32> = kept
        .iter()
        .flat_map(|[a, b, c, d]| [*a, *b, *c, *a, *c, *d])
        .collect();
    Geometry {
        name: if open { "open box" } else { "box" }.into(),
        parts: vec![Part {
            first_index: 0,
            index_count: indices.len() as u32,
            first_wire_index: 0,
            wire_index_count: 0,
        }],
        vertices,
        indices,
        wire_indices: Vec::new(),
        attributes: Vec::new(),
    }
}
