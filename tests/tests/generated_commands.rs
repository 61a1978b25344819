//! The `dgc` submission (`VK_EXT_device_generated_commands`, Mesa 25's lavapipe): under every
//! culler it draws the picture `groups-mdi-replay` draws, frame by frame while the camera
//! orbits, as one generated-commands execution per pass (one for both passes of the opaque
//! surfaces where a GPU culler splits them by back faces). Validation is on; the messages the
//! 1.3.239 layer gives about the extension, which it predates, are the only ones excused
//! (`cadr_core::vk` instance module).
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::sync::Arc;

use cadr_core::generate::{generate, GeneratorSpec};
use cadr_core::graph::SceneGraph;
use cadr_core::render::{Camera, FrameStats, DEFAULT_DIRECTION};
use cadr_core::scene::flatten;
use cadr_core::technique::{Combination, ShadeMode};
use cadr_core::tree::SceneTree;
use cadr_core::view::View;
use cadr_tests::back_face_cases::{draw, four_boxes, CASES, SIZE as SIZE_OF_CASES};
use cadr_tests::images::{compare, SAME_PICTURE};
use cadr_tests::{
    assert_no_validation_errors, frame_with_picks, move_apart, placed_nodes, plugin_registry,
    scene_wide, test_device, SceneView,
};

const SIZE: (u32, u32) = (200, 150);

/// The test device, which must have `VK_EXT_device_generated_commands` (Mesa 25's lavapipe).
fn dgc_device() -> Arc<cadr_core::vk::Device> {
    let device = test_device();
    assert!(
        device.capabilities().device_generated_commands,
        "the default driver ({}) has no VK_EXT_device_generated_commands: run scripts/setup.sh",
        device.adapter().name
    );
    device
}

#[test]
fn dgc_draws_what_groups_mdi_replay_draws_under_every_culler() {
    let device = dgc_device();
    let scene = generate(&GeneratorSpec::Cabinet { cabinets: 6 });
    let bounds = flatten(&scene).unwrap().bounds;
    let aspect = f64::from(SIZE.0) / f64::from(SIZE.1);
    let mut cameras = vec![Camera::fit(&bounds, aspect, DEFAULT_DIRECTION); 3];
    cameras.extend((0..3).map(|i| Camera::orbit(&bounds, aspect, 0.3 * f64::from(i), 1.2)));

    let parts = flatten(&scene).unwrap().draws.len() as u64;
    let (mut graph, _) = SceneGraph::from_scene(&scene).unwrap();
    let mut tree = SceneTree::build(&mut graph);
    let registry = plugin_registry(&device);
    let mut view = View::new(&device, Arc::clone(&registry), SIZE.0, SIZE.1).unwrap();
    let mut render = |combination: &Combination| -> Vec<(image::RgbaImage, FrameStats)> {
        view.techniques_mut().select(combination).unwrap();
        cameras
            .iter()
            .map(|camera| {
                let stats = view.render(&graph, &mut tree, camera).unwrap();
                (view.renderer().read_rgba8().unwrap(), stats)
            })
            .collect()
    };
    let reference = render(&scene_wide("groups-mdi-replay", "none"));
    for culler in ["none", "frustum", "gpu-frustum", "gpu-occlusion"] {
        let frames = render(&scene_wide("dgc", culler));
        for (frame, ((image, stats), (expected, reference_stats))) in
            frames.iter().zip(&reference).enumerate()
        {
            let difference = compare(image, expected).unwrap();
            assert!(
                difference.within(SAME_PICTURE),
                "dgc / {culler}, frame {frame}: {difference:?}"
            );
            // Executions, not a draw call per part where the driver's preprocess memory allows
            // (lavapipe's grows with the square of the sequences, and cuts passes small).
            assert!(
                (1..=parts).contains(&stats.draw_calls),
                "dgc / {culler}, frame {frame}: {} draw calls",
                stats.draw_calls
            );
            if culler == "none" {
                assert_eq!(stats.triangles, reference_stats.triangles, "frame {frame}");
            }
            assert!(stats.triangles > 0 && stats.triangles <= reference_stats.triangles);
        }
    }
    drop(view);
    assert_no_validation_errors(&device);
}

/// The preprocess memory the `dgc` submission asks for, from the same query it makes
/// (`vkGetGeneratedCommandsMemoryRequirementsEXT`, a draw-token layout of 20-byte sequences),
/// for the part counts of gen:demo, gen:graphicscard and gen:racecar: printed for
/// docs/BENCHMARKS.md. (Mesa 25.0's lavapipe answers with the square of the sequences,
/// wrapped at 4 GiB; the submission runs passes in chunks because of it.)
#[test]
fn the_preprocess_memory_query_answers_for_every_scene_size() {
    use cadr_core::vk::{
        dgc, raw as vk, ColorTarget, DepthUse, GraphicsPipelineDesc, Pipeline, PipelineLayout,
        ShaderModule, ShaderStage, COLOR_FORMAT,
    };
    let device = test_device();
    let compile = |name: &str, source: &str, stage| {
        let words = cadr_core::shaders::compile_glsl(name, source, stage, &[]).unwrap();
        ShaderModule::from_spirv(&device, name, &words, stage).unwrap()
    };
    let vertex = compile(
        "point.vert",
        "#version 460\nvoid main() { gl_Position = vec4(0.0, 0.0, 0.5, 1.0); }\n",
        ShaderStage::Vertex,
    );
    let fragment = compile(
        "white.frag",
        "#version 460\nlayout(location = 0) out vec4 c;\nvoid main() { c = vec4(1.0); }\n",
        ShaderStage::Fragment,
    );
    // The push constants of cadr's pipelines: 128 bytes for the vertex stage.
    let layout =
        PipelineLayout::new(&device, "push", &[], 128, vk::ShaderStageFlags::VERTEX).unwrap();
    let pipeline = Pipeline::graphics(
        &device,
        &GraphicsPipelineDesc {
            layout: &layout,
            vertex: &vertex,
            geometry: None,
            fragment: &fragment,
            vertex_layout: None,
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            depth_bias: false,
            triangle_outlines: false,
            cull_back_faces: false,
            indirect_bindable: false,
            colors: &[ColorTarget::replaced(COLOR_FORMAT)],
            depth: DepthUse::TestAndWrite,
            vertex_constants: &[],
            samples: 1,
            name: "preprocess query",
        },
    )
    .unwrap();
    let functions = dgc::Device::new(device.instance().raw(), device.raw()).unwrap();
    // Sequences of a draw, and (the push parameter path's) of a 96-byte parameter block pushed
    // before the draw.
    let push_token = dgc::PushConstantToken {
        update_range: vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::VERTEX)
            .size(96),
    };
    let draws = [dgc::LayoutToken::draw_indexed(0)];
    let blocks = [
        dgc::LayoutToken::push_constant(&push_token, 0),
        dgc::LayoutToken::draw_indexed(96),
    ];
    println!("{}:", device.adapter().name);
    let mut sizes = Vec::new();
    for (tokens, stride, pipeline_layout, kind) in [
        (&draws[..], 20, vk::PipelineLayout::null(), "draws"),
        (&blocks[..], 116, layout.raw(), "parameter blocks and draws"),
    ] {
        let info = dgc::LayoutCreateInfo::new(
            dgc::LayoutUsageFlags::default(),
            vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
            stride,
            pipeline_layout,
            tokens,
        );
        // SAFETY: the info and its tokens live for the call.
        let commands_layout = unsafe { functions.create_layout(&info, None) }.unwrap();
        sizes.extend(preprocess_sizes(
            &functions,
            commands_layout,
            &pipeline,
            kind,
        ));
        // SAFETY: nothing uses the layout.
        unsafe { functions.destroy_layout(commands_layout, None) };
    }
    assert!(sizes.iter().all(|&size| size > 0), "{sizes:?}");
    drop(pipeline);
    assert_no_validation_errors(&device);
}

/// The preprocess memory `commands_layout` (of sequences of `kind`) asks for with `pipeline`,
/// printed per scene size.
fn preprocess_sizes(
    functions: &cadr_core::vk::dgc::Device,
    commands_layout: cadr_core::vk::dgc::IndirectCommandsLayout,
    pipeline: &cadr_core::vk::Pipeline,
    kind: &str,
) -> Vec<u64> {
    use cadr_core::vk::dgc;
    let mut sizes = Vec::new();
    for (scene, sequences) in [
        ("one part", 1),
        ("gen:demo", 1654),
        ("gen:graphicscard", 68_000),
        ("gen:racecar", 98_000),
    ] {
        let pipeline_info = dgc::GeneratedCommandsPipelineInfo::new(pipeline.raw());
        let query = dgc::MemoryRequirementsInfo::new(
            commands_layout,
            dgc::IndirectExecutionSet::null(),
            Some(&pipeline_info),
            sequences,
        );
        // SAFETY: the layout and the pipeline are alive.
        let needs = unsafe { functions.memory_requirements(&query) };
        println!(
            "preprocess memory of {kind} for {scene} ({sequences} sequences): {} bytes",
            needs.size
        );
        assert!(needs.alignment.is_power_of_two(), "{needs:?}");
        sizes.push(needs.size);
    }
    sizes
}

/// Where a GPU culler splits the opaque surfaces into closed parts drawn with their back faces
/// culled and the others drawn with both, `dgc` draws the two passes from one stream in which
/// the GPU picks each part's pipeline from an execution set: the picture is the one drawing
/// both faces of every part shows (an open box seen from inside, an inside-out box, a mirrored
/// copy, a cut, the eye inside a box), and each phase binds one pipeline and runs one execution
/// for its surfaces where the split's two passes would bind two.
#[test]
fn dgc_draws_the_split_surfaces_from_one_stream_whose_pipelines_the_gpu_picks() {
    dgc_device();
    for case in &CASES {
        let (reference, _) = draw(case, "individual-indirect-count", "none");
        for culling in ["gpu-frustum", "gpu-occlusion", "gpu-clusters"] {
            let (image, stats) = draw(case, "dgc", culling);
            let difference = compare(&image, &reference).unwrap();
            assert!(
                difference.within(SAME_PICTURE),
                "{}, dgc / {culling}: {difference:?}",
                case.name
            );
            // The same combination drawing the split as two streams binds one pipeline more
            // per phase; with one stream, every bound pipeline runs one execution.
            let (_, two_streams) = draw(case, "individual-indirect-count", culling);
            if case.mode == ShadeMode::Solid {
                let phases = if culling == "gpu-frustum" { 1 } else { 2 };
                assert_eq!(
                    stats.pipeline_binds + phases,
                    two_streams.pipeline_binds,
                    "{}, dgc / {culling}: one surface pipeline bound in each phase",
                    case.name
                );
                assert_eq!(
                    stats.draw_calls, stats.pipeline_binds,
                    "{}, dgc / {culling}: one execution per bound pipeline",
                    case.name
                );
            }
            assert_eq!(stats.triangles, two_streams.triangles, "{}", case.name);
        }
    }
}

/// One view swapping cullers and display modes back and forth under `dgc`: each swap may make
/// new pipelines (at the handles of destroyed ones), and the execution sets of the split must
/// follow, so every frame draws its mode's picture.
#[test]
fn dgc_follows_swapped_cullers_and_display_modes_in_one_view() {
    let case = &CASES[0];
    let aspect = f64::from(SIZE_OF_CASES.0) / f64::from(SIZE_OF_CASES.1);
    let camera = Camera::look_at(case.eye, case.target, 60.0, aspect, 0.05, 100.0);
    let references: Vec<image::RgbaImage> = [ShadeMode::Solid, ShadeMode::Edges]
        .iter()
        .map(|&mode| {
            let mut f = SceneView::new(test_device(), &four_boxes(), SIZE_OF_CASES, camera);
            f.view
                .techniques_mut()
                .select(&scene_wide("individual-indirect-count", "none"))
                .unwrap();
            f.view.techniques_mut().set_shade_mode(mode).unwrap();
            f.render()
        })
        .collect();
    let mut f = SceneView::new(test_device(), &four_boxes(), SIZE_OF_CASES, camera);
    let steps = [
        ("gpu-frustum", 0),
        ("gpu-occlusion", 0),
        ("gpu-occlusion", 1),
        ("gpu-clusters", 1),
        ("gpu-clusters", 0),
        ("gpu-frustum", 1),
        ("gpu-frustum", 0),
    ];
    for (step, &(culling, mode)) in steps.iter().enumerate() {
        f.view
            .techniques_mut()
            .select(&scene_wide("dgc", culling))
            .unwrap();
        f.view
            .techniques_mut()
            .set_shade_mode([ShadeMode::Solid, ShadeMode::Edges][mode])
            .unwrap();
        // The first frame after a swap records; the second may replay.
        for frame in 0..2 {
            let image = f.render();
            let difference = compare(&image, &references[mode]).unwrap();
            assert!(
                difference.within(SAME_PICTURE),
                "step {step} ({culling}, mode {mode}), frame {frame}: {difference:?}"
            );
        }
    }
    f.assert_no_validation_errors();
}

/// `push` under `dgc` with a GPU culler: the culler writes each draw's parameter block (world
/// matrix, material, flags, instance id) before its command and a push-constant token pushes
/// it, so the picture is the one `push` draws from the CPU with the baseline, frame by frame
/// while the camera orbits and parts move (replaying the recorded frame as `ssbo-index` does:
/// nothing on the CPU follows the moves), and picking finds the same parts. With a CPU
/// culler nothing would write the blocks: the combination is refused, saying why.
#[test]
fn dgc_pushes_the_parameter_blocks_a_gpu_culler_writes() {
    let device = dgc_device();
    let scene = generate(&GeneratorSpec::Cabinet { cabinets: 4 });
    let bounds = flatten(&scene).unwrap().bounds;
    let aspect = f64::from(SIZE.0) / f64::from(SIZE.1);
    let (mut graph, handles) = SceneGraph::from_scene(&scene).unwrap();
    let moving = placed_nodes(&graph, &handles, 6);
    assert!(
        moving.len() > 1,
        "the cabinets have transform nodes to move"
    );
    let mut tree = SceneTree::build(&mut graph);
    let registry = plugin_registry(&device);
    let mut view = View::new(&device, Arc::clone(&registry), SIZE.0, SIZE.1).unwrap();
    // Per frame: the parts moved apart by the frame's step, the camera a step further round.
    let mut frames = |combination: &Combination| {
        view.techniques_mut().select(combination).unwrap();
        (0..4)
            .map(|frame| {
                move_apart(&mut graph, &moving, bounds.radius() * 0.05, frame);
                tree.update(&mut graph);
                let camera = Camera::orbit(&bounds, aspect, 0.25 * frame as f64, 1.2);
                frame_with_picks(&mut view, (&graph, &mut tree), &camera, frame == 3)
            })
            .collect::<Vec<_>>()
    };
    let reference = frames(&Combination::built_in());
    for culling in ["gpu-frustum", "gpu-occlusion", "gpu-clusters"] {
        let combination = Combination {
            vertex: "arena".into(),
            parameters: "push".into(),
            submission: "dgc".into(),
            culling: culling.into(),
            ..Combination::built_in()
        };
        let indexed = frames(&scene_wide("dgc", culling));
        for (frame, (((image, stats, picked), (expected, _, expected_picks)), (_, indexed, _))) in
            frames(&combination)
                .iter()
                .zip(&reference)
                .zip(&indexed)
                .enumerate()
        {
            let difference = compare(image, expected).unwrap();
            assert!(
                difference.within(SAME_PICTURE),
                "push / dgc / {culling}, frame {frame}: {difference:?}"
            );
            assert_eq!(
                picked, expected_picks,
                "push / dgc / {culling}, frame {frame}"
            );
            // The moved parts' blocks are written on the GPU: the recorded frame is replayed
            // while parts move, and the moves upload what they do with parameters found from
            // the instance index (the transform hierarchy stays on the GPU). The first frame
            // after a swap records; it uploads the whole scene where the swap moved the
            // hierarchy to the GPU.
            assert!(
                frame < 2 || stats.replayed,
                "push / dgc / {culling}, frame {frame}"
            );
            // One pipeline bound per stream, as with ssbo-index, whose back-face split shares
            // one stream (see the split test above): two streams would bind one more per phase.
            // So here each sequence is the pipeline's index, the block and the draw.
            assert_eq!(
                stats.pipeline_binds, indexed.pipeline_binds,
                "push / dgc / {culling}, frame {frame}"
            );
            assert!(
                frame == 0 || stats.bytes_uploaded == indexed.bytes_uploaded,
                "push / dgc / {culling}, frame {frame}: {} bytes uploaded, {} with ssbo-index",
                stats.bytes_uploaded,
                indexed.bytes_uploaded
            );
            // The blocks come with the commands: no parameter is pushed from the CPU per draw.
            assert!(
                stats.parameter_updates <= stats.draw_calls,
                "push / dgc / {culling}, frame {frame}: {} parameter updates for {} executions",
                stats.parameter_updates,
                stats.draw_calls
            );
        }
    }
    // A CPU culler writes no blocks; the baseline `push` per draw is still there for it.
    for culling in ["none", "frustum"] {
        let combination = Combination {
            vertex: "arena".into(),
            parameters: "push".into(),
            submission: "dgc".into(),
            culling: culling.into(),
            ..Combination::built_in()
        };
        let refusal = view
            .techniques_mut()
            .select(&combination)
            .unwrap_err()
            .to_string();
        assert!(
            refusal.contains("parameter block") && refusal.contains(&format!("'{culling}'")),
            "{refusal}"
        );
    }
    drop(view);
    assert_no_validation_errors(&device);
}
