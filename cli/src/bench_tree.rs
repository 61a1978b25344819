//! `cadr bench-tree`: what the incremental scene tree costs against a full rebuild, measured
//! in one run on one scene, and what each kind of edit uploads to the GPU, measured on the one
//! GPU scene every renderer draws from.

use std::time::Instant;

use cadr_core::gpu_scene::GpuScene;
use cadr_core::gpu_scene::Transforms;
use cadr_core::graph::{NodeFlags, NodeHandle, NodeKind, SceneGraph};
use cadr_core::scene::Material;
use cadr_core::tree::SceneTree;
use cadr_core::vk::{Device, DeviceOptions};
use glam::{DMat4, DVec3};

/// Median of `runs` timings of `f`, in milliseconds.
fn median_ms(runs: usize, mut f: impl FnMut()) -> f64 {
    let mut samples: Vec<f64> = (0..runs)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    samples.sort_by(f64::total_cmp);
    samples[samples.len() / 2]
}

/// The Transforms that place parts: those with a Geo child.
fn part_placements(graph: &SceneGraph) -> Vec<NodeHandle> {
    graph
        .nodes()
        .filter(|(_, n)| matches!(n.kind, NodeKind::Transform { .. }))
        .filter(|(_, n)| {
            n.children().iter().any(|l| {
                graph
                    .node(l.node)
                    .is_ok_and(|c| matches!(c.kind, NodeKind::Geo { .. }))
            })
        })
        .map(|(h, _)| h)
        .collect()
}

/// Every `len / count`-th item: a deterministic spread-out sample.
fn spread<T: Copy>(items: &[T], count: usize) -> Vec<T> {
    let count = count.clamp(1, items.len().max(1));
    (0..count)
        .filter_map(|i| items.get(i * items.len() / count).copied())
        .collect()
}

struct Row {
    edit: String,
    edit_ms: f64,
    update_ms: f64,
    matrices: u64,
    records: u64,
    bytes: u64,
}

/// The scene under edit, the GPU scene that follows it, and the rows measured so far.
struct EditBench {
    graph: SceneGraph,
    tree: SceneTree,
    gpu_scene: GpuScene,
    runs: usize,
    rows: Vec<Row>,
    /// The first upload that failed, reported once every edit was measured.
    upload_error: Option<String>,
}

impl EditBench {
    /// Applies `apply` `runs` times (with the run's index), each followed by the tree's
    /// update and the GPU scene's upload, and keeps the medians and the last upload as a row.
    fn measure(&mut self, edit: String, mut apply: impl FnMut(&mut SceneGraph, usize)) {
        let (mut edit_samples, mut update_samples) = (Vec::new(), Vec::new());
        let (mut matrices, mut records, mut bytes) = (0, 0, 0);
        for run in 0..self.runs {
            let start = Instant::now();
            apply(&mut self.graph, run);
            edit_samples.push(start.elapsed().as_secs_f64() * 1e3);
            let start = Instant::now();
            self.tree.update(&mut self.graph);
            self.tree.take_changes();
            update_samples.push(start.elapsed().as_secs_f64() * 1e3);
            // What the GPU scene uploads for this edit.
            let synced = self
                .gpu_scene
                .sync(&self.graph, &mut self.tree, Transforms::Host)
                .and_then(|()| self.gpu_scene.flush_uploads());
            if let Err(e) = synced {
                self.upload_error.get_or_insert(e.to_string());
            }
            let upload = self.gpu_scene.last_upload();
            (matrices, records, bytes) = (upload.matrices, upload.records, upload.bytes);
        }
        edit_samples.sort_by(f64::total_cmp);
        update_samples.sort_by(f64::total_cmp);
        self.rows.push(Row {
            edit,
            edit_ms: edit_samples[self.runs / 2],
            update_ms: update_samples[self.runs / 2],
            matrices,
            records,
            bytes,
        });
    }

    /// Moves one part placement, 1 % of them and all of them.
    fn measure_transforms(&mut self, placements: &[NodeHandle]) {
        let n = placements.len();
        for (label, count) in [
            ("1 transform", 1),
            ("1% of transforms", n.div_ceil(100)),
            ("100% of transforms", n),
        ] {
            let sample = spread(placements, count);
            let originals: Vec<DMat4> = sample
                .iter()
                .map(|&h| {
                    self.graph
                        .node(h)
                        .map(|n| n.local_matrix())
                        .unwrap_or_default()
                })
                .collect();
            self.measure(format!("{label} ({})", sample.len()), |graph, run| {
                let lift = DMat4::from_translation(DVec3::new(0.0, 0.01 * (run + 1) as f64, 0.0));
                for (&h, original) in sample.iter().zip(&originals) {
                    let _ = graph.set_matrix(h, lift * *original);
                }
            });
        }
    }

    /// Changes the colour of the first material a part uses.
    fn measure_material(&mut self) {
        let material = self.graph.nodes().find_map(|(_, n)| match &n.kind {
            NodeKind::Geo { part_materials, .. } => part_materials.first().copied(),
            _ => None,
        });
        let Some(material) = material else { return };
        self.measure("1 material".into(), |graph, run| {
            let shade = 0.2 + 0.1 * (run % 5) as f32;
            let _ = graph.set_material(
                material,
                Material {
                    name: "bench".into(),
                    base_color: [shade, 0.3, 0.4, 1.0],
                    ..Material::default()
                },
            );
        });
    }

    /// Replaces the first geometry with a copy of itself.
    fn measure_geometry(&mut self) {
        let geometry = self
            .graph
            .geometry_handle_at(0)
            .and_then(|h| Some((h, self.graph.geometry(h).ok()?.into_owned())));
        let Some((handle, original)) = geometry else {
            return;
        };
        self.measure(
            format!("1 geometry ({} triangles)", original.indices.len() / 3),
            |graph, _| {
                let _ = graph.replace_geometry(handle, original.clone());
            },
        );
    }

    /// Hides and shows 1 % of the part placements in turn.
    fn measure_hiding(&mut self, placements: &[NodeHandle]) {
        let hidden = spread(placements, placements.len().div_ceil(100));
        self.measure(format!("hide/show 1% ({})", hidden.len()), |graph, run| {
            for &h in &hidden {
                let _ = graph.set_flags(
                    h,
                    NodeFlags {
                        visible: run % 2 == 1,
                        ..NodeFlags::default()
                    },
                );
            }
        });
    }
}

pub fn bench_tree(scene_text: &str, runs: usize) -> Result<(), String> {
    let crate::LoadedGraph {
        mut graph,
        name: scene_name,
        ..
    } = crate::load_graph(scene_text, &[])?;
    let build_ms = median_ms(runs, || {
        SceneTree::build(&mut graph);
    });
    let mut tree = SceneTree::build(&mut graph);
    tree.take_changes();
    let device = Device::new(&DeviceOptions::default()).map_err(|e| e.to_string())?;
    let mut gpu_scene =
        GpuScene::new(&device, &graph, &mut tree, Transforms::Host).map_err(|e| e.to_string())?;
    gpu_scene.flush_uploads().map_err(|e| e.to_string())?;
    let initial_upload = gpu_scene.last_upload();
    let placements = part_placements(&graph);
    let mut bench = EditBench {
        graph,
        tree,
        gpu_scene,
        runs,
        rows: Vec::new(),
        upload_error: None,
    };
    bench.measure_transforms(&placements);
    bench.measure_material();
    bench.measure_geometry();
    bench.measure_hiding(&placements);
    if let Some(error) = bench.upload_error {
        return Err(format!("uploading to the GPU scene: {error}"));
    }
    let tree = &bench.tree;
    let instances = tree.instance_count();
    let (matrix_bytes, other_bytes) = tree.memory_bytes();
    println!(
        "scene:        {} ({} instances on {} paths, {} part placements)",
        scene_name,
        instances,
        tree.node_count(),
        placements.len()
    );
    println!("build tree:   {build_ms:.2} ms (median of {runs})");
    println!(
        "GPU scene:    {} bytes uploaded at creation ({} of geometry), on {}",
        initial_upload.bytes,
        initial_upload.geometry_bytes,
        device.adapter().name
    );
    println!(
        "memory:       {:.1} bytes per instance besides matrices, {:.1} bytes per instance of f64 world matrices",
        other_bytes as f64 / instances.max(1) as f64,
        matrix_bytes as f64 / instances.max(1) as f64
    );
    print_rows(&bench.rows, build_ms);
    println!(
        "goal <= 64 bytes per instance besides matrices: {:.1} ({})",
        other_bytes as f64 / instances.max(1) as f64,
        if other_bytes <= 64 * instances.max(1) {
            "met"
        } else {
            "missed"
        }
    );
    Ok(())
}

/// The table of edits against a rebuild taking `build_ms`, and the goal for 1 % of the
/// transforms.
fn print_rows(rows: &[Row], build_ms: f64) {
    println!();
    println!(
        "{:<26} {:>10} {:>11} {:>10} {:>10} {:>12} {:>10}",
        "edit", "edit ms", "update ms", "/ rebuild", "matrices", "records", "bytes/frame"
    );
    for row in rows {
        println!(
            "{:<26} {:>10.3} {:>11.3} {:>9.2}% {:>10} {:>12} {:>10}",
            row.edit,
            row.edit_ms,
            row.update_ms,
            100.0 * row.update_ms / build_ms,
            row.matrices,
            row.records,
            row.bytes
        );
    }
    if let Some(one_percent) = rows.iter().find(|r| r.edit.starts_with("1% of")) {
        println!();
        println!(
            "goal 1% of transforms <= 5% of a rebuild: {:.2}% ({})",
            100.0 * one_percent.update_ms / build_ms,
            if one_percent.update_ms <= 0.05 * build_ms {
                "met"
            } else {
                "missed"
            }
        );
    }
}
