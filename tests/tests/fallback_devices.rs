//! Devices without Vulkan 1.4's extras: on Debian 12's own driver (Mesa 22.3's lavapipe,
//! unpacked by `scripts/setup.sh`), what needs mesh shaders is refused with the reason, not
//! crashed into; on SwiftShader, which lacks `drawIndirectCount`, the GPU cullers draw through
//! `individual-mdi`. Each test runs in a process of its own pointed at its driver alone.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::sync::Arc;

use cadr_core::generate::{generate, GeneratorSpec};
use cadr_core::graph::{NodeFlags, SceneGraph};
use cadr_core::render::{Camera, FrameStats, DEFAULT_DIRECTION};
use cadr_core::scene::flatten;
use cadr_core::tree::SceneTree;
use cadr_core::view::View;
use cadr_core::vk::raw as vk;
use cadr_core::vk::{
    draw_mesh_tasks, ColorTarget, DepthUse, MeshPipelineDesc, OneShot, Pipeline, PipelineLayout,
    ShaderModule, ShaderStage, COLOR_FORMAT,
};
use cadr_tests::images::{compare, SAME_PICTURE, VISIBLE_CHANGE};
use cadr_tests::{assert_no_validation_errors, mesa22_device, scene_wide, swiftshader_device};

const FRAGMENT: &str =
    "#version 460\nlayout(location = 0) out vec4 c;\nvoid main() { c = vec4(1.0); }\n";

#[test]
fn mesh_shaders_are_refused_with_the_reason_on_mesa_22_3() {
    let device = mesa22_device();
    assert!(!device.capabilities().mesh_shader);
    let words = cadr_core::shaders::compile_glsl("fill.frag", FRAGMENT, ShaderStage::Fragment, &[])
        .expect("compiles");
    let fragment =
        ShaderModule::from_spirv(&device, "fill.frag", &words, ShaderStage::Fragment).unwrap();
    let layout =
        PipelineLayout::new(&device, "none", &[], 0, vk::ShaderStageFlags::empty()).unwrap();
    // No mesh shader module can be made here; the fragment module stands in, as the check
    // comes before any use of it.
    let error = Pipeline::mesh(
        &device,
        &MeshPipelineDesc {
            layout: &layout,
            task: None,
            mesh: &fragment,
            fragment: &fragment,
            depth_bias: false,
            triangle_outlines: false,
            cull_back_faces: false,
            mesh_constants: &[],
            colors: &[ColorTarget::replaced(COLOR_FORMAT)],
            depth: DepthUse::TestAndWrite,
            samples: 1,
            name: "clusters",
        },
    )
    .err()
    .expect("refused");
    let message = error.to_string();
    assert!(
        message.contains("pipeline 'clusters' needs VK_EXT_mesh_shader")
            && message.contains("llvmpipe"),
        "{message}"
    );
    let mut one_shot = OneShot::begin(&device, "no mesh draw").unwrap();
    let error =
        draw_mesh_tasks(&device, one_shot.command_buffer(), [1, 1, 1]).expect_err("refused");
    assert!(
        error
            .to_string()
            .contains("vkCmdDrawMeshTasksEXT needs VK_EXT_mesh_shader"),
        "{error}"
    );
    one_shot.submit_and_wait().unwrap();
    assert_no_validation_errors(&device);
}

#[test]
fn the_dgc_and_mesh_tasks_submissions_are_refused_with_the_reason_on_mesa_22_3() {
    let device = mesa22_device();
    assert!(!device.capabilities().device_generated_commands);
    let registry = cadr_tests::plugin_registry(&device);
    let view =
        cadr_core::view::View::new(&device, std::sync::Arc::clone(&registry), 64, 64).unwrap();
    let error = view
        .techniques()
        .check(&cadr_tests::scene_wide("dgc", "gpu-frustum"))
        .expect_err("refused");
    let message = error.to_string();
    assert!(
        message.contains("dgc") && message.contains("VK_EXT_device_generated_commands"),
        "{message}"
    );
    // Nor mesh shaders: the submission that draws by mesh workgroups is refused too.
    let mesh_tasks = cadr_core::technique::Combination {
        vertex: "pulling".into(),
        ..cadr_tests::scene_wide("mesh-tasks", "gpu-clusters")
    };
    let message = view.techniques().check(&mesh_tasks).expect_err("refused");
    assert!(
        message.contains("mesh-tasks") && message.contains("VK_EXT_mesh_shader"),
        "{message}"
    );
    drop(view);
    assert_no_validation_errors(&device);
}

/// Renders the camera's frames of `graph` (its tree `tree`) through `view`, with every instance
/// but the first of each `keep_one_in` hidden in the last frame, which follows a frame that drew
/// them all.
fn frames_then_most_hidden(
    view: &mut View,
    (graph, tree): (&mut SceneGraph, &mut SceneTree),
    cameras: &[Camera],
    keep_one_in: usize,
) -> Vec<(image::RgbaImage, FrameStats)> {
    let mut frames: Vec<_> = cameras
        .iter()
        .map(|camera| {
            let stats = view.render(graph, tree, camera).unwrap();
            (view.renderer().read_rgba8().unwrap(), stats)
        })
        .collect();
    let geo_nodes: Vec<_> = tree
        .instances()
        .filter_map(|id| tree.path(tree.instance(id)?.tree_node).last().copied())
        .collect();
    let hidden: Vec<_> = geo_nodes
        .into_iter()
        .enumerate()
        .filter(|(i, _)| i % keep_one_in != 0)
        .map(|(_, node)| node)
        .collect();
    let set_visible = |graph: &mut SceneGraph, tree: &mut SceneTree, visible: bool| {
        for &node in &hidden {
            let flags = NodeFlags {
                visible,
                ..graph.node(node).unwrap().flags
            };
            graph.set_flags(node, flags).unwrap();
        }
        tree.update(graph);
    };
    set_visible(graph, tree, false);
    let camera = cameras.last().unwrap();
    let stats = view.render(graph, tree, camera).unwrap();
    frames.push((view.renderer().read_rgba8().unwrap(), stats));
    set_visible(graph, tree, true);
    frames
}

/// Issue 41's fallback: SwiftShader lacks `drawIndirectCount`, so the GPU cullers' commands are
/// drawn by their capacity (`individual-mdi`, one `vkCmdDrawIndexedIndirect` per pass), the
/// culler leaving every command past its counts empty. Frame by frame (a still view, an orbit,
/// then most parts hidden right after a frame that drew them all, when last frame's commands
/// lie past the count) each GPU culler draws what the CPU culler draws; the count-reading
/// submission is refused, naming the feature.
#[test]
fn gpu_cullers_draw_by_capacity_on_swiftshader_which_lacks_draw_indirect_count() {
    let device = swiftshader_device(false);
    assert!(!device.capabilities().draw_indirect_count);
    let registry = cadr_tests::plugin_registry(&device);
    let mut view = View::new(&device, Arc::clone(&registry), 160, 120).unwrap();
    let by_count = scene_wide("individual-indirect-count", "gpu-occlusion");
    let why = view.techniques().check(&by_count).expect_err("refused");
    assert!(
        why.contains("individual-indirect-count") && why.contains("drawIndirectCount"),
        "{why}"
    );
    // Cluster culling at full detail draws exactly the parts' triangles.
    view.techniques_mut().set_lod_error(0.0).unwrap();
    let scene = generate(&GeneratorSpec::Demo);
    let (mut graph, _) = SceneGraph::from_scene(&scene).unwrap();
    let mut tree = SceneTree::build(&mut graph);
    let bounds = flatten(&scene).unwrap().bounds;
    let aspect = 160.0 / 120.0;
    let still = Camera::fit(&bounds, aspect, DEFAULT_DIRECTION);
    let cameras: Vec<Camera> = [still, still]
        .into_iter()
        .chain((0..3).map(|i| Camera::orbit(&bounds, aspect, f64::from(i) / 10.0, 1.0)))
        .collect();
    let mut results = Vec::new();
    for culler in ["frustum", "gpu-frustum", "gpu-occlusion", "gpu-clusters"] {
        view.techniques_mut()
            .select(&scene_wide("individual-mdi", culler))
            .unwrap();
        let frames = frames_then_most_hidden(&mut view, (&mut graph, &mut tree), &cameras, 7);
        results.push((culler, frames));
    }
    let (_, reference) = &results[0];
    let (hidden, all) = (&reference[cameras.len()].0, &reference[cameras.len() - 1].0);
    let hiding = compare(hidden, all).unwrap();
    assert!(
        hiding.mean > VISIBLE_CHANGE,
        "hiding most parts shows: {hiding:?}"
    );
    for (culler, frames) in &results[1..] {
        for (frame, ((image, stats), (expected, cpu))) in frames.iter().zip(reference).enumerate() {
            let difference = compare(image, expected).unwrap();
            assert!(
                difference.within(SAME_PICTURE),
                "{culler}, frame {frame}: {difference:?}"
            );
            // Only the draws the culler counted: one call per pass, whatever the room.
            assert!(
                stats.triangles <= cpu.triangles && stats.draw_calls <= 4,
                "{culler}, frame {frame}: {stats:?} against {cpu:?}"
            );
        }
    }
    drop(view);
    assert_no_validation_errors(&device);
}
