//! `mesh-tasks`: the commands a GPU culler wrote, drawn by mesh workgroups (plugin ABI 1.23,
//! `CADR_TRAIT_MESH_SHADING`). For each pass the host built as a mesh pipeline
//! (`CADR_PASS_MESH_TRIANGLES`, `CADR_PASS_MESH_PICK`), it pushes where the pass's commands, their count and the
//! scene's indices lie and launches a task workgroup per 32 commands; the host's task shader
//! reads the count and launches a mesh workgroup per chunk of each command's triangles. The
//! other passes (edge lines, the hidden silhouettes' geometry shader) are drawn as
//! `individual-indirect-count` draws them.

use std::sync::Arc;

use cadr_plugin_sdk::abi;
use cadr_plugin_sdk::vk::{self, Handle};
use cadr_plugin_sdk::{Gpu, Record, Submission, Technique};

use super::record::{bind_pass, record_gpu_pass};

/// The `mesh-tasks` submission.
pub struct MeshTasks {
    gpu: Arc<Gpu>,
}

impl Technique for MeshTasks {
    fn create(gpu: Arc<Gpu>) -> Result<Self, String> {
        if gpu.mesh_shader.is_none() {
            return Err("the device has no VK_EXT_mesh_shader".into());
        }
        Ok(Self { gpu })
    }
}

impl MeshTasks {
    /// The device address of `buffer` (made with `SHADER_DEVICE_ADDRESS` usage).
    fn address(&self, buffer: u64) -> u64 {
        let info = vk::BufferDeviceAddressInfo::default().buffer(vk::Buffer::from_raw(buffer));
        // SAFETY: the culler's and the scene's buffers are live and made with
        // SHADER_DEVICE_ADDRESS usage (plugin ABI 1.23, CadrMeshTaskPush).
        unsafe { self.gpu.device.get_buffer_device_address(&info) }
    }

    /// What the host's task and mesh shaders read for the commands of `source`.
    fn push_for(&self, source: &abi::CadrGpuDraws, indices: u64) -> abi::CadrMeshTaskPush {
        abi::CadrMeshTaskPush {
            commands: self.address(source.commands) + source.commands_offset,
            count: self.address(source.count_buffer) + source.count_offset,
            indices,
            max_draws: source.max_draws,
            stride_words: source.stride / 4,
        }
    }

    /// Binds the mesh pass `pass` and draws the commands of `source` by mesh workgroups.
    fn record_mesh_pass(
        &self,
        record: &Record<'_>,
        pass: &abi::CadrPass,
        source: &abi::CadrGpuDraws,
        indices: u64,
    ) -> Result<(), String> {
        let functions = self
            .gpu
            .mesh_shader
            .as_ref()
            .ok_or("the device has no VK_EXT_mesh_shader")?;
        let command_buffer = record.command_buffer();
        bind_pass(&self.gpu, record, pass, (command_buffer, record.stats()));
        let push = self.push_for(source, indices).to_le_bytes();
        let tasks = source.max_draws.div_ceil(abi::CADR_MESH_COMMANDS_PER_TASK);
        // SAFETY: recording inside rendering with the pass's mesh pipeline bound; the layout's
        // one push-constant range (vertex, task and mesh stages) covers bytes 128-159; the
        // buffers the addresses name live until the frame is done.
        unsafe {
            self.gpu.device.cmd_push_constants(
                command_buffer,
                record.layout(),
                MESH_PUSH_STAGES,
                abi::CADR_MESH_TASK_PUSH_OFFSET,
                &push,
            );
            functions.cmd_draw_mesh_tasks(command_buffer, tasks, 1, 1);
        }
        record.count(|s| s.draw_calls += 1);
        Ok(())
    }
}

/// The stages of the host's one push-constant range in a mesh-shading combination.
const MESH_PUSH_STAGES: vk::ShaderStageFlags = vk::ShaderStageFlags::from_raw(
    vk::ShaderStageFlags::VERTEX.as_raw()
        | vk::ShaderStageFlags::TASK_EXT.as_raw()
        | vk::ShaderStageFlags::MESH_EXT.as_raw(),
);

impl Submission for MeshTasks {
    fn prepare(&mut self, _record: &Record<'_>) -> Result<(), String> {
        Ok(())
    }

    fn record(&mut self, record: &Record<'_>) -> Result<(), String> {
        let draws = record.gpu_draws().ok_or(
            "mesh-tasks draws only the commands a gpu- culler writes, and this frame has none",
        )?;
        let indices = record.scene().raw().index_buffer.address;
        if indices == 0 {
            return Err("the scene's index buffer has no device address".into());
        }
        for (pass, source) in record.passes().iter().zip(draws) {
            let mesh = matches!(
                pass.kind,
                abi::CADR_PASS_MESH_TRIANGLES | abi::CADR_PASS_MESH_PICK
            );
            if !mesh {
                record_gpu_pass(&self.gpu, record, pass, source);
            } else if source.commands != 0 && source.max_draws != 0 {
                self.record_mesh_pass(record, pass, source, indices)?;
            }
        }
        Ok(())
    }
}
