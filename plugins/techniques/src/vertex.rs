//! Vertex paths: how vertices and indices reach the vertex shader (the seeds' VBO, VAB/VAO
//! and bindless rows in Vulkan form).
//!
//! - `per-part`: vertex and index buffers bound at every part's own offsets;
//! - `per-geometry`: bound at each geometry's offsets, re-bound only when the geometry changes;
//! - `arena`: the scene's buffers bound once, offsets in each draw;
//! - `pulling`: no vertex input; the shader reads vertices from a storage buffer;
//! - `pulling-address`: the same through a buffer device address in a push constant.

use std::ffi::CStr;
use std::sync::Arc;

use crate::{KEEPS_FRAME_SLOTS, REPLAYABLE, SHARES_PIPELINES};
use cadr_plugin_sdk::abi::{self, CadrBindState, CadrDrawBase, CadrInstance, CadrVertexInput};
use cadr_plugin_sdk::vk;
use cadr_plugin_sdk::vulkan_failure;
use cadr_plugin_sdk::{technique_library, Bind, Gpu, Scene, Technique, VertexPath};

/// The snippet of the paths with vertex input (locations 0 and 1), whose vertex lies at
/// `index` in the scene's vertex buffer. Every snippet defines CADR_VERTEX_INDEX, where the host
/// finds the vertex's texture coordinate and colour.
macro_rules! attributes_snippet {
    ($index:literal) => {
        match CStr::from_bytes_with_nul(
            concat!(
                "
layout(location = 0) in vec3 cadr_in_position;
layout(location = 1) in vec3 cadr_in_normal;
vec3 cadr_vertex_position() { return cadr_in_position; }
vec3 cadr_vertex_normal() { return cadr_in_normal; }
#define CADR_VERTEX_INDEX
uint cadr_vertex_index() { return ",
                $index,
                "; }
\0"
            )
            .as_bytes(),
        ) {
            Ok(snippet) => snippet,
            Err(_) => panic!("a snippet is one C string"),
        }
    };
}

/// The scene bound at 0: draws offset their vertices, `gl_VertexIndex` counts from the start.
const ARENA_SNIPPET: &CStr = attributes_snippet!("uint(gl_VertexIndex)");

/// The bound paths count vertices from the binding's start: the geometry's first vertex is
/// pushed (bytes 96-99) with every binding.
const BOUND_SNIPPET: &CStr = attributes_snippet!("cadr_push.words[0].x + uint(gl_VertexIndex)");

fn attributes() -> CadrVertexInput {
    CadrVertexInput {
        stride: 24,
        attribute_count: 2,
        formats: [vk::Format::R32G32B32_SFLOAT.as_raw(); 4],
        offsets: [0, 12, 0, 0],
    }
}

/// The index buffer and the element a geometry's (or part's) indices start at, for the pass.
fn index_source(bind: &Bind<'_>, drawn: &CadrInstance, per_part: bool) -> (vk::Buffer, u32) {
    let scene = bind.scene().raw();
    if bind.pass_kind() == abi::CADR_PASS_EDGES {
        let first = if per_part {
            drawn.first_wire_index
        } else {
            drawn.geometry_first_wire_index
        };
        (cadr_plugin_sdk::buffer(&scene.wire_index_buffer), first)
    } else {
        let first = if per_part {
            drawn.first_index
        } else {
            drawn.geometry_first_index
        };
        (cadr_plugin_sdk::buffer(&scene.index_buffer), first)
    }
}

/// Binds vertex and index buffers at the given element offsets and pushes the vertex offset.
fn bind_buffers(gpu: &Gpu, bind: &Bind<'_>, index: (vk::Buffer, u32), vertex_base: u32) {
    let scene = bind.scene().raw();
    let vertex_bytes = u64::from(vertex_base) * u64::from(scene.vertex_stride);
    // SAFETY: recording; the scene's buffers outlive the frame; offsets lie inside them.
    unsafe {
        gpu.device.cmd_bind_vertex_buffers(
            bind.command_buffer(),
            0,
            &[cadr_plugin_sdk::buffer(&scene.vertex_buffer)],
            &[vertex_bytes],
        );
        gpu.device.cmd_bind_index_buffer(
            bind.command_buffer(),
            index.0,
            u64::from(index.1) * 4,
            vk::IndexType::UINT32,
        );
        // Bytes 96-99 lie in the layout's 128-byte vertex range.
        gpu.device.cmd_push_constants(
            bind.command_buffer(),
            bind.layout(),
            vk::ShaderStageFlags::VERTEX,
            96,
            &vertex_base.to_le_bytes(),
        );
    }
    bind.count(|s| s.vertex_binds += 1);
}

/// Binds vertex and index buffers per draw at each part's offsets (`PER_PART`) or at each
/// geometry's; a binding equal to the bound one (same index start and vertex base) is skipped.
pub struct Bound<const PER_PART: bool> {
    gpu: Arc<Gpu>,
}

impl<const PER_PART: bool> Technique for Bound<PER_PART> {
    fn create(gpu: Arc<Gpu>) -> Result<Self, String> {
        Ok(Self { gpu })
    }
}

impl<const PER_PART: bool> VertexPath for Bound<PER_PART> {
    fn shader_snippet(&self) -> &CStr {
        BOUND_SNIPPET
    }
    fn vertex_input(&self) -> CadrVertexInput {
        attributes()
    }
    fn bind_draw(
        &self,
        bind: &Bind<'_>,
        drawn: &CadrInstance,
        state: &mut CadrBindState,
    ) -> CadrDrawBase {
        let index = index_source(bind, drawn, PER_PART);
        let key = u64::from(index.1) << 32 | u64::from(drawn.vertex_base);
        if state.valid == 0 || state.words[0] != key {
            bind_buffers(&self.gpu, bind, index, drawn.vertex_base);
            state.valid = 1;
            state.words[0] = key;
        }
        CadrDrawBase {
            index_base: index.1,
            vertex_base: drawn.vertex_base,
            ok: 1,
        }
    }
}

/// What the paths that bind the whole scene once answer for every draw: the binding starts at
/// element 0, so draws use absolute offsets.
const SCENE_BOUND_AT_ZERO: CadrDrawBase = CadrDrawBase {
    index_base: 0,
    vertex_base: 0,
    ok: 1,
};

/// Binds the scene's buffers once per pass.
pub struct Arena {
    gpu: Arc<Gpu>,
}

impl Technique for Arena {
    fn create(gpu: Arc<Gpu>) -> Result<Self, String> {
        Ok(Self { gpu })
    }
}

/// The index buffer of the pass, bound at 0.
fn bind_whole_index_buffer(gpu: &Gpu, bind: &Bind<'_>) {
    let scene = bind.scene().raw();
    let buffer = if bind.pass_kind() == abi::CADR_PASS_EDGES {
        &scene.wire_index_buffer
    } else {
        &scene.index_buffer
    };
    // SAFETY: recording; the buffer outlives the frame.
    unsafe {
        gpu.device.cmd_bind_index_buffer(
            bind.command_buffer(),
            cadr_plugin_sdk::buffer(buffer),
            0,
            vk::IndexType::UINT32,
        )
    };
    bind.count(|s| s.vertex_binds += 1);
}

impl VertexPath for Arena {
    fn shader_snippet(&self) -> &CStr {
        ARENA_SNIPPET
    }
    fn vertex_input(&self) -> CadrVertexInput {
        attributes()
    }
    fn bind_pass(&self, bind: &Bind<'_>, _state: &mut CadrBindState) {
        let scene = bind.scene().raw();
        // SAFETY: recording; the vertex buffer outlives the frame.
        unsafe {
            self.gpu.device.cmd_bind_vertex_buffers(
                bind.command_buffer(),
                0,
                &[cadr_plugin_sdk::buffer(&scene.vertex_buffer)],
                &[0],
            )
        };
        bind_whole_index_buffer(&self.gpu, bind);
    }
    fn bind_draw(
        &self,
        _bind: &Bind<'_>,
        _drawn: &CadrInstance,
        _state: &mut CadrBindState,
    ) -> CadrDrawBase {
        SCENE_BOUND_AT_ZERO
    }
}

/// Vertex pulling from a storage buffer (set 3).
pub struct Pulling {
    gpu: Arc<Gpu>,
    layout: vk::DescriptorSetLayout,
    pool: vk::DescriptorPool,
    set: vk::DescriptorSet,
    bound_generation: u64,
}

impl Technique for Pulling {
    fn create(gpu: Arc<Gpu>) -> Result<Self, String> {
        let device = &gpu.device;
        let binding = [vk::DescriptorSetLayoutBinding::default()
            .binding(0)
            .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
            .descriptor_count(1)
            .stage_flags(gpu.path_stages())];
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&binding);
        // SAFETY: the info lives for the call.
        let layout = unsafe { device.create_descriptor_set_layout(&info, gpu.allocator()) }
            .map_err(vulkan_failure("vkCreateDescriptorSetLayout"))?;
        let sizes = [vk::DescriptorPoolSize::default()
            .ty(vk::DescriptorType::STORAGE_BUFFER)
            .descriptor_count(1)];
        let pool_info = vk::DescriptorPoolCreateInfo::default()
            .max_sets(1)
            .pool_sizes(&sizes);
        // SAFETY: as above.
        let pool = match unsafe { device.create_descriptor_pool(&pool_info, gpu.allocator()) } {
            Ok(pool) => pool,
            Err(e) => {
                // SAFETY: created above, unused.
                unsafe { device.destroy_descriptor_set_layout(layout, gpu.allocator()) };
                return Err(vulkan_failure("vkCreateDescriptorPool")(e));
            }
        };
        let mut this = Self {
            gpu: Arc::clone(&gpu),
            layout,
            pool,
            set: vk::DescriptorSet::null(),
            bound_generation: 0,
        };
        let layouts = [layout];
        let alloc = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(pool)
            .set_layouts(&layouts);
        // SAFETY: the pool has room for this one set.
        this.set = unsafe { gpu.device.allocate_descriptor_sets(&alloc) }
            .map_err(vulkan_failure("vkAllocateDescriptorSets"))?[0];
        Ok(this)
    }
}

impl Drop for Pulling {
    fn drop(&mut self) {
        // SAFETY: the host destroys instances after the GPU is done with them.
        unsafe {
            self.gpu
                .device
                .destroy_descriptor_pool(self.pool, self.gpu.allocator());
            self.gpu
                .device
                .destroy_descriptor_set_layout(self.layout, self.gpu.allocator());
        }
    }
}

const PULLING_SNIPPET: &CStr = c"
layout(set = 3, binding = 0, std430) readonly buffer CadrVertices { float cadr_vertex_data[]; };
vec3 cadr_vertex_position() {
    uint base = uint(gl_VertexIndex) * 6u;
    return vec3(cadr_vertex_data[base], cadr_vertex_data[base + 1u], cadr_vertex_data[base + 2u]);
}
vec3 cadr_vertex_normal() {
    uint base = uint(gl_VertexIndex) * 6u + 3u;
    return vec3(cadr_vertex_data[base], cadr_vertex_data[base + 1u], cadr_vertex_data[base + 2u]);
}
#define CADR_VERTEX_INDEX
uint cadr_vertex_index() { return uint(gl_VertexIndex); }
";

impl VertexPath for Pulling {
    fn shader_snippet(&self) -> &CStr {
        PULLING_SNIPPET
    }
    fn vertex_input(&self) -> CadrVertexInput {
        CadrVertexInput::default()
    }
    fn set_layout(&self) -> vk::DescriptorSetLayout {
        self.layout
    }
    fn prepare(
        &mut self,
        scene: &Scene<'_>,
        _command_buffer: vk::CommandBuffer,
    ) -> Result<(), String> {
        let raw = scene.raw();
        if raw.buffers_generation != self.bound_generation {
            let info = [vk::DescriptorBufferInfo::default()
                .buffer(cadr_plugin_sdk::buffer(&raw.vertex_buffer))
                .range(vk::WHOLE_SIZE)];
            let write = [vk::WriteDescriptorSet::default()
                .dst_set(self.set)
                .dst_binding(0)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(&info)];
            // SAFETY: the host calls prepare after the previous frame finished.
            unsafe { self.gpu.device.update_descriptor_sets(&write, &[]) };
            self.bound_generation = raw.buffers_generation;
        }
        Ok(())
    }
    fn bind_pass(&self, bind: &Bind<'_>, _state: &mut CadrBindState) {
        // SAFETY: recording; the set matches set 3 of the layout.
        unsafe {
            self.gpu.device.cmd_bind_descriptor_sets(
                bind.command_buffer(),
                vk::PipelineBindPoint::GRAPHICS,
                bind.layout(),
                3,
                &[self.set],
                &[],
            )
        };
        bind_whole_index_buffer(&self.gpu, bind);
    }
    fn bind_draw(
        &self,
        _bind: &Bind<'_>,
        _drawn: &CadrInstance,
        _state: &mut CadrBindState,
    ) -> CadrDrawBase {
        SCENE_BOUND_AT_ZERO
    }
}

/// Vertex pulling through a buffer device address pushed once per pass.
pub struct PullingAddress {
    gpu: Arc<Gpu>,
}

impl Technique for PullingAddress {
    fn create(gpu: Arc<Gpu>) -> Result<Self, String> {
        Ok(Self { gpu })
    }
}

const PULLING_ADDRESS_SNIPPET: &CStr = c"
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer CadrVertexData { float values[]; };
vec3 cadr_pulled(uint offset) {
    CadrVertexData data = CadrVertexData(cadr_push.words[0].xy);
    uint base = uint(gl_VertexIndex) * 6u + offset;
    return vec3(data.values[base], data.values[base + 1u], data.values[base + 2u]);
}
vec3 cadr_vertex_position() { return cadr_pulled(0u); }
vec3 cadr_vertex_normal() { return cadr_pulled(3u); }
#define CADR_VERTEX_INDEX
uint cadr_vertex_index() { return uint(gl_VertexIndex); }
";

impl VertexPath for PullingAddress {
    fn shader_snippet(&self) -> &CStr {
        PULLING_ADDRESS_SNIPPET
    }
    fn vertex_input(&self) -> CadrVertexInput {
        CadrVertexInput::default()
    }
    fn bind_pass(&self, bind: &Bind<'_>, _state: &mut CadrBindState) {
        let address = bind.scene().raw().vertex_buffer.address;
        let mut words = [0u8; 16];
        words[..8].copy_from_slice(&address.to_le_bytes());
        // SAFETY: recording; bytes 96-111 lie in the layout's 128-byte vertex range.
        unsafe {
            self.gpu.device.cmd_push_constants(
                bind.command_buffer(),
                bind.layout(),
                vk::ShaderStageFlags::VERTEX,
                96,
                &words,
            )
        };
        bind.count(|s| s.vertex_binds += 1);
        bind_whole_index_buffer(&self.gpu, bind);
    }
    fn bind_draw(
        &self,
        _bind: &Bind<'_>,
        _drawn: &CadrInstance,
        _state: &mut CadrBindState,
    ) -> CadrDrawBase {
        SCENE_BOUND_AT_ZERO
    }
}

/// What `per-geometry` offers its partners: the parts of a geometry share one binding.
pub(crate) const GEOMETRY: u64 = abi::CADR_TRAIT_GEOMETRY_SHARES_BINDING;

/// `per-geometry`, the built-in vertex path.
pub type PerGeometry = Bound<false>;
const SCENE: u64 = abi::CADR_TRAIT_GEOMETRY_SHARES_BINDING | abi::CADR_TRAIT_SCENE_SHARES_BINDING;

technique_library! {
    pub fn entry;
    library: "cadr vertex paths",
    techniques: [
        vertex Bound<true> {
            name: "per-part",
            description: "Vertex and index buffers bound at every part's offsets (the seeds' VBO, no state reuse).",
            features: 0, provides: REPLAYABLE | KEEPS_FRAME_SLOTS | SHARES_PIPELINES, needs: 0,
        },
        vertex Arena {
            name: "arena",
            description: "The scene's vertex and index arenas bound once; offsets travel in each draw.",
            features: 0, provides: SCENE | REPLAYABLE | KEEPS_FRAME_SLOTS | SHARES_PIPELINES, needs: 0,
        },
        vertex Pulling {
            name: "pulling",
            description: "No vertex input: the shader pulls vertices from a storage buffer by gl_VertexIndex.",
            features: 0, provides: SCENE | abi::CADR_TRAIT_MESH_SHADING | REPLAYABLE | KEEPS_FRAME_SLOTS | SHARES_PIPELINES, needs: 0,
        },
        vertex PullingAddress {
            name: "pulling-address",
            description: "Vertex pulling through a buffer device address pushed once per pass (bindless).",
            features: abi::CADR_FEATURE_BUFFER_DEVICE_ADDRESS, provides: SCENE | REPLAYABLE | KEEPS_FRAME_SLOTS | SHARES_PIPELINES, needs: 0,
        },
    ]
}
