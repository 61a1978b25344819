//! Mesh shaders in the Vulkan layer (`VK_EXT_mesh_shader`) on the default driver, Mesa 25's
//! lavapipe: a task shader launches mesh workgroups, each of which draws one quad, directly
//! and through an indirect draw whose count the GPU reads. Validation is on.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::sync::Arc;

use cadr_core::shaders::compile_glsl;
use cadr_core::vk::{
    begin_rendering, draw_mesh_tasks, draw_mesh_tasks_indirect_count, end_rendering, raw as vk,
    Buffer, ColorTarget, DepthSharing, DepthUse, Device, MemoryLocation, MeshPipelineDesc,
    OffscreenTarget, OneShot, Pipeline, PipelineLayout, RenderingTarget, ShaderModule, ShaderStage,
    COLOR_FORMAT,
};
use cadr_tests::{assert_no_validation_errors, test_device};

const SIZE: u32 = 64;
/// Columns of the picture: task workgroup `i` has mesh workgroup `i` draw a quad over column `i`.
const COLUMNS: u32 = 4;

const TASK: &str = r#"#version 460
#extension GL_EXT_mesh_shader : require
layout(local_size_x = 1) in;
taskPayloadSharedEXT uint column;
void main() {
    column = gl_WorkGroupID.x;
    EmitMeshTasksEXT(1, 1, 1);
}
"#;

const MESH: &str = r#"#version 460
#extension GL_EXT_mesh_shader : require
layout(local_size_x = 1) in;
layout(triangles, max_vertices = 4, max_primitives = 2) out;
taskPayloadSharedEXT uint column;
void main() {
    SetMeshOutputsEXT(4, 2);
    float left = -1.0 + 2.0 * float(column) / 4.0;
    float right = left + 2.0 / 4.0;
    gl_MeshVerticesEXT[0].gl_Position = vec4(left, -1.0, 0.5, 1.0);
    gl_MeshVerticesEXT[1].gl_Position = vec4(right, -1.0, 0.5, 1.0);
    gl_MeshVerticesEXT[2].gl_Position = vec4(right, 1.0, 0.5, 1.0);
    gl_MeshVerticesEXT[3].gl_Position = vec4(left, 1.0, 0.5, 1.0);
    gl_PrimitiveTriangleIndicesEXT[0] = uvec3(0, 1, 2);
    gl_PrimitiveTriangleIndicesEXT[1] = uvec3(0, 2, 3);
}
"#;

const FRAGMENT: &str = r#"#version 460
layout(location = 0) out vec4 colour;
void main() { colour = vec4(1.0, 0.5, 0.0, 1.0); }
"#;

fn module(device: &Arc<Device>, name: &str, source: &str, stage: ShaderStage) -> ShaderModule {
    let words = compile_glsl(name, source, stage, &[]).expect("the shader compiles");
    ShaderModule::from_spirv(device, name, &words, stage).expect("shader module")
}

/// The quad pipeline: task, mesh and fragment stages, colour and depth targets.
fn quad_pipeline(device: &Arc<Device>, layout: &PipelineLayout) -> Pipeline {
    let task = module(device, "quads.task", TASK, ShaderStage::Task);
    let mesh = module(device, "quads.mesh", MESH, ShaderStage::Mesh);
    let fragment = module(device, "quads.frag", FRAGMENT, ShaderStage::Fragment);
    Pipeline::mesh(
        device,
        &MeshPipelineDesc {
            layout,
            task: Some(&task),
            mesh: &mesh,
            fragment: &fragment,
            depth_bias: false,
            triangle_outlines: false,
            cull_back_faces: false,
            mesh_constants: &[],
            colors: &[ColorTarget::replaced(COLOR_FORMAT)],
            depth: DepthUse::TestAndWrite,
            samples: 1,
            name: "mesh shader quads",
        },
    )
    .expect("mesh pipeline")
}

/// Renders one frame with `pipeline` bound and `draw` recording the draw; returns which
/// columns are covered (their centre pixel is the fragment shader's orange).
fn covered_columns(
    device: &Arc<Device>,
    pipeline: &Pipeline,
    draw: impl FnOnce(vk::CommandBuffer),
) -> Vec<bool> {
    let target = OffscreenTarget::new(device, (SIZE, SIZE), 1, DepthSharing::Own).expect("target");
    let extent = vk::Extent2D {
        width: SIZE,
        height: SIZE,
    };
    let mut one_shot = OneShot::begin(device, "mesh shader frame").expect("command buffer");
    let command_buffer = one_shot.command_buffer();
    let rendering = RenderingTarget {
        color: &target.color,
        clear_color: vk::ClearColorValue {
            float32: [0.0, 0.0, 0.0, 1.0],
        },
        depth: &target.depth,
        keep_depth: false,
        shade_from_depth: false,
        store_depth: false,
        extent,
        secondary: false,
        resume: false,
        extra_colors: &[],
        multisampled: None,
    };
    begin_rendering(device, command_buffer, &rendering);
    // SAFETY: the pipeline outlives the submission waited for below.
    unsafe {
        device.raw().cmd_bind_pipeline(
            command_buffer,
            vk::PipelineBindPoint::GRAPHICS,
            pipeline.raw(),
        )
    };
    draw(command_buffer);
    end_rendering(device, command_buffer, &rendering);
    one_shot.submit_and_wait().expect("submit");
    let pixels = target.read_rgba8(device).expect("read back");
    (0..COLUMNS)
        .map(|column| {
            let x = (column * SIZE / COLUMNS + SIZE / (2 * COLUMNS)) as usize;
            let y = (SIZE / 2) as usize;
            let at = 4 * (y * SIZE as usize + x);
            pixels[at] == 255 && pixels[at + 2] == 0
        })
        .collect()
}

#[test]
fn task_and_mesh_shaders_draw_directly_and_with_a_count_the_gpu_reads() {
    let device = test_device();
    assert!(
        device.capabilities().mesh_shader,
        "the default driver ({}) has no mesh shaders: run scripts/setup.sh (Mesa 25)",
        device.adapter().name
    );
    let layout = PipelineLayout::new(&device, "quads", &[], 0, vk::ShaderStageFlags::empty())
        .expect("layout");
    let pipeline = quad_pipeline(&device, &layout);

    let direct = covered_columns(&device, &pipeline, |command_buffer| {
        draw_mesh_tasks(&device, command_buffer, [3, 1, 1]).expect("direct draw");
    });
    assert_eq!(direct, [true, true, true, false], "three task workgroups");

    // Two commands, (1, 1, 1) and (4, 1, 1) task workgroups; the GPU reads how many to draw.
    let commands: Vec<u8> = [1u32, 1, 1, 4, 1, 1]
        .iter()
        .flat_map(|w| w.to_le_bytes())
        .collect();
    let commands = Buffer::with_data(
        &device,
        "mesh commands",
        &commands,
        vk::BufferUsageFlags::INDIRECT_BUFFER,
    )
    .expect("commands");
    for (count, expected) in [
        (0u32, [false; 4]),
        (1, [true, false, false, false]),
        (2, [true; 4]),
    ] {
        let mut count_buffer = Buffer::new(
            &device,
            "mesh command count",
            4,
            vk::BufferUsageFlags::INDIRECT_BUFFER,
            MemoryLocation::CpuToGpu,
        )
        .expect("count");
        count_buffer
            .write(0, &count.to_le_bytes())
            .expect("write the count");
        let drawn = covered_columns(&device, &pipeline, |command_buffer| {
            draw_mesh_tasks_indirect_count(
                &device,
                command_buffer,
                (&commands, 0),
                (&count_buffer, 0),
                2,
            )
            .expect("indirect count draw");
        });
        assert_eq!(drawn, expected, "{count} commands drawn");
    }
    drop(pipeline);
    assert_no_validation_errors(&device);
}
