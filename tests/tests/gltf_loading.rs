//! glTF loading: valid files in every container, the 2CylinderEngine CAD model, and bad files
//! that must give errors naming the problem.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use cadr_core::load::{load_file, load_gltf_bytes, LoadError};
use cadr_core::scene::{flatten, SceneStats};
use cadr_tests::fixtures::{
    scratch_dir, CubeGltf, INDICES_OFFSET, NORMALS_OFFSET, POSITIONS_OFFSET,
};
use cadr_tests::CYLINDER_ENGINE_GLB;
use std::path::Path;

fn stats_of(path: &Path) -> SceneStats {
    let scene = load_file(path).unwrap_or_else(|e| panic!("{e}"));
    let flat = flatten(&scene).expect("flatten");
    SceneStats::new(&scene, &flat)
}

#[test]
fn cube_loads_the_same_from_every_container() {
    let dir = scratch_dir("containers");
    let cube = CubeGltf::new();
    let separate = stats_of(&cube.write_separate(&dir, "separate"));
    let embedded = stats_of(&cube.write_embedded(&dir, "embedded"));
    let glb = stats_of(&cube.write_glb(&dir, "binary"));
    assert_eq!(separate, embedded);
    assert_eq!(separate, glb);
    assert_eq!(separate.nodes, 3);
    assert_eq!(separate.geometries, 1);
    assert_eq!(separate.parts, 2, "two primitives become two parts");
    assert_eq!(separate.materials, 2);
    assert_eq!(separate.mesh_instances, 2, "the mesh is instanced twice");
    assert_eq!(separate.instances, 4);
    assert_eq!(separate.triangles, 24);
    assert_eq!(separate.stored_triangles, 12);
}

#[test]
fn shared_nodes_are_instanced_on_every_path() {
    let dir = scratch_dir("shared");
    let mut cube = CubeGltf::new();
    // The bolt node 3 hangs under both 1 and 2: drawn twice, stored once.
    cube.nodes = r#"[
        {"children": [1, 2]},
        {"children": [3], "translation": [-2, 0, 0]},
        {"children": [3], "translation": [2, 0, 0]},
        {"mesh": 0, "scale": [1, 2, 1]}
    ]"#
    .into();
    let scene = load_file(&cube.write_glb(&dir, "shared")).expect("load");
    let flat = flatten(&scene).expect("flatten");
    assert_eq!(flat.instances.len(), 2);
    let xs: Vec<f64> = flat.instances.iter().map(|i| i.world.w_axis.x).collect();
    assert_eq!(xs, vec![-2.0, 2.0]);
    assert_eq!(
        flat.instances[0].world.y_axis.y, 2.0,
        "scale of the shared node applies on each path"
    );
}

#[test]
fn cylinder_engine_has_the_expected_statistics() {
    let stats = stats_of(Path::new(CYLINDER_ENGINE_GLB));
    assert_eq!(stats.nodes, 82);
    assert_eq!(stats.parts, 34, "34 primitives");
    assert_eq!(
        stats.triangles, 121_496,
        "triangles drawn over all instances"
    );
    assert_eq!(stats.stored_triangles, 75_730);
    assert!(!stats.bounds.is_empty());
}

fn load_error(name: &str, write: impl FnOnce(&Path) -> std::path::PathBuf) -> String {
    let dir = scratch_dir(name);
    let path = write(&dir);
    match load_file(&path) {
        Ok(_) => panic!("{name}: a bad file loaded without error"),
        Err(error) => {
            let text = error.to_string();
            assert!(
                text.contains(&path.file_name().unwrap().to_string_lossy().to_string()),
                "error names the file: {text}"
            );
            text
        }
    }
}

#[test]
fn truncated_glb_is_refused() {
    let text = load_error("truncated", |dir| {
        let bytes = CubeGltf::new().glb();
        let path = dir.join("truncated.glb");
        std::fs::write(&path, &bytes[..bytes.len() - 100]).unwrap();
        path
    });
    assert!(
        text.contains("not a valid glTF") || text.contains("buffer 0"),
        "{text}"
    );
}

#[test]
fn truncated_external_buffer_is_refused() {
    let text = load_error("short_bin", |dir| {
        let path = CubeGltf::new().write_separate(dir, "short");
        let bin = dir.join("short.bin");
        let data = std::fs::read(&bin).unwrap();
        std::fs::write(&bin, &data[..500]).unwrap();
        path
    });
    assert!(
        text.contains("buffer 0 declares 720 bytes") && text.contains("500"),
        "{text}"
    );
}

#[test]
fn missing_buffer_file_is_refused() {
    let text = load_error("missing", |dir| {
        let path = CubeGltf::new().write_separate(dir, "lonely");
        std::fs::remove_file(dir.join("lonely.bin")).unwrap();
        path
    });
    assert!(
        text.contains("buffer 0 refers to") && text.contains("lonely.bin"),
        "{text}"
    );
}

#[test]
fn index_out_of_range_is_refused() {
    let text = load_error("index", |dir| {
        let mut cube = CubeGltf::new();
        cube.set_u32(INDICES_OFFSET + 4 * 20, 999);
        cube.write_glb(dir, "index")
    });
    assert!(
        text.contains(
            "mesh 0 ('cube') primitive 1: index 2 is 999, but the primitive has 24 vertices"
        ),
        "{text}"
    );
}

#[test]
fn non_finite_position_is_refused() {
    let text = load_error("nan", |dir| {
        let mut cube = CubeGltf::new();
        cube.set_f32(POSITIONS_OFFSET + 12 * 5 + 4, f32::NAN);
        cube.write_glb(dir, "nan")
    });
    assert!(text.contains("POSITION 5 is not finite"), "{text}");
}

#[test]
fn non_finite_normal_is_refused() {
    let text = load_error("inf", |dir| {
        let mut cube = CubeGltf::new();
        cube.set_f32(NORMALS_OFFSET, f32::INFINITY);
        cube.write_glb(dir, "inf")
    });
    assert!(text.contains("NORMAL 0 is not finite"), "{text}");
}

#[test]
fn non_finite_node_transform_is_refused() {
    // JSON has no NaN literal, but 1e39 overflows f32 to infinity.
    let text = load_error("node_inf", |dir| {
        let mut cube = CubeGltf::new();
        cube.nodes = r#"[{"children": [1]}, {"mesh": 0, "translation": [1e39, 0, 0]}]"#.into();
        cube.write_glb(dir, "node_inf")
    });
    assert!(
        text.contains("node 1") && text.contains("non-finite"),
        "{text}"
    );
}

#[test]
fn node_cycle_is_refused() {
    let text = load_error("cycle", |dir| {
        let mut cube = CubeGltf::new();
        cube.nodes = r#"[{"name": "a", "children": [1]}, {"name": "b", "children": [2]}, {"name": "c", "mesh": 0, "children": [1]}]"#.into();
        cube.write_glb(dir, "cycle")
    });
    assert!(text.contains("cycle through node"), "{text}");
}

#[test]
fn accessor_beyond_its_view_is_refused() {
    let text = load_error("accessor", |dir| {
        let cube = CubeGltf::new();
        let json = cube.json(Some("accessor.bin")).replace(
            r#""count": 24, "type": "VEC3", "min""#,
            r#""count": 2400, "type": "VEC3", "min""#,
        );
        std::fs::write(dir.join("accessor.bin"), &cube.bin).unwrap();
        let path = dir.join("accessor.gltf");
        std::fs::write(&path, json).unwrap();
        path
    });
    assert!(
        text.contains("accessor 0 (POSITION, 2400 elements)"),
        "{text}"
    );
}

#[test]
fn a_primitive_naming_a_missing_position_accessor_is_refused_not_a_panic() {
    // The glTF crate's own validation indexes the accessor list with this index before it
    // checks it: it panicked (issue 14's one-byte mutation), both as .gltf and as .glb.
    for glb in [false, true] {
        let text = load_error("missing-accessor", |dir| {
            let cube = CubeGltf::new();
            let uri = (!glb).then_some("missing.bin");
            let json = cube.json(uri).replacen(
                r#""POSITION": 0, "NORMAL": 1}, "indices": 3"#,
                r#""POSITION": 9, "NORMAL": 1}, "indices": 3"#,
                1,
            );
            assert!(json.contains(r#""POSITION": 9"#), "the fixture changed");
            if glb {
                let path = dir.join("missing.glb");
                std::fs::write(&path, cube.glb_with_json(&json)).unwrap();
                path
            } else {
                std::fs::write(dir.join("missing.bin"), &cube.bin).unwrap();
                let path = dir.join("missing.gltf");
                std::fs::write(&path, json).unwrap();
                path
            }
        });
        assert!(
            text.contains("meshes[0].primitives[1].attributes.POSITION names accessor 9"),
            "{text}"
        );
    }
}

#[test]
fn garbage_and_unsupported_files_are_refused() {
    let text = load_error("garbage", |dir| {
        let path = dir.join("garbage.gltf");
        std::fs::write(&path, b"\x00\x01 this is not json").unwrap();
        path
    });
    assert!(text.contains("not a valid glTF"), "{text}");
    let text = load_error("required_extension", |dir| {
        let mut cube = CubeGltf::new();
        cube.extra = r#""extensionsRequired": ["KHR_draco_mesh_compression"], "extensionsUsed": ["KHR_draco_mesh_compression"],"#.into();
        cube.write_glb(dir, "draco")
    });
    assert!(text.contains("KHR_draco_mesh_compression"), "{text}");
    let err = load_file(Path::new("/nonexistent/dir/model.glb")).unwrap_err();
    assert!(matches!(err, LoadError::Io { .. }), "{err}");
    let err = load_file(Path::new("model.obj")).unwrap_err();
    assert!(err.to_string().contains("unknown scene format"), "{err}");
}

#[test]
fn every_truncation_of_a_glb_fails_cleanly() {
    // Whatever the cut, the loader reports an error and never panics.
    let bytes = CubeGltf::new().glb();
    for cut in (0..bytes.len()).step_by(7) {
        let result = load_gltf_bytes(&bytes[..cut], Path::new("cut.glb"));
        assert!(
            result.is_err(),
            "a GLB cut at {cut} of {} bytes loaded",
            bytes.len()
        );
    }
}

#[test]
fn textures_do_not_break_loading() {
    // Textures are not drawn yet; a material with one (even a missing image file) still loads
    // with its factors.
    let dir = scratch_dir("textured");
    let mut cube = CubeGltf::new();
    cube.extra =
        r#""images": [{"uri": "missing-texture.png"}], "textures": [{"source": 0}],"#.into();
    let json = cube.json(Some("textured.bin")).replace(
        r#""baseColorFactor": [0.8, 0.1, 0.1, 1.0],"#,
        r#""baseColorFactor": [0.8, 0.1, 0.1, 1.0], "baseColorTexture": {"index": 0},"#,
    );
    assert!(json.contains("baseColorTexture"));
    std::fs::write(dir.join("textured.bin"), &cube.bin).unwrap();
    let path = dir.join("textured.gltf");
    std::fs::write(&path, json).unwrap();
    let scene = load_file(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.materials[0].base_color, [0.8, 0.1, 0.1, 1.0]);
}

#[test]
fn a_small_file_that_expands_past_the_memory_budget_is_refused() {
    // Three levels of a thousand references to the same child: a billion parts from 13 kB.
    // SAFETY: nextest runs each test in a process of its own; no other thread reads it.
    std::env::set_var(cadr_core::memory_budget::VARIABLE, "1G");
    let text = load_error("expansion", |dir| {
        let mut cube = CubeGltf::new();
        let thousand = |child: u32| format!("[{}]", vec![child.to_string(); 1000].join(","));
        cube.nodes = format!(
            r#"[{{"children": {}}}, {{"children": {}}}, {{"children": {}}}, {{"mesh": 0}}]"#,
            thousand(1),
            thousand(2),
            thousand(3)
        );
        cube.write_glb(dir, "expansion")
    });
    assert!(
        text.contains("expands to 2000000000 drawn parts")
            && text.contains("memory budget of 1.0 GiB")
            && text.contains("CADR_MEMORY_BUDGET"),
        "{text}"
    );
}

#[test]
fn a_buffer_naming_a_device_is_refused_not_read_forever() {
    let text = load_error("device_buffer", |dir| {
        let cube = CubeGltf::new();
        let path = dir.join("zero.gltf");
        std::fs::write(&path, cube.json(Some("/dev/zero"))).unwrap();
        path
    });
    assert!(
        text.contains("buffer 0 refers to '/dev/zero'") && text.contains("not a regular file"),
        "{text}"
    );
}

#[test]
fn an_accessor_of_count_zero_is_refused_not_a_panic() {
    let text = load_error("count_zero", |dir| {
        let cube = CubeGltf::new();
        let json = cube
            .json(None)
            .replacen(r#""count": 24"#, r#""count": 0"#, 1);
        assert!(
            json.contains(r#""count": 0"#),
            "the fixture changed: {json}"
        );
        std::fs::write(dir.join("zero.glb"), cube.glb_with_json(&json)).unwrap();
        dir.join("zero.glb")
    });
    assert!(text.contains("has count 0"), "{text}");
}

#[test]
fn a_glb_length_shorter_than_its_header_is_refused_not_a_panic() {
    let mut bytes = CubeGltf::new().glb();
    bytes[8..12].copy_from_slice(&4u32.to_le_bytes());
    let text = load_gltf_bytes(&bytes, Path::new("short-header.glb"))
        .unwrap_err()
        .to_string();
    assert!(
        text.contains("short-header.glb") && text.contains("length is 4 bytes"),
        "{text}"
    );
}

/// The glTF findings of the fuzz campaigns and of the audit of the glTF crate
/// (`fuzz/findings/gltf/`, made by `fuzz/make_seeds.py`): each made cadr or the glTF crate panic
/// or abort; each is now refused with an error that names the file and what is wrong in it.
#[test]
fn each_gltf_finding_is_refused_naming_what_is_wrong() {
    let findings = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/findings/gltf");
    let expected = [
        (
            "image-buffer-view-without-mime-type.glb",
            "images[0] has a bufferView but no mimeType",
        ),
        (
            "image-without-uri-or-buffer-view.gltf",
            "images[0] has neither a uri nor a bufferView",
        ),
        (
            "byte-stride-shorter-than-element.gltf",
            "accessor 0 (POSITION) has 12-byte elements, but bufferView 0 has a byteStride of 4",
        ),
        (
            "sparse-values-with-byte-stride.gltf",
            "accessor 0 (POSITION) has sparse values in bufferView 2, which has a byteStride of 4; glTF forbids one there",
        ),
        (
            "buffer-view-end-past-u64.glb",
            "bufferView 4 covers bytes 18446744073709551608..18446744073709551624 of buffer 0",
        ),
        (
            "viewless-accessor-of-four-billion-elements.gltf",
            "accessor 0 (POSITION) has no bufferView and its 4000000000 elements would take about 238.4 GiB of host memory, more than the memory budget",
        ),
    ];
    for (file, message) in expected {
        let path = findings.join(file);
        let error = load_file(&path).expect_err(file);
        assert!(
            !matches!(error, LoadError::ReaderPanicked { .. }),
            "{file}: refused only by the panic boundary: {error}"
        );
        let text = error.to_string();
        assert!(
            text.contains(file) && text.contains(message),
            "{file}: {text}"
        );
    }
}

/// Packs a GLB of `json` and `bin`, each chunk padded to four bytes.
fn packed_glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let pad = |mut bytes: Vec<u8>, with: u8| {
        bytes.resize(bytes.len().div_ceil(4) * 4, with);
        bytes
    };
    let (json, bin) = (pad(json.as_bytes().to_vec(), b' '), pad(bin.to_vec(), 0));
    let mut glb = b"glTF".to_vec();
    glb.extend(2_u32.to_le_bytes());
    glb.extend((12 + 8 + json.len() as u32 + 8 + bin.len() as u32).to_le_bytes());
    for (chunk, kind) in [(&json, b"JSON"), (&bin, b"BIN\0")] {
        glb.extend((chunk.len() as u32).to_le_bytes());
        glb.extend(kind);
        glb.extend(chunk);
    }
    glb
}

/// A sparse accessor's indices and values lie in views of their own: a file's buffers are read
/// a mesh's accessors at a time, and those views are read with the base, whether the buffer is
/// a `.bin` beside a `.gltf` or a GLB's binary chunk, giving the scene loaded from memory.
#[test]
fn sparse_accessors_read_from_files_give_the_scene_read_from_memory() {
    let mut bin = Vec::new();
    for position in [[0.0_f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        position.iter().for_each(|c| bin.extend(c.to_le_bytes()));
    }
    bin.extend(2_u16.to_le_bytes());
    bin.extend([0, 0]);
    [0.0_f32, 0.0, 1.0]
        .iter()
        .for_each(|c| bin.extend(c.to_le_bytes()));
    let json = |buffer: &str| {
        format!(
            r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":52{buffer}}}],"bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":4}},{{"buffer":0,"byteOffset":40,"byteLength":12}}],"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,1],"sparse":{{"count":1,"indices":{{"bufferView":1,"componentType":5123}},"values":{{"bufferView":2}}}}}}],"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],"nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}]}}"#
        )
    };
    let glb = packed_glb(&json(""), &bin);
    let from_memory = load_gltf_bytes(&glb, Path::new("sparse.glb")).unwrap();
    let positions: Vec<[f32; 3]> = from_memory.geometries[0]
        .vertices
        .iter()
        .map(|v| v.position)
        .collect();
    assert!(positions.contains(&[0.0, 0.0, 1.0]), "{positions:?}");

    let dir = scratch_dir("sparse-files");
    std::fs::write(dir.join("sparse.glb"), &glb).unwrap();
    std::fs::write(dir.join("sparse.bin"), &bin).unwrap();
    std::fs::write(dir.join("sparse.gltf"), json(r#","uri":"sparse.bin""#)).unwrap();
    for name in ["sparse.glb", "sparse.gltf"] {
        let mut from_file = load_file(&dir.join(name)).unwrap();
        from_file.name = from_memory.name.clone();
        assert_eq!(from_file, from_memory, "{name}");
    }
}
