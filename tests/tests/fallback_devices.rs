//! Devices without Vulkan 1.4's extras: on Debian 12's own driver (Mesa 22.3's lavapipe,
//! unpacked by `scripts/setup.sh`), what needs mesh shaders is refused with the reason, not
//! crashed into. Each test runs in a process of its own pointed at that driver alone.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use cadr_core::vk::raw as vk;
use cadr_core::vk::{
    draw_mesh_tasks, ColorTarget, DepthUse, MeshPipelineDesc, OneShot, Pipeline, PipelineLayout,
    ShaderModule, ShaderStage, COLOR_FORMAT,
};
use cadr_tests::{assert_no_validation_errors, mesa22_device};

const FRAGMENT: &str =
    "#version 460\nlayout(location = 0) out vec4 c;\nvoid main() { c = vec4(1.0); }\n";

#[test]
fn mesh_shaders_are_refused_with_the_reason_on_mesa_22_3() {
    let device = mesa22_device();
    assert!(!device.capabilities().mesh_shader);
    let words = cadr_core::shaders::compile_glsl("fill.frag", FRAGMENT, ShaderStage::Fragment, &[])
        .expect("compiles");
    let fragment =
        ShaderModule::from_spirv(&device, "fill.frag", &words, ShaderStage::Fragment).unwrap();
    let layout =
        PipelineLayout::new(&device, "none", &[], 0, vk::ShaderStageFlags::empty()).unwrap();
    // No mesh shader module can be made here; the fragment module stands in, as the check
    // comes before any use of it.
    let error = Pipeline::mesh(
        &device,
        &MeshPipelineDesc {
            layout: &layout,
            task: None,
            mesh: &fragment,
            fragment: &fragment,
            depth_bias: false,
            triangle_outlines: false,
            cull_back_faces: false,
            mesh_constants: &[],
            colors: &[ColorTarget::replaced(COLOR_FORMAT)],
            depth: DepthUse::TestAndWrite,
            samples: 1,
            name: "clusters",
        },
    )
    .err()
    .expect("refused");
    let message = error.to_string();
    assert!(
        message.contains("pipeline 'clusters' needs VK_EXT_mesh_shader")
            && message.contains("llvmpipe"),
        "{message}"
    );
    let mut one_shot = OneShot::begin(&device, "no mesh draw").unwrap();
    let error =
        draw_mesh_tasks(&device, one_shot.command_buffer(), [1, 1, 1]).expect_err("refused");
    assert!(
        error
            .to_string()
            .contains("vkCmdDrawMeshTasksEXT needs VK_EXT_mesh_shader"),
        "{error}"
    );
    one_shot.submit_and_wait().unwrap();
    assert_no_validation_errors(&device);
}

#[test]
fn the_dgc_and_mesh_tasks_submissions_are_refused_with_the_reason_on_mesa_22_3() {
    let device = mesa22_device();
    assert!(!device.capabilities().device_generated_commands);
    let registry = cadr_tests::plugin_registry(&device);
    let view =
        cadr_core::view::View::new(&device, std::sync::Arc::clone(&registry), 64, 64).unwrap();
    let error = view
        .techniques()
        .check(&cadr_tests::scene_wide("dgc", "gpu-frustum"))
        .expect_err("refused");
    let message = error.to_string();
    assert!(
        message.contains("dgc") && message.contains("VK_EXT_device_generated_commands"),
        "{message}"
    );
    // Nor mesh shaders: the submission that draws by mesh workgroups is refused too.
    let mesh_tasks = cadr_core::technique::Combination {
        vertex: "pulling".into(),
        ..cadr_tests::scene_wide("mesh-tasks", "gpu-clusters")
    };
    let message = view.techniques().check(&mesh_tasks).expect_err("refused");
    assert!(
        message.contains("mesh-tasks") && message.contains("VK_EXT_mesh_shader"),
        "{message}"
    );
    drop(view);
    assert_no_validation_errors(&device);
}
