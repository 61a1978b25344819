//! The scene and views that show where back faces can show (`tests/tests/back_faces.rs`, and
//! the `dgc` submission's shared streams in `tests/tests/generated_commands.rs`): four boxes
//! (a closed one, a mirrored copy, an open one, an inside-out one), seen from outside, into the
//! open box, from inside the closed one, cut by a section plane, and with edges.

use cadr_core::render::{Camera, FrameStats, Section};
use cadr_core::scene::{Geometry, Material, MeshRef, Node, Scene};
use cadr_core::technique::ShadeMode;
use glam::{DMat4, DVec3, DVec4};

use crate::fixtures::unit_box;
use crate::{scene_wide, test_device, SceneView};

/// The pictures' size.
pub const SIZE: (u32, u32) = (160, 120);

/// The closed unit box wound the other way: closed, but inside out.
pub fn inside_out_box() -> Geometry {
    let mut geometry = unit_box(false);
    for triangle in geometry.indices.chunks_exact_mut(3) {
        triangle.swap(1, 2);
    }
    geometry.name = "inside-out box".into();
    geometry
}

/// Four boxes of four colours: a closed one at the origin, a mirrored copy of it at -x, an
/// open one (no +z face) at +x, and an inside-out one at -z.
pub fn four_boxes() -> Scene {
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
pub struct Case {
    /// What the case shows.
    pub name: &'static str,
    /// The eye.
    pub eye: DVec3,
    /// What it looks at.
    pub target: DVec3,
    /// The section planes (none: no section).
    pub planes: &'static [DVec4],
    /// The display mode.
    pub mode: ShadeMode,
}

pub const CASES: [Case; 5] = [
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

/// Draws `case` with `submission` and culler `culling`: the picture and the steady frame's
/// statistics.
pub fn draw(case: &Case, submission: &str, culling: &str) -> (image::RgbaImage, FrameStats) {
    let aspect = f64::from(SIZE.0) / f64::from(SIZE.1);
    let camera = Camera::look_at(case.eye, case.target, 60.0, aspect, 0.05, 100.0);
    let mut f = SceneView::new(test_device(), &four_boxes(), SIZE, camera);
    f.view
        .techniques_mut()
        .select(&scene_wide(submission, culling))
        .expect("a valid combination");
    f.view
        .techniques_mut()
        .set_shade_mode(case.mode)
        .expect("a display mode");
    if !case.planes.is_empty() {
        let mut section = Section::none();
        section.set_planes(case.planes).expect("valid planes");
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
