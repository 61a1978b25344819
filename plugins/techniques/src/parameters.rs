//! Parameter paths: how matrices and materials reach the shaders (the seeds' glUniform /
//! ubosub, uborange, indexed and bindless rows in Vulkan form).
//!
//! - `push`: the matrix and material values pushed per draw (push constants, as the plugin
//!   ABI's parameter block, which `dgc` pushes from a GPU culler's commands instead);
//! - `ubo-dynamic`: uniform buffers bound with dynamic offsets, one descriptor set per update
//!   frequency (set 1 per object matrix, set 2 per material);
//! - `ssbo-index`: storage-buffer arrays indexed through `firstInstance` (no per-draw commands);
//! - `address`: the same arrays through buffer device addresses pushed once per pass.

use std::ffi::CStr;
use std::sync::Arc;

use crate::{KEEPS_FRAME_SLOTS, REPLAYABLE, SHARES_PIPELINES};
use cadr_plugin_sdk::abi::{self, CadrBindState, CadrInstance};
use cadr_plugin_sdk::vk;
use cadr_plugin_sdk::vulkan_failure;
use cadr_plugin_sdk::{technique_library, Bind, Gpu, HostBuffer, ParameterPath, Scene, Technique};

fn push(gpu: &Gpu, bind: &Bind<'_>, offset: u32, bytes: &[u8]) {
    // SAFETY: recording; the range lies in the layout's 128-byte vertex range.
    unsafe {
        gpu.device.cmd_push_constants(
            bind.command_buffer(),
            bind.layout(),
            vk::ShaderStageFlags::VERTEX,
            offset,
            bytes,
        )
    };
    bind.count(|s| s.parameter_binds += 1);
}

/// Flags and instance id as the two last words of `cadr_push.vectors[1]` (bytes 88-95).
fn flags_and_instance(drawn: &CadrInstance, id: u32) -> [u8; 8] {
    let mut bytes = [0; 8];
    bytes[..4].copy_from_slice(&drawn.flags.to_le_bytes());
    bytes[4..].copy_from_slice(&id.to_le_bytes());
    bytes
}

/// Values pushed per draw.
pub struct Push {
    gpu: Arc<Gpu>,
}

impl Technique for Push {
    fn create(gpu: Arc<Gpu>) -> Result<Self, String> {
        Ok(Self { gpu })
    }
}

const PUSH_SNIPPET: &CStr = c"
CadrObject cadr_object() {
    CadrObject object;
    object.world = cadr_push.matrix;
    object.base_color = cadr_push.vectors[0];
    object.surface = cadr_push.vectors[1].xy;
    object.flags = floatBitsToUint(cadr_push.vectors[1].z);
    object.instance = floatBitsToUint(cadr_push.vectors[1].w);
    return object;
}
";

impl ParameterPath for Push {
    fn shader_snippet(&self) -> &CStr {
        PUSH_SNIPPET
    }
    fn layout(&self) -> ([vk::DescriptorSetLayout; 2], u32) {
        ([vk::DescriptorSetLayout::null(); 2], 96)
    }
    fn bind_draw(
        &self,
        bind: &Bind<'_>,
        id: u32,
        drawn: &CadrInstance,
        state: &mut CadrBindState,
    ) -> u32 {
        if state.valid == 1 && state.words[0] == u64::from(id) {
            return id;
        }
        let scene = bind.scene();
        let matrix = scene
            .matrices()
            .get(drawn.matrix as usize)
            .copied()
            .unwrap_or_default();
        let material = scene
            .materials()
            .get(drawn.material as usize)
            .copied()
            .unwrap_or_default();
        let block = abi::CadrParameterBlock::new(&matrix, &material, drawn.flags, id);
        push(&self.gpu, bind, 0, &block.to_le_bytes());
        state.valid = 1;
        state.words[0] = u64::from(id);
        id
    }
}

/// Creates a descriptor set layout with one binding per type given, for the stages of paths
/// (`Gpu::path_stages`).
fn set_layout(gpu: &Gpu, types: &[vk::DescriptorType]) -> Result<vk::DescriptorSetLayout, String> {
    let bindings: Vec<vk::DescriptorSetLayoutBinding> = types
        .iter()
        .enumerate()
        .map(|(i, &ty)| {
            vk::DescriptorSetLayoutBinding::default()
                .binding(i as u32)
                .descriptor_type(ty)
                .descriptor_count(1)
                .stage_flags(gpu.path_stages())
        })
        .collect();
    let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
    // SAFETY: the info lives for the call.
    unsafe {
        gpu.device
            .create_descriptor_set_layout(&info, gpu.allocator())
    }
    .map_err(vulkan_failure("vkCreateDescriptorSetLayout"))
}

/// Descriptor layouts, a pool and one set per layout; destroyed together.
struct Sets {
    gpu: Arc<Gpu>,
    layouts: Vec<vk::DescriptorSetLayout>,
    pool: vk::DescriptorPool,
    sets: Vec<vk::DescriptorSet>,
}

impl Sets {
    fn new(gpu: &Arc<Gpu>, per_set: &[&[vk::DescriptorType]]) -> Result<Self, String> {
        let mut this = Self {
            gpu: Arc::clone(gpu),
            layouts: Vec::new(),
            pool: vk::DescriptorPool::null(),
            sets: Vec::new(),
        };
        for types in per_set {
            let layout = set_layout(gpu, types)?;
            this.layouts.push(layout);
        }
        let mut sizes: Vec<vk::DescriptorPoolSize> = Vec::new();
        for &ty in per_set.iter().flat_map(|t| t.iter()) {
            sizes.push(vk::DescriptorPoolSize::default().ty(ty).descriptor_count(1));
        }
        let info = vk::DescriptorPoolCreateInfo::default()
            .max_sets(per_set.len() as u32)
            .pool_sizes(&sizes);
        // SAFETY: the info lives for the call.
        this.pool = unsafe { gpu.device.create_descriptor_pool(&info, gpu.allocator()) }
            .map_err(vulkan_failure("vkCreateDescriptorPool"))?;
        let alloc = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(this.pool)
            .set_layouts(&this.layouts);
        // SAFETY: the pool was sized for exactly these sets.
        this.sets = unsafe { gpu.device.allocate_descriptor_sets(&alloc) }
            .map_err(vulkan_failure("vkAllocateDescriptorSets"))?;
        Ok(this)
    }

    fn write(
        &self,
        set: usize,
        binding: u32,
        ty: vk::DescriptorType,
        buffer: vk::Buffer,
        range: u64,
    ) {
        let info = [vk::DescriptorBufferInfo::default()
            .buffer(buffer)
            .range(range)];
        let write = [vk::WriteDescriptorSet::default()
            .dst_set(self.sets[set])
            .dst_binding(binding)
            .descriptor_type(ty)
            .buffer_info(&info)];
        // SAFETY: written in prepare, after the previous frame finished.
        unsafe { self.gpu.device.update_descriptor_sets(&write, &[]) };
    }
}

impl Drop for Sets {
    fn drop(&mut self) {
        // SAFETY: the host destroys instances after the GPU is done with them; null handles
        // (from a failed constructor) are ignored.
        unsafe {
            self.gpu
                .device
                .destroy_descriptor_pool(self.pool, self.gpu.allocator());
            for &layout in &self.layouts {
                self.gpu
                    .device
                    .destroy_descriptor_set_layout(layout, self.gpu.allocator());
            }
        }
    }
}

/// Dynamic-offset uniform buffers: matrices (set 1) and materials (set 2).
pub struct UboDynamic {
    gpu: Arc<Gpu>,
    sets: Sets,
    matrices: Option<HostBuffer>,
    materials: Option<HostBuffer>,
    matrix_stride: u64,
    material_stride: u64,
    capacity: (u32, u32),
}

impl Technique for UboDynamic {
    fn create(gpu: Arc<Gpu>) -> Result<Self, String> {
        let dynamic = [vk::DescriptorType::UNIFORM_BUFFER_DYNAMIC];
        let sets = Sets::new(&gpu, &[&dynamic, &dynamic])?;
        let align = gpu.min_uniform_buffer_offset_alignment;
        Ok(Self {
            sets,
            matrices: None,
            materials: None,
            matrix_stride: 64_u64.div_ceil(align) * align,
            material_stride: 32_u64.div_ceil(align) * align,
            capacity: (0, 0),
            gpu,
        })
    }
}

const UBO_SNIPPET: &CStr = c"
layout(set = 1, binding = 0, std140) uniform CadrObjectMatrix { mat4 cadr_object_matrix; };
layout(set = 2, binding = 0, std140) uniform CadrMaterialBlock { vec4 cadr_material_color; vec4 cadr_material_surface; };
CadrObject cadr_object() {
    CadrObject object;
    object.world = cadr_object_matrix;
    object.base_color = cadr_material_color;
    object.surface = cadr_material_surface.xy;
    object.flags = floatBitsToUint(cadr_push.vectors[1].z);
    object.instance = floatBitsToUint(cadr_push.vectors[1].w);
    return object;
}
";

impl ParameterPath for UboDynamic {
    fn shader_snippet(&self) -> &CStr {
        UBO_SNIPPET
    }
    fn layout(&self) -> ([vk::DescriptorSetLayout; 2], u32) {
        ([self.sets.layouts[0], self.sets.layouts[1]], 96)
    }
    fn prepare(
        &mut self,
        scene: &Scene<'_>,
        _command_buffer: vk::CommandBuffer,
    ) -> Result<(), String> {
        let (matrices, materials) = (scene.matrices(), scene.materials());
        let needed = (matrices.len().max(1) as u32, materials.len().max(1) as u32);
        let rewrite_all = needed.0 > self.capacity.0 || needed.1 > self.capacity.1;
        if rewrite_all {
            let capacity = (needed.0.next_power_of_two(), needed.1.next_power_of_two());
            let usage = vk::BufferUsageFlags::UNIFORM_BUFFER;
            self.matrices = Some(self.gpu.create_buffer(
                "ubo-dynamic matrices",
                u64::from(capacity.0) * self.matrix_stride,
                usage,
                abi::CADR_MEMORY_CPU_TO_GPU,
            )?);
            self.materials = Some(self.gpu.create_buffer(
                "ubo-dynamic materials",
                u64::from(capacity.1) * self.material_stride,
                usage,
                abi::CADR_MEMORY_CPU_TO_GPU,
            )?);
            self.capacity = capacity;
            let ty = vk::DescriptorType::UNIFORM_BUFFER_DYNAMIC;
            if let (Some(m), Some(t)) = (&self.matrices, &self.materials) {
                self.sets.write(0, 0, ty, m.raw(), 64);
                self.sets.write(1, 0, ty, t.raw(), 32);
            }
        }
        let (Some(matrix_buffer), Some(material_buffer)) =
            (self.matrices.as_mut(), self.materials.as_mut())
        else {
            return Err("uniform buffers missing".into());
        };
        let matrix_slots: Box<dyn Iterator<Item = u32>> = if rewrite_all {
            Box::new(0..matrices.len() as u32)
        } else {
            Box::new(scene.dirty_matrices().iter().copied())
        };
        for slot in matrix_slots {
            if let Some(matrix) = matrices.get(slot as usize) {
                matrix_buffer.write(u64::from(slot) * self.matrix_stride, &matrix.to_le_bytes())?;
            }
        }
        let material_slots: Box<dyn Iterator<Item = u32>> = if rewrite_all {
            Box::new(0..materials.len() as u32)
        } else {
            Box::new(scene.dirty_materials().iter().copied())
        };
        for slot in material_slots {
            if let Some(material) = materials.get(slot as usize) {
                material_buffer.write(
                    u64::from(slot) * self.material_stride,
                    &material.to_le_bytes(),
                )?;
            }
        }
        Ok(())
    }
    fn bind_draw(
        &self,
        bind: &Bind<'_>,
        id: u32,
        drawn: &CadrInstance,
        state: &mut CadrBindState,
    ) -> u32 {
        // words: [matrix slot + 1, material slot + 1, instance + 1] of what is bound.
        if state.valid == 0 {
            state.words = [0; 3];
            state.valid = 1;
        }
        let bind_set = |set: u32, descriptor: vk::DescriptorSet, offset: u64| {
            // SAFETY: recording; the set matches the layout; the offset lies in the buffer.
            unsafe {
                self.gpu.device.cmd_bind_descriptor_sets(
                    bind.command_buffer(),
                    vk::PipelineBindPoint::GRAPHICS,
                    bind.layout(),
                    set,
                    &[descriptor],
                    &[offset as u32],
                )
            };
            bind.count(|s| s.parameter_binds += 1);
        };
        if state.words[0] != u64::from(drawn.matrix) + 1 {
            bind_set(
                1,
                self.sets.sets[0],
                u64::from(drawn.matrix) * self.matrix_stride,
            );
            state.words[0] = u64::from(drawn.matrix) + 1;
        }
        if state.words[1] != u64::from(drawn.material) + 1 {
            bind_set(
                2,
                self.sets.sets[1],
                u64::from(drawn.material) * self.material_stride,
            );
            state.words[1] = u64::from(drawn.material) + 1;
        }
        if state.words[2] != u64::from(id) + 1 {
            push(&self.gpu, bind, 88, &flags_and_instance(drawn, id));
            state.words[2] = u64::from(id) + 1;
        }
        id
    }
}

/// Storage-buffer arrays indexed by the instance index (set 1).
pub struct SsboIndex {
    gpu: Arc<Gpu>,
    sets: Sets,
    bound_generation: u64,
}

impl Technique for SsboIndex {
    fn create(gpu: Arc<Gpu>) -> Result<Self, String> {
        let storage = [vk::DescriptorType::STORAGE_BUFFER; 3];
        Ok(Self {
            sets: Sets::new(&gpu, &[&storage])?,
            gpu,
            bound_generation: 0,
        })
    }
}

const SSBO_SNIPPET: &CStr = c"
struct CadrRecord { uint matrix; uint material; uint flags; uint instance; };
struct CadrMaterialValues { vec4 base_color; vec4 surface; };
layout(set = 1, binding = 0, std430) readonly buffer CadrRecords { CadrRecord cadr_records[]; };
layout(set = 1, binding = 1, std430) readonly buffer CadrMatrices { mat4 cadr_matrices[]; };
layout(set = 1, binding = 2, std430) readonly buffer CadrMaterials { CadrMaterialValues cadr_materials[]; };
CadrObject cadr_object() {
    CadrRecord record = cadr_records[gl_InstanceIndex];
    CadrObject object;
    object.world = cadr_matrices[record.matrix];
    object.base_color = cadr_materials[record.material].base_color;
    object.surface = cadr_materials[record.material].surface.xy;
    object.flags = record.flags;
    object.instance = record.instance;
    return object;
}
";

impl ParameterPath for SsboIndex {
    fn shader_snippet(&self) -> &CStr {
        SSBO_SNIPPET
    }
    fn layout(&self) -> ([vk::DescriptorSetLayout; 2], u32) {
        ([self.sets.layouts[0], vk::DescriptorSetLayout::null()], 0)
    }
    fn prepare(
        &mut self,
        scene: &Scene<'_>,
        _command_buffer: vk::CommandBuffer,
    ) -> Result<(), String> {
        let raw = scene.raw();
        if raw.buffers_generation != self.bound_generation {
            let ty = vk::DescriptorType::STORAGE_BUFFER;
            for (binding, buffer) in [
                &raw.instance_buffer,
                &raw.matrix_buffer,
                &raw.material_buffer,
            ]
            .into_iter()
            .enumerate()
            {
                self.sets.write(
                    0,
                    binding as u32,
                    ty,
                    cadr_plugin_sdk::buffer(buffer),
                    vk::WHOLE_SIZE,
                );
            }
            self.bound_generation = raw.buffers_generation;
        }
        Ok(())
    }
    fn bind_pass(&self, bind: &Bind<'_>, _state: &mut CadrBindState) {
        // SAFETY: recording; the set matches set 1 of the layout.
        unsafe {
            self.gpu.device.cmd_bind_descriptor_sets(
                bind.command_buffer(),
                vk::PipelineBindPoint::GRAPHICS,
                bind.layout(),
                1,
                &[self.sets.sets[0]],
                &[],
            )
        };
        bind.count(|s| s.parameter_binds += 1);
    }
    fn bind_draw(
        &self,
        _bind: &Bind<'_>,
        id: u32,
        _drawn: &CadrInstance,
        _state: &mut CadrBindState,
    ) -> u32 {
        id
    }
}

/// The arrays through buffer device addresses pushed once per pass.
pub struct Address {
    gpu: Arc<Gpu>,
}

impl Technique for Address {
    fn create(gpu: Arc<Gpu>) -> Result<Self, String> {
        Ok(Self { gpu })
    }
}

const ADDRESS_SNIPPET: &CStr = c"
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
struct CadrRecordValues { uint matrix; uint material; uint flags; uint instance; };
struct CadrMaterialEntry { vec4 base_color; vec4 surface; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer CadrRecordArray { CadrRecordValues values[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer CadrMatrixArray { mat4 values[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer CadrMaterialArray { CadrMaterialEntry values[]; };
CadrObject cadr_object() {
    uvec4 first = floatBitsToUint(cadr_push.vectors[0]);
    uvec4 second = floatBitsToUint(cadr_push.vectors[1]);
    CadrRecordValues record = CadrRecordArray(first.xy).values[gl_InstanceIndex];
    CadrMaterialEntry material = CadrMaterialArray(second.xy).values[record.material];
    CadrObject object;
    object.world = CadrMatrixArray(first.zw).values[record.matrix];
    object.base_color = material.base_color;
    object.surface = material.surface.xy;
    object.flags = record.flags;
    object.instance = record.instance;
    return object;
}
";

impl ParameterPath for Address {
    fn shader_snippet(&self) -> &CStr {
        ADDRESS_SNIPPET
    }
    fn layout(&self) -> ([vk::DescriptorSetLayout; 2], u32) {
        ([vk::DescriptorSetLayout::null(); 2], 96)
    }
    fn bind_pass(&self, bind: &Bind<'_>, _state: &mut CadrBindState) {
        let scene = bind.scene().raw();
        let mut bytes = [0u8; 24];
        bytes[..8].copy_from_slice(&scene.instance_buffer.address.to_le_bytes());
        bytes[8..16].copy_from_slice(&scene.matrix_buffer.address.to_le_bytes());
        bytes[16..].copy_from_slice(&scene.material_buffer.address.to_le_bytes());
        push(&self.gpu, bind, 64, &bytes);
    }
    fn bind_draw(
        &self,
        _bind: &Bind<'_>,
        id: u32,
        _drawn: &CadrInstance,
        _state: &mut CadrBindState,
    ) -> u32 {
        id
    }
}

technique_library! {
    pub fn entry;
    library: "cadr parameter paths",
    techniques: [
        parameters UboDynamic {
            name: "ubo-dynamic",
            description: "Uniform buffers bound with dynamic offsets, one set per update frequency: matrix per object, material per batch (the seeds' uborange).",
            features: 0, provides: abi::CADR_TRAIT_READS_HOST_MATRICES | abi::CADR_TRAIT_REPLAYABLE | KEEPS_FRAME_SLOTS | SHARES_PIPELINES, needs: 0,
        },
        parameters SsboIndex {
            name: "ssbo-index",
            description: "Records, matrices and materials in storage buffers, found through firstInstance; nothing per draw (the seeds' indexed/indexedmdi).",
            features: 0, provides: abi::CADR_TRAIT_PARAMETERS_FROM_INSTANCE_INDEX | abi::CADR_TRAIT_MESH_SHADING | REPLAYABLE | KEEPS_FRAME_SLOTS | SHARES_PIPELINES, needs: 0,
        },
        parameters Address {
            name: "address",
            description: "The same arrays through buffer device addresses pushed once per pass (the seeds' bindless).",
            features: abi::CADR_FEATURE_BUFFER_DEVICE_ADDRESS,
            provides: abi::CADR_TRAIT_PARAMETERS_FROM_INSTANCE_INDEX | REPLAYABLE | KEEPS_FRAME_SLOTS | SHARES_PIPELINES, needs: 0,
        },
    ]
}
