//! Closed parts drawn with their back faces culled by the rasterizer: the GPU cullers route
//! them into a pass of their own (`CadrBackFacePasses`), and the picture is the one drawing
//! both faces of every part shows, also where back faces can show: an open part seen from
//! inside, an inside-out mesh, a mirrored copy, a part a section plane cuts, a part holding the
//! eye, and with edges drawn over the surfaces.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use cadr_core::render::{Camera, FrameStats, Section};
use cadr_core::scene::{Geometry, Material, MeshRef, Node, Scene};
use cadr_core::technique::ShadeMode;
use cadr_tests::fixtures::unit_box;
use cadr_tests::images::{compare, SAME_PICTURE};
use cadr_tests::{scene_wide, test_device, SceneView};
use glam::{DMat4, DVec3, DVec4};

const SIZE: (u32, u32) = (160, 120);

/// The closed unit box wound the other way: closed, but inside out.
fn inside_out_box() -> Geometry {
    let mut geometry = unit_box(false);
    for triangle in geometry.indices.chunks_exact_mut(3) {
        triangle.swap(1, 2);
    }
    geometry.name = "inside-out box".into();
    geometry
}

/// Four boxes of four colours: a closed one at the origin, a mirrored copy of it at -x, an
/// open one (no +z face) at +x, and an inside-out one at -z.
fn four_boxes() -> Scene {
    let colour = |name: &str, rgb: [f32; 3]| Material {
        name: name.into(),
        base_color: [rgb[0], rgb[1], rgb[2], 1.0],
        roughness: 0.8,
        ..Material::default()
    };
    let mut scene = Scene {
        name: "four boxes".into(),
        geometries: vec![unit_box(false), unit_box(true), inside_out_box()],
        materials: vec![
            colour("red", [0.8, 0.2, 0.2]),
            colour("green", [0.2, 0.7, 0.2]),
            colour("blue", [0.2, 0.3, 0.8]),
            colour("yellow", [0.8, 0.7, 0.2]),
        ],
        ..Scene::default()
    };
    let places = [
        (0, DMat4::IDENTITY),
        (
            0,
            DMat4::from_translation(DVec3::new(-3.0, 0.0, 0.0))
                * DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0)),
        ),
        (1, DMat4::from_translation(DVec3::new(3.0, 0.0, 0.0))),
        (2, DMat4::from_translation(DVec3::new(0.0, 0.0, -3.0))),
    ];
    for (i, (geometry, local)) in places.into_iter().enumerate() {
        let mut node = Node::new(format!("box {i}"));
        node.local = local;
        node.mesh = Some(MeshRef::new(geometry, vec![i as u32]));
        scene.nodes.push(node);
        scene.roots.push(i as u32);
    }
    scene
}

/// A case: where the eye is and what it looks at, the section planes, the display mode.
struct Case {
    name: &'static str,
    eye: DVec3,
    target: DVec3,
    planes: &'static [DVec4],
    mode: ShadeMode,
}

const CASES: [Case; 5] = [
    Case {
        name: "outside",
        eye: DVec3::new(4.0, 5.0, 9.0),
        target: DVec3::ZERO,
        planes: &[],
        mode: ShadeMode::Solid,
    },
    Case {
        name: "into the open box",
        eye: DVec3::new(3.3, 0.4, 3.0),
        target: DVec3::new(3.0, 0.0, 0.0),
        planes: &[],
        mode: ShadeMode::Solid,
    },
    Case {
        name: "inside the closed box",
        eye: DVec3::new(0.2, 0.1, 0.3),
        target: DVec3::new(-1.0, 0.0, 0.0),
        planes: &[],
        mode: ShadeMode::Solid,
    },
    Case {
        name: "a cut through every box",
        eye: DVec3::new(2.0, 6.0, 7.0),
        target: DVec3::new(0.0, 0.0, -1.0),
        planes: &[DVec4::new(0.0, -1.0, 0.0, 0.0)],
        mode: ShadeMode::Solid,
    },
    Case {
        name: "edges",
        eye: DVec3::new(-4.0, 3.0, 8.0),
        target: DVec3::ZERO,
        planes: &[],
        mode: ShadeMode::Edges,
    },
];

/// Draws `case` with culler `culling`: the picture and the steady frame's statistics.
fn draw(case: &Case, culling: &str) -> (image::RgbaImage, FrameStats) {
    let aspect = f64::from(SIZE.0) / f64::from(SIZE.1);
    let camera = Camera::look_at(case.eye, case.target, 60.0, aspect, 0.05, 100.0);
    let mut f = SceneView::new(test_device(), &four_boxes(), SIZE, camera);
    f.view
        .techniques_mut()
        .select(&scene_wide("individual-indirect-count", culling))
        .unwrap();
    f.view.techniques_mut().set_shade_mode(case.mode).unwrap();
    if !case.planes.is_empty() {
        let mut section = Section::none();
        section.set_planes(case.planes).unwrap();
        section.set_caps(false);
        f.view.set_section(section);
    }
    f.render();
    let image = f.render();
    let stats = f
        .view
        .render(&f.graph, &mut f.tree, &f.camera)
        .expect("a steady frame");
    f.assert_no_validation_errors();
    (image, stats)
}

#[test]
fn closed_parts_drawn_without_back_faces_look_as_with_them_and_the_others_keep_theirs() {
    for case in &CASES {
        // No culler: every part in one pass, both faces drawn.
        let (reference, all) = draw(case, "none");
        for culling in ["gpu-frustum", "gpu-occlusion", "gpu-clusters"] {
            let (image, stats) = draw(case, culling);
            let difference = compare(&image, &reference).unwrap();
            assert!(
                difference.within(SAME_PICTURE),
                "{}, {culling}: {difference:?}",
                case.name
            );
            // The solid surfaces are split in two passes, each with its own pipeline, in every
            // phase of the culler (gpu-occlusion and gpu-clusters draw in two).
            if case.mode == ShadeMode::Solid {
                let phases = if culling == "gpu-frustum" { 1 } else { 2 };
                assert_eq!(
                    stats.pipeline_binds,
                    phases * (all.pipeline_binds + 1),
                    "{}, {culling}: two surface pipelines in each phase",
                    case.name
                );
            }
        }
    }
}
