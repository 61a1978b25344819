//! The GPU scene's compute pipelines: the scatter of sparse uploads (`shaders/scatter.comp`)
//! and the transform hierarchy (`shaders/transforms.comp`), with their layouts and push
//! constants. Each GPU scene owns its own; the pipelines are made on first use.

use std::sync::{Arc, OnceLock};

use crate::error::RenderResult;
use crate::shaders::{self, ShaderSource};
use crate::vk::raw as vk;
use crate::vk::{DescriptorSetLayout, Device, Pipeline, PipelineLayout};

/// Push constants of `scatter.comp`: one dispatch scatters the items of one array.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ScatterParameters {
    /// Items in the dispatch.
    pub item_count: u32,
    /// 32-bit words per item, without its slot.
    pub item_words: u32,
    /// The index of the dispatch's first word in the update buffer.
    pub first_word: u32,
}

/// The stages of `transforms.comp` (see `gpu_scene/hierarchy.rs`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HierarchyStage {
    /// Moved roots mark themselves.
    Stamp = 0,
    /// Ranges of the roots not below another, laid end to end.
    Roots = 1,
    /// Every node multiplies the locals up to its root.
    Leaves = 2,
    /// The nodes one depth below their roots multiply their parent's world matrix.
    Level = 3,
}

/// Push constants of `transforms.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct HierarchyParameters {
    /// A [`HierarchyStage`].
    pub stage: u32,
    /// The index of the first local matrix's slot word in the update buffer.
    pub first_word: u32,
    /// Local matrices uploaded this frame (the moved roots among them are marked): the
    /// entries of the roots list.
    pub root_count: u32,
    /// This frame's stamp (never 0).
    pub stamp: u32,
    /// Nodes in the moved ranges.
    pub total: u32,
    /// The depth below the roots a `Level` dispatch updates.
    pub level: u32,
}

/// The scatter and transform hierarchy pipelines of one GPU scene.
pub struct ScenePipelines {
    device: Arc<Device>,
    /// The scatter pipeline's set: the compact updates and the array they go into.
    scatter_set_layout: DescriptorSetLayout,
    scatter_layout: PipelineLayout,
    /// Made on first use (each pipeline costs a shader compile and, on lavapipe, a JIT compile
    /// of 60–150 ms, so only what a scene uses is made).
    scatter: OnceLock<Pipeline>,
    /// The transform hierarchy's set: updates, locals, nodes, order, stamps, roots, worlds.
    hierarchy_set_layout: DescriptorSetLayout,
    hierarchy_layout: PipelineLayout,
    hierarchy: OnceLock<Pipeline>,
}

impl ScenePipelines {
    /// Creates the layouts; the pipelines are made on first use.
    pub fn new(device: &Arc<Device>) -> RenderResult<Self> {
        let compute = vk::ShaderStageFlags::COMPUTE;
        let compute_storage = (vk::DescriptorType::STORAGE_BUFFER, compute);
        let scatter_set_layout =
            DescriptorSetLayout::new(device, "scatter set layout", &[compute_storage; 2])?;
        let scatter_layout = PipelineLayout::new(
            device,
            "scatter layout",
            &[scatter_set_layout.raw()],
            std::mem::size_of::<ScatterParameters>() as u32,
            compute,
        )?;
        let hierarchy_set_layout =
            DescriptorSetLayout::new(device, "hierarchy set layout", &[compute_storage; 7])?;
        let hierarchy_layout = PipelineLayout::new(
            device,
            "hierarchy layout",
            &[hierarchy_set_layout.raw()],
            std::mem::size_of::<HierarchyParameters>() as u32,
            compute,
        )?;
        Ok(Self {
            device: Arc::clone(device),
            scatter_set_layout,
            scatter_layout,
            scatter: OnceLock::new(),
            hierarchy_set_layout,
            hierarchy_layout,
            hierarchy: OnceLock::new(),
        })
    }

    /// The scatter pipeline's set layout.
    pub fn scatter_set_layout(&self) -> &DescriptorSetLayout {
        &self.scatter_set_layout
    }

    /// The scatter pipeline's layout.
    pub fn scatter_layout(&self) -> vk::PipelineLayout {
        self.scatter_layout.raw()
    }

    /// The scatter compute pipeline.
    pub fn scatter(&self) -> RenderResult<vk::Pipeline> {
        self.compute(&self.scatter, &self.scatter_layout, &shaders::SCATTER_COMP)
    }

    /// The transform hierarchy's set layout.
    pub fn hierarchy_set_layout(&self) -> &DescriptorSetLayout {
        &self.hierarchy_set_layout
    }

    /// The transform hierarchy's pipeline layout.
    pub fn hierarchy_layout(&self) -> vk::PipelineLayout {
        self.hierarchy_layout.raw()
    }

    /// The transform hierarchy's compute pipeline.
    pub fn hierarchy(&self) -> RenderResult<vk::Pipeline> {
        self.compute(
            &self.hierarchy,
            &self.hierarchy_layout,
            &shaders::TRANSFORMS_COMP,
        )
    }

    /// The compute pipeline in `slot`, made from `shader` on first use.
    fn compute(
        &self,
        slot: &OnceLock<Pipeline>,
        layout: &PipelineLayout,
        shader: &ShaderSource,
    ) -> RenderResult<vk::Pipeline> {
        if let Some(pipeline) = slot.get() {
            return Ok(pipeline.raw());
        }
        let module = shaders::module(&self.device, shader)?;
        let made = Pipeline::compute(&self.device, layout, &module, shader.name)?;
        // Another thread may have made one meanwhile: the first is kept, `made` is dropped.
        Ok(slot.get_or_init(|| made).raw())
    }
}
