//! CSF: round trips, the reference layout, version fix-ups, compression, and malformed files
//! that must give errors naming the structure and field.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use cadr_core::csf::{
    csf_from_scene, load_csf, read_csf, save_csf, scene_from_csf, write_csf, write_csf_file,
    FLAG_UNIQUE_NODES, MAGIC,
};
use cadr_core::generate::{generate, GeneratorSpec};
use cadr_core::load::{load_bytes, load_file, SceneFormat};
use cadr_core::scene::{flatten, Scene};
use cadr_tests::assert_same_drawing;
use cadr_tests::fixtures::{rich_csf_file as rich_file, scratch_dir, CubeGltf};

fn cube_scene() -> Scene {
    let dir = scratch_dir("csf_cube");
    load_file(&CubeGltf::new().write_glb(&dir, "cube")).unwrap()
}

fn cube_csf_bytes() -> Vec<u8> {
    write_csf(&csf_from_scene(&cube_scene()).unwrap(), 6)
}

fn u32_at(bytes: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap())
}

fn u64_at(bytes: &[u8], at: usize) -> usize {
    u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap()) as usize
}

fn put_u32(bytes: &mut [u8], at: usize, value: u32) {
    bytes[at..at + 4].copy_from_slice(&value.to_le_bytes());
}

fn put_u64(bytes: &mut [u8], at: usize, value: u64) {
    bytes[at..at + 8].copy_from_slice(&value.to_le_bytes());
}

#[test]
fn scenes_round_trip_through_csf() {
    for scene in [cube_scene(), generate(&GeneratorSpec::Demo)] {
        let file = csf_from_scene(&scene).unwrap();
        let bytes = write_csf(&file, 6);
        let read = read_csf(&bytes).unwrap();
        assert_eq!(read, file, "what is written is read back exactly");
        let back = scene_from_csf(&read, "round trip").unwrap();
        back.validate().unwrap();
        assert_same_drawing(&scene, &back);
        assert_eq!(
            back.geometries[0].wire_indices, scene.geometries[0].wire_indices,
            "wire indices survive"
        );
        assert_eq!(
            back.nodes[0].name, scene.nodes[0].name,
            "names survive as node metas"
        );
        // CSF has no alpha modes: what it keeps is the colour (its alpha the opacity).
        let kept = |s: &cadr_core::scene::Scene| {
            s.materials
                .iter()
                .map(|m| (m.name.clone(), m.base_color, m.metallic, m.roughness))
                .collect::<Vec<_>>()
        };
        assert_eq!(
            kept(&back),
            kept(&scene),
            "colour, metallic and roughness survive"
        );
    }
}

#[test]
fn shared_subgraphs_are_unfolded_into_a_tree() {
    let mut scene = cube_scene();
    // Node 2 now also hangs under node 1: a DAG with 3 paths to meshes.
    scene.nodes[1].children.push(2);
    let file = csf_from_scene(&scene).unwrap();
    assert_eq!(file.file_flags & FLAG_UNIQUE_NODES, FLAG_UNIQUE_NODES);
    assert_eq!(
        file.nodes.len(),
        4,
        "the shared node is written once per path"
    );
    assert_same_drawing(&scene, &scene_from_csf(&file, "tree").unwrap());
}

#[test]
fn written_files_have_the_reference_layout() {
    let bytes = cube_csf_bytes();
    assert_eq!(u32_at(&bytes, 0) as i32, MAGIC);
    assert_eq!(u32_at(&bytes, 4), 6);
    assert_eq!(u32_at(&bytes, 8), FLAG_UNIQUE_NODES);
    assert_eq!(
        u64_at(&bytes, 40),
        88,
        "the geometry array follows the 88-byte header"
    );
    let pointers = u64_at(&bytes, 32);
    let count = u32_at(&bytes, 12) as usize;
    assert_eq!(pointers % 8, 0);
    assert_eq!(
        pointers + 8 * count,
        bytes.len(),
        "the pointer table ends the file"
    );
    let mut previous_target = 0;
    for i in 0..count {
        let location = u64_at(&bytes, pointers + 8 * i);
        assert!(
            location >= 40 && location.is_multiple_of(8) && location + 8 <= bytes.len(),
            "entry {i}: {location}"
        );
        let target = u64_at(&bytes, location);
        assert!(
            target >= 88 && target < pointers,
            "entry {i} points to {target}"
        );
        assert_eq!(target % 4, 0);
        assert!(
            target > previous_target,
            "depth-first: every block follows the previous one"
        );
        previous_target = target;
    }
    let header_locations: Vec<usize> = (0..count)
        .map(|i| u64_at(&bytes, pointers + 8 * i))
        .filter(|&l| l < 88)
        .collect();
    assert_eq!(
        header_locations,
        vec![40, 48, 56, 64, 72],
        "geometries, materials, nodes, node and geometry metas"
    );
}

#[test]
fn older_versions_read_with_their_fix_ups() {
    let file = csf_from_scene(&cube_scene()).unwrap();
    let current = scene_from_csf(&file, "v6").unwrap();
    for version in 2..=5 {
        let mut bytes = write_csf(&file, version);
        let header = if version >= 5 { 88 } else { 64 };
        assert_eq!(u64_at(&bytes, 40), header, "v{version} header size");
        if version < 4 {
            // Slot 3 of a node part was lineWidth: whatever it holds, nodeIDX reads as -1.
            let node1 = u64_at(&bytes, 56) + 160;
            let parts = u64_at(&bytes, node1 + 144);
            put_u32(&mut bytes, parts + 8, 1.5_f32.to_bits());
        }
        if version < 3 {
            put_u32(&mut bytes, 8, 7); // "hasUniqueNodes" was a boolean
        }
        let read = read_csf(&bytes).unwrap_or_else(|e| panic!("v{version}: {e}"));
        assert_eq!(read.version, version);
        assert_eq!(read.file_flags & FLAG_UNIQUE_NODES, FLAG_UNIQUE_NODES);
        assert!(
            read.nodes
                .iter()
                .flat_map(|n| &n.parts)
                .all(|p| p.node == -1),
            "v{version}"
        );
        let scene = scene_from_csf(&read, "old").unwrap();
        assert_same_drawing(&current, &scene);
        if version < 5 {
            assert_eq!(scene.nodes[0].name, "node 0", "no metas before version 5");
        }
    }
}

#[test]
fn files_longer_than_their_content_and_gzip_files_load() {
    let mut bytes = cube_csf_bytes();
    let file = read_csf(&bytes).unwrap();
    bytes.resize(bytes.len().div_ceil(4096) * 4096, 0); // the Linux reference writer pads
    assert_eq!(read_csf(&bytes).unwrap(), file);
    let dir = scratch_dir("csf_gz");
    let gz = dir.join("cube.csf.gz");
    save_csf(&file, &gz).unwrap();
    assert_eq!(
        &std::fs::read(&gz).unwrap()[..2],
        &[0x1f, 0x8b],
        "gzip magic"
    );
    assert_eq!(load_csf(&gz).unwrap(), file);
    let scene = load_file(&gz).unwrap();
    assert_same_drawing(&cube_scene(), &scene);
}

/// Written to a file, one geometry at a time, with blocks larger than what the writer holds
/// (a geometry's arrays of several megabytes go straight to the file, the fields before them
/// are patched in place), a file has the bytes of the same file written in memory.
#[test]
fn a_file_written_to_disk_a_geometry_at_a_time_has_the_bytes_written_in_memory() {
    let scene = generate(&GeneratorSpec::Grid {
        parts: 2,
        triangles_per_part: 40_000.0,
    });
    let file = csf_from_scene(&scene).unwrap();
    let largest = file.geometries.iter().map(|g| g.vertices.len() * 4).max();
    assert!(
        largest > Some(1 << 20),
        "{largest:?} bytes of positions at most"
    );
    let in_memory = write_csf(&file, 6);
    let directory = scratch_dir("csf-streamed");
    std::fs::create_dir_all(&directory).unwrap();
    let path = directory.join("grid.csf");
    let mut output = std::fs::File::create(&path).unwrap();
    write_csf_file(&file, &mut file.geometries.as_slice(), 6, &mut output).unwrap();
    drop(output);
    assert!(
        std::fs::read(&path).unwrap() == in_memory,
        "the files differ"
    );
    assert_eq!(read_csf(&in_memory).unwrap(), file);
    std::fs::remove_file(&path).unwrap();
}

#[test]
fn channels_metas_and_payloads_survive_a_csf_round_trip() {
    let file = rich_file();
    assert_eq!(read_csf(&write_csf(&file, 6)).unwrap(), file);
}

#[test]
fn hidden_parts_sub_transforms_and_missing_normals_convert() {
    let scene = scene_from_csf(&rich_file(), "rich").unwrap();
    scene.validate().unwrap();
    let flat = flatten(&scene).unwrap();
    assert_eq!(flat.draws.len(), 2, "the inactive part is not drawn");
    let placed = flat.instances[flat.draws[0].instance as usize].world;
    assert_eq!(
        placed.w_axis.x, 5.0,
        "part 0 is placed by child node 1's matrix"
    );
    assert_eq!(
        flat.instances[flat.draws[1].instance as usize]
            .world
            .w_axis
            .x,
        -3.0
    );
    let normal = scene.geometries[1].vertices[0].normal;
    assert!(
        (normal[1].abs() - 1.0).abs() < 1e-6,
        "computed normal of the y=0 triangle: {normal:?}"
    );
    assert_eq!(scene.nodes[0].name, "assembly");
    assert_eq!(scene.geometries[0].wire_indices.len(), 8);
    assert_eq!(scene.geometries[0].parts[1].first_wire_index, 4);
}

#[test]
fn flat_files_draw_every_node() {
    let mut file = rich_file();
    file.root = -1;
    for node in &mut file.nodes {
        node.children.clear();
        for part in &mut node.parts {
            part.node = -1;
        }
    }
    let scene = scene_from_csf(&read_csf(&write_csf(&file, 6)).unwrap(), "flat").unwrap();
    assert_eq!(scene.roots, vec![0, 1, 2]);
    let mut with_children = file.clone();
    with_children.nodes[0].children.push(1);
    let error = read_csf(&write_csf(&with_children, 6))
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("node 0 numChildren") && error.contains("flat file"),
        "{error}"
    );
}

type Mutation = fn(&mut Vec<u8>);

/// Where geometry 0 starts.
fn geometry(bytes: &[u8]) -> usize {
    u64_at(bytes, 40)
}

/// Where node `n` starts.
fn node(bytes: &[u8], n: usize) -> usize {
    u64_at(bytes, 56) + 160 * n
}

#[test]
fn malformed_files_name_the_structure_and_field() {
    let cases: Vec<(&str, Mutation, &str)> = vec![
        ("bad magic", |b| put_u32(b, 0, 0x1234_5678), "header magic"),
        (
            "version 1",
            |b| put_u32(b, 4, 1),
            "header version: 1 is not supported",
        ),
        ("version 7", |b| put_u32(b, 4, 7), "header version: 7"),
        ("truncated header", |b| b.truncate(50), "header size"),
        (
            "negative count",
            |b| put_u32(b, 16, u32::MAX),
            "header numGeometries: count -1",
        ),
        (
            "root out of range",
            |b| put_u32(b, 28, 99),
            "header rootIDX",
        ),
        (
            "array beyond the file",
            |b| put_u64(b, 56, 1 << 40),
            "header nodesOFFSET: bytes",
        ),
        (
            "array inside the header",
            |b| put_u64(b, 48, 16),
            "inside the header",
        ),
        (
            "misaligned array",
            |b| {
                let g = geometry(b) as u64;
                put_u64(b, 40, g + 4)
            },
            "not aligned to 8",
        ),
        (
            "vertex count overflow",
            |b| {
                let g = geometry(b);
                put_u32(b, g + 68, i32::MAX as u32)
            },
            "geometry 0 vertexOFFSET",
        ),
        (
            "huge channel count",
            |b| {
                let g = geometry(b);
                put_u32(b, g + 16, i32::MAX as u32)
            },
            "geometry 0 normalOFFSET",
        ),
        (
            "parts exceed indices",
            |b| {
                let g = geometry(b);
                put_u32(b, g + 72, 3)
            },
            "geometry 0 parts: the parts use 36 solid indices, but the geometry has 3",
        ),
        (
            "index out of range",
            |b| {
                let g = geometry(b);
                let i = u64_at(b, g + 104);
                put_u32(b, i + 8, 500)
            },
            "geometry 0 part 0 indexSolidOFFSET: index 2 is 500",
        ),
        (
            "node parts disagree",
            |b| {
                let n = node(b, 1);
                put_u32(b, n + 132, 1)
            },
            "node 1 numParts: 1, but its geometry 0 has 2 parts",
        ),
        (
            "geometry index out of range",
            |b| {
                let n = node(b, 1);
                put_u32(b, n + 128, 9)
            },
            "node 1 geometryIDX: 9",
        ),
        (
            "material out of range",
            |b| {
                let n = node(b, 1);
                let p = u64_at(b, n + 144);
                put_u32(b, p + 4, 42)
            },
            "node 1 part 0 materialIDX: 42",
        ),
        (
            "child out of range",
            |b| {
                let n = node(b, 0);
                let c = u64_at(b, n + 152);
                put_u32(b, c, 77)
            },
            "node 0 childrenOFFSET: child 0 is 77",
        ),
        (
            "cycle",
            |b| {
                let n = node(b, 0);
                let c = u64_at(b, n + 152);
                put_u32(b, c, 0)
            },
            "node 0 childrenOFFSET: child 0 closes a cycle",
        ),
    ];
    for (name, mutate, expected) in cases {
        let mut bytes = cube_csf_bytes();
        mutate(&mut bytes);
        let error = read_csf(&bytes)
            .err()
            .unwrap_or_else(|| panic!("{name}: accepted"));
        assert!(
            error.to_string().contains(expected),
            "{name}: '{error}' does not contain '{expected}'"
        );
    }
}

#[test]
fn every_truncation_fails_cleanly() {
    let bytes = cube_csf_bytes();
    let content_end = u64_at(&bytes, 32); // the pointer table is not needed to read
    for cut in 0..bytes.len() {
        let result = read_csf(&bytes[..cut]);
        if cut < content_end {
            assert!(result.is_err(), "cut at {cut} of {}", bytes.len());
        }
    }
}

#[test]
fn a_pointer_table_the_reference_loader_cannot_use_is_refused() {
    // The reference loader relocates through the table before anything else: a table outside
    // the file, or an entry that is not a pointer field inside it, makes it read out of bounds.
    let good = cube_csf_bytes();
    let pointers = u32_at(&good, 12) as usize;
    let table = u64::from_le_bytes(good[32..40].try_into().unwrap()) as usize;
    assert!(pointers > 0 && table + 8 * pointers <= good.len());
    read_csf(&good).unwrap();

    let mut far = good.clone();
    far[32..40].copy_from_slice(&(1u64 << 40).to_le_bytes());
    let error = read_csf(&far).unwrap_err().to_string();
    assert!(
        error.contains("pointersOFFSET") && error.contains("beyond the end of the file"),
        "{error}"
    );

    let mut unaligned = good.clone();
    unaligned[32..40].copy_from_slice(&(table as u64 + 4).to_le_bytes());
    let error = read_csf(&unaligned).unwrap_err().to_string();
    assert!(error.contains("not aligned to 8 bytes"), "{error}");

    for bad_entry in [good.len() as u64, 36, 41] {
        let mut wild = good.clone();
        let last = table + 8 * (pointers - 1);
        wild[last..last + 8].copy_from_slice(&bad_entry.to_le_bytes());
        let error = read_csf(&wild).unwrap_err().to_string();
        assert!(
            error.contains(&format!(
                "entry {} points at offset {bad_entry}",
                pointers - 1
            )),
            "{error}"
        );
    }
}

#[test]
fn malformed_csf_files_on_disk_name_the_file() {
    let dir = scratch_dir("csf_bad");
    let path = dir.join("broken.csf");
    std::fs::write(&path, &cube_csf_bytes()[..100]).unwrap();
    let error = load_file(&path).unwrap_err().to_string();
    assert!(
        error.contains("broken.csf") && error.contains("OFFSET"),
        "{error}"
    );
    let gz = dir.join("notgzip.csf.gz");
    std::fs::write(&gz, b"plain bytes").unwrap();
    let error = load_file(&gz).unwrap_err().to_string();
    assert!(error.contains("notgzip.csf.gz"), "{error}");
}

/// An uncompressed CSF file on disk is read where each array lies, never whole: it must give
/// what its bytes give in memory, scene or error, whole, cut anywhere, or malformed.
#[test]
fn a_csf_file_read_from_disk_gives_what_its_bytes_give_in_memory() {
    let dir = scratch_dir("csf_from_disk");
    let path = dir.join("read.csf");
    let outcome = |result: Result<Scene, cadr_core::load::LoadError>| match result {
        Ok(scene) => Ok(scene),
        Err(error) => Err(error.to_string()),
    };
    let same = |bytes: &[u8], what: &str| {
        std::fs::write(&path, bytes).unwrap();
        let from_disk = outcome(load_file(&path));
        let in_memory = outcome(load_bytes(bytes, SceneFormat::Csf, &path));
        assert_eq!(from_disk, in_memory, "{what}");
        from_disk.is_ok()
    };
    let rich = write_csf(&rich_file(), 6);
    assert!(same(&rich, "the rich file"));
    let cube = cube_csf_bytes();
    assert!(same(&cube, "the cube"));
    for cut in (0..cube.len()).step_by(5) {
        same(&cube[..cut], &format!("the cube cut at {cut}"));
    }
    let mut far = cube.clone();
    put_u64(&mut far, 56, 1 << 40);
    assert!(!same(&far, "nodes beyond the file"));
}
