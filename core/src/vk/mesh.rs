//! Mesh-shader pipelines (`VK_EXT_mesh_shader`): an optional task stage launches mesh
//! workgroups, each of which writes its own vertices and triangles, with no vertex input or
//! index buffer. Where the device lacks the extension ([`Capabilities::mesh_shader`]), making
//! one is refused with the reason, and callers draw through the vertex pipeline instead.

use std::sync::Arc;

use ash::vk;

use super::pipeline::{specialization_constants, stage, RasterState};
use super::{
    Buffer, Capabilities, ColorTarget, DepthUse, Device, Pipeline, PipelineLayout, ShaderModule,
    VkError, VkResult,
};

/// Bytes of one `VkDrawMeshTasksIndirectCommandEXT` (three workgroup counts).
pub const DRAW_MESH_TASKS_COMMAND_BYTES: u32 = 12;

/// What a mesh-shader pipeline differs in; the rest is as for
/// [`super::GraphicsPipelineDesc`] (dynamic viewport and scissor, dynamic rendering).
pub struct MeshPipelineDesc<'a> {
    /// The pipeline layout.
    pub layout: &'a PipelineLayout,
    /// The task shader, or `None` when the draw launches mesh workgroups itself.
    pub task: Option<&'a ShaderModule>,
    /// The mesh shader.
    pub mesh: &'a ShaderModule,
    /// The fragment shader.
    pub fragment: &'a ShaderModule,
    /// Pushes triangles back (constant and slope factor 1) so that edge lines win the depth test.
    pub depth_bias: bool,
    /// Draws triangles as their three edges (polygon mode LINE).
    pub triangle_outlines: bool,
    /// Culls the triangles wound clockwise on screen (as [`super::GraphicsPipelineDesc`]).
    pub cull_back_faces: bool,
    /// Values of the mesh shader's specialization constants 0, 1, … (u32 each).
    pub mesh_constants: &'a [u32],
    /// The colour attachments, in order.
    pub colors: &'a [ColorTarget],
    /// How it uses depth.
    pub depth: DepthUse,
    /// Samples per pixel of the attachments it draws into (1 without MSAA).
    pub samples: u32,
    /// The debug name.
    pub name: &'a str,
}

fn unsupported(device: &Device, what: &str) -> VkError {
    VkError::Unsupported {
        device: device.adapter().name.clone(),
        reason: format!("{what} needs VK_EXT_mesh_shader with task and mesh shaders"),
    }
}

impl Pipeline {
    /// A mesh-shader pipeline as `desc` describes it; refused where the device lacks
    /// [`Capabilities::mesh_shader`], and multisampled on llvmpipe, which draws such triangles
    /// in the wrong place.
    pub fn mesh(device: &Arc<Device>, desc: &MeshPipelineDesc<'_>) -> VkResult<Self> {
        let Capabilities { mesh_shader, .. } = device.capabilities();
        if !mesh_shader {
            return Err(unsupported(device, &format!("pipeline '{}'", desc.name)));
        }
        if desc.samples > 1 && device.adapter().name.starts_with("llvmpipe") {
            return Err(VkError::Unsupported {
                device: device.adapter().name.clone(),
                reason: format!(
                    "pipeline '{}' with {} samples per pixel: llvmpipe rasterizes multisampled mesh-shader triangles in the wrong place (Mesa 25.0: one quad of a quarter of the target covers all of it), so cadr does not draw mesh shading with MSAA there; turn MSAA off or choose a submission that draws with the vertex pipeline (individual-indirect-count)",
                    desc.name, desc.samples
                ),
            });
        }
        let (constant_entries, constant_bytes) = specialization_constants(desc.mesh_constants);
        let specialization = vk::SpecializationInfo::default()
            .map_entries(&constant_entries)
            .data(&constant_bytes);
        let mut stages: Vec<_> = desc.task.into_iter().map(stage).collect();
        stages.push(stage(desc.mesh).specialization_info(&specialization));
        stages.push(stage(desc.fragment));
        Self::rasterizing(
            device,
            &RasterState {
                layout: desc.layout,
                depth_bias: desc.depth_bias,
                triangle_outlines: desc.triangle_outlines,
                cull_back_faces: desc.cull_back_faces,
                indirect_bindable: false,
                colors: desc.colors,
                depth: desc.depth,
                samples: desc.samples,
                name: desc.name,
            },
            &stages,
            None,
        )
    }
}

/// Records a draw of `groups` (x, y, z) task workgroups (mesh workgroups where the bound
/// pipeline has no task stage) into `command_buffer`, which is recording inside a rendering
/// with a mesh pipeline bound; refused where the device lacks [`Capabilities::mesh_shader`].
pub fn draw_mesh_tasks(
    device: &Device,
    command_buffer: vk::CommandBuffer,
    groups: [u32; 3],
) -> VkResult<()> {
    let Some(commands) = &device.mesh_shader else {
        return Err(unsupported(device, "vkCmdDrawMeshTasksEXT"));
    };
    // SAFETY: the caller records inside a rendering with a mesh pipeline bound; the
    // extension's commands were loaded for this device.
    unsafe { commands.cmd_draw_mesh_tasks(command_buffer, groups[0], groups[1], groups[2]) };
    Ok(())
}

/// Records an indirect draw of at most `max_draws` `VkDrawMeshTasksIndirectCommandEXT`s read
/// from `commands` (tightly packed, from byte `offset`), as many as the `u32` at
/// `count_offset` of `count` says when the GPU runs it: the GPU decides how much is drawn.
/// Refused where the device lacks [`Capabilities::mesh_shader`] or `drawIndirectCount`.
pub fn draw_mesh_tasks_indirect_count(
    device: &Device,
    command_buffer: vk::CommandBuffer,
    (commands, offset): (&Buffer, u64),
    (count, count_offset): (&Buffer, u64),
    max_draws: u32,
) -> VkResult<()> {
    let Some(mesh_shader) = &device.mesh_shader else {
        return Err(unsupported(device, "vkCmdDrawMeshTasksIndirectCountEXT"));
    };
    if !device.capabilities().draw_indirect_count {
        return Err(VkError::Unsupported {
            device: device.adapter().name.clone(),
            reason: "vkCmdDrawMeshTasksIndirectCountEXT needs drawIndirectCount".into(),
        });
    }
    // SAFETY: the caller records inside a rendering with a mesh pipeline bound, and keeps both
    // buffers (made with INDIRECT_BUFFER usage) alive until the GPU has run the draw.
    unsafe {
        mesh_shader.cmd_draw_mesh_tasks_indirect_count(
            command_buffer,
            commands.raw(),
            offset,
            count.raw(),
            count_offset,
            max_draws,
            DRAW_MESH_TASKS_COMMAND_BYTES,
        )
    };
    Ok(())
}
