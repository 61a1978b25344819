//! Every shader compiles and validates; the Rust mirrors of shader structs match their layout.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use cadr_core::render::{
    DrawIndices, DrawParameters, FrameUniforms, GpuScene, MaterialParameters, MatrixUpdate,
    Renderer,
};
use cadr_core::shaders::{ALL, INCLUDES, TEMPLATES};
use cadr_core::vk::{compile_glsl, ShaderStage, VkError};
use cadr_tests::{assert_no_validation_errors, test_device};

#[test]
fn shaders_compile_and_validate() {
    for shader in ALL {
        let words = compile_glsl(shader.name, shader.source, shader.stage, INCLUDES)
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            words.first(),
            Some(&0x0723_0203),
            "{} is SPIR-V",
            shader.name
        );
        assert_eq!(ShaderStage::from_file_name(shader.name), Some(shader.stage));
    }
    // Creating the pipelines runs the layer's SPIR-V validation and interface checks.
    let device = test_device();
    let scene = cadr_core::scene::Scene::default();
    let gpu_scene = GpuScene::upload(&device, &scene).expect("upload");
    let renderer = Renderer::new(&device, 8, 8).expect("renderer");
    let pipelines = renderer.pipelines();
    for (name, pipeline) in [
        ("baseline", pipelines.baseline()),
        ("resident", pipelines.resident()),
        ("pick", pipelines.pick()),
        ("scatter", pipelines.scatter()),
    ] {
        pipeline.unwrap_or_else(|e| panic!("{name} pipeline: {e}"));
    }
    drop(renderer);
    drop(gpu_scene);
    assert_no_validation_errors(&device);
}

#[test]
fn every_shader_file_is_listed() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
    for entry in std::fs::read_dir(&dir).expect("shaders/") {
        let name = entry
            .expect("entry")
            .file_name()
            .to_string_lossy()
            .into_owned();
        if ShaderStage::from_file_name(&name).is_some() {
            assert!(
                ALL.iter().chain(TEMPLATES).any(|s| s.name == name),
                "{name} is not in cadr_core::shaders::ALL or TEMPLATES"
            );
        } else if name.ends_with(".glsl") {
            assert!(
                INCLUDES.iter().any(|(n, _)| *n == name),
                "{name} is not in INCLUDES"
            );
        }
    }
}

#[test]
fn shader_struct_mirrors_have_std140_layout() {
    assert_eq!(std::mem::size_of::<FrameUniforms>(), 176);
    assert_eq!(std::mem::offset_of!(FrameUniforms, view_rotation), 64);
    assert_eq!(std::mem::offset_of!(FrameUniforms, eye_high), 128);
    assert_eq!(std::mem::offset_of!(FrameUniforms, eye_low), 144);
    assert_eq!(std::mem::offset_of!(FrameUniforms, light), 160);
    assert_eq!(
        std::mem::size_of::<MatrixUpdate>(),
        96,
        "std430: slot, 3 pad, mat4, vec4"
    );
    assert_eq!(std::mem::offset_of!(MatrixUpdate, translation_low), 80);
    assert_eq!(std::mem::offset_of!(MatrixUpdate, matrix), 16);
    assert_eq!(std::mem::size_of::<MaterialParameters>(), 32);
    assert_eq!(std::mem::size_of::<DrawIndices>(), 16);

    assert_eq!(std::mem::size_of::<DrawParameters>(), 96);
    assert_eq!(std::mem::offset_of!(DrawParameters, base_color), 64);
    assert_eq!(std::mem::offset_of!(DrawParameters, surface), 80);
    assert!(
        std::mem::size_of::<DrawParameters>() <= 128,
        "fits the guaranteed push constant size"
    );
}

#[test]
fn compile_errors_name_the_shader_and_line() {
    let broken = "#version 460\nvoid main() {\n  undefined_function();\n}\n";
    let error = compile_glsl("broken.frag", broken, ShaderStage::Fragment, INCLUDES).unwrap_err();
    let text = error.to_string();
    assert!(matches!(error, VkError::ShaderCompile { .. }));
    assert!(
        text.contains("broken.frag") && text.contains(":3:"),
        "{text}"
    );
    let missing = "#version 460\n#include \"nowhere.glsl\"\nvoid main() {}\n";
    let text = compile_glsl("include.frag", missing, ShaderStage::Fragment, INCLUDES)
        .unwrap_err()
        .to_string();
    assert!(text.contains("nowhere.glsl"), "{text}");
}
