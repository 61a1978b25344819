//! The `mesh-tasks` submission (plugin ABI 1.23, `CADR_TRAIT_MESH_SHADING`) on Mesa 25's
//! lavapipe: the commands a GPU culler writes, drawn by mesh workgroups that compute every
//! vertex as the vertex shader does, draw the picture `individual-indirect-count` draws from
//! the same commands — while parts move and the camera orbits, in the display modes that mix
//! mesh pipelines (surfaces, caps) with vertex pipelines (edge lines, hidden silhouettes) —
//! and pick the same parts. Validation is on.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::sync::Arc;

use glam::DVec4;

use cadr_core::generate::{generate, GeneratorSpec};
use cadr_core::graph::SceneGraph;
use cadr_core::render::{Camera, FrameStats, Section};
use cadr_core::scene::flatten;
use cadr_core::technique::{Combination, ShadeMode};
use cadr_core::tree::SceneTree;
use cadr_core::view::View;
use cadr_tests::images::{compare, SAME_PICTURE};
use cadr_tests::{
    assert_no_validation_errors, frame_with_picks, move_apart, placed_nodes, plugin_registry,
    test_device,
};

const SIZE: (u32, u32) = (200, 150);

/// `pulling` / `ssbo-index` (paths whose snippets run in a mesh shader) with `submission` and
/// `culling`.
fn pulled(submission: &str, culling: &str) -> Combination {
    Combination {
        vertex: "pulling".into(),
        parameters: "ssbo-index".into(),
        submission: submission.into(),
        culling: culling.into(),
        ..Combination::built_in()
    }
}

/// What one frame of the sequence shows: the display mode, with dashed hidden lines and their
/// silhouettes, and with a section capped.
#[derive(Clone, Copy, Debug)]
struct Look {
    mode: ShadeMode,
    dashed: bool,
    section: bool,
}

const SOLID: Look = Look {
    mode: ShadeMode::Solid,
    dashed: false,
    section: false,
};

#[test]
fn mesh_workgroups_draw_the_vertex_pipelines_picture_under_every_gpu_culler() {
    let device = test_device();
    assert!(
        device.capabilities().mesh_shader,
        "the default driver ({}) has no VK_EXT_mesh_shader: run scripts/setup.sh",
        device.adapter().name
    );
    // Curved parts of about a thousand triangles: commands of many 32-triangle chunks (whole
    // parts with gpu-frustum and gpu-occlusion, clusters with gpu-clusters).
    let scene = generate(&GeneratorSpec::Fine {
        units: 2,
        detail: 1,
        unique: false,
    });
    let bounds = flatten(&scene).unwrap().bounds;
    let aspect = f64::from(SIZE.0) / f64::from(SIZE.1);
    let (mut graph, handles) = SceneGraph::from_scene(&scene).unwrap();
    let moving = placed_nodes(&graph, &handles, 6);
    assert!(moving.len() > 1, "gen:fine has transform nodes to move");
    let mut tree = SceneTree::build(&mut graph);
    let registry = plugin_registry(&device);
    let mut view = View::new(&device, Arc::clone(&registry), SIZE.0, SIZE.1).unwrap();
    let looks = [
        SOLID,
        SOLID,
        SOLID,
        SOLID,
        Look {
            mode: ShadeMode::Edges,
            ..SOLID
        },
        Look {
            mode: ShadeMode::XRay,
            ..SOLID
        },
        Look {
            mode: ShadeMode::HiddenLine,
            dashed: true,
            ..SOLID
        },
        Look {
            mode: ShadeMode::Edges,
            section: true,
            ..SOLID
        },
    ];
    // The frames of `combination`, and whether it drew the triangle passes with mesh pipelines.
    let mut frames = |combination: &Combination| {
        view.techniques_mut().select(combination).unwrap();
        let meshed = view.techniques().mesh_shading();
        let frames = looks
            .iter()
            .enumerate()
            .map(|(frame, look)| {
                move_apart(&mut graph, &moving, bounds.radius() * 0.04, frame);
                tree.update(&mut graph);
                let techniques = view.techniques_mut();
                techniques.set_shade_mode(look.mode).unwrap();
                techniques.set_dashed_hidden_lines(look.dashed);
                let mut section = Section::none();
                if look.section {
                    let centre = bounds.center();
                    section
                        .set_planes(&[DVec4::new(1.0, 0.0, 0.0, -centre.x)])
                        .unwrap();
                    section.set_caps(true);
                }
                view.set_section(section);
                let camera = Camera::orbit(&bounds, aspect, 0.2 * frame as f64, 1.1);
                // Picked after the solid frames, whose replay is checked.
                frame_with_picks(&mut view, (&graph, &mut tree), &camera, frame == 3)
            })
            .collect::<Vec<(image::RgbaImage, FrameStats, Vec<(u32, u32)>)>>();
        (frames, meshed)
    };
    for culling in ["gpu-frustum", "gpu-occlusion", "gpu-clusters"] {
        let (expected, vertex_pipelines) = frames(&pulled("individual-indirect-count", culling));
        let (drawn, mesh_pipelines) = frames(&pulled("mesh-tasks", culling));
        assert!(
            mesh_pipelines && !vertex_pipelines,
            "mesh-tasks draws the triangle passes with mesh pipelines, the other not"
        );
        for (frame, ((image, stats, picked), (reference, reference_stats, reference_picks))) in
            drawn.iter().zip(&expected).enumerate()
        {
            let look = looks[frame];
            let difference = compare(image, reference).unwrap();
            assert!(
                difference.within(SAME_PICTURE),
                "mesh-tasks / {culling}, frame {frame} ({look:?}): {difference:?}"
            );
            assert_eq!(
                picked, reference_picks,
                "mesh-tasks / {culling}, frame {frame}"
            );
            // One draw call per pass, as with one vkCmdDrawIndexedIndirectCount per pass.
            assert_eq!(
                stats.draw_calls, reference_stats.draw_calls,
                "mesh-tasks / {culling}, frame {frame} ({look:?})"
            );
            // The selection stays on the GPU: the recorded frame replays while parts move.
            if (2..4).contains(&frame) {
                assert!(stats.replayed, "mesh-tasks / {culling}, frame {frame}");
            }
        }
        let picked = &drawn[3].2;
        assert!(!picked.is_empty(), "the whole view picks some parts");
    }
    assert_no_validation_errors(&device);
}

#[test]
fn mesh_tasks_is_refused_without_paths_that_run_in_mesh_shaders_or_a_gpu_culler() {
    let device = test_device();
    let registry = plugin_registry(&device);
    let view = View::new(&device, Arc::clone(&registry), 16, 16).unwrap();
    let refusal = |combination: Combination| view.techniques().check(&combination).unwrap_err();
    let arena = refusal(Combination {
        vertex: "arena".into(),
        ..pulled("mesh-tasks", "gpu-clusters")
    });
    assert!(
        arena.contains("needs a vertex path whose shader also runs in a mesh shader")
            && arena.contains("'arena'"),
        "{arena}"
    );
    // `address` finds parameters from the instance index too, by addresses it pushes to the
    // vertex stage alone.
    let address = refusal(Combination {
        parameters: "address".into(),
        ..pulled("mesh-tasks", "gpu-frustum")
    });
    assert!(
        address.contains("needs a parameter path") && address.contains("'address'"),
        "{address}"
    );
    let frustum = refusal(pulled("mesh-tasks", "frustum"));
    assert!(
        frustum.contains("needs a GPU culler") && frustum.contains("'frustum'"),
        "{frustum}"
    );
    view.techniques()
        .check(&pulled("mesh-tasks", "gpu-occlusion"))
        .unwrap();
    assert_no_validation_errors(&device);
}
