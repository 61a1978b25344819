//! `mesh-tasks`: the commands a GPU culler wrote, drawn by mesh workgroups (plugin ABI 1.23,
//! `CADR_TRAIT_MESH_SHADING`). For each pass the host built as a mesh pipeline
//! (`CADR_PASS_MESH_TRIANGLES`, `CADR_PASS_MESH_PICK`), it pushes where the pass's commands and
//! the scene's indices lie and draws with `vkCmdDrawMeshTasksIndirectCountEXT`, the culler's
//! count saying how many draws of one task workgroup: the host's task shader of draw `i` reads
//! command `i` and launches a mesh workgroup per 32 of its triangles. The other passes (edge
//! lines, the hidden silhouettes' geometry shader) are drawn as `individual-indirect-count`
//! draws them.

use std::sync::Arc;

use cadr_plugin_sdk::abi;
use cadr_plugin_sdk::vk::{self, Handle};
use cadr_plugin_sdk::{grown_capacity, Gpu, HostBuffer, Record, Submission, Technique};

use super::record::{bind_pass, record_gpu_pass, GpuDrawCount};

/// Bytes of one `VkDrawMeshTasksIndirectCommandEXT`.
const TASK_DRAW_BYTES: u64 = 12;

/// The `mesh-tasks` submission.
pub struct MeshTasks {
    gpu: Arc<Gpu>,
    /// Draws of one task workgroup each (`{1, 1, 1}`), as many as the largest pass may have.
    task_draws: Option<HostBuffer>,
    /// Those it held before it grew: recorded frames may still draw from them, so they live as
    /// long as the technique (growth doubles, so they hold less than the current one).
    outgrown: Vec<HostBuffer>,
}

impl Technique for MeshTasks {
    fn create(gpu: Arc<Gpu>) -> Result<Self, String> {
        if gpu.mesh_shader.is_none() {
            return Err("the device has no VK_EXT_mesh_shader".into());
        }
        Ok(Self {
            gpu,
            task_draws: None,
            outgrown: Vec::new(),
        })
    }
}

impl MeshTasks {
    /// The device address of `buffer` (made with `SHADER_DEVICE_ADDRESS` usage).
    fn address(&self, buffer: u64) -> u64 {
        let info = vk::BufferDeviceAddressInfo::default().buffer(vk::Buffer::from_raw(buffer));
        // SAFETY: the culler's buffers are live and made with SHADER_DEVICE_ADDRESS usage
        // (plugin ABI 1.23, CadrMeshTaskPush).
        unsafe { self.gpu.device.get_buffer_device_address(&info) }
    }

    /// Makes the buffer of task draws hold at least `draws` of them.
    fn reserve_task_draws(&mut self, draws: u32) -> Result<(), String> {
        let needed = u64::from(draws.max(1)) * TASK_DRAW_BYTES;
        let held = self.task_draws.as_ref().map_or(0, HostBuffer::size);
        if held >= needed {
            return Ok(());
        }
        let size = grown_capacity(held, needed) / TASK_DRAW_BYTES * TASK_DRAW_BYTES;
        let mut buffer = self.gpu.create_buffer(
            "mesh task draws",
            size,
            vk::BufferUsageFlags::INDIRECT_BUFFER,
            abi::CADR_MEMORY_CPU_TO_GPU,
        )?;
        let one_workgroup: Vec<u8> = (0..size / 4).flat_map(|_| 1u32.to_le_bytes()).collect();
        buffer.write(0, &one_workgroup)?;
        self.outgrown.extend(self.task_draws.replace(buffer));
        Ok(())
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
        let task_draws = self.task_draws.as_ref().ok_or("no task draws")?;
        let command_buffer = record.command_buffer();
        bind_pass(&self.gpu, record, pass, (command_buffer, record.stats()));
        let push = abi::CadrMeshTaskPush {
            commands: self.address(source.commands) + source.commands_offset,
            indices,
            stride_words: source.stride / 4,
            reserved: 0,
        }
        .to_le_bytes();
        // SAFETY: recording inside rendering with the pass's mesh pipeline bound; the layout's
        // one push-constant range (vertex, task and mesh stages) covers bytes 128-151; the
        // task draws hold `max_draws` draws, and the buffers live until the frame is done.
        unsafe {
            self.gpu.device.cmd_push_constants(
                command_buffer,
                record.layout(),
                MESH_PUSH_STAGES,
                abi::CADR_MESH_TASK_PUSH_OFFSET,
                &push,
            );
            functions.cmd_draw_mesh_tasks_indirect_count(
                command_buffer,
                task_draws.raw(),
                0,
                vk::Buffer::from_raw(source.count_buffer),
                source.count_offset,
                source.max_draws,
                TASK_DRAW_BYTES as u32,
            );
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

/// Whether `pass` is drawn by a mesh pipeline.
fn is_mesh_pass(pass: &abi::CadrPass) -> bool {
    matches!(
        pass.kind,
        abi::CADR_PASS_MESH_TRIANGLES | abi::CADR_PASS_MESH_PICK
    )
}

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
        let most = record
            .passes()
            .iter()
            .zip(draws)
            .filter(|(pass, _)| is_mesh_pass(pass))
            .map(|(_, source)| source.max_draws)
            .max()
            .unwrap_or(0);
        self.reserve_task_draws(most)?;
        for (pass, source) in record.passes().iter().zip(draws) {
            if !is_mesh_pass(pass) {
                record_gpu_pass(&self.gpu, record, pass, source, GpuDrawCount::Read);
            } else if source.commands != 0 && source.max_draws != 0 {
                self.record_mesh_pass(record, pass, source, indices)?;
            }
        }
        Ok(())
    }
}
