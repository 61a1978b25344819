//! Loading a scene for a graph (`SceneSource::load_for_graph`, then
//! `SceneGraph::import_loaded`): each geometry goes to the graph's page file as soon as it is
//! made, so that loading holds no more geometry than the graph's memory limit, and the graph
//! made so is the graph an import of the scene loaded whole makes. This binary installs cadr's
//! counting allocator to see the heap's peak; its tests run one at a time (they share it).
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use cadr_core::graph::SceneGraph;
use cadr_core::host_heap::{bytes_in_use, peak_bytes_in_use, reset_peak, CountingAllocator};
use cadr_core::load::SceneSource;
use cadr_core::scene::{Geometry, Scene};
use cadr_tests::c_programs::scratch_dir;

#[global_allocator]
static HEAP: CountingAllocator = CountingAllocator;

/// The heap's peak is one for the whole process: one test at a time.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// gen:fine with every unit's geometries of its own (what a model larger than memory is).
const UNIQUE_UNITS: &str = "gen:fine:units=12,detail=2,unique=1";

fn scene_bytes(scene: &Scene) -> u64 {
    scene.geometries.iter().map(Geometry::host_bytes).sum()
}

/// The bytes of the scene's largest geometry.
fn largest_geometry_bytes(scene: &Scene) -> u64 {
    scene
        .geometries
        .iter()
        .map(Geometry::host_bytes)
        .max()
        .unwrap()
}

/// The most the heap grew over `work`, and its result.
fn heap_growth<R>(work: impl FnOnce() -> R) -> (u64, R) {
    let before = bytes_in_use();
    reset_peak();
    let result = work();
    (peak_bytes_in_use().saturating_sub(before), result)
}

/// The scene a fresh graph holds after importing `scene` whole (the plain road).
fn imported_whole(scene: &Scene) -> Scene {
    let mut graph = SceneGraph::new();
    let root = graph.root();
    graph.import(scene, root).unwrap();
    graph.to_scene().unwrap()
}

/// Loads `source` for a fresh graph with `limit` bytes of geometry in memory and imports it;
/// returns the graph and the heap's growth while loading.
fn loaded_for_graph(source: &SceneSource, limit: u64) -> (SceneGraph, u64) {
    let mut graph = SceneGraph::new();
    graph.set_geometry_memory_limit(limit);
    let (growth, loaded) = heap_growth(|| source.load_for_graph(graph.geometry_memory_left()));
    let (outline, geometries) = loaded.unwrap();
    let root = graph.root();
    graph.import_loaded(&outline, geometries, root).unwrap();
    (graph, growth)
}

#[test]
fn a_generated_scene_loaded_for_a_graph_holds_no_more_geometry_than_the_graph_keeps() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|p| p.into_inner());
    let source = SceneSource::parse(UNIQUE_UNITS).unwrap();
    let (whole_growth, whole) = heap_growth(|| source.load().unwrap());
    let total = scene_bytes(&whole);
    assert!(whole_growth >= total, "a whole load holds every geometry");
    let limit = total / 8;
    let (graph, growth) = loaded_for_graph(&source, limit);

    // What loading may hold beyond the limit: the generator's templates (one of each part of
    // each of the four variants, which the units copy), the unit being made (a bolt, a washer
    // and one variant's parts: under half the templates) and the outline.
    let templates = SceneSource::parse("gen:fine:units=1,detail=2").unwrap();
    let templates = scene_bytes(&templates.load().unwrap());
    let allowance = limit + templates + templates / 2 + (1 << 20);
    println!(
        "geometry {:.1} MB; loading grew the heap {:.1} MB whole, {:.1} MB for a graph keeping {:.1} MB",
        total as f64 / 1e6,
        whole_growth as f64 / 1e6,
        growth as f64 / 1e6,
        limit as f64 / 1e6
    );
    assert!(
        growth <= allowance,
        "loading for the graph grew the heap {growth} bytes, more than the limit and the templates ({allowance})"
    );
    let memory = graph.geometry_memory();
    assert!(memory.resident_bytes <= limit);
    assert!(memory.paged_geometries * 2 > whole.geometries.len() as u64);
    assert_eq!(graph.to_scene().unwrap(), imported_whole(&whole));
}

/// Writes `scene` to `name` in `directory` and returns the path.
fn saved(scene: &Scene, directory: &Path, name: &str) -> PathBuf {
    let path = directory.join(name);
    cadr_core::save::save_scene(scene, &path).unwrap();
    path
}

#[test]
fn csf_and_gltf_files_loaded_for_a_graph_page_their_geometries_and_import_as_loaded_whole() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|p| p.into_inner());
    let generated = SceneSource::parse(UNIQUE_UNITS).unwrap().load().unwrap();
    let scratch = scratch_dir("loading-memory-units");
    for name in ["units.csf", "units.csf.gz", "units.glb", "units.gltf"] {
        let path = saved(&generated, &scratch, name);
        let source = SceneSource::File(path.clone());
        let (whole_growth, whole) = heap_growth(|| source.load().unwrap());
        let limit = scene_bytes(&whole) / 8;
        let (graph, growth) = loaded_for_graph(&source, limit);
        println!(
            "{name}: loading grew the heap {:.1} MB whole, {:.1} MB for a graph keeping {:.1} MB",
            whole_growth as f64 / 1e6,
            growth as f64 / 1e6,
            limit as f64 / 1e6
        );
        let memory = graph.geometry_memory();
        assert!(memory.resident_bytes <= limit, "{name}");
        assert!(memory.paged_geometries > 0, "{name}");
        assert_eq!(graph.to_scene().unwrap(), imported_whole(&whole), "{name}");
        // No file is read whole: a CSF file is read where each array lies (a `.csf.gz` from
        // the temporary file it is unpacked into as it streams), a glTF file's buffers a
        // mesh's accessors at a time. Loading holds the limit and the geometry being read (the
        // file's arrays or accessors, the geometry made of them, and the little the file's
        // structures and the decompressor take).
        assert!(
            growth * 5 < whole_growth * 4,
            "{name}: {growth} bytes for the graph against {whole_growth} whole"
        );
        let largest = largest_geometry_bytes(&whole);
        let allowance = limit + 3 * largest + (1 << 20);
        assert!(
            growth <= allowance,
            "{name}: {growth} bytes, more than the limit and one geometry ({allowance})"
        );
        std::fs::remove_file(&path).unwrap();
    }
}

/// A figure of this process's from `/proc/self/status` (`VmRSS`, `VmHWM`), in bytes.
fn process_status_bytes(field: &str) -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap();
    let line = status
        .lines()
        .find_map(|line| line.strip_prefix(field)?.strip_prefix(':'))
        .unwrap_or_else(|| panic!("/proc/self/status has no {field}"));
    let kilobytes: u64 = line.trim().trim_end_matches(" kB").parse().unwrap();
    kilobytes * 1024
}

/// The most this process's resident memory (its heap and every other page it holds) grew over
/// `work`.
fn resident_growth<R>(work: impl FnOnce() -> R) -> (u64, R) {
    // Writing 5 to `clear_refs` sets the peak (`VmHWM`) back to what is resident now.
    std::fs::write("/proc/self/clear_refs", "5")
        .expect("/proc/self/clear_refs sets back the peak of resident memory");
    let before = process_status_bytes("VmRSS");
    let result = work();
    (process_status_bytes("VmHWM").saturating_sub(before), result)
}

/// A glTF file much larger than the graph's memory limit is never read whole: each mesh's
/// accessors are read before it is converted, and the memory they took is given back as
/// loading goes on, so that the process's resident memory grows by the limit, about a mesh
/// and the bytes read between two releases, not by the file.
#[test]
fn a_gltf_file_is_read_a_mesh_at_a_time_and_its_memory_given_back() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|p| p.into_inner());
    let generated = SceneSource::parse("gen:fine:units=40,detail=2,unique=1")
        .unwrap()
        .load()
        .unwrap();
    let scratch = scratch_dir("loading-memory-large");
    let limit = scene_bytes(&generated) / 16;
    let largest = largest_geometry_bytes(&generated);
    let allowance = limit + 3 * largest + cadr_core::load::GLTF_BYTES_BETWEEN_RELEASES + (4 << 20);
    for name in ["large.glb", "large.gltf"] {
        let path = saved(&generated, &scratch, name);
        let file_bytes: u64 = written_files(&scratch, name)
            .iter()
            .map(|file| file.len() as u64)
            .sum();
        // The test tells a file read (or kept) whole from one read a mesh at a time.
        assert!(file_bytes > 2 * allowance, "{name}: {file_bytes} bytes");
        let source = SceneSource::File(path);
        let (growth, loaded) = resident_growth(|| source.load_for_graph(limit));
        let (_, geometries) = loaded.unwrap();
        println!(
            "{name}: loading grew resident memory {:.1} MB for a file of {:.1} MB, a limit of {:.1} MB",
            growth as f64 / 1e6,
            file_bytes as f64 / 1e6,
            limit as f64 / 1e6
        );
        assert!(geometries.memory().paged_geometries > 0, "{name}");
        assert!(
            growth <= allowance,
            "{name}: resident memory grew {growth} bytes, more than the limit, a mesh and the bytes read between releases ({allowance})"
        );
    }
    std::fs::remove_dir_all(&scratch).unwrap();
}

/// The files `name` in `directory` stands for: itself, and a `.gltf`'s `.bin` beside it.
fn written_files(directory: &Path, name: &str) -> Vec<Vec<u8>> {
    let mut files = vec![std::fs::read(directory.join(name)).unwrap()];
    if let Some(stem) = name.strip_suffix(".gltf") {
        files.push(std::fs::read(directory.join(format!("{stem}.bin"))).unwrap());
    }
    files
}

/// Converting (`cadr convert`): the scene loaded with its geometries past a limit in a page
/// file, then written one geometry at a time, makes the very files a save of the whole scene
/// makes, in every format, and the save holds one geometry and the writer's buffer, not the
/// scene. A geometry whose page cannot be read back fails the save with an error that names it.
#[test]
fn a_scene_converted_from_its_page_file_is_the_file_saved_whole() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|p| p.into_inner());
    let source = SceneSource::parse(UNIQUE_UNITS).unwrap();
    let whole = source.load().unwrap();
    let total = scene_bytes(&whole);
    let (expected_directory, converted_directory) = (
        scratch_dir("loading-memory-saved"),
        scratch_dir("loading-memory-converted"),
    );
    for name in ["units.csf", "units.csf.gz", "units.glb", "units.gltf"] {
        saved(&whole, &expected_directory, name);
        let (outline, geometries) = source.load_for_graph(total / 8).unwrap();
        assert!(geometries.memory().paged_geometries > 0, "{name}");
        let path = converted_directory.join(name);
        let (growth, notes) =
            heap_growth(|| cadr_core::save::save_outline(&outline, &geometries, &path).unwrap());
        println!(
            "{name}: the save grew the heap {:.1} MB for a scene of {:.1} MB",
            growth as f64 / 1e6,
            total as f64 / 1e6
        );
        assert!(notes.is_empty(), "{notes:?}");
        assert!(
            written_files(&converted_directory, name) == written_files(&expected_directory, name),
            "{name}: the files differ"
        );
        // One geometry read back, what it is made into and the writer's buffer (the CSF
        // writer's 1 MiB; glTF's JSON, which grows with the nodes, not the geometry).
        let allowance = 4 * largest_geometry_bytes(&whole) + (2 << 20);
        assert!(
            growth <= allowance && growth * 2 < total,
            "{name}: {growth} bytes, more than one geometry and the writer's ({allowance})"
        );

        // The page file cut short: the first paged geometry cannot be read back.
        let page_file = geometries.memory().page_file.unwrap();
        std::fs::OpenOptions::new()
            .write(true)
            .open(&page_file)
            .unwrap()
            .set_len(16)
            .unwrap();
        let error = cadr_core::save::save_outline(&outline, &geometries, &path)
            .unwrap_err()
            .to_string();
        assert!(
            error.contains(&path.display().to_string()) && error.contains("geometry '"),
            "{name}: {error}"
        );
    }

    // Where no temporary file can be made in the page directory, a GLB's buffer and a
    // `.csf.gz` are made in memory instead: the same files, with a warning.
    // SAFETY of the environment: nextest runs each test in a process of its own.
    std::env::set_var("CADR_PAGE_DIR", converted_directory.join("missing"));
    for name in ["units.glb", "units.csf.gz"] {
        let path = converted_directory.join(name);
        cadr_core::save::save_scene(&whole, &path).unwrap();
        assert!(
            written_files(&converted_directory, name) == written_files(&expected_directory, name),
            "{name}: the files made in memory differ"
        );
    }
    std::env::remove_var("CADR_PAGE_DIR");
}

#[test]
fn a_refused_import_of_a_loaded_scene_changes_nothing_and_leaves_no_page_file() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|p| p.into_inner());
    let source = SceneSource::parse("gen:fine:units=2,detail=1,unique=1").unwrap();
    let mut graph = SceneGraph::new();
    graph.set_geometry_memory_limit(0);
    let (outline, geometries) = source.load_for_graph(0).unwrap();
    let page_file: PathBuf = geometries.memory().page_file.unwrap();
    assert!(page_file.exists());
    let before = graph.to_scene().unwrap();

    // A parent that is not a node of this graph: refused before anything is added.
    let stale = {
        let mut other = SceneGraph::new();
        let group = other.create_group("elsewhere");
        other.destroy_node(group).unwrap();
        group
    };
    let error = graph
        .import_loaded(&outline, geometries, stale)
        .unwrap_err();
    assert!(
        error.to_string().contains("belongs to another graph"),
        "{error}"
    );
    assert_eq!(graph.to_scene().unwrap(), before);
    assert_eq!(graph.geometry_memory().paged_geometries, 0);
    assert!(
        !Path::new(&page_file).exists(),
        "the load's page file goes with it"
    );
}

#[test]
fn a_scene_described_one_geometry_at_a_time_gives_the_whole_loads_figures() {
    use cadr_core::scene::closure::{count_closed_parts, ClosedPartCounter};
    use cadr_core::scene::{flatten, flatten_outline, SceneStats};
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|p| p.into_inner());
    let generated = SceneSource::parse(UNIQUE_UNITS).unwrap().load().unwrap();
    let scratch = scratch_dir("loading-memory-described");
    let path = saved(&generated, &scratch, "described.csf");
    let source = SceneSource::File(path.clone());
    let whole = source.load().unwrap();
    let whole_stats = SceneStats::new(&whole, &flatten(&whole).unwrap());

    let mut counter = ClosedPartCounter::default();
    let (growth, outline) = heap_growth(|| source.load_through(&mut counter).unwrap());
    let flat = flatten_outline(&outline, &counter.summaries).unwrap();
    assert_eq!(
        SceneStats::of_outline(&outline, &flat, &counter.summaries),
        whole_stats
    );
    let counts = counter.counts;
    assert_eq!(counts, count_closed_parts(&whole));
    assert!(counts.closed > 0, "gen:fine's parts are closed: {counts:?}");
    // What `cadr info` holds: the geometry being read (its CSF arrays, the geometry made of
    // them and its closure's maps), never the scene.
    let largest = largest_geometry_bytes(&whole);
    println!(
        "described with the heap grown {:.1} MB; the scene is {:.1} MB",
        growth as f64 / 1e6,
        scene_bytes(&whole) as f64 / 1e6
    );
    assert!(
        growth <= 4 * largest + (1 << 20) && growth * 4 < scene_bytes(&whole),
        "{growth} bytes to describe the scene, whose largest geometry is {largest}"
    );
    std::fs::remove_file(&path).unwrap();
}
