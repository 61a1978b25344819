//! Every shader compiles and validates; the Rust mirrors of shader structs match their layout.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use cadr_core::frame::Renderer;
use cadr_core::gpu_scene::{ScatterParameters, ScenePipelines};
use cadr_core::render::FrameUniforms;
use cadr_core::shaders::{compile_glsl, with_defines, ALL, INCLUDES, TEMPLATES};
use cadr_core::technique::fragment_defines;
use cadr_core::vk::{Capabilities, ShaderStage};
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
    // The fragment shaders, and the geometry shader compiled with the same lines, also as a
    // device with every optional feature compiles them (the bindless texture table, the pixel
    // keys): lavapipe draws only the other variant, and SwiftShader, which has the table, has
    // no geometry shaders.
    let everything = Capabilities {
        bindless_textures: 1,
        fragment_stores_and_atomics: true,
        ..Capabilities::default()
    };
    let defines = fragment_defines(everything);
    assert!(defines.contains("CADR_BINDLESS_TEXTURES"), "{defines}");
    let pass_stages = [ShaderStage::Fragment, ShaderStage::Geometry];
    for shader in ALL.iter().filter(|s| pass_stages.contains(&s.stage)) {
        let source = with_defines(shader.source, &defines);
        compile_glsl(shader.name, &source, shader.stage, INCLUDES)
            .unwrap_or_else(|e| panic!("with every feature: {e}"));
    }
    // Creating the pipelines runs the layer's SPIR-V validation and interface checks.
    let device = test_device();
    let renderer = Renderer::new(&device, 8, 8).expect("renderer");
    renderer
        .make_overlay_pipelines()
        .unwrap_or_else(|e| panic!("pipelines over the picture: {e}"));
    drop(renderer);
    let scene_pipelines = ScenePipelines::new(&device).expect("scene pipelines");
    scene_pipelines
        .scatter()
        .unwrap_or_else(|e| panic!("scatter pipeline: {e}"));
    scene_pipelines
        .hierarchy()
        .unwrap_or_else(|e| panic!("transform hierarchy pipeline: {e}"));
    drop(scene_pipelines);
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
    assert_eq!(std::mem::size_of::<FrameUniforms>(), 464);
    assert_eq!(std::mem::offset_of!(FrameUniforms, edge_color), 432);
    assert_eq!(std::mem::offset_of!(FrameUniforms, highlight), 448);
    assert_eq!(std::mem::offset_of!(FrameUniforms, target), 384);
    assert_eq!(std::mem::offset_of!(FrameUniforms, background_top), 400);
    assert_eq!(std::mem::offset_of!(FrameUniforms, background_bottom), 416);
    assert_eq!(std::mem::offset_of!(FrameUniforms, section_planes), 176);
    assert_eq!(std::mem::offset_of!(FrameUniforms, section_colors), 272);
    assert_eq!(std::mem::offset_of!(FrameUniforms, section), 368);
    assert_eq!(std::mem::offset_of!(FrameUniforms, view_rotation), 64);
    assert_eq!(std::mem::offset_of!(FrameUniforms, eye_high), 128);
    assert_eq!(std::mem::offset_of!(FrameUniforms, eye_low), 144);
    assert_eq!(std::mem::offset_of!(FrameUniforms, light), 160);
    // scatter.comp's push constants: item count, words per item, first word.
    assert_eq!(std::mem::size_of::<ScatterParameters>(), 12);
    assert_eq!(std::mem::offset_of!(ScatterParameters, first_word), 8);
}

#[test]
fn compile_errors_name_the_shader_and_line() {
    let broken = "#version 460\nvoid main() {\n  undefined_function();\n}\n";
    let error = compile_glsl("broken.frag", broken, ShaderStage::Fragment, INCLUDES).unwrap_err();
    let text = error.to_string();
    assert_eq!(
        error.name, "broken.frag",
        "a shader error, not a Vulkan one"
    );
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
