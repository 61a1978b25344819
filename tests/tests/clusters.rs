//! Cluster culling and level of detail (`gpu-clusters`): at full detail it draws the picture
//! per-part culling draws with at most half the triangles on curved parts (the back faces of
//! closed parts go, and the clusters hidden behind what was visible last frame); at the
//! default threshold the picture stays within FLIP 0.02 of full detail while the triangles
//! drawn follow the pixels covered, far faceted parts are drawn as their proxies, and no part
//! ever vanishes for being far.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::sync::Arc;

use cadr_core::generate::{generate, GeneratorSpec};
use cadr_core::graph::SceneGraph;
use cadr_core::render::pick::PixelRect;
use cadr_core::render::{Camera, FrameStats, DEFAULT_DIRECTION};
use cadr_core::scene::{flatten, Aabb, Scene};
use cadr_core::technique::ShadeMode;
use cadr_core::tree::SceneTree;
use cadr_core::view::View;
use cadr_core::vk::Device;
use cadr_tests::images::{compare, is_background, SAME_PICTURE};
use cadr_tests::{assert_no_validation_errors, gpu_culled, plugin_registry, test_device};

const SIZE: (u32, u32) = (240, 180);

fn aspect() -> f64 {
    f64::from(SIZE.0) / f64::from(SIZE.1)
}

fn bounds(scene: &Scene) -> Aabb {
    flatten(scene).unwrap().bounds
}

/// One view of `scene`, drawing with `culler` (scene-wide techniques).
struct Drawing {
    view: View,
    graph: SceneGraph,
    tree: SceneTree,
}

impl Drawing {
    fn new(device: &Arc<Device>, scene: &Scene) -> Self {
        let (mut graph, _) = SceneGraph::from_scene(scene).unwrap();
        let tree = SceneTree::build(&mut graph);
        let registry = plugin_registry(device);
        let view = View::new(device, registry, SIZE.0, SIZE.1).unwrap();
        Self { view, graph, tree }
    }

    /// Draws `camera` four times with `culler` at `lod_error`, each frame recorded (occlusion's
    /// history settles from the third), and returns the last picture and its statistics.
    fn draw(
        &mut self,
        culler: &str,
        lod_error: f32,
        camera: &Camera,
    ) -> (image::RgbaImage, FrameStats) {
        self.choose(culler, lod_error);
        self.view.techniques_mut().set_frame_replay(false);
        let mut stats = None;
        for _ in 0..4 {
            stats = Some(
                self.view
                    .render(&self.graph, &mut self.tree, camera)
                    .unwrap(),
            );
        }
        (self.view.renderer().read_rgba8().unwrap(), stats.unwrap())
    }

    fn choose(&mut self, culler: &str, lod_error: f32) {
        let combination = gpu_culled(self.view.renderer().device(), culler);
        self.view.techniques_mut().select(&combination).unwrap();
        self.view.techniques_mut().set_lod_error(lod_error).unwrap();
    }

    /// The instance picked at pixel (`x`, `y`), if any.
    fn pick(&mut self, camera: &Camera, (x, y): (u32, u32)) -> Option<u32> {
        self.view.sync(&self.graph, &mut self.tree).unwrap();
        let hits = self
            .view
            .pick(&self.tree, camera, PixelRect::pixel(x, y))
            .unwrap();
        hits.first().map(|hit| hit.instance)
    }
}

fn fine(units: u32, detail: u32) -> Scene {
    generate(&GeneratorSpec::Fine {
        units,
        detail,
        unique: false,
    })
}

#[test]
fn at_full_detail_clusters_draw_the_per_part_picture_without_back_faces() {
    let device = test_device();
    for scene in [fine(4, 2), generate(&GeneratorSpec::Demo)] {
        let bounds = bounds(&scene);
        let mut drawing = Drawing::new(&device, &scene);
        let (mut per_part, mut in_clusters, mut fewer) = (0, 0, 0);
        for turn in 0..4 {
            let camera = Camera::orbit(&bounds, aspect(), f64::from(turn) / 8.0, 1.4);
            let (reference, parts) = drawing.draw("gpu-occlusion", 0.0, &camera);
            let (image, clusters) = drawing.draw("gpu-clusters", 0.0, &camera);
            let difference = compare(&image, &reference).unwrap();
            assert!(
                difference.within(SAME_PICTURE),
                "{}, turn {turn}: {difference:?}",
                scene.name
            );
            println!(
                "{}, turn {turn}: {} triangles per part, {} in clusters ({} clusters)",
                scene.name, parts.triangles, clusters.triangles, clusters.draws
            );
            assert!(clusters.triangles <= parts.triangles, "{}", scene.name);
            per_part += parts.triangles;
            in_clusters += clusters.triangles;
            if clusters.triangles * 8 <= parts.triangles * 5 {
                fewer += 1;
            }
        }
        if scene.name.starts_with("fine") {
            // Closed curved parts: their far sides face away, and the clusters a part hides of
            // itself or of its neighbours (a bolt's shank under the flange) are occluded.
            assert!(
                in_clusters * 2 <= per_part,
                "clusters draw at most half the triangles: {in_clusters} of {per_part}"
            );
            assert_eq!(fewer, 4, "clusters draw under 5/8 of them in every frame");
        }
    }
    assert_no_validation_errors(&device);
}

#[test]
fn every_display_mode_draws_its_per_part_picture_with_clusters_at_full_detail() {
    // Back faces go only in passes that hide them: the translucent surfaces of X-ray, the
    // silhouettes and the section caps keep theirs.
    let device = test_device();
    let scene = fine(2, 1);
    let bounds = bounds(&scene);
    let camera = Camera::orbit(&bounds, aspect(), 0.15, 1.3);
    let mut drawing = Drawing::new(&device, &scene);
    let mut section = cadr_core::render::Section::none();
    section
        .set_planes(&[glam::DVec4::new(1.0, 0.0, 0.0, -bounds.center().x)])
        .unwrap();
    for cut in [false, true] {
        if cut {
            drawing.view.set_section(section.clone());
        }
        for mode in ShadeMode::ALL {
            drawing.view.techniques_mut().set_shade_mode(mode).unwrap();
            let (reference, _) = drawing.draw("gpu-occlusion", 0.0, &camera);
            drawing.view.techniques_mut().set_shade_mode(mode).unwrap();
            let (image, _) = drawing.draw("gpu-clusters", 0.0, &camera);
            let difference = compare(&image, &reference).unwrap();
            if !difference.within(SAME_PICTURE) {
                image
                    .save(format!("/tmp/w/dbg-{}-{cut}-clusters.png", mode.name()))
                    .unwrap();
                reference
                    .save(format!("/tmp/w/dbg-{}-{cut}-parts.png", mode.name()))
                    .unwrap();
            }
            assert!(
                difference.within(SAME_PICTURE),
                "{} (cut {cut}): {difference:?}",
                mode.name()
            );
        }
    }
    drop(drawing);
    assert_no_validation_errors(&device);
}

#[test]
fn picking_finds_the_part_drawn_at_every_pixel_of_a_grid() {
    let device = test_device();
    let scene = fine(1, 2);
    let bounds = bounds(&scene);
    let camera = Camera::fit(&bounds, aspect(), DEFAULT_DIRECTION);
    let mut drawing = Drawing::new(&device, &scene);
    // Over the middle of the view, where the unit is.
    let grid: Vec<(u32, u32)> = (0..10)
        .flat_map(|i| {
            (0..7).map(move |j| (SIZE.0 / 4 + i * SIZE.0 / 20, SIZE.1 / 4 + j * SIZE.1 / 14))
        })
        .collect();
    drawing.choose("gpu-clusters", 0.0);
    // Pixels inside a part at full detail: the part there is also the part two pixels away
    // on every side (a simplified outline may move by the threshold, a pixel).
    let mut inside: Vec<((u32, u32), Option<u32>)> = Vec::new();
    for &(x, y) in &grid {
        let part = drawing.pick(&camera, (x, y));
        if part.is_none() {
            continue;
        }
        let around = [(x - 2, y), (x + 2, y), (x, y - 2), (x, y + 2)];
        if around
            .iter()
            .all(|&pixel| drawing.pick(&camera, pixel) == part)
        {
            inside.push(((x, y), part));
        }
    }
    let parts: std::collections::HashSet<_> = inside.iter().map(|(_, part)| part).collect();
    assert!(
        inside.len() >= 12 && parts.len() >= 4,
        "the grid crosses parts: {inside:?}"
    );
    drawing.choose("gpu-clusters", 1.0);
    for &(pixel, part) in &inside {
        assert_eq!(drawing.pick(&camera, pixel), part, "pixel {pixel:?}");
    }
    drop(drawing);
    assert_no_validation_errors(&device);
}

/// Far faceted parts (gen:grid's prisms of 400 triangles, every vertex on a crease, which the
/// simplification keeps) are drawn as their stand-ins, tens of triangles each instead of
/// hundreds: no part goes missing and the picture stays close to full detail.
#[test]
fn far_faceted_parts_are_drawn_as_their_stand_ins_and_none_goes_missing() {
    let device = test_device();
    let scene = generate(&GeneratorSpec::parse("grid:parts=8000,tris=400").unwrap());
    let parts = flatten(&scene).unwrap().instances.len() as u64;
    let mut drawing = Drawing::new(&device, &scene);
    // Seen from 16 times the scene's radius, every part is a pixel or two across; from 4
    // times, a few pixels: the coarser stand-ins, then the finer ones.
    for (distance, fewer) in [(16.0, 20), (4.0, 15)] {
        let far = Camera::orbit(&bounds(&scene), aspect(), 0.1, distance);
        let (full, full_stats) = drawing.draw("gpu-clusters", 0.0, &far);
        let (lod, lod_stats) = drawing.draw("gpu-clusters", 1.0, &far);
        let difference = compare(&lod, &full).unwrap();
        let (covered_full, covered) = (
            cadr_tests::images::covered_fraction(&full),
            cadr_tests::images::covered_fraction(&lod),
        );
        println!(
            "distance {distance}: full detail {} triangles, at 1 px {} triangles in {} clusters for {parts} parts; covered {covered_full} and {covered}: {difference:?}",
            full_stats.triangles, lod_stats.triangles, lod_stats.draws
        );
        assert!(
            lod_stats.triangles * fewer <= full_stats.triangles,
            "distance {distance}: {} of {} triangles at 1 px",
            lod_stats.triangles,
            full_stats.triangles
        );
        assert!(
            (covered - covered_full).abs() < 0.01,
            "distance {distance}: no part goes missing: {covered} of the picture covered against {covered_full}"
        );
        assert!(
            difference.mean <= 0.03,
            "distance {distance}: FLIP at 1 px: {difference:?}"
        );
    }
    drop(drawing);
    assert_no_validation_errors(&device);
}

#[test]
fn level_of_detail_follows_the_pixels_and_keeps_the_picture() {
    let device = test_device();
    let scene = fine(4, 4);
    let parts = flatten(&scene).unwrap().instances.len() as u64;
    let bounds = bounds(&scene);
    let mut drawing = Drawing::new(&device, &scene);
    let near = Camera::fit(&bounds, aspect(), DEFAULT_DIRECTION);
    let (full, full_stats) = drawing.draw("gpu-clusters", 0.0, &near);
    let (lod, lod_stats) = drawing.draw("gpu-clusters", 1.0, &near);
    let difference = compare(&lod, &full).unwrap();
    println!(
        "full detail {} triangles, at 1 px {} triangles: {difference:?}",
        full_stats.triangles, lod_stats.triangles
    );
    assert!(difference.mean <= 0.02, "FLIP at 1 px: {difference:?}");
    assert!(
        lod_stats.triangles * 4 <= full_stats.triangles,
        "{} of {} triangles at 1 px",
        lod_stats.triangles,
        full_stats.triangles
    );
    // Coarser thresholds never draw more; far away, less; never nothing of a part.
    let counts: Vec<u64> = [0.5, 1.0, 2.0, 8.0, 1e6]
        .iter()
        .map(|&pixels| drawing.draw("gpu-clusters", pixels, &near).1.triangles)
        .collect();
    assert!(
        counts.windows(2).all(|pair| pair[1] <= pair[0]),
        "thresholds 0.5 to 1e6 px: {counts:?}"
    );
    let far = Camera::orbit(&bounds, aspect(), 0.1, 6.0);
    let (_, far_stats) = drawing.draw("gpu-clusters", 1.0, &far);
    assert!(
        far_stats.triangles < lod_stats.triangles,
        "far {} triangles, near {}",
        far_stats.triangles,
        lod_stats.triangles
    );
    // Every part in sight keeps a cluster. Four of the 76 parts are hidden from this view (the
    // per-part occlusion culler draws 72 at full detail); a hidden part's coarsest cluster may
    // be hidden too (on SwiftShader at this size, one is), so the parts that count are those the
    // occlusion culler finds visible.
    let (_, in_sight) = drawing.draw("gpu-occlusion", 0.0, &near);
    assert!(
        in_sight.draws * 10 >= parts * 9,
        "{} of {parts} parts in sight",
        in_sight.draws
    );
    let (_, coarsest) = drawing.draw("gpu-clusters", 1e6, &near);
    assert!(
        coarsest.draws >= in_sight.draws,
        "every part in sight keeps a cluster: {} clusters for {} parts in sight",
        coarsest.draws,
        in_sight.draws
    );
    assert!(drawing.view.techniques_mut().set_lod_error(-1.0).is_err());
    assert!(drawing
        .view
        .techniques_mut()
        .set_lod_error(f32::NAN)
        .is_err());
    drop(drawing);
    assert_no_validation_errors(&device);
}

/// The pixels where `edges` (a picture with edge lines) differs from `solid` (the same view
/// without them): where the lines are.
fn line_pixels(edges: &image::RgbaImage, solid: &image::RgbaImage) -> usize {
    edges
        .pixels()
        .zip(solid.pixels())
        .filter(|(a, b)| a.0.iter().zip(b.0).any(|(&x, y)| x.abs_diff(y) > 24))
        .count()
}

/// The dark pixels of an X-ray picture: its edge lines (its surfaces are light and
/// translucent, and hide no line).
fn dark_pixels(xray: &image::RgbaImage) -> usize {
    xray.pixels()
        .filter(|p| p.0[..3].iter().all(|&c| c < 70))
        .count()
}

#[test]
fn far_parts_edges_are_drawn_from_their_coarser_levels_and_keep_the_picture() {
    let device = test_device();
    let scene = fine(4, 4);
    let bounds = bounds(&scene);
    let camera = Camera::fit(&bounds, aspect(), DEFAULT_DIRECTION);
    let mut drawing = Drawing::new(&device, &scene);
    drawing.view.renderer_mut().set_silhouettes(false).unwrap();
    let mut draw = |mode: ShadeMode, lod_error: f32| {
        drawing.view.techniques_mut().set_shade_mode(mode).unwrap();
        drawing.draw("gpu-clusters", lod_error, &camera).0
    };
    let full = draw(ShadeMode::Edges, 0.0);
    let full_lines = line_pixels(&full, &draw(ShadeMode::Solid, 0.0));
    let default = draw(ShadeMode::Edges, 1.0);
    let default_lines = line_pixels(&default, &draw(ShadeMode::Solid, 1.0));
    let difference = compare(&default, &full).unwrap();
    let xray_full = dark_pixels(&draw(ShadeMode::XRay, 0.0));
    let xray_coarsest = dark_pixels(&draw(ShadeMode::XRay, 1e6));
    println!(
        "line pixels: full detail {full_lines}, at 1 px {default_lines}; FLIP at 1 px \
         {difference:?}; X-ray's dark pixels: full detail {xray_full}, past every error \
         {xray_coarsest}"
    );
    // At the default threshold the edges look as they do whole: about as many pixels, and a
    // FLIP near what the surfaces' level of detail alone costs a picture of thin lines (0.022
    // on Mesa 25 lavapipe; through the command line, with silhouettes on, 0.021 before the
    // edges had levels).
    assert!(difference.mean <= 0.03, "FLIP at 1 px: {difference:?}");
    assert!(
        default_lines * 20 >= full_lines * 17 && default_lines * 20 <= full_lines * 23,
        "line pixels at 1 px {default_lines} against {full_lines}"
    );
    // Past every error each part's edges are their coarsest level (a bore's circle a line
    // across it): X-ray, whose surfaces hide no line, shows fewer line pixels (0.70 of full
    // detail's), where the edges drawn whole over the coarsest surfaces showed more (1.42).
    assert!(
        xray_coarsest * 10 <= xray_full * 9,
        "X-ray's line pixels past every error {xray_coarsest} against {xray_full}"
    );
    drop(drawing);
    assert_no_validation_errors(&device);
}

#[test]
fn a_real_cad_model_keeps_its_picture_at_the_default_threshold() {
    let device = test_device();
    let scene =
        cadr_core::load::load_file(std::path::Path::new(cadr_tests::CYLINDER_ENGINE_GLB)).unwrap();
    let bounds = bounds(&scene);
    let mut drawing = Drawing::new(&device, &scene);
    for turn in [0.0, 0.3] {
        let camera = Camera::orbit(&bounds, aspect(), turn, 1.6);
        let (full, full_stats) = drawing.draw("gpu-clusters", 0.0, &camera);
        let (lod, lod_stats) = drawing.draw("gpu-clusters", 1.0, &camera);
        let difference = compare(&lod, &full).unwrap();
        println!(
            "turn {turn}: {} of {} triangles at 1 px: {difference:?}",
            lod_stats.triangles, full_stats.triangles
        );
        assert!(difference.mean <= 0.02, "turn {turn}: {difference:?}");
        assert!(lod_stats.triangles < full_stats.triangles, "turn {turn}");
    }
    drop(drawing);
    assert_no_validation_errors(&device);
}

#[test]
fn where_the_cut_switches_levels_no_crack_shows_the_background() {
    // Seen close and at a slant, the near clusters of a part are fine and the far ones coarse:
    // groups simplified with their borders locked meet without gaps, so no pixel farther
    // inside a part's full-detail outline than the threshold shows the background (the
    // outline itself may move by the threshold).
    let device = test_device();
    let scene = fine(1, 6);
    let bounds = bounds(&scene);
    let mut drawing = Drawing::new(&device, &scene);
    let camera = Camera::orbit(&bounds, aspect(), 0.05, 0.7);
    let (full, full_stats) = drawing.draw("gpu-clusters", 0.0, &camera);
    // Covered pixels of the full-detail picture, summed over every rectangle from the origin.
    let (w, h) = (SIZE.0 as usize, SIZE.1 as usize);
    let mut sums = vec![0u32; (w + 1) * (h + 1)];
    for y in 0..h {
        for x in 0..w {
            let covered = u32::from(!is_background(&full, x as u32, y as u32));
            sums[(y + 1) * (w + 1) + x + 1] =
                covered + sums[y * (w + 1) + x + 1] + sums[(y + 1) * (w + 1) + x]
                    - sums[y * (w + 1) + x];
        }
    }
    // Pixels whose every neighbour within `d` is covered at full detail.
    let inside = |d: usize| -> Vec<(u32, u32)> {
        let mut pixels = Vec::new();
        for y in d..h.saturating_sub(d) {
            for x in d..w.saturating_sub(d) {
                let (x0, y0, x1, y1) = (x - d, y - d, x + d + 1, y + d + 1);
                let covered = sums[y1 * (w + 1) + x1] + sums[y0 * (w + 1) + x0]
                    - sums[y0 * (w + 1) + x1]
                    - sums[y1 * (w + 1) + x0];
                if covered as usize == (2 * d + 1) * (2 * d + 1) {
                    pixels.push((x as u32, y as u32));
                }
            }
        }
        pixels
    };
    let mut triangles = vec![full_stats.triangles];
    for pixels in [1.0f32, 4.0, 16.0] {
        let (image, stats) = drawing.draw("gpu-clusters", pixels, &camera);
        triangles.push(stats.triangles);
        let inner = inside(pixels.ceil() as usize + 1);
        assert!(
            inner.len() > 3_000,
            "{pixels} px: {} pixels inside",
            inner.len()
        );
        let holes: Vec<_> = inner
            .iter()
            .filter(|&&(x, y)| is_background(&image, x, y))
            .collect();
        assert!(
            holes.is_empty(),
            "{pixels} px: background at {:?}",
            &holes[..holes.len().min(10)]
        );
    }
    assert!(
        triangles.windows(2).all(|pair| pair[1] < pair[0]),
        "each threshold draws a coarser cut: {triangles:?}"
    );
    drop(drawing);
    assert_no_validation_errors(&device);
}
