//! The bindless texture path (descriptor indexing: each texture an image of its own size in a
//! table the shaders index by slot) against the texture array every device has. Both run on
//! SwiftShader, the tests' driver with descriptor indexing; lavapipe has none, so the rest of
//! the suite draws through the array. This test binary points the Vulkan loader at SwiftShader
//! alone (`cadr_tests::swiftshader_device`).
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::collections::HashSet;
use std::sync::Arc;

use cadr_core::gpu_scene::MAX_LAYER_SIZE;
use cadr_core::load::load_file;
use cadr_core::render::Camera;
use cadr_core::scene::{Material, Scene, Texture, TextureRef, UvTransform};
use cadr_core::technique::{Combination, ShadeMode};
use cadr_core::vk::Device;
use cadr_tests::fixtures::{give_texture, quad_scene, scratch_dir, textured, textured_gltf};
use cadr_tests::images::{color_at, compare, SAME_PICTURE};
use cadr_tests::{all_combinations, swiftshader_device, SceneView};
use glam::DVec3;

const SIZE: (u32, u32) = (480, 480);

/// The scene seen straight on, fitted.
fn front_view(device: Arc<Device>, scene: &Scene) -> SceneView {
    let bounds = cadr_core::scene::flatten(scene).unwrap().bounds;
    let camera = Camera::fit(&bounds, 1.0, DVec3::Z);
    SceneView::new(device, scene, SIZE, camera)
}

/// The textured fixture (a repeated nearest-magnified checker, an alpha mask, vertex colours,
/// a translucent texture) draws alike through the table and through the array, solid and in
/// X-ray (the translucent pass samples textures too), and a click goes through the mask's
/// hole on both.
#[test]
fn the_bindless_path_draws_textures_as_the_array_does() {
    let dir = scratch_dir("bindless_fixture");
    let scene = load_file(&textured_gltf(&dir)).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    let half = textured::QUAD_SIZE / 2.0;
    let mut pictures = Vec::new();
    for texture_array_only in [false, true] {
        let device = swiftshader_device(texture_array_only);
        let bindless = device.capabilities().bindless_textures;
        assert_eq!(
            bindless > 0,
            !texture_array_only,
            "SwiftShader binds {bindless} textures"
        );
        let mut f = front_view(device, &scene);
        let solid = f.render();
        let (x, y) = textured::MASKED;
        let hole = DVec3::new(x - half / 2.0, y, 0.0);
        let kept = DVec3::new(x + half / 2.0, y, 0.0);
        assert_eq!(f.material_picked_at(hole), "backdrop");
        assert_eq!(f.material_picked_at(kept), "masked");
        f.view
            .techniques_mut()
            .set_shade_mode(ShadeMode::XRay)
            .unwrap();
        let xray = f.render();
        pictures.push((solid, xray));
        f.assert_no_validation_errors();
    }
    let [(bindless_solid, bindless_xray), (array_solid, array_xray)] = &pictures[..] else {
        unreachable!("two paths")
    };
    // The fixture's textures are small enough that the array keeps their texels: the same
    // picture (they were identical to the bit on SwiftShader 153).
    for (name, bindless, array) in [
        ("solid", bindless_solid, array_solid),
        ("X-ray", bindless_xray, array_xray),
    ] {
        let difference = compare(bindless, array).unwrap();
        assert!(
            difference.within(SAME_PICTURE),
            "{name}: the table and the array differ by {difference:?}"
        );
    }
    // And the textures are there: the checker's cells alternate.
    let camera = Camera::fit(
        &cadr_core::scene::flatten(&scene).unwrap().bounds,
        1.0,
        DVec3::Z,
    );
    let cell = textured::QUAD_SIZE / 16.0;
    let (x, y) = textured::CHECKER;
    let cell_center = |i: f64| DVec3::new(x - half + cell * (i + 0.5), y - half + cell * 0.5, 0.0);
    let (a, b) = (
        color_at(bindless_solid, &camera, cell_center(4.0)),
        color_at(bindless_solid, &camera, cell_center(5.0)),
    );
    let brightness = |c: [f32; 3]| c.iter().sum::<f32>() / 3.0;
    assert!(
        (brightness(a) - brightness(b)).abs() > 0.4,
        "checker cells {a:?} and {b:?}"
    );
}

/// Texels of the striped texture: `width` × 4, columns alternating black and white.
fn stripes(width: u32) -> Texture {
    let texels: Vec<u8> = (0..4)
        .flat_map(|_| {
            (0..width).flat_map(|x| {
                let value = if x % 2 == 0 { 0 } else { 255 };
                [value, value, value, 255]
            })
        })
        .collect();
    Texture {
        name: "stripes".into(),
        width,
        height: 4,
        texels: Arc::new(texels),
        sampler: cadr_core::scene::Sampler {
            magnify_nearest: true,
            ..Default::default()
        },
    }
}

/// A 2 × 2 quad textured with `texture`, showing the first `fraction` of it across.
fn striped_quad(texture: Texture, fraction: f32) -> Scene {
    let striped = Material {
        name: "striped".into(),
        base_color: [1.0; 4],
        base_color_texture: Some(TextureRef {
            texture: 0,
            transform: UvTransform::IDENTITY,
        }),
        ..Material::default()
    };
    quad_scene(striped, vec![texture], fraction)
}

/// The brightest and darkest pixel along the middle row of the quad's picture.
fn row_range(image: &image::RgbaImage) -> (f32, f32) {
    let y = image.height() / 2;
    let margin = image.width() / 4;
    let values: Vec<f32> = (margin..image.width() - margin)
        .map(|x| {
            let p = image.get_pixel(x, y).0;
            f32::from(p[0]) / 255.0
        })
        .collect();
    let darkest = values.iter().copied().fold(f32::MAX, f32::min);
    let brightest = values.iter().copied().fold(f32::MIN, f32::max);
    (darkest, brightest)
}

/// A texture wider than the array's layers keeps its every texel in the table: one-texel
/// stripes of a 4096-texel-wide texture, magnified, stay black and white, where the array
/// (its layers at most `MAX_LAYER_SIZE` wide) averages them to grey.
#[test]
fn a_texture_wider_than_the_arrays_layers_keeps_its_texels() {
    let width = MAX_LAYER_SIZE * 4;
    // 128 texels across the quad: about 3 pixels a texel.
    let scene = striped_quad(stripes(width), 128.0 / width as f32);
    let mut ranges = Vec::new();
    for texture_array_only in [false, true] {
        let mut f = front_view(swiftshader_device(texture_array_only), &scene);
        let image = f.render();
        ranges.push(row_range(&image));
        f.assert_no_validation_errors();
    }
    let [(table_dark, table_bright), (array_dark, array_bright)] = ranges[..] else {
        unreachable!("two paths")
    };
    assert!(
        table_dark < 0.25 && table_bright > 0.75,
        "the table's stripes run from {table_dark} to {table_bright}"
    );
    assert!(
        array_bright - array_dark < 0.3,
        "the array's stripes run from {array_dark} to {array_bright}: not averaged?"
    );
}

/// A texture added at run time is the only one uploaded with the table (the others keep their
/// images), where the array uploads every texture again; both draw it.
#[test]
fn a_new_texture_uploads_only_itself_into_the_table() {
    let scene = striped_quad(stripes(256), 1.0);
    let mut uploaded = Vec::new();
    for texture_array_only in [false, true] {
        let mut f = front_view(swiftshader_device(texture_array_only), &scene);
        f.render();
        let green = Texture {
            name: "green".into(),
            width: 2,
            height: 2,
            texels: Arc::new([0u8, 200, 0, 255].repeat(4)),
            sampler: Default::default(),
        };
        let texture = f.graph.create_texture(green).unwrap();
        give_texture(&mut f.graph, 0, texture);
        let image = f.render();
        let center = color_at(&image, &f.camera, DVec3::ZERO);
        assert!(
            center[1] > center[0] + 0.3 && center[1] > center[2] + 0.3,
            "green: {center:?}"
        );
        uploaded.push(f.view.scene().unwrap().last_upload().texture_bytes);
        f.assert_no_validation_errors();
    }
    // The table: the 2 × 2 texture and its 1 × 1 mip. The array: both textures again, as
    // two 256 × 256 layers with their mips.
    let layer_bytes: u64 = (0..=8u64).map(|m| (256u64 >> m).pow(2) * 4).sum();
    assert_eq!(uploaded, [(4 + 1) * 4, 2 * layer_bytes]);
}

/// A texture after an emptied slot keeps its place in the table: the first texture is
/// destroyed, and the quad still shows the second.
#[test]
fn a_texture_after_an_emptied_slot_keeps_its_place() {
    let mut scene = striped_quad(stripes(8), 1.0);
    scene.textures.push(Texture {
        name: "green".into(),
        width: 2,
        height: 2,
        texels: Arc::new([0u8, 200, 0, 255].repeat(4)),
        sampler: Default::default(),
    });
    if let Some(reference) = &mut scene.materials[0].base_color_texture {
        reference.texture = 1;
    }
    let mut f = front_view(swiftshader_device(false), &scene);
    let first = f.graph.texture_handle_at(0).unwrap();
    f.graph.destroy_texture(first).unwrap();
    let image = f.render();
    let center = color_at(&image, &f.camera, DVec3::ZERO);
    assert!(
        center[1] > center[0] + 0.3 && center[1] > center[2] + 0.3,
        "green: {center:?}"
    );
    f.assert_no_validation_errors();
}

/// Every vertex and parameter path (each hands the shared shaders the material, and so the
/// texture slot, its own way) samples the table like the built-in combination.
#[test]
fn every_vertex_and_parameter_path_samples_the_table_alike() {
    let dir = scratch_dir("bindless_paths");
    let scene = load_file(&textured_gltf(&dir)).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    let mut f = front_view(swiftshader_device(false), &scene);
    let reference = f.render();
    let built_in = Combination::built_in();
    let valid: Vec<Combination> = all_combinations(f.view.techniques().registry())
        .into_iter()
        .filter(|c| c.submission == built_in.submission && c.culling == built_in.culling)
        .filter(|c| f.view.techniques().check(c).is_ok())
        .collect();
    let mut parameter_paths = HashSet::new();
    for combination in &valid {
        f.view.techniques_mut().select(combination).unwrap();
        let difference = compare(&f.render(), &reference).unwrap();
        assert!(
            difference.within(SAME_PICTURE),
            "{combination}: {difference:?}"
        );
        parameter_paths.insert(combination.parameters.clone());
    }
    assert!(
        parameter_paths.len() >= 3,
        "parameter paths checked: {parameter_paths:?}"
    );
    f.assert_no_validation_errors();
}
