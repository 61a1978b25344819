//! GPU culling (`gpu-frustum`, `gpu-occlusion`): an orbit of several frames draws what no
//! culling draws, frame by frame, with fewer triangles where the frustum cuts or housings hide
//! (parts seen only through gaps included);
//! combinations that cannot draw the GPU's commands are refused with the reason.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::sync::Arc;

use glam::{DMat4, DQuat, DVec3};

use cadr_core::generate::{generate, GeneratorSpec, GeometryBuilder};
use cadr_core::graph::SceneGraph;
use cadr_core::render::{Camera, FrameStats, DEFAULT_DIRECTION};
use cadr_core::scene::{flatten, Aabb, Geometry, Material, MeshRef, Node, Scene};
use cadr_core::technique::{Combination, Techniques};
use cadr_core::tree::SceneTree;
use cadr_core::view::View;
use cadr_tests::images::{compare, SAME_PICTURE};
use cadr_tests::{assert_no_validation_errors, gpu_culled, plugin_registry, test_device};

const SIZE: (u32, u32) = (200, 150);

/// Renders `cameras` with each culling technique in turn through one view; per culler, the
/// images and frame statistics.
fn render_frames(
    source: &Scene,
    cullers: &[&str],
    cameras: &[Camera],
) -> Vec<Vec<(image::RgbaImage, FrameStats)>> {
    let device = test_device();
    let (mut graph, _) = SceneGraph::from_scene(source).unwrap();
    let mut tree = SceneTree::build(&mut graph);
    let registry = plugin_registry(&device);
    let mut view = View::new(&device, Arc::clone(&registry), SIZE.0, SIZE.1).unwrap();
    let results = cullers
        .iter()
        .map(|culler| {
            view.techniques_mut()
                .select(&gpu_culled(&device, culler))
                .unwrap();
            cameras
                .iter()
                .map(|camera| {
                    let stats = view.render(&graph, &mut tree, camera).unwrap();
                    (view.renderer().read_rgba8().unwrap(), stats)
                })
                .collect()
        })
        .collect();
    drop(view);
    assert_no_validation_errors(&device);
    results
}

fn bounds(scene: &Scene) -> Aabb {
    flatten(scene).unwrap().bounds
}

fn aspect() -> f64 {
    f64::from(SIZE.0) / f64::from(SIZE.1)
}

#[test]
fn gpu_culling_follows_an_orbit_frame_by_frame() {
    let scene = generate(&GeneratorSpec::Demo);
    let bounds = bounds(&scene);
    let cameras: Vec<Camera> = (0..6)
        .map(|i| Camera::orbit(&bounds, aspect(), f64::from(i) / 12.0, 1.0))
        .collect();
    let cullers = ["none", "gpu-frustum", "gpu-occlusion"];
    let results = render_frames(&scene, &cullers, &cameras);
    let mut cut = 0;
    for (frame, (reference, all)) in results[0].iter().enumerate() {
        for (index, culler) in cullers.iter().enumerate().skip(1) {
            let (image, stats) = &results[index][frame];
            let difference = compare(image, reference).unwrap();
            assert!(
                difference.within(SAME_PICTURE),
                "{culler}, frame {frame}: {difference:?}"
            );
            assert!(
                stats.triangles <= all.triangles,
                "{culler}, frame {frame}: {} triangles of {}",
                stats.triangles,
                all.triangles
            );
        }
        let (frustum, occlusion) = (&results[1][frame].1, &results[2][frame].1);
        // Occlusion tests the frustum too: it never draws what the frustum culls.
        assert!(occlusion.triangles <= frustum.triangles, "frame {frame}");
        if frustum.triangles < all.triangles * 9 / 10 {
            cut += 1;
        }
    }
    assert!(
        cut >= 3,
        "the orbit is close enough that the frustum cuts ({cut} frames)"
    );
}

/// `still_frames` frames of the fitted view, then three of an orbit close around `bounds`. The
/// first frame knows nothing of the last; from the third on, what was visible is what phase 0
/// draws. Then the camera moves: what comes into view is drawn in the same frame.
fn still_then_orbiting(bounds: &Aabb, still_frames: usize) -> Vec<Camera> {
    let still = Camera::fit(bounds, aspect(), DEFAULT_DIRECTION);
    let orbit = (0..3).map(|i| Camera::orbit(bounds, aspect(), 0.1 + f64::from(i) * 0.05, 1.6));
    std::iter::repeat_n(still, still_frames)
        .chain(orbit)
        .collect()
}

#[test]
fn gpu_occlusion_skips_what_housings_hide() {
    let scene = generate(&GeneratorSpec::Cabinet { cabinets: 12 });
    let cameras = still_then_orbiting(&bounds(&scene), 4);
    for (frame, (occluded, all)) in occluded_frames(&scene, &cameras).into_iter().enumerate() {
        if frame >= 2 {
            assert!(
                occluded * 5 <= all,
                "frame {frame}: {occluded} triangles drawn of {all}"
            );
        }
    }
}

/// A camera 6 units in front of a wall at z = 0, looking at its middle.
fn facing_the_wall() -> Camera {
    Camera::look_at(
        DVec3::new(0.0, 0.0, 6.0),
        DVec3::ZERO,
        45.0,
        aspect(),
        0.1,
        50.0,
    )
}

/// A unit cube around the origin, and its triangles.
fn unit_cube() -> (Geometry, u64) {
    let mut builder = GeometryBuilder::new("unit cube");
    builder.cuboid(DVec3::splat(-0.5), DVec3::splat(0.5), DMat4::IDENTITY);
    let cube = builder.finish();
    let triangles = cube.indices.len() as u64 / 3;
    (cube, triangles)
}

/// A node drawing the scene's first geometry (a unit cube) scaled, turned and moved.
fn placed_cube(name: &str, scale: DVec3, rotation: DQuat, at: DVec3) -> Node {
    let mut node = Node::new(name);
    node.mesh = Some(MeshRef::new(0, vec![0]));
    node.local = DMat4::from_scale_rotation_translation(scale, rotation, at);
    node
}

/// A wall, and behind it a long thin rod lying along it: both are a unit cube placed by a
/// scaling matrix. The rod's sphere reaches far in front of the wall, its box does not. With the
/// parts' and clusters' boxes (plugin ABI 1.20), `gpu-occlusion` and `gpu-clusters` find the rod
/// hidden and draw only the wall, once they know what the last frame showed, and the picture is
/// what no culling draws.
#[test]
fn boxes_find_a_rod_hidden_behind_a_wall_where_spheres_cannot() {
    let (cube, cube_triangles) = unit_cube();
    let placed =
        |name: &str, scale: DVec3, at: DVec3| placed_cube(name, scale, DQuat::IDENTITY, at);
    let mut root = Node::new("wall and rod");
    root.children = vec![1, 2];
    let scene = Scene {
        name: "wall and rod".into(),
        geometries: vec![cube],
        materials: vec![Material::default()],
        nodes: vec![
            root,
            placed("wall", DVec3::new(40.0, 40.0, 0.2), DVec3::ZERO),
            placed("rod", DVec3::new(3.0, 0.1, 0.1), DVec3::new(0.0, 0.0, -0.6)),
        ],
        roots: vec![0],
        ..Scene::default()
    };
    let camera = facing_the_wall();
    assert_box_cullers_draw(&scene, camera, (2, 1), cube_triangles, "only the wall");
}

/// Renders four frames of `scene` from `camera` without culling and with each culler that
/// tests boxes, and checks that every frame draws the same picture, that no culling draws
/// `all` parts of `part_triangles` each, and that the cullers, from the third frame on (once
/// they know what the last one showed), draw `drawn` of them (`what`: which).
fn assert_box_cullers_draw(
    scene: &Scene,
    camera: Camera,
    (all, drawn): (u64, u64),
    part_triangles: u64,
    what: &str,
) {
    let results = render_frames(
        scene,
        &["none", "gpu-occlusion", "gpu-clusters"],
        &[camera; 4],
    );
    for (culler, frames) in ["gpu-occlusion", "gpu-clusters"].iter().zip(&results[1..]) {
        for (frame, ((reference, unculled), (image, culled))) in
            results[0].iter().zip(frames).enumerate()
        {
            assert_eq!(unculled.triangles_rasterized, all * part_triangles);
            let difference = compare(image, reference).unwrap();
            assert!(
                difference.within(SAME_PICTURE),
                "{what}: {culler}, frame {frame}: {difference:?}"
            );
            if frame >= 2 {
                assert_eq!(
                    culled.triangles_rasterized,
                    drawn * part_triangles,
                    "{what}: {culler}, frame {frame}"
                );
            }
        }
    }
}

/// A wall with a small square hole, and behind it a rod lying along the wall's diagonal. The
/// hole off the diagonal lies inside the rod's screen rect but outside its outline: the box
/// tests find the rod hidden (its hull is tested under each texel, not its rect against the
/// farthest depth in it) and draw only the wall. The hole on the diagonal shows the rod, and it
/// is drawn. Either way the picture is what no culling draws.
#[test]
fn a_rod_seen_through_no_hole_in_the_wall_is_found_hidden() {
    let (cube, cube_triangles) = unit_cube();
    // The wall's four pieces around the hole `hole` ± 0.15 (x, y), 0.2 thick at z = 0.
    let wall_piece = |name: &str, min: [f64; 2], max: [f64; 2]| {
        let (min, max) = (
            DVec3::new(min[0], min[1], -0.1),
            DVec3::new(max[0], max[1], 0.1),
        );
        placed_cube(name, max - min, DQuat::IDENTITY, 0.5 * (min + max))
    };
    let camera = facing_the_wall();
    // Through the hole off the diagonal the rod lies more than a unit away; through the one on
    // it, in plain sight.
    for (hole, rod_shows) in [([-0.8, 0.8], false), ([-0.8, -0.8], true)] {
        let (x0, x1, y0, y1) = (
            hole[0] - 0.15,
            hole[0] + 0.15,
            hole[1] - 0.15,
            hole[1] + 0.15,
        );
        let mut root = Node::new("wall and rod");
        root.children = (1..=5).collect();
        let scene = Scene {
            name: "wall with a hole, and a rod".into(),
            geometries: vec![cube.clone()],
            materials: vec![Material::default()],
            nodes: vec![
                root,
                wall_piece("left", [-20.0, -20.0], [x0, 20.0]),
                wall_piece("right", [x1, -20.0], [20.0, 20.0]),
                wall_piece("below", [x0, -20.0], [x1, y0]),
                wall_piece("above", [x0, y1], [x1, 20.0]),
                placed_cube(
                    "rod",
                    DVec3::new(3.0, 0.1, 0.1),
                    DQuat::from_rotation_z(std::f64::consts::FRAC_PI_4),
                    DVec3::new(0.0, 0.0, -0.6),
                ),
            ],
            roots: vec![0],
            ..Scene::default()
        };
        let drawn = if rod_shows { 5 } else { 4 };
        let what = format!("hole at {hole:?}, the rod drawn: {rod_shows}");
        assert_box_cullers_draw(&scene, camera, (5, drawn), cube_triangles, &what);
    }
}

/// Where, along x at depth `z` (world units; the camera looks down -z at x = 0), `camera` puts
/// the pixel edge `pixel` (in pixels from the target's left).
fn x_at_pixel_edge(camera: &Camera, pixel: f64, z: f64) -> f64 {
    let clip = camera.projection * camera.view;
    let pixel_of = |x: f64| {
        let c = clip * DVec3::new(x, 0.0, z).extend(1.0);
        (c.x / c.w * 0.5 + 0.5) * f64::from(SIZE.0)
    };
    let (at_zero, per_unit) = (pixel_of(0.0), pixel_of(1.0) - pixel_of(0.0));
    (pixel - at_zero) / per_unit
}

/// Two tiles with a gap of one pixel between them, and behind the left one a cube four pixels
/// wide whose right edge comes within a pixel of the gap (three quarters of a pixel past the
/// edge between the pixel column it reaches and the gap's). The cube shows no pixel, yet the
/// texel of two pixels that holds its last column also holds the gap's: a depth pyramid whose
/// finest level keeps the farthest depth of 2 × 2 pixels finds it in sight. Its finest level is
/// the depth image itself, so the culler tests the cube pixel by pixel and draws the tiles
/// alone.
#[test]
fn a_small_part_beside_a_one_pixel_gap_is_found_hidden_pixel_by_pixel() {
    let (cube, cube_triangles) = unit_cube();
    let camera = facing_the_wall();
    // Pixel edges on the tiles' front faces (z = 0.1) and on the cube's (z = -0.5): the gap is
    // column 101 (an odd one, sharing a 2-pixel texel with column 100), the cube ends at 100.75.
    let (tile_front, cube_front) = (0.1, -0.5);
    let left_end = x_at_pixel_edge(&camera, 101.0, tile_front);
    let right_start = x_at_pixel_edge(&camera, 102.0, tile_front);
    let cube_end = x_at_pixel_edge(&camera, 100.75, cube_front);
    let cube_start = x_at_pixel_edge(&camera, 96.75, cube_front);
    let placed = |name: &str, min: DVec3, max: DVec3| {
        placed_cube(name, max - min, DQuat::IDENTITY, 0.5 * (min + max))
    };
    let mut root = Node::new("tiles and a cube");
    root.children = vec![1, 2, 3];
    let scene = Scene {
        name: "tiles with a gap, and a cube behind".into(),
        geometries: vec![cube],
        materials: vec![Material::default()],
        nodes: vec![
            root,
            placed(
                "left tile",
                DVec3::new(-3.0, -2.0, -0.1),
                DVec3::new(left_end, 2.0, tile_front),
            ),
            placed(
                "right tile",
                DVec3::new(right_start, -2.0, -0.1),
                DVec3::new(3.0, 2.0, tile_front),
            ),
            placed(
                "cube",
                DVec3::new(cube_start, -0.07, cube_front - 0.2),
                DVec3::new(cube_end, 0.07, cube_front),
            ),
        ],
        roots: vec![0],
        ..Scene::default()
    };
    assert_box_cullers_draw(&scene, camera, (3, 2), cube_triangles, "the tiles alone");
}

/// Renders `cameras` without culling and with `gpu-occlusion`, checks that every frame draws
/// the same picture both ways, and gives each frame's triangles: occlusion's, then all.
fn occluded_frames(scene: &Scene, cameras: &[Camera]) -> Vec<(u64, u64)> {
    let results = render_frames(scene, &["none", "gpu-occlusion"], cameras);
    let mut triangles = Vec::new();
    for (frame, ((reference, all), (image, occluded))) in
        results[0].iter().zip(&results[1]).enumerate()
    {
        let difference = compare(image, reference).unwrap();
        assert!(
            difference.within(SAME_PICTURE),
            "frame {frame}: {difference:?}"
        );
        println!(
            "frame {frame}: {} of {} triangles",
            occluded.triangles, all.triangles
        );
        triangles.push((occluded.triangles, all.triangles));
    }
    triangles
}

/// The grid's parts stand in a cube with gaps between them, so many of the parts behind are
/// seen only through those gaps: the depth-pyramid test must keep every part that shows a
/// pixel, seen in perspective from an orbit and through a host's orthographic projection, and
/// still skip some.
#[test]
fn gpu_occlusion_keeps_what_shows_through_the_gaps_of_a_grid() {
    let scene = generate(&GeneratorSpec::Grid {
        parts: 4000,
        triangles_per_part: 12.0,
    });
    let bounds = bounds(&scene);
    // Each view twice: the first frame has the last view's visibility history, the second its
    // own.
    let mut cameras: Vec<Camera> = (0..3)
        .map(|i| Camera::orbit(&bounds, aspect(), 0.1 + f64::from(i) * 0.13, 2.2))
        .flat_map(|camera| [camera, camera])
        .collect();
    let fitted = Camera::fit(&bounds, aspect(), DEFAULT_DIRECTION);
    let (radius, distance) = (bounds.radius(), fitted.eye().distance(bounds.center()));
    let mut orthographic = DMat4::orthographic_rh(
        -radius * aspect(),
        radius * aspect(),
        -radius,
        radius,
        distance - radius * 1.1,
        distance + radius * 1.1,
    );
    orthographic.y_axis.y *= -1.0;
    let parallel = Camera {
        view: fitted.view,
        projection: orthographic,
    };
    cameras.extend([parallel, parallel]);

    for (frame, (occluded, all)) in occluded_frames(&scene, &cameras).into_iter().enumerate() {
        // Most of the cube shows through its gaps; what is hidden, from a view's second frame
        // on, is skipped.
        if frame % 2 == 1 {
            assert!(
                occluded < all,
                "frame {frame}: {occluded} of {all} triangles"
            );
        }
    }
}

#[test]
fn gpu_cullers_need_a_submission_that_draws_their_commands() {
    let device = test_device();
    let registry = plugin_registry(&device);
    let view = View::new(&device, Arc::clone(&registry), SIZE.0, SIZE.1).unwrap();
    let techniques: &Techniques = view.techniques();
    for culler in ["gpu-frustum", "gpu-occlusion"] {
        techniques.check(&gpu_culled(&device, culler)).unwrap();
        let refusals = [
            (
                Combination {
                    submission: "groups-mdi".into(),
                    ..gpu_culled(&device, culler)
                },
                // The culler is what is refused here: the partners suit each other.
                "draws the GPU-written commands (individual-indirect-count, dgc, individual-mdi)",
            ),
            (
                Combination {
                    vertex: "per-geometry".into(),
                    ..gpu_culled(&device, culler)
                },
                "binds the whole scene",
            ),
            (
                Combination {
                    parameters: "push".into(),
                    ..gpu_culled(&device, culler)
                },
                "instance index",
            ),
        ];
        for (refused, reason) in refusals {
            let why = techniques.check(&refused).unwrap_err();
            assert!(
                why.contains("needs") && why.contains(reason),
                "{refused}: {why}"
            );
        }
    }
}

#[test]
fn sub_pixel_culling_drops_small_parts_only_when_asked() {
    let scene = generate(&GeneratorSpec::Grid {
        parts: 512,
        triangles_per_part: 12.0,
    });
    let bounds = bounds(&scene);
    let far = Camera::fit(&bounds, aspect(), DEFAULT_DIRECTION);
    // An eye inside the first part: its bounding sphere holds the eye.
    let flat = flatten(&scene).unwrap();
    let first = flat.instances[0];
    let part = scene.geometries[first.geometry as usize].bounds();
    let inside = first.world.transform_point3(part.center());
    let radius = bounds.radius();
    let near = Camera::look_at(
        inside,
        inside + glam::DVec3::new(1.0, 0.3, 0.2),
        40.0,
        aspect(),
        radius * 1e-4,
        radius * 3.0,
    );

    let device = test_device();
    let (mut graph, _) = SceneGraph::from_scene(&scene).unwrap();
    let mut tree = SceneTree::build(&mut graph);
    let registry = plugin_registry(&device);
    let mut view = View::new(&device, Arc::clone(&registry), SIZE.0, SIZE.1).unwrap();
    view.techniques_mut()
        .select(&gpu_culled(&device, "none"))
        .unwrap();
    let all = view.render(&graph, &mut tree, &far).unwrap().triangles;
    let reference = view.renderer().read_rgba8().unwrap();
    assert_eq!(view.techniques().min_pixels(), 0.0, "off by default");
    for culler in ["gpu-frustum", "gpu-occlusion"] {
        view.techniques_mut()
            .select(&gpu_culled(&device, culler))
            .unwrap();
        let mut triangles = |view: &mut View, pixels: f32, camera: &Camera| {
            view.techniques_mut().set_min_pixels(pixels).unwrap();
            // Occlusion's first frames draw without a visibility history; the third is settled.
            (0..3)
                .map(|_| view.render(&graph, &mut tree, camera).unwrap().triangles)
                .last()
                .unwrap()
        };
        let unculled = triangles(&mut view, 0.0, &far);
        if culler == "gpu-frustum" {
            // The view holds the whole grid: nothing is outside the frustum.
            assert_eq!(unculled, all, "{culler}: off keeps all");
        } else {
            assert!(
                unculled <= all,
                "{culler}: occlusion alone: {unculled} of {all}"
            );
        }
        let image = view.renderer().read_rgba8().unwrap();
        let difference = compare(&image, &reference).unwrap();
        assert!(difference.within(SAME_PICTURE), "{culler}: {difference:?}");
        let thresholds = [1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0, 1e5];
        let counts: Vec<u64> = thresholds
            .iter()
            .map(|&pixels| triangles(&mut view, pixels, &far))
            .collect();
        println!("{culler}: {all} triangles; at {thresholds:?} pixels: {counts:?}");
        assert!(
            counts.windows(2).all(|pair| pair[1] <= pair[0]),
            "{culler}: a larger threshold never draws more: {counts:?}"
        );
        assert_eq!(
            counts[counts.len() - 1],
            0,
            "{culler}: wider than the view culls all"
        );
        assert!(
            counts.iter().any(|&count| count > 0 && count < unculled),
            "{culler}: near parts outlast far ones at some threshold: {counts:?}"
        );
        // A sphere holding the eye is never too small, whatever the threshold.
        let around_eye = triangles(&mut view, 1e5, &near);
        assert!(around_eye > 0, "{culler}: the part around the eye is kept");
        view.techniques_mut().set_min_pixels(0.0).unwrap();
    }
    assert!(view.techniques_mut().set_min_pixels(-1.0).is_err());
    assert!(view.techniques_mut().set_min_pixels(f32::NAN).is_err());
    drop(view);
    assert_no_validation_errors(&device);
}

#[test]
fn each_pass_of_a_culled_frame_is_timed_and_the_times_make_the_frame() {
    let scene = generate(&GeneratorSpec::Grid {
        parts: 300,
        triangles_per_part: 12.0,
    });
    let camera = Camera::fit(&bounds(&scene), aspect(), DEFAULT_DIRECTION);
    let device = test_device();
    let (mut graph, _) = SceneGraph::from_scene(&scene).unwrap();
    let mut tree = SceneTree::build(&mut graph);
    let registry = plugin_registry(&device);
    let mut view = View::new(&device, Arc::clone(&registry), SIZE.0, SIZE.1).unwrap();
    for (culler, passes) in [
        (
            "none",
            &[
                "prepare and cull",
                "surfaces phase 0",
                "background",
                "techniques after the passes",
            ][..],
        ),
        (
            "gpu-occlusion",
            &[
                "prepare and cull",
                "surfaces phase 0",
                "cull phase 1",
                "surfaces phase 1",
                "background",
                "techniques after the passes",
            ][..],
        ),
    ] {
        view.techniques_mut()
            .select(&gpu_culled(&device, culler))
            .unwrap();
        // The first frame uploads the scene; the third replays the second's recording.
        for frame in 0..3 {
            let stats = view.render(&graph, &mut tree, &camera).unwrap();
            let times = view.renderer().gpu_pass_times();
            let names: Vec<&str> = times.iter().map(|(name, _)| *name).collect();
            let drawn = if names.first() == Some(&"uploads") {
                &names[1..]
            } else {
                &names[..]
            };
            assert_eq!(drawn, passes, "{culler}, frame {frame}");
            assert!(
                times.iter().all(|(_, us)| *us >= 0.0),
                "{culler}, frame {frame}: {times:?}"
            );
            let sum: f64 = times.iter().map(|(_, us)| us).sum();
            let frame_us = stats.gpu_us.unwrap();
            assert!(
                (sum - frame_us).abs() <= 1e-6 * frame_us + 0.01,
                "{culler}, frame {frame}: {sum} µs in the passes, {frame_us} µs in all"
            );
            assert_eq!(stats.replayed, frame == 2, "{culler}, frame {frame}");
        }
    }
    drop(view);
    assert_no_validation_errors(&device);
}
