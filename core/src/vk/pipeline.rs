//! Pipeline objects, each owning its Vulkan handle and destroying it when dropped: descriptor
//! set layouts, pipeline layouts, descriptor sets with their pool, and graphics and compute
//! pipelines built the way cadr builds them (dynamic rendering, dynamic viewport and scissor).

use super::host_memory::core_callbacks as host_callbacks;
use std::sync::Arc;

use ash::vk;

use super::{Device, ShaderModule, VkResult, VkResultExt, DEPTH_FORMAT};

/// A descriptor set layout.
pub struct DescriptorSetLayout {
    device: Arc<Device>,
    raw: vk::DescriptorSetLayout,
    /// The type and descriptor count of each binding, which a pool for its sets is sized by.
    types: Vec<(vk::DescriptorType, u32)>,
    /// Whether some binding may be updated while a set of it is bound: its sets come from a
    /// pool made for that.
    update_after_bind: bool,
}

/// One binding of a [`DescriptorSetLayout`] made with [`DescriptorSetLayout::with_bindings`].
#[derive(Clone, Copy, Debug)]
pub struct LayoutBinding {
    /// What it holds.
    pub ty: vk::DescriptorType,
    /// The stages that read it.
    pub stages: vk::ShaderStageFlags,
    /// Descriptors in it: 1, or the length of an array.
    pub count: u32,
    /// An array indexed at run time whose elements need not all be written
    /// (`PARTIALLY_BOUND`), and which may be written while a set is bound but not in use
    /// (`UPDATE_AFTER_BIND`, whose higher limits a table of textures needs): descriptor
    /// indexing, which the device must have enabled.
    pub indexed_array: bool,
}

impl LayoutBinding {
    /// One descriptor of `ty` read by `stages`.
    pub fn one(ty: vk::DescriptorType, stages: vk::ShaderStageFlags) -> Self {
        Self {
            ty,
            stages,
            count: 1,
            indexed_array: false,
        }
    }
}

impl DescriptorSetLayout {
    /// A layout with one descriptor per binding: binding `i` is `bindings[i]` (type, stages).
    pub fn new(
        device: &Arc<Device>,
        name: &str,
        bindings: &[(vk::DescriptorType, vk::ShaderStageFlags)],
    ) -> VkResult<Self> {
        let bindings: Vec<LayoutBinding> = bindings
            .iter()
            .map(|&(ty, stages)| LayoutBinding::one(ty, stages))
            .collect();
        Self::with_bindings(device, name, &bindings)
    }

    /// A layout whose binding `i` is `bindings[i]`.
    pub fn with_bindings(
        device: &Arc<Device>,
        name: &str,
        bindings: &[LayoutBinding],
    ) -> VkResult<Self> {
        let raw_bindings: Vec<vk::DescriptorSetLayoutBinding<'_>> = bindings
            .iter()
            .enumerate()
            .map(|(i, binding)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(i as u32)
                    .descriptor_type(binding.ty)
                    .descriptor_count(binding.count)
                    .stage_flags(binding.stages)
            })
            .collect();
        let flags: Vec<vk::DescriptorBindingFlags> = bindings
            .iter()
            .map(|binding| {
                if binding.indexed_array {
                    vk::DescriptorBindingFlags::PARTIALLY_BOUND
                        | vk::DescriptorBindingFlags::UPDATE_AFTER_BIND
                } else {
                    vk::DescriptorBindingFlags::empty()
                }
            })
            .collect();
        let update_after_bind = bindings.iter().any(|binding| binding.indexed_array);
        let mut binding_flags =
            vk::DescriptorSetLayoutBindingFlagsCreateInfo::default().binding_flags(&flags);
        let mut info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&raw_bindings);
        if update_after_bind {
            info = info
                .flags(vk::DescriptorSetLayoutCreateFlags::UPDATE_AFTER_BIND_POOL)
                .push_next(&mut binding_flags);
        }
        // Mesa 25's lavapipe leaks what it allocated when a later allocation in this call fails.
        // SAFETY: the info and its chain live for the call; indexed arrays are asked for only
        // on a device with descriptor indexing enabled (the caller's contract).
        let raw = super::fault::with_first_host_memory_fault_only(|| unsafe {
            device
                .raw()
                .create_descriptor_set_layout(&info, host_callbacks())
        })
        .or_vk("vkCreateDescriptorSetLayout")?;
        device.set_name(raw, name);
        Ok(Self {
            device: Arc::clone(device),
            raw,
            types: bindings.iter().map(|b| (b.ty, b.count)).collect(),
            update_after_bind,
        })
    }

    /// The Vulkan handle.
    pub fn raw(&self) -> vk::DescriptorSetLayout {
        self.raw
    }
}

impl Drop for DescriptorSetLayout {
    fn drop(&mut self) {
        // SAFETY: owners drop layouts after the pipelines and sets made from them are done.
        unsafe {
            self.device
                .raw()
                .destroy_descriptor_set_layout(self.raw, host_callbacks())
        };
    }
}

/// A pipeline layout: descriptor set layouts and one push-constant range.
pub struct PipelineLayout {
    device: Arc<Device>,
    raw: vk::PipelineLayout,
}

impl PipelineLayout {
    /// Sets `sets` (set `i` is `sets[i]`) and `push_bytes` of push constants for `push_stages`.
    pub fn new(
        device: &Arc<Device>,
        name: &str,
        sets: &[vk::DescriptorSetLayout],
        push_bytes: u32,
        push_stages: vk::ShaderStageFlags,
    ) -> VkResult<Self> {
        let push = [vk::PushConstantRange::default()
            .stage_flags(push_stages)
            .size(push_bytes)];
        // No push constants: no range (a range may not be empty).
        let ranges = if push_bytes == 0 {
            &push[..0]
        } else {
            &push[..]
        };
        let info = vk::PipelineLayoutCreateInfo::default()
            .set_layouts(sets)
            .push_constant_ranges(ranges);
        // Mesa 22.3's lavapipe writes into a failed allocation of the device's callbacks here:
        // an injected host-memory failure would crash the driver, not test cadr.
        let raw = super::fault::without_host_memory_faults(|| {
            // SAFETY: the info lives for the call.
            unsafe { device.raw().create_pipeline_layout(&info, host_callbacks()) }
        })
        .or_vk("vkCreatePipelineLayout")?;
        device.set_name(raw, name);
        Ok(Self {
            device: Arc::clone(device),
            raw,
        })
    }

    /// The Vulkan handle.
    pub fn raw(&self) -> vk::PipelineLayout {
        self.raw
    }
}

impl Drop for PipelineLayout {
    fn drop(&mut self) {
        // SAFETY: owners drop the layout after the GPU is done with its pipelines.
        unsafe {
            self.device
                .raw()
                .destroy_pipeline_layout(self.raw, host_callbacks())
        };
    }
}

/// A graphics or compute pipeline.
pub struct Pipeline {
    device: Arc<Device>,
    raw: vk::Pipeline,
}

impl Pipeline {
    /// A full-screen pass over the picture (no vertex input, no depth): `vertex` draws one
    /// triangle covering the target, `fragment` writes the picture's colour format blended
    /// by `blend`.
    pub fn fullscreen(
        device: &Arc<Device>,
        layout: &PipelineLayout,
        (vertex, fragment): (&ShaderModule, &ShaderModule),
        blend: Blend,
        name: &str,
    ) -> VkResult<Self> {
        let colors = [ColorTarget {
            format: super::COLOR_FORMAT,
            writes: true,
            blend: Some(blend),
        }];
        Self::graphics(
            device,
            &GraphicsPipelineDesc {
                layout,
                vertex,
                geometry: None,
                fragment,
                vertex_layout: None,
                topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                depth_bias: false,
                triangle_outlines: false,
                cull_back_faces: false,
                indirect_bindable: false,
                colors: &colors,
                depth: DepthUse::None,
                vertex_constants: &[],
                samples: 1,
                name,
            },
        )
    }

    /// A graphics pipeline as [`GraphicsPipelineDesc`] describes it.
    pub fn graphics(device: &Arc<Device>, desc: &GraphicsPipelineDesc<'_>) -> VkResult<Self> {
        let (constant_entries, constant_bytes) = specialization_constants(desc.vertex_constants);
        let specialization = vk::SpecializationInfo::default()
            .map_entries(&constant_entries)
            .data(&constant_bytes);
        let mut stages = vec![vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::VERTEX)
            .module(desc.vertex.raw())
            .name(c"main")
            .specialization_info(&specialization)];
        stages.extend(desc.geometry.map(stage));
        stages.push(stage(desc.fragment));
        let layout = desc.vertex_layout.unwrap_or(VertexLayout {
            stride: 0,
            attributes: &[],
        });
        let vertex_bindings = [vk::VertexInputBindingDescription::default()
            .binding(0)
            .stride(layout.stride)
            .input_rate(vk::VertexInputRate::VERTEX)];
        let vertex_attributes: Vec<vk::VertexInputAttributeDescription> = layout
            .attributes
            .iter()
            .enumerate()
            .map(|(location, &(format, offset))| {
                vk::VertexInputAttributeDescription::default()
                    .location(location as u32)
                    .binding(0)
                    .format(format)
                    .offset(offset)
            })
            .collect();
        let vertex_input = match desc.vertex_layout {
            Some(_) => vk::PipelineVertexInputStateCreateInfo::default()
                .vertex_binding_descriptions(&vertex_bindings)
                .vertex_attribute_descriptions(&vertex_attributes),
            None => vk::PipelineVertexInputStateCreateInfo::default(),
        };
        let input_assembly =
            vk::PipelineInputAssemblyStateCreateInfo::default().topology(desc.topology);
        Self::rasterizing(
            device,
            &RasterState {
                layout: desc.layout,
                depth_bias: desc.depth_bias,
                triangle_outlines: desc.triangle_outlines,
                cull_back_faces: desc.cull_back_faces,
                indirect_bindable: desc.indirect_bindable,
                colors: desc.colors,
                depth: desc.depth,
                samples: desc.samples,
                name: desc.name,
            },
            &stages,
            Some((&vertex_input, &input_assembly)),
        )
    }

    /// Creates a pipeline that rasterizes into `raster`'s targets from `stages`, with
    /// `vertex_input` and its input assembly (`None` for mesh-shader pipelines, which have
    /// neither).
    pub(super) fn rasterizing(
        device: &Arc<Device>,
        raster: &RasterState<'_>,
        stages: &[vk::PipelineShaderStageCreateInfo<'_>],
        vertex_input: Option<(
            &vk::PipelineVertexInputStateCreateInfo<'_>,
            &vk::PipelineInputAssemblyStateCreateInfo<'_>,
        )>,
    ) -> VkResult<Self> {
        let desc = raster;
        let viewport = vk::PipelineViewportStateCreateInfo::default()
            .viewport_count(1)
            .scissor_count(1);
        let rasterization = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(if desc.triangle_outlines {
                vk::PolygonMode::LINE
            } else {
                vk::PolygonMode::FILL
            })
            .cull_mode(if desc.cull_back_faces {
                vk::CullModeFlags::BACK
            } else {
                vk::CullModeFlags::NONE
            })
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .depth_bias_enable(desc.depth_bias)
            .depth_bias_constant_factor(1.0)
            .depth_bias_slope_factor(1.0)
            .line_width(1.0);
        let multisample = vk::PipelineMultisampleStateCreateInfo::default()
            .rasterization_samples(vk::SampleCountFlags::from_raw(desc.samples));
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(desc.depth != DepthUse::None)
            .depth_write_enable(desc.depth == DepthUse::TestAndWrite)
            .depth_compare_op(match desc.depth {
                DepthUse::TestBehind => vk::CompareOp::GREATER,
                DepthUse::TestEqual => vk::CompareOp::EQUAL,
                _ => vk::CompareOp::LESS_OR_EQUAL,
            });
        let blend_attachments: Vec<vk::PipelineColorBlendAttachmentState> = desc
            .colors
            .iter()
            .map(|target| {
                let state = vk::PipelineColorBlendAttachmentState::default().color_write_mask(
                    if target.writes {
                        vk::ColorComponentFlags::RGBA
                    } else {
                        vk::ColorComponentFlags::empty()
                    },
                );
                match target.blend {
                    Some(blend) => state
                        .blend_enable(true)
                        .src_color_blend_factor(blend.src_color)
                        .dst_color_blend_factor(blend.dst_color)
                        .color_blend_op(blend.color_op)
                        .src_alpha_blend_factor(blend.src_alpha)
                        .dst_alpha_blend_factor(blend.dst_alpha)
                        .alpha_blend_op(blend.alpha_op),
                    None => state,
                }
            })
            .collect();
        let blend =
            vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend_attachments);
        let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let color_formats: Vec<vk::Format> = desc.colors.iter().map(|c| c.format).collect();
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(&color_formats)
            .depth_attachment_format(if desc.depth == DepthUse::None {
                vk::Format::UNDEFINED
            } else {
                DEPTH_FORMAT
            });
        // Given, the flags replace the create info's own (which cadr leaves empty).
        let mut flags = vk::PipelineCreateFlags2CreateInfoKHR::default()
            .flags(super::dgc::PIPELINE_CREATE_2_INDIRECT_BINDABLE);
        let mut info = vk::GraphicsPipelineCreateInfo::default()
            .stages(stages)
            .viewport_state(&viewport)
            .rasterization_state(&rasterization)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(desc.layout.raw())
            .push_next(&mut rendering);
        if desc.indirect_bindable {
            info = info.push_next(&mut flags);
        }
        if let Some((vertex_input, input_assembly)) = vertex_input {
            info = info
                .vertex_input_state(vertex_input)
                .input_assembly_state(input_assembly);
        }
        let info = [info];
        // Lavapipe leaks what it allocated when a later allocation in this call fails.
        let pipelines = crate::timings::time(crate::timings::Phase::PipelineCreation, || {
            super::fault::with_first_host_memory_fault_only(|| {
                // SAFETY: every struct the info points to lives until the call returns; the
                // modules are alive during the call (pipelines do not keep them).
                unsafe {
                    device.raw().create_graphics_pipelines(
                        device.pipeline_cache(),
                        &info,
                        host_callbacks(),
                    )
                }
            })
        })
        .map_err(|(_, result)| result)
        .or_vk("vkCreateGraphicsPipelines")?;
        device.set_name(pipelines[0], desc.name);
        Ok(Self {
            device: Arc::clone(device),
            raw: pipelines[0],
        })
    }

    /// A compute pipeline running `shader`'s `main`.
    pub fn compute(
        device: &Arc<Device>,
        layout: &PipelineLayout,
        shader: &ShaderModule,
        name: &str,
    ) -> VkResult<Self> {
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(shader.raw())
            .name(c"main");
        let info = [vk::ComputePipelineCreateInfo::default()
            .stage(stage)
            .layout(layout.raw())];
        // SAFETY: the info and the module live for the call.
        let pipelines = crate::timings::time(crate::timings::Phase::PipelineCreation, || unsafe {
            device
                .raw()
                .create_compute_pipelines(device.pipeline_cache(), &info, host_callbacks())
        })
        .map_err(|(_, result)| result)
        .or_vk("vkCreateComputePipelines")?;
        device.set_name(pipelines[0], name);
        Ok(Self {
            device: Arc::clone(device),
            raw: pipelines[0],
        })
    }

    /// The Vulkan handle.
    pub fn raw(&self) -> vk::Pipeline {
        self.raw
    }
}

impl Drop for Pipeline {
    fn drop(&mut self) {
        // SAFETY: owners drop pipelines after the GPU finished the frames that use them.
        unsafe {
            self.device
                .raw()
                .destroy_pipeline(self.raw, host_callbacks())
        };
    }
}

/// Binding 0's stride and its attributes (format, offset) at locations 0, 1, ….
#[derive(Clone, Copy, Debug)]
pub struct VertexLayout<'a> {
    /// Bytes from one vertex to the next.
    pub stride: u32,
    /// Format and offset of each attribute, at locations 0, 1, ….
    pub attributes: &'a [(vk::Format, u32)],
}

/// How a pipeline uses the depth attachment ([`DEPTH_FORMAT`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthUse {
    /// Tested (LESS_OR_EQUAL) and written: opaque surfaces and lines.
    TestAndWrite,
    /// Tested, not written: translucent surfaces.
    Test,
    /// Passing only behind what was drawn (GREATER), not written: hidden lines.
    TestBehind,
    /// Passing only on what was drawn (EQUAL), not written: a second pass over the surface
    /// each pixel shows, drawn with the same vertex shader and depth bias as the first.
    TestEqual,
    /// No depth attachment: full-screen passes.
    None,
}

/// How a colour attachment is blended, as in `VkPipelineColorBlendAttachmentState`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Blend {
    /// Source factor for colour.
    pub src_color: vk::BlendFactor,
    /// Destination factor for colour.
    pub dst_color: vk::BlendFactor,
    /// Operation for colour.
    pub color_op: vk::BlendOp,
    /// Source factor for alpha.
    pub src_alpha: vk::BlendFactor,
    /// Destination factor for alpha.
    pub dst_alpha: vk::BlendFactor,
    /// Operation for alpha.
    pub alpha_op: vk::BlendOp,
}

impl Blend {
    /// Premultiplied colour over what is there: `src + dst × (1 − src.a)`.
    pub const PREMULTIPLIED_OVER: Blend = Blend {
        src_color: vk::BlendFactor::ONE,
        dst_color: vk::BlendFactor::ONE_MINUS_SRC_ALPHA,
        color_op: vk::BlendOp::ADD,
        src_alpha: vk::BlendFactor::ONE,
        dst_alpha: vk::BlendFactor::ONE_MINUS_SRC_ALPHA,
        alpha_op: vk::BlendOp::ADD,
    };

    /// Darkens what is there by the source's alpha, keeping its alpha (coverage):
    /// `dst × (1 − src.a)`.
    pub const DARKEN: Blend = Blend {
        src_color: vk::BlendFactor::ZERO,
        dst_color: vk::BlendFactor::ONE_MINUS_SRC_ALPHA,
        color_op: vk::BlendOp::ADD,
        src_alpha: vk::BlendFactor::ZERO,
        dst_alpha: vk::BlendFactor::ONE,
        alpha_op: vk::BlendOp::ADD,
    };

    /// Opaque colour under what is there, whose alpha is its coverage:
    /// `src × (1 − dst.a) + dst`, ending opaque.
    pub const UNDER: Blend = Blend {
        src_color: vk::BlendFactor::ONE_MINUS_DST_ALPHA,
        dst_color: vk::BlendFactor::ONE,
        color_op: vk::BlendOp::ADD,
        src_alpha: vk::BlendFactor::ONE_MINUS_DST_ALPHA,
        dst_alpha: vk::BlendFactor::ONE,
        alpha_op: vk::BlendOp::ADD,
    };
}

/// One colour attachment of a pipeline.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ColorTarget {
    /// Its format.
    pub format: vk::Format,
    /// Whether the pipeline writes it (all four components).
    pub writes: bool,
    /// How it is blended; `None` replaces.
    pub blend: Option<Blend>,
}

impl ColorTarget {
    /// Written, not blended.
    pub fn replaced(format: vk::Format) -> Self {
        Self {
            format,
            writes: true,
            blend: None,
        }
    }

    /// Not written (the attachment is there for the rendering's sake).
    pub fn untouched(format: vk::Format) -> Self {
        Self {
            format,
            writes: false,
            blend: None,
        }
    }
}

/// What cadr's graphics pipelines differ in. The rest is shared: dynamic viewport and scissor,
/// no face culling, LESS_OR_EQUAL depth tests, dynamic rendering.
pub struct GraphicsPipelineDesc<'a> {
    /// The pipeline layout.
    pub layout: &'a PipelineLayout,
    /// The vertex shader.
    pub vertex: &'a ShaderModule,
    /// A geometry shader between the two, or `None` (it needs
    /// [`super::Capabilities::geometry_shader`]).
    pub geometry: Option<&'a ShaderModule>,
    /// The fragment shader.
    pub fragment: &'a ShaderModule,
    /// `None` for no vertex input (vertex pulling).
    pub vertex_layout: Option<VertexLayout<'a>>,
    /// Triangles or lines.
    pub topology: vk::PrimitiveTopology,
    /// Pushes triangles back (constant and slope factor 1) so that edge lines win the depth test.
    pub depth_bias: bool,
    /// Draws triangles as their three edges (polygon mode LINE: the wireframe display mode).
    pub triangle_outlines: bool,
    /// Culls the triangles wound clockwise on screen: the back faces of parts wound
    /// counter-clockwise seen from outside.
    pub cull_back_faces: bool,
    /// May be put into an execution set of device-generated commands, for the GPU to pick
    /// per sequence (`VK_PIPELINE_CREATE_2_INDIRECT_BINDABLE_BIT_EXT`; only where
    /// [`super::Capabilities::device_generated_commands`]).
    pub indirect_bindable: bool,
    /// The colour attachments, in order (a pipeline that writes none of them draws depth
    /// only: the hidden-line display mode's surfaces).
    pub colors: &'a [ColorTarget],
    /// How it uses depth.
    pub depth: DepthUse,
    /// Values of the vertex shader's specialization constants 0, 1, … (u32 each).
    pub vertex_constants: &'a [u32],
    /// Samples per pixel of the attachments it draws into (1 without MSAA).
    pub samples: u32,
    /// The debug name.
    pub name: &'a str,
}

/// The stage that runs `module`'s `main`, for the stage it was compiled for.
pub(super) fn stage(module: &ShaderModule) -> vk::PipelineShaderStageCreateInfo<'static> {
    vk::PipelineShaderStageCreateInfo::default()
        .stage(module.stage().flag())
        .module(module.raw())
        .name(c"main")
}

/// The map entries and data of specialization constants 0, 1, … (constant_id = i is
/// `constants[i]`, a u32 each).
pub(super) fn specialization_constants(
    constants: &[u32],
) -> (Vec<vk::SpecializationMapEntry>, Vec<u8>) {
    let entries = (0..constants.len())
        .map(|i| {
            vk::SpecializationMapEntry::default()
                .constant_id(i as u32)
                .offset(4 * i as u32)
                .size(4)
        })
        .collect();
    let bytes = constants.iter().flat_map(|c| c.to_ne_bytes()).collect();
    (entries, bytes)
}

/// What every rasterizing pipeline (vertex or mesh shaders) says about its targets.
pub(super) struct RasterState<'a> {
    pub(super) layout: &'a PipelineLayout,
    pub(super) depth_bias: bool,
    pub(super) triangle_outlines: bool,
    pub(super) cull_back_faces: bool,
    pub(super) indirect_bindable: bool,
    pub(super) colors: &'a [ColorTarget],
    pub(super) depth: DepthUse,
    pub(super) samples: u32,
    pub(super) name: &'a str,
}

/// The pool sizes that hold one set of each of `layouts`: per descriptor type, the bindings
/// of that type across them.
fn pool_sizes(layouts: &[&DescriptorSetLayout]) -> Vec<vk::DescriptorPoolSize> {
    pool_sizes_of(
        layouts
            .iter()
            .flat_map(|layout| layout.types.iter().copied()),
    )
}

/// The pool sizes that hold `count` descriptors of each (type, count) of `bindings`.
fn pool_sizes_of(
    bindings: impl Iterator<Item = (vk::DescriptorType, u32)>,
) -> Vec<vk::DescriptorPoolSize> {
    let mut sizes: Vec<vk::DescriptorPoolSize> = Vec::new();
    for (ty, count) in bindings {
        match sizes.iter_mut().find(|size| size.ty == ty) {
            Some(size) => size.descriptor_count += count,
            None => sizes.push(
                vk::DescriptorPoolSize::default()
                    .ty(ty)
                    .descriptor_count(count),
            ),
        }
    }
    sizes
}

/// A descriptor pool, its sets and the layouts it was made for; destroyed together.
pub struct DescriptorSets {
    device: Arc<Device>,
    pool: vk::DescriptorPool,
    /// The sets, one per layout given.
    pub sets: Vec<vk::DescriptorSet>,
}

impl DescriptorSets {
    /// Allocates one set per layout from a pool sized for exactly them: as many descriptors
    /// of each type as their bindings hold (a device may refuse a set its pool has no room
    /// for, where another allocates it anyway).
    pub fn new(
        device: &Arc<Device>,
        name: &str,
        layouts: &[&DescriptorSetLayout],
    ) -> VkResult<Self> {
        let sizes = pool_sizes(layouts);
        let flags = if layouts.iter().any(|layout| layout.update_after_bind) {
            vk::DescriptorPoolCreateFlags::UPDATE_AFTER_BIND
        } else {
            vk::DescriptorPoolCreateFlags::empty()
        };
        let info = vk::DescriptorPoolCreateInfo::default()
            .flags(flags)
            .max_sets(layouts.len() as u32)
            .pool_sizes(&sizes);
        // SAFETY: the info lives for the call.
        let pool = unsafe { device.raw().create_descriptor_pool(&info, host_callbacks()) }
            .or_vk("vkCreateDescriptorPool")?;
        device.set_name(pool, name);
        let mut this = Self {
            device: Arc::clone(device),
            pool,
            sets: Vec::new(),
        };
        let raw_layouts: Vec<vk::DescriptorSetLayout> =
            layouts.iter().map(|layout| layout.raw).collect();
        let alloc = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(pool)
            .set_layouts(&raw_layouts);
        // SAFETY: the pool was sized for exactly these sets.
        this.sets = unsafe { device.raw().allocate_descriptor_sets(&alloc) }
            .or_vk("vkAllocateDescriptorSets")?;
        // The sets are not named (the pool is): Mesa 22.3's lavapipe does not free the names of
        // sets destroyed with their pool, which the leak check of the allocation callbacks sees.
        Ok(this)
    }

    /// Points `binding` of set `set` at `buffer` (whole range).
    pub fn write_buffer(
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
        // SAFETY: callers update sets only while no submitted command buffer uses them (frames
        // are waited for before the next is recorded).
        unsafe { self.device.raw().update_descriptor_sets(&write, &[]) };
    }
}

impl DescriptorSets {
    /// Points `binding` of set `set` at `view`, a sampled image in `SHADER_READ_ONLY_OPTIMAL`
    /// (read with `texelFetch`, no sampler).
    pub fn write_sampled_image(&self, set: usize, binding: u32, view: vk::ImageView) {
        self.write_sampled_images(set, binding, 0, &[view]);
    }

    /// Points elements `first..first + views.len()` of the array `binding` of set `set` at
    /// `views`, sampled images in `SHADER_READ_ONLY_OPTIMAL`.
    pub fn write_sampled_images(
        &self,
        set: usize,
        binding: u32,
        first: u32,
        views: &[vk::ImageView],
    ) {
        if views.is_empty() {
            return;
        }
        let infos: Vec<vk::DescriptorImageInfo> = views
            .iter()
            .map(|&view| {
                vk::DescriptorImageInfo::default()
                    .image_view(view)
                    .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)
            })
            .collect();
        let write = [vk::WriteDescriptorSet::default()
            .dst_set(self.sets[set])
            .dst_binding(binding)
            .dst_array_element(first)
            .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
            .image_info(&infos)];
        // SAFETY: as in `write_buffer`.
        unsafe { self.device.raw().update_descriptor_sets(&write, &[]) };
    }

    /// Points `binding` of set `set` at `sampler`.
    pub fn write_sampler(&self, set: usize, binding: u32, sampler: vk::Sampler) {
        let info = [vk::DescriptorImageInfo::default().sampler(sampler)];
        let write = [vk::WriteDescriptorSet::default()
            .dst_set(self.sets[set])
            .dst_binding(binding)
            .descriptor_type(vk::DescriptorType::SAMPLER)
            .image_info(&info)];
        // SAFETY: as in `write_buffer`.
        unsafe { self.device.raw().update_descriptor_sets(&write, &[]) };
    }
}

impl DescriptorSets {
    /// Points `binding` of set `set` at `view`, in `SHADER_READ_ONLY_OPTIMAL`, sampled with
    /// `sampler`.
    pub fn write_combined_image(
        &self,
        set: usize,
        binding: u32,
        view: vk::ImageView,
        sampler: vk::Sampler,
    ) {
        let info = [vk::DescriptorImageInfo::default()
            .image_view(view)
            .sampler(sampler)
            .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)];
        let write = [vk::WriteDescriptorSet::default()
            .dst_set(self.sets[set])
            .dst_binding(binding)
            .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
            .image_info(&info)];
        // SAFETY: as in `write_buffer`.
        unsafe { self.device.raw().update_descriptor_sets(&write, &[]) };
    }
}

impl Drop for DescriptorSets {
    fn drop(&mut self) {
        // SAFETY: owners drop their sets after the GPU is done with them; sets go with the pool.
        unsafe {
            self.device
                .raw()
                .destroy_descriptor_pool(self.pool, host_callbacks())
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pool_holds_every_binding_of_its_layouts() {
        use vk::DescriptorType as T;
        // The frame set's bindings, then a second layout's.
        let frame = [
            T::UNIFORM_BUFFER,
            T::STORAGE_BUFFER,
            T::STORAGE_BUFFER,
            T::STORAGE_BUFFER,
            T::STORAGE_BUFFER,
            T::COMBINED_IMAGE_SAMPLER,
            T::COMBINED_IMAGE_SAMPLER,
            T::STORAGE_BUFFER,
            T::STORAGE_BUFFER,
        ];
        let counts = |types: &[T]| -> Vec<(T, u32)> {
            pool_sizes_of(types.iter().map(|&ty| (ty, 1)))
                .iter()
                .map(|size| (size.ty, size.descriptor_count))
                .collect()
        };
        assert_eq!(
            counts(&frame),
            [
                (T::UNIFORM_BUFFER, 1),
                (T::STORAGE_BUFFER, 6),
                (T::COMBINED_IMAGE_SAMPLER, 2)
            ]
        );
        let two_sets: Vec<T> = frame
            .iter()
            .chain(&[T::SAMPLED_IMAGE; 2])
            .copied()
            .collect();
        assert_eq!(
            counts(&two_sets),
            [
                (T::UNIFORM_BUFFER, 1),
                (T::STORAGE_BUFFER, 6),
                (T::COMBINED_IMAGE_SAMPLER, 2),
                (T::SAMPLED_IMAGE, 2)
            ]
        );
        assert_eq!(counts(&[]), []);
        // An array binding counts its length.
        let table: Vec<(T, u32)> = pool_sizes_of(
            [
                (T::SAMPLER, 1),
                (T::SAMPLED_IMAGE, 4096),
                (T::SAMPLED_IMAGE, 1),
            ]
            .into_iter(),
        )
        .iter()
        .map(|size| (size.ty, size.descriptor_count))
        .collect();
        assert_eq!(table, [(T::SAMPLER, 1), (T::SAMPLED_IMAGE, 4097)]);
    }
}
