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
    /// Whether the section's caps are painted.
    pub caps: bool,
    /// The display mode.
    pub mode: ShadeMode,
    /// Whether hidden lines are drawn dashed (hidden-line mode).
    pub dashed: bool,
    /// Whether a GPU culler's frame splits the surfaces by back faces (the frame keeps within
    /// the four passes a phase that cadr's cullers handle).
    pub split: bool,
}

/// A case of the solid mode without caps or dashes.
const fn solid(name: &'static str, eye: DVec3, target: DVec3, planes: &'static [DVec4]) -> Case {
    Case {
        name,
        eye,
        target,
        planes,
        caps: false,
        mode: ShadeMode::Solid,
        dashed: false,
        split: true,
    }
}

/// The plane that cuts every box through its middle, keeping y <= 0.
const MIDDLE: &[DVec4] = &[DVec4::new(0.0, -1.0, 0.0, 0.0)];

/// The cases: where back faces show in the solid mode, and the edge modes.
pub const CASES: [Case; 8] = [
    solid("outside", DVec3::new(4.0, 5.0, 9.0), DVec3::ZERO, &[]),
    solid(
        "into the open box",
        DVec3::new(3.3, 0.4, 3.0),
        DVec3::new(3.0, 0.0, 0.0),
        &[],
    ),
    solid(
        "inside the closed box",
        DVec3::new(0.2, 0.1, 0.3),
        DVec3::new(-1.0, 0.0, 0.0),
        &[],
    ),
    solid(
        "a cut through every box",
        DVec3::new(2.0, 6.0, 7.0),
        DVec3::new(0.0, 0.0, -1.0),
        MIDDLE,
    ),
    Case {
        mode: ShadeMode::Edges,
        ..solid("edges", DVec3::new(-4.0, 3.0, 8.0), DVec3::ZERO, &[])
    },
    Case {
        mode: ShadeMode::Edges,
        caps: true,
        ..solid(
            "edges, caps painted over the lines of a cut",
            DVec3::new(2.0, 6.0, 7.0),
            DVec3::new(0.0, 0.0, -1.0),
            MIDDLE,
        )
    },
    Case {
        mode: ShadeMode::HiddenLine,
        ..solid("hidden-line", DVec3::new(-4.0, 3.0, 8.0), DVec3::ZERO, &[])
    },
    // Surfaces, dashed hidden lines, hidden silhouettes and visible lines: four passes already.
    Case {
        mode: ShadeMode::HiddenLine,
        dashed: true,
        split: false,
        ..solid(
            "hidden-line, dashed",
            DVec3::new(-4.0, 3.0, 8.0),
            DVec3::ZERO,
            &[],
        )
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
    f.view.techniques_mut().set_dashed_hidden_lines(case.dashed);
    if !case.planes.is_empty() {
        let mut section = Section::none();
        section.set_planes(case.planes).expect("valid planes");
        section.set_caps(case.caps);
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
