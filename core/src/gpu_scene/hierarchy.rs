//! The transform hierarchy on the GPU (seed 003's transform system, its "model explosion
//! view"): when no active technique reads world matrices on the host, a moved assembly node
//! uploads only its local matrix (through the sparse upload, marked as a moved root) and
//! `shaders/transforms.comp` recomputes the world matrices of the moved subtrees in the scene's
//! matrix buffer. The host does work in proportion to the moved nodes, not to what lies below
//! them.
//!
//! The GPU walks a layout of the tree: its nodes in depth-first order, so that each subtree is
//! one range, with each node's parent, range and depth. The layout is rebuilt (O(tree)) only
//! when the tree's structure changed since it was made and something moves.
//!
//! Each frame with moved roots runs, after the scatter:
//! 1. *stamp*: every moved root marks itself;
//! 2. *roots*: one work group drops the roots that lie below another moved root and lays the
//!    others' ranges end to end (a prefix sum);
//! 3. either *leaves*, one dispatch in which every node of a range multiplies the local
//!    matrices up to its root and the root's parent's world matrix, or *levels*, one dispatch
//!    per depth below the roots, each node multiplying its parent's world matrix, just
//!    written, by its local matrix. [`plan`] chooses from the shape of the moved subtrees:
//!    leaves cost the summed depths, levels a dispatch and a barrier per depth.
//!
//! Translations stay split into f32 high and low parts as everywhere on the GPU, and the
//! shader adds them with error-free sums, so a part far from the origin keeps its precision.

use std::sync::Arc;

use glam::DMat4;

use super::compute::{HierarchyParameters, HierarchyStage, ScenePipelines};
use crate::error::RenderResult;
use crate::tree::{BitSet, SceneTree};
use crate::vk::raw as vk;
use crate::vk::{memory_barrier, record_dispatch, Buffer, DescriptorSets, Device, MemoryLocation};

use super::geometry::usage;
use crate::commands_key::mix;
use crate::render::split_f64;

/// Where the world matrices of moved subtrees are computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transforms {
    /// On the host, in f64, and uploaded per changed slot: what techniques that read host
    /// matrices need.
    Host,
    /// On the GPU (the transform hierarchy): a moved node uploads its local matrix only.
    Gpu,
}

/// 32-bit words of one local matrix on the GPU: columns 0–2 as rotation and scale with the
/// translation's low part in w, then the translation's high part.
pub const LOCAL_WORDS: usize = 15;
/// Bytes of one local matrix on the GPU (with its slot, a moved node uploads 64 bytes).
pub const LOCAL_BYTES: usize = LOCAL_WORDS * 4;

/// The top bit of a slot word in the sparse upload marks a moved root for the hierarchy pass
/// (the scatter masks it off).
pub const MOVED_ROOT_MARK: u32 = 1 << 31;

const NONE: u32 = u32::MAX;

/// Work items a dispatch and its barrier cost, in units of one matrix product, for the plan.
const DISPATCH_COST: u64 = 4096;
/// What a thread that skips its node costs in a level dispatch, as a fraction of a product.
const SKIP_COST_DIVISOR: u64 = 8;

/// A local matrix as the GPU holds it (affine: the bottom row is taken as 0, 0, 0, 1).
pub fn gpu_local(local: &DMat4) -> [f32; LOCAL_WORDS] {
    let (high, low) = split_f64(local.w_axis.truncate());
    let m = local.as_mat4().to_cols_array_2d();
    [
        m[0][0], m[0][1], m[0][2], low[0], //
        m[1][0], m[1][1], m[1][2], low[1], //
        m[2][0], m[2][1], m[2][2], low[2], //
        high[0], high[1], high[2],
    ]
}

/// How the moved subtrees are brought up to date.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HierarchyMethod {
    /// One dispatch; every node multiplies the locals up to its root.
    Leaves,
    /// One dispatch per depth below the roots.
    Levels,
}

/// What one frame's hierarchy pass does (known on the host before recording).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HierarchyPlan {
    /// Moved roots uploaded (marked slots), nested ones included.
    pub roots: u32,
    /// Nodes whose world matrix is recomputed (the ranges of the roots not below another).
    pub nodes: u32,
    /// Depths below the roots (the level dispatches, less one).
    pub height: u32,
    /// The chosen method.
    pub method: HierarchyMethod,
}

/// The tree laid out for the GPU, with its shape per node.
struct Layout {
    structure_generation: u64,
    parent: Vec<u32>,
    /// Position in depth-first order (the start of the node's range).
    first: Vec<u32>,
    /// Nodes in the subtree.
    size: Vec<u32>,
    /// Depths below the node (0 for a leaf).
    height: Vec<u32>,
    /// Sum over the subtree of (depth below the node + 1): the products the leaf method does.
    walk: Vec<u64>,
}

impl Layout {
    fn build(tree: &SceneTree) -> (Self, Vec<[u32; 4]>, Vec<u32>) {
        let capacity = tree.node_capacity();
        let mut layout = Self {
            structure_generation: tree.structure_generation(),
            parent: vec![NONE; capacity],
            first: vec![0; capacity],
            size: vec![0; capacity],
            height: vec![0; capacity],
            walk: vec![0; capacity],
        };
        let mut depth = vec![0u32; capacity];
        let mut order = Vec::with_capacity(tree.node_count());
        let mut stack = vec![tree.root()];
        while let Some(t) = stack.pop() {
            let i = t as usize;
            layout.first[i] = order.len() as u32;
            order.push(t);
            if let Some(parent) = tree.parent(t) {
                layout.parent[i] = parent;
                depth[i] = depth[parent as usize] + 1;
            }
            stack.extend(tree.children(t).iter().rev());
        }
        for &t in order.iter().rev() {
            let i = t as usize;
            let (mut size, mut height, mut walk) = (1u32, 0u32, 1u64);
            for &c in tree.children(t) {
                let c = c as usize;
                size += layout.size[c];
                height = height.max(layout.height[c] + 1);
                walk += layout.walk[c] + u64::from(layout.size[c]);
            }
            (layout.size[i], layout.height[i], layout.walk[i]) = (size, height, walk);
        }
        let nodes = (0..capacity)
            .map(|i| [layout.parent[i], layout.first[i], depth[i], layout.size[i]])
            .collect();
        (layout, nodes, order)
    }
}

/// The hierarchy's GPU buffers and the host's copy of the layout.
pub(super) struct TransformHierarchy {
    device: Arc<Device>,
    layout: Option<Layout>,
    /// Per tree node: parent, first, depth, size.
    nodes: Option<Buffer>,
    /// Tree nodes in depth-first order.
    order: Option<Buffer>,
    /// Per tree node: the stamp of the last frame it was a moved root.
    stamps: Option<Buffer>,
    /// Per moved root: node, first, size (0 when below another root), prefix.
    roots: Option<Buffer>,
    stamp: u32,
    sets: Option<DescriptorSets>,
    /// The serials of the buffers the set was written for.
    written: [u64; 7],
    /// Counts the writes of the set (a recording that uses it is stale after one).
    sets_generation: u64,
    /// The moved roots while a plan is made (empty between plans).
    marked: BitSet,
    /// This frame's plan, made at sync.
    plan: Option<HierarchyPlan>,
    /// The pass made ready for recording, if any.
    ready: Option<ReadyPass>,
    /// A method chosen by the caller instead of the plan's (benchmarks, tests).
    pub(super) forced: Option<HierarchyMethod>,
}

impl TransformHierarchy {
    pub(super) fn new(device: &Arc<Device>) -> Self {
        Self {
            device: Arc::clone(device),
            layout: None,
            nodes: None,
            order: None,
            stamps: None,
            roots: None,
            stamp: 0,
            sets: None,
            written: [0; 7],
            sets_generation: 0,
            marked: BitSet::default(),
            plan: None,
            ready: None,
            forced: None,
        }
    }

    /// Forgets this frame's plan (every world matrix goes up from the host instead).
    pub(super) fn cancel(&mut self) {
        self.plan = None;
        self.ready = None;
    }

    /// Plans this frame's pass for `moved` roots (alive tree nodes, sorted, without repeats),
    /// laying the tree out again first if its structure changed. None when nothing moved.
    pub(super) fn plan(
        &mut self,
        tree: &SceneTree,
        moved: &[u32],
    ) -> RenderResult<Option<HierarchyPlan>> {
        self.plan = None;
        if moved.is_empty() {
            return Ok(None);
        }
        if self
            .layout
            .as_ref()
            .is_none_or(|l| l.structure_generation != tree.structure_generation())
        {
            self.upload_layout(tree)?;
        }
        let Some(layout) = &self.layout else {
            return Ok(None);
        };
        let mut chosen = plan(layout, moved, &mut self.marked);
        chosen.method = self.forced.unwrap_or(chosen.method);
        self.plan = Some(chosen);
        self.ensure_roots(moved.len())?;
        Ok(self.plan)
    }

    fn upload_layout(&mut self, tree: &SceneTree) -> RenderResult<()> {
        let (layout, nodes, order) = Layout::build(tree);
        let device = &self.device;
        let storage = usage(device, vk::BufferUsageFlags::empty());
        let make = |name: &str, bytes: &[u8]| -> RenderResult<Buffer> {
            let mut buffer = Buffer::new(
                device,
                name,
                (bytes.len() as u64).max(16),
                storage,
                MemoryLocation::GpuOnly,
            )?;
            buffer.upload_at(0, bytes)?;
            Ok(buffer)
        };
        self.nodes = Some(make("hierarchy nodes", bytemuck::cast_slice(&nodes))?);
        self.order = Some(make("hierarchy order", bytemuck::cast_slice(&order))?);
        let stamps_needed = (nodes.len() * 4) as u64;
        if self
            .stamps
            .as_ref()
            .is_none_or(|s| s.size() < stamps_needed)
        {
            let zeros = vec![0u8; nodes.len().next_power_of_two().max(64) * 4];
            self.stamps = Some(make("hierarchy stamps", &zeros)?);
        }
        self.layout = Some(layout);
        Ok(())
    }

    fn ensure_roots(&mut self, count: usize) -> RenderResult<()> {
        let needed = (count * 16) as u64;
        if self.roots.as_ref().is_none_or(|r| r.size() < needed) {
            self.roots = Some(Buffer::new(
                &self.device,
                "hierarchy roots",
                needed.next_power_of_two().max(1024),
                vk::BufferUsageFlags::STORAGE_BUFFER,
                MemoryLocation::GpuOnly,
            )?);
        }
        Ok(())
    }

    /// Readies this frame's pass (after the scatter that writes the locals): `updates` holds
    /// the scatter's compact items, `local_count` locals from `first_word` (the moved roots
    /// among them marked); `locals` and `worlds` are the scene's arrays; `same_roots` says
    /// whether the moved roots are those of the last pass made ready. Returns the plan it
    /// carries out, which [`TransformHierarchy::record`] records.
    pub(super) fn prepare(
        &mut self,
        pipelines: &ScenePipelines,
        updates: &Buffer,
        (first_word, local_count): (u32, u32),
        (locals, worlds): (&Buffer, &Buffer),
        same_roots: bool,
    ) -> RenderResult<Option<HierarchyPlan>> {
        self.ready = None;
        let Some(plan) = self.plan.take() else {
            return Ok(None);
        };
        if local_count == 0 || plan.nodes == 0 {
            return Ok(None);
        }
        let (Some(nodes), Some(order), Some(stamps), Some(roots)) =
            (&self.nodes, &self.order, &self.stamps, &self.roots)
        else {
            return Ok(None);
        };
        let targets = [updates, locals, nodes, order, stamps, roots, worlds];
        let serials = targets.map(Buffer::serial);
        if self.sets.is_none() {
            self.sets = Some(DescriptorSets::new(
                &self.device,
                "hierarchy",
                &[pipelines.hierarchy_set_layout()],
            )?);
            self.sets_generation += 1;
        }
        let Some(sets) = &self.sets else {
            return Ok(None);
        };
        if self.written != serials {
            for (binding, buffer) in targets.iter().enumerate() {
                sets.write_buffer(
                    0,
                    binding as u32,
                    vk::DescriptorType::STORAGE_BUFFER,
                    buffer.raw(),
                    vk::WHOLE_SIZE,
                );
            }
            self.written = serials;
            self.sets_generation += 1;
        }
        // A new stamp tells this frame's roots from the last one's; with the same roots, the
        // nodes that carry the last stamp are exactly this frame's roots, so it serves again
        // (and the pass records the same commands).
        if !same_roots || self.stamp == 0 {
            self.stamp = self.stamp.wrapping_add(1).max(1);
        }
        self.ready = Some(ReadyPass {
            plan,
            first_word,
            local_count,
        });
        Ok(Some(plan))
    }

    /// What the commands [`TransformHierarchy::record`] records for the pass made ready
    /// depend on: equal keys record equal commands.
    pub(super) fn commands_key(&self) -> u64 {
        let Some(ready) = &self.ready else {
            return 0;
        };
        let plan = ready.plan;
        let mut key = mix(self.sets_generation, u64::from(self.stamp));
        key = mix(
            key,
            u64::from(ready.first_word) << 32 | u64::from(ready.local_count),
        );
        key = mix(key, u64::from(plan.nodes) << 32 | u64::from(plan.height));
        mix(key, plan.method as u64)
    }

    /// Records the pass made ready (nothing when none is).
    pub(super) fn record(
        &self,
        pipelines: &ScenePipelines,
        command_buffer: vk::CommandBuffer,
    ) -> RenderResult<()> {
        let (Some(ready), Some(sets)) = (&self.ready, &self.sets) else {
            return Ok(());
        };
        let plan = ready.plan;
        let pipeline = (pipelines.hierarchy()?, pipelines.hierarchy_layout());
        let device = &self.device;
        let dispatch = |stage: HierarchyStage, level: u32, groups: u32| {
            let parameters = HierarchyParameters {
                stage: stage as u32,
                first_word: ready.first_word,
                root_count: ready.local_count,
                stamp: self.stamp,
                total: plan.nodes,
                level,
            };
            compute_barrier(device, command_buffer);
            record_dispatch(
                device,
                command_buffer,
                pipeline,
                sets.sets[0],
                bytemuck::bytes_of(&parameters),
                groups,
            );
        };
        let node_groups = plan.nodes.div_ceil(64);
        dispatch(HierarchyStage::Stamp, 0, ready.local_count.div_ceil(64));
        dispatch(HierarchyStage::Roots, 0, 1);
        match plan.method {
            HierarchyMethod::Leaves => dispatch(HierarchyStage::Leaves, 0, node_groups),
            HierarchyMethod::Levels => {
                for level in 0..=plan.height {
                    dispatch(HierarchyStage::Level, level, node_groups);
                }
            }
        }
        Ok(())
    }
}

/// A pass made ready for recording: its plan and where its roots lie in the update buffer.
#[derive(Clone, Copy, Debug)]
struct ReadyPass {
    plan: HierarchyPlan,
    first_word: u32,
    local_count: u32,
}

/// Compute writes before the barrier are seen by compute reads and writes after it.
fn compute_barrier(device: &Device, command_buffer: vk::CommandBuffer) {
    let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
    memory_barrier(
        device,
        command_buffer,
        (compute, vk::AccessFlags2::SHADER_WRITE),
        (
            compute,
            vk::AccessFlags2::SHADER_READ | vk::AccessFlags2::SHADER_WRITE,
        ),
    );
}

/// The plan for `moved` roots: the ranges of the roots that lie below no other moved root, and
/// the cheaper method for their shape. `marked` is scratch, empty before and after.
fn plan(layout: &Layout, moved: &[u32], marked: &mut BitSet) -> HierarchyPlan {
    for &t in moved {
        marked.insert(t);
    }
    let below_another = |t: u32| {
        let mut p = layout.parent[t as usize];
        while p != NONE {
            if marked.contains(p) {
                return true;
            }
            p = layout.parent[p as usize];
        }
        false
    };
    let (mut nodes, mut height, mut walk) = (0u64, 0u32, 0u64);
    for &t in moved {
        if below_another(t) {
            continue;
        }
        let i = t as usize;
        nodes += u64::from(layout.size[i]);
        height = height.max(layout.height[i]);
        walk += layout.walk[i];
    }
    marked.clear();
    let levels = nodes + u64::from(height + 1) * (nodes / SKIP_COST_DIVISOR + DISPATCH_COST);
    HierarchyPlan {
        roots: moved.len() as u32,
        nodes: nodes as u32,
        height,
        method: if levels < walk {
            HierarchyMethod::Levels
        } else {
            HierarchyMethod::Leaves
        },
    }
}
