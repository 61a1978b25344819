//! A small valid glTF scene (two cube instances with two materials) in every container
//! (.gltf + .bin, embedded data URI, .glb), and ways to break it.

use std::path::{Path, PathBuf};

use base64::Engine as _;
use cadr_core::csf::{
    CsfFile, CsfGeometry, CsfGeometryPart, CsfMaterial, CsfMeta, CsfNode, CsfNodePart,
    FLAG_UNIQUE_NODES,
};

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

/// A fresh empty directory for one test's files (under the system temporary directory).
pub fn scratch_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("cadr-tests-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create scratch dir");
    dir
}

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
