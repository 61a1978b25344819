//! MSAA: the colour pass drawn with several samples per pixel smooths edges without changing
//! the picture, in every display mode and through every kind of technique (sampled), with the
//! transparency methods and the GPU cullers' phases; the pick pass stays exact; counts the
//! device does not offer are refused with the ones it does.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::collections::HashSet;
use std::sync::Arc;

use cadr_core::generate::{generate, GeneratorSpec};
use cadr_core::render::pick::PixelRect;
use cadr_core::scene::Scene;
use cadr_core::technique::{Combination, ShadeMode};
use cadr_core::vk::Device;
use cadr_tests::images::{
    assert_matches_reference, compare, ImageDifference, Tolerance, DEFAULT_TOLERANCE,
};
use cadr_tests::{
    all_combinations, scene_wide, test_device, test_device_with_synchronization_checks, SceneView,
};

const SIZE: (u32, u32) = (160, 120);

/// How far an anti-aliased picture may be from the one-sample one, both seen at a quarter of
/// their size (box-filtered, as from afar): the same parts in the same colours. Pixel by pixel
/// they differ along every edge, and the line modes are mostly edges (measured here: means of
/// 0.010 solid to 0.025 X-ray, 0.04 with the exact transparency method, which keeps one
/// fragment per pixel and so does not smooth translucent edges).
const MSAA_AGAINST_ONE_SAMPLE: Tolerance = Tolerance {
    mean: 0.05,
    p99: 0.35,
};

/// The difference of two pictures seen at a quarter of their size.
fn difference_from_afar(a: &image::RgbaImage, b: &image::RgbaImage) -> ImageDifference {
    let (width, height) = (a.width() / 4, a.height() / 4);
    compare(
        &image::imageops::thumbnail(a, width, height),
        &image::imageops::thumbnail(b, width, height),
    )
    .unwrap()
}

/// For one scene drawn with MSAA by two combinations on one device.
const SAME_MSAA_PICTURE: Tolerance = Tolerance {
    mean: 0.01,
    p99: 0.25,
};

/// The demo (or `scene`) in a fitted view.
fn fixture(device: Arc<Device>, scene: &Scene) -> SceneView {
    SceneView::fitted(device, scene, SIZE)
}

/// Two frames, the second read back: replaying techniques draw it from their recording.
fn render(f: &mut SceneView) -> image::RgbaImage {
    f.render();
    f.render()
}

/// The highest MSAA level the device offers.
fn highest_msaa(f: &SceneView) -> u32 {
    f.device.sample_counts().last().copied().unwrap_or(1)
}

fn distinct_colours(image: &image::RgbaImage) -> usize {
    image
        .pixels()
        .map(|p| [p[0], p[1], p[2]])
        .collect::<HashSet<_>>()
        .len()
}

#[test]
fn msaa_smooths_edges_and_keeps_the_picture() {
    let mut f = fixture(test_device(), &generate(&GeneratorSpec::Demo));
    let samples = highest_msaa(&f);
    assert!(
        samples >= 4,
        "the test device offers MSAA (lavapipe has 4x): {:?}",
        f.device.sample_counts()
    );
    for mode in ShadeMode::ALL {
        f.view.techniques_mut().set_shade_mode(mode).unwrap();
        f.view.renderer_mut().set_msaa(1).unwrap();
        let aliased = render(&mut f);
        f.view.renderer_mut().set_msaa(samples).unwrap();
        assert_eq!(f.view.renderer().msaa(), samples);
        let smooth = render(&mut f);
        if mode == ShadeMode::Edges && samples == 4 {
            assert_matches_reference("display_demo_edges_msaa4", &smooth, DEFAULT_TOLERANCE);
        }
        let difference = difference_from_afar(&smooth, &aliased);
        assert!(
            difference.within(MSAA_AGAINST_ONE_SAMPLE),
            "{}: {samples}x is another picture: {difference:?}",
            mode.name()
        );
        // Edges blend the colours either side of them: colours one sample cannot make.
        let (one, many) = (distinct_colours(&aliased), distinct_colours(&smooth));
        assert!(
            many as f64 > 1.3 * one as f64,
            "{}: {many} colours with {samples}x against {one} with one sample",
            mode.name()
        );
    }
    f.assert_no_validation_errors();
}

#[test]
fn sample_counts_the_device_does_not_offer_are_refused_and_drawing_goes_on() {
    let mut f = fixture(test_device(), &generate(&GeneratorSpec::Demo));
    let offered = f.device.sample_counts();
    assert_eq!(offered[0], 1, "one sample is always offered");
    let before = render(&mut f);
    for refused in [0, 3, 128].into_iter().chain(
        [2, 8, 16]
            .into_iter()
            .filter(|count| !offered.contains(count)),
    ) {
        let error = f.view.renderer_mut().set_msaa(refused).unwrap_err();
        let text = error.to_string();
        assert!(
            text.contains(&format!("MSAA {refused}x")) && text.contains("offers 1"),
            "{text}"
        );
        assert_eq!(f.view.renderer().msaa(), 1, "a refusal changes nothing");
    }
    let after = render(&mut f);
    assert_eq!(before, after, "the renderer draws on as before");
    f.assert_no_validation_errors();
}

#[test]
fn picking_stays_exact_with_msaa() {
    let mut f = fixture(test_device(), &generate(&GeneratorSpec::Demo));
    let rect = PixelRect {
        x: 40,
        y: 30,
        width: 80,
        height: 60,
    };
    let pick = |f: &mut SceneView| {
        f.view.sync(&f.graph, &mut f.tree).unwrap();
        f.view
            .pick(&f.tree, &f.camera, rect)
            .unwrap()
            .into_iter()
            .map(|hit| (hit.instance, hit.pixel, hit.depth.to_bits()))
            .collect::<Vec<_>>()
    };
    let one_sample = pick(&mut f);
    assert!(one_sample.len() > 10, "{} hits", one_sample.len());
    let samples = highest_msaa(&f);
    f.view.renderer_mut().set_msaa(samples).unwrap();
    // A frame drawn with MSAA between, as a viewer does.
    render(&mut f);
    assert_eq!(pick(&mut f), one_sample, "the same hits, pixels and depths");
    f.assert_no_validation_errors();
}

/// A sample of the valid combinations (every seventh, and the GPU occlusion culler, whose
/// second phase reads the resolved depth), each mode: the same picture as the built-in
/// combination draws with MSAA.
#[test]
fn every_kind_of_technique_draws_with_msaa_like_the_built_in_one() {
    let mut f = fixture(test_device(), &generate(&GeneratorSpec::Demo));
    let samples = highest_msaa(&f);
    f.view.renderer_mut().set_msaa(samples).unwrap();
    let combinations = all_combinations(f.view.techniques().registry());
    let occlusion = scene_wide("individual-indirect-count", "gpu-occlusion");
    let sample: Vec<Combination> = combinations
        .iter()
        .filter(|c| f.view.techniques().check(c).is_ok())
        .step_by(7)
        .cloned()
        .chain([occlusion])
        .collect();
    let mut checked = HashSet::new();
    let mut refused_mesh_shading = 0;
    for (i, mode) in ShadeMode::ALL.into_iter().enumerate() {
        f.view
            .techniques_mut()
            .select(&Combination::built_in())
            .unwrap();
        f.view.techniques_mut().set_shade_mode(mode).unwrap();
        let reference = render(&mut f);
        // Each mode a share of the sample, the occlusion culler in every one.
        for combination in sample
            .iter()
            .enumerate()
            .filter(|(j, c)| j % 3 == i % 3 || c.culling == "gpu-occlusion")
            .map(|(_, c)| c)
        {
            f.view.techniques_mut().select(combination).unwrap();
            f.view.techniques_mut().set_shade_mode(mode).unwrap();
            if f.view.techniques().mesh_shading() && f.device.adapter().name.starts_with("llvmpipe")
            {
                // llvmpipe draws multisampled mesh-shader triangles in the wrong place: the
                // frame is refused with the reason, and the next one draws again.
                f.tree.update(&mut f.graph);
                let error = f.view.render(&f.graph, &mut f.tree, &f.camera).unwrap_err();
                assert!(
                    error
                        .to_string()
                        .contains("mesh-shader triangles in the wrong place"),
                    "{combination}: {error}"
                );
                refused_mesh_shading += 1;
                continue;
            }
            let image = render(&mut f);
            let difference = compare(&image, &reference).unwrap();
            assert!(
                difference.within(SAME_MSAA_PICTURE),
                "{combination} [{}]: {difference:?}",
                mode.name()
            );
            checked.insert(combination.to_string());
        }
    }
    assert!(checked.len() > 10, "{} combinations checked", checked.len());
    println!("mesh shading refused with MSAA: {refused_mesh_shading} times");
    f.assert_no_validation_errors();
}

/// Translucent parts with MSAA, under the synchronization checks: the methods' targets are
/// multisampled and resolved before the merge reads them.
#[test]
fn both_transparency_methods_draw_xray_with_msaa() {
    let device = test_device_with_synchronization_checks();
    let mut f = fixture(device, &generate(&GeneratorSpec::Demo));
    f.view
        .techniques_mut()
        .set_shade_mode(ShadeMode::XRay)
        .unwrap();
    let samples = highest_msaa(&f);
    for method in ["weighted-blended", "per-pixel-lists"] {
        let combination = Combination {
            transparency: method.into(),
            // Threads record secondary command buffers, which inherit the sample count.
            submission: "groups-threads".into(),
            ..Combination::built_in()
        };
        f.view.techniques_mut().select(&combination).unwrap();
        f.view.renderer_mut().set_msaa(1).unwrap();
        let one_sample = render(&mut f);
        f.view.renderer_mut().set_msaa(samples).unwrap();
        let smooth = render(&mut f);
        let difference = difference_from_afar(&smooth, &one_sample);
        assert!(
            difference.within(MSAA_AGAINST_ONE_SAMPLE),
            "{method}: {difference:?}"
        );
    }
    f.assert_no_validation_errors();
}
