//! Safe views of the ABI structs a technique receives.

use std::ffi::c_void;

use ash::vk;
use ash::vk::Handle;
use cadr_plugin_abi as abi;

fn slice<'a, T>(pointer: *const T, count: usize) -> &'a [T] {
    if pointer.is_null() || count == 0 {
        &[]
    } else {
        // SAFETY: the host guarantees `count` valid entries for the frame.
        unsafe { std::slice::from_raw_parts(pointer, count) }
    }
}

/// Which instances one pass needs: the host's filter and, since ABI 1.11, its exclusion.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct PassFilter {
    /// The instances the pass may need ([`abi::CadrPassFilter`]).
    pub keep: abi::CadrPassFilter,
    /// Of those, the ones it does not need ([`abi::CadrPassExclusion`]).
    pub exclude: abi::CadrPassExclusion,
}

impl PassFilter {
    /// Whether an instance with `flags` is needed.
    pub fn keeps(&self, flags: abi::CadrInstanceFlags) -> bool {
        self.keep.keeps(flags) && !self.exclude.excludes(flags)
    }
}

/// The filters of a context's `count` passes: filters and exclusions, each at its pointer
/// where the context's `size` covers the pointer's field (at its offset) and the pointer is not
/// null; else every pass keeps every instance and excludes none.
fn pass_filters<'a>(
    size: u32,
    (filters_at, filters): (usize, *const abi::CadrPassFilter),
    (exclusions_at, exclusions): (usize, *const abi::CadrPassExclusion),
    count: u32,
) -> impl Iterator<Item = PassFilter> + 'a {
    let covers = |at: usize| size as usize >= at + std::mem::size_of::<usize>();
    let count = count as usize;
    let filters: &'a [abi::CadrPassFilter] = if covers(filters_at) {
        slice(filters, count)
    } else {
        &[]
    };
    let exclusions: &'a [abi::CadrPassExclusion] = if covers(exclusions_at) {
        slice(exclusions, count)
    } else {
        &[]
    };
    (0..count).map(move |pass| PassFilter {
        keep: filters.get(pass).copied().unwrap_or_default(),
        exclude: exclusions.get(pass).copied().unwrap_or_default(),
    })
}

/// The `pass_filters` method of a view whose `raw` context of type `$context` has
/// `pass_filters` and `pass_exclusions`.
macro_rules! pass_filters_method {
    ($context:ty) => {
        /// Since ABI 1.9: the filter of each pass (which instances it needs), one per pass,
        /// with its exclusion since ABI 1.11; every instance for a host older than ABI 1.9 or
        /// one that passes none.
        pub fn pass_filters(&self) -> impl Iterator<Item = PassFilter> + 'a {
            let raw = self.raw;
            let filters = (
                std::mem::offset_of!($context, pass_filters),
                raw.pass_filters,
            );
            let exclusions = (
                std::mem::offset_of!($context, pass_exclusions),
                raw.pass_exclusions,
            );
            pass_filters(raw.size, filters, exclusions, raw.pass_count)
        }
    };
}

/// The extension of `kind` in `chain` as a `T` (which starts with its header), where the
/// writer's struct is at least as long as `T`.
///
/// # Safety
/// `chain` is null or a valid chain of extension structs alive for `'a`, and an extension of
/// `kind` is a `T`.
unsafe fn extension<'a, T>(
    chain: *const abi::CadrExtension,
    kind: abi::CadrExtensionKind,
) -> Option<&'a T> {
    // SAFETY: the caller's contract.
    let header = unsafe { abi::find_extension(chain, kind) }?;
    if (header.size as usize) < std::mem::size_of::<T>() {
        return None;
    }
    // SAFETY: an extension of this kind is a `T` (its header first) of at least that size.
    Some(unsafe { &*std::ptr::from_ref(header).cast::<T>() })
}

/// The scene during one frame.
#[derive(Clone, Copy, Debug)]
pub struct Scene<'a> {
    raw: &'a abi::CadrSceneView,
}

impl<'a> Scene<'a> {
    /// Wraps the host's view.
    ///
    /// # Safety
    /// `raw` is null or a valid scene view for the frame.
    pub unsafe fn from_raw(raw: *const abi::CadrSceneView) -> Option<Self> {
        // SAFETY: per the contract.
        unsafe { raw.as_ref() }.map(|raw| Self { raw })
    }

    /// The raw view (to pass on).
    pub fn raw(&self) -> &'a abi::CadrSceneView {
        self.raw
    }

    /// The scene's clusters ([`abi::CadrSceneClusters`]), from a host of ABI 1.14 or later.
    pub fn clusters(&self) -> Option<&'a abi::CadrSceneClusters> {
        let end =
            std::mem::offset_of!(abi::CadrSceneView, extensions) + std::mem::size_of::<usize>();
        if (self.raw.size as usize) < end {
            return None;
        }
        // SAFETY: the host's chain is valid as long as the view; an extension of this kind is a
        // `CadrSceneClusters`.
        unsafe { extension(self.raw.extensions, abi::CADR_EXTENSION_SCENE_CLUSTERS) }
    }

    /// The boxes of the scene's clusters ([`abi::CadrSceneClusterBoxes`]), from a host of ABI
    /// 1.20 or later; `None` from an older host, whose clusters have only their spheres.
    pub fn cluster_boxes(&self) -> Option<&'a abi::CadrSceneClusterBoxes> {
        self.clusters()?;
        // SAFETY: the host's chain (checked to be there by `clusters`) is valid as long as the
        // view; an extension of this kind is a `CadrSceneClusterBoxes`.
        unsafe { extension(self.raw.extensions, abi::CADR_EXTENSION_SCENE_CLUSTER_BOXES) }
    }

    /// The boxes of the instances' parts ([`abi::CadrScenePartBoxes`]), from a host of ABI 1.20
    /// or later; `None` from an older host, whose parts have only their spheres.
    pub fn part_boxes(&self) -> Option<&'a abi::CadrScenePartBoxes> {
        self.clusters()?;
        // SAFETY: the host's chain (checked to be there by `clusters`) is valid as long as the
        // view; an extension of this kind is a `CadrScenePartBoxes`.
        unsafe { extension(self.raw.extensions, abi::CADR_EXTENSION_SCENE_PART_BOXES) }
    }

    /// The geometry streaming's requests ([`abi::CadrSceneStreaming`]), from a host of ABI 1.21
    /// or later whose scene streams; `None` otherwise (every geometry at full detail).
    pub fn streaming(&self) -> Option<&'a abi::CadrSceneStreaming> {
        self.clusters()?;
        // SAFETY: the host's chain (checked to be there by `clusters`) is valid as long as the
        // view; an extension of this kind is a `CadrSceneStreaming`.
        unsafe { extension(self.raw.extensions, abi::CADR_EXTENSION_SCENE_STREAMING) }
    }

    /// Which frame slot is being recorded ([`abi::CadrFrameSlot`]), from a host of ABI 1.15 or
    /// later; `None` from an older host, which records one frame at a time (slot 0 of 1, every
    /// earlier frame finished).
    pub fn frame_slot(&self) -> Option<&'a abi::CadrFrameSlot> {
        let end =
            std::mem::offset_of!(abi::CadrSceneView, extensions) + std::mem::size_of::<usize>();
        if (self.raw.size as usize) < end {
            return None;
        }
        // SAFETY: the host's chain is valid as long as the view; an extension of this kind is a
        // `CadrFrameSlot`.
        unsafe { extension(self.raw.extensions, abi::CADR_EXTENSION_FRAME_SLOT) }
    }

    /// Whether the host asks for parameter blocks this frame ([`abi::CadrParameterBlocks`],
    /// from a host of ABI 1.22 or later where the parameter path, the submission and the GPU
    /// culler announce [`abi::CADR_TRAIT_PARAMETER_BLOCKS`]): the culler writes each command
    /// after its instance's [`abi::CadrParameterBlock`], and the submission pushes it.
    pub fn parameter_blocks(&self) -> bool {
        // The chain is there where the frame slot is (ABI 1.15 or later).
        self.frame_slot().is_some_and(|_| {
            // SAFETY: the host's chain is valid as long as the view; an extension of this kind
            // is a `CadrParameterBlocks`.
            let blocks: Option<&abi::CadrParameterBlocks> =
                unsafe { extension(self.raw.extensions, abi::CADR_EXTENSION_PARAMETER_BLOCKS) };
            blocks.is_some()
        })
    }

    /// Every instance id's instance.
    pub fn instances(&self) -> &'a [abi::CadrInstance] {
        slice(self.raw.instances, self.raw.instance_count as usize)
    }

    /// The drawn bits (one per instance id).
    pub fn drawn_bits(&self) -> &'a [u64] {
        slice(
            self.raw.drawn_bits,
            (self.raw.instance_count as usize).div_ceil(64),
        )
    }

    /// Whether instance `id` is drawn this frame.
    pub fn is_drawn(&self, id: u32) -> bool {
        self.drawn_bits()
            .get(id as usize / 64)
            .is_some_and(|word| word >> (id % 64) & 1 == 1)
    }

    /// The drawn instance ids, ascending (walked by trailing zeros).
    pub fn drawn_ids(&self) -> impl Iterator<Item = u32> + 'a {
        self.drawn_bits()
            .iter()
            .enumerate()
            .flat_map(|(index, &word)| {
                let mut bits = word;
                std::iter::from_fn(move || {
                    (bits != 0).then(|| {
                        let bit = bits.trailing_zeros();
                        bits &= bits - 1;
                        index as u32 * 64 + bit
                    })
                })
            })
    }

    /// Matrices on the CPU.
    pub fn matrices(&self) -> &'a [abi::CadrMatrix] {
        slice(self.raw.matrices, self.raw.matrix_count as usize)
    }

    /// Materials on the CPU.
    pub fn materials(&self) -> &'a [abi::CadrMaterial] {
        slice(self.raw.materials, self.raw.material_count as usize)
    }

    /// Matrix slots changed since the last frame.
    pub fn dirty_matrices(&self) -> &'a [u32] {
        slice(
            self.raw.dirty_matrices,
            self.raw.dirty_matrix_count as usize,
        )
    }

    /// Material slots changed since the last frame.
    pub fn dirty_materials(&self) -> &'a [u32] {
        slice(
            self.raw.dirty_materials,
            self.raw.dirty_material_count as usize,
        )
    }
}

/// A `VkBuffer` from a buffer reference.
pub fn buffer(reference: &abi::CadrBufferRef) -> vk::Buffer {
    vk::Buffer::from_raw(reference.buffer)
}

/// What a path binds with.
#[derive(Debug)]
pub struct Bind<'a> {
    raw: &'a abi::CadrBindContext,
}

impl<'a> Bind<'a> {
    /// Wraps the host's (or submission's) bind context.
    ///
    /// # Safety
    /// `raw` is a valid bind context for the call.
    pub unsafe fn from_raw(raw: *const abi::CadrBindContext) -> Option<Self> {
        // SAFETY: per the contract.
        unsafe { raw.as_ref() }.map(|raw| Self { raw })
    }

    /// The command buffer.
    pub fn command_buffer(&self) -> vk::CommandBuffer {
        vk::CommandBuffer::from_raw(self.raw.command_buffer as u64)
    }

    /// The pipeline layout.
    pub fn layout(&self) -> vk::PipelineLayout {
        vk::PipelineLayout::from_raw(self.raw.pipeline_layout)
    }

    /// `CADR_PASS_*`.
    pub fn pass_kind(&self) -> abi::CadrPassKind {
        self.raw.pass_kind
    }

    /// The scene.
    pub fn scene(&self) -> Scene<'a> {
        Scene {
            // SAFETY: the context's scene is valid for the frame.
            raw: unsafe { &*self.raw.scene },
        }
    }

    /// Adds to this recording's counters.
    pub fn count(&self, add: impl FnOnce(&mut abi::CadrStats)) {
        // SAFETY: each recording thread has its own counters, valid for the call.
        if let Some(stats) = unsafe { self.raw.stats.as_mut() } {
            add(stats);
        }
    }
}

/// A path (vertex or parameter) the submission drives, called through its vtable.
#[derive(Clone, Copy, Debug)]
pub struct Path<V> {
    raw: abi::CadrPathRef<V>,
}

// SAFETY: the ABI requires the bind functions to be thread-safe.
unsafe impl<V> Send for Path<V> {}
// SAFETY: as above.
unsafe impl<V> Sync for Path<V> {}

impl Path<abi::CadrVertexPathVtable> {
    /// Binds what stays bound for the pass.
    pub fn bind_pass(&self, bind: &abi::CadrBindContext, state: &mut abi::CadrBindState) {
        // SAFETY: the host passes a live instance and its vtable.
        if let Some(f) = unsafe { (*self.raw.vtable).bind_pass } {
            // SAFETY: as above; the pointers are valid for the call.
            unsafe { f(self.raw.instance, bind, state) }
        }
    }

    /// Binds for the draw of `drawn`; where the binding starts.
    pub fn bind_draw(
        &self,
        bind: &abi::CadrBindContext,
        drawn: &abi::CadrInstance,
        state: &mut abi::CadrBindState,
    ) -> abi::CadrDrawBase {
        // SAFETY: as in bind_pass.
        match unsafe { (*self.raw.vtable).bind_draw } {
            // SAFETY: as above.
            Some(f) => unsafe { f(self.raw.instance, bind, drawn, state) },
            None => abi::CadrDrawBase::default(),
        }
    }
}

impl Path<abi::CadrParameterPathVtable> {
    /// Binds what stays bound for the pass.
    pub fn bind_pass(&self, bind: &abi::CadrBindContext, state: &mut abi::CadrBindState) {
        // SAFETY: the host passes a live instance and its vtable.
        if let Some(f) = unsafe { (*self.raw.vtable).bind_pass } {
            // SAFETY: as above; the pointers are valid for the call.
            unsafe { f(self.raw.instance, bind, state) }
        }
    }

    /// Binds instance `id`'s parameters; the `firstInstance` to draw with.
    pub fn bind_draw(
        &self,
        bind: &abi::CadrBindContext,
        id: u32,
        drawn: &abi::CadrInstance,
        state: &mut abi::CadrBindState,
    ) -> u32 {
        // SAFETY: as in bind_pass.
        match unsafe { (*self.raw.vtable).bind_draw } {
            // SAFETY: as above.
            Some(f) => unsafe { f(self.raw.instance, bind, id, drawn, state) },
            None => id,
        }
    }
}

/// What a submission records with.
#[derive(Debug)]
pub struct Record<'a> {
    raw: &'a abi::CadrRecordContext,
}

impl<'a> Record<'a> {
    /// Wraps the host's record context.
    ///
    /// # Safety
    /// `raw` is a valid record context for the call.
    pub unsafe fn from_raw(raw: *const abi::CadrRecordContext) -> Option<Self> {
        // SAFETY: per the contract.
        unsafe { raw.as_ref() }.map(|raw| Self { raw })
    }

    /// The primary command buffer.
    pub fn command_buffer(&self) -> vk::CommandBuffer {
        vk::CommandBuffer::from_raw(self.raw.command_buffer as u64)
    }

    /// The pipeline layout.
    pub fn layout(&self) -> vk::PipelineLayout {
        vk::PipelineLayout::from_raw(self.raw.pipeline_layout)
    }

    /// The frame uniforms' set (set 0).
    pub fn frame_set(&self) -> vk::DescriptorSet {
        vk::DescriptorSet::from_raw(self.raw.frame_set)
    }

    /// The passes.
    pub fn passes(&self) -> &'a [abi::CadrPass] {
        slice(self.raw.passes, self.raw.pass_count as usize)
    }

    /// The format of the pass's colour attachment, where the host says it (ABI 1.1 and later;
    /// the pick pass draws ids into R32_UINT): secondary command buffers inherit it. `None`
    /// means the device's colour format (`CadrVulkan::color_format`).
    pub fn color_format(&self) -> Option<vk::Format> {
        let end = std::mem::offset_of!(abi::CadrRecordContext, color_format) + 4;
        (self.raw.size as usize >= end && self.raw.color_format != 0)
            .then(|| vk::Format::from_raw(self.raw.color_format))
    }

    /// Every colour attachment's format, in order: the pass's (`default` where the host does
    /// not say) and, since ABI 1.7, the transparency targets the rendering also has. Secondary
    /// command buffers inherit all of them.
    pub fn color_formats(&self, default: vk::Format) -> Vec<vk::Format> {
        let mut formats = vec![self.color_format().unwrap_or(default)];
        let end = std::mem::offset_of!(abi::CadrRecordContext, extra_color_formats)
            + std::mem::size_of::<[i32; 2]>();
        if self.raw.size as usize >= end {
            let count = (self.raw.extra_color_count as usize).min(2);
            formats.extend(
                self.raw.extra_color_formats[..count]
                    .iter()
                    .map(|&f| vk::Format::from_raw(f)),
            );
        }
        formats
    }

    /// Since ABI 1.8: the samples per pixel of the rendering's attachments (1 without MSAA,
    /// and where the host does not say): secondary command buffers inherit it.
    pub fn rasterization_samples(&self) -> vk::SampleCountFlags {
        let end = std::mem::offset_of!(abi::CadrRecordContext, rasterization_samples) + 4;
        if self.raw.size as usize >= end && self.raw.rasterization_samples != 0 {
            vk::SampleCountFlags::from_raw(self.raw.rasterization_samples)
        } else {
            vk::SampleCountFlags::TYPE_1
        }
    }

    pass_filters_method!(abi::CadrRecordContext);

    /// Since ABI 1.3: the draw sources a GPU culler wrote for this phase, one per pass, or
    /// `None` when the submission draws its own lists.
    pub fn gpu_draws(&self) -> Option<&'a [abi::CadrGpuDraws]> {
        let end = std::mem::offset_of!(abi::CadrRecordContext, phase) + 4;
        if (self.raw.size as usize) < end || self.raw.gpu_draws.is_null() {
            return None;
        }
        Some(slice(self.raw.gpu_draws, self.raw.pass_count as usize))
    }

    /// Since ABI 1.3: the phase of the frame being recorded (0 for older hosts).
    pub fn phase(&self) -> u32 {
        let end = std::mem::offset_of!(abi::CadrRecordContext, phase) + 4;
        if (self.raw.size as usize) < end {
            0
        } else {
            self.raw.phase
        }
    }

    /// Target size.
    pub fn extent(&self) -> vk::Extent2D {
        vk::Extent2D {
            width: self.raw.width,
            height: self.raw.height,
        }
    }

    /// The scene.
    pub fn scene(&self) -> Scene<'a> {
        Scene {
            // SAFETY: the context's scene is valid for the frame.
            raw: unsafe { &*self.raw.scene },
        }
    }

    /// The vertex path.
    pub fn vertex(&self) -> Path<abi::CadrVertexPathVtable> {
        Path {
            raw: self.raw.vertex,
        }
    }

    /// The parameter path.
    pub fn parameters(&self) -> Path<abi::CadrParameterPathVtable> {
        Path {
            raw: self.raw.parameters,
        }
    }

    /// Changes whenever recorded commands would differ.
    pub fn commands_key(&self) -> u64 {
        self.raw.commands_key
    }

    /// A bind context for recording `pass_kind` into `command_buffer`, counting into `stats`
    /// (which must outlive its use).
    pub fn bind_context(
        &self,
        command_buffer: vk::CommandBuffer,
        pass_kind: abi::CadrPassKind,
        stats: *mut abi::CadrStats,
    ) -> abi::CadrBindContext {
        abi::CadrBindContext {
            size: std::mem::size_of::<abi::CadrBindContext>() as u32,
            command_buffer: command_buffer.as_raw() as *mut c_void,
            pipeline_layout: self.raw.pipeline_layout,
            pass_kind,
            scene: self.raw.scene,
            stats,
        }
    }

    /// The frame's counters, to pass to bind contexts recorded on this thread.
    pub fn stats(&self) -> *mut abi::CadrStats {
        self.raw.stats
    }

    /// Adds to the frame's counters.
    pub fn count(&self, add: impl FnOnce(&mut abi::CadrStats)) {
        // SAFETY: the host's counters are valid for the call and not shared during it.
        if let Some(stats) = unsafe { self.raw.stats.as_mut() } {
            add(stats);
        }
    }
}

/// What culling reads.
#[derive(Debug)]
pub struct CullInput<'a> {
    raw: &'a abi::CadrCullInput,
}

impl<'a> CullInput<'a> {
    /// Wraps the host's input.
    ///
    /// # Safety
    /// `raw` is a valid cull input for the call.
    pub unsafe fn from_raw(raw: *const abi::CadrCullInput) -> Option<Self> {
        // SAFETY: per the contract.
        unsafe { raw.as_ref() }.map(|raw| Self { raw })
    }

    /// The scene.
    pub fn scene(&self) -> Scene<'a> {
        Scene {
            // SAFETY: valid for the call.
            raw: unsafe { &*self.raw.scene },
        }
    }

    /// Candidate bits.
    pub fn candidate_bits(&self) -> &'a [u64] {
        let words = (self.scene().raw.instance_count as usize).div_ceil(64);
        slice(self.raw.candidate_bits, words)
    }

    /// World matrices (f64, column-major) per matrix slot.
    pub fn world_matrices(&self) -> &'a [[f64; 16]] {
        slice(
            self.raw.world_matrices.cast::<[f64; 16]>(),
            self.scene().raw.matrix_count as usize,
        )
    }

    /// The frustum planes.
    pub fn planes(&self) -> &'a [[f64; 4]; 6] {
        &self.raw.planes
    }

    /// Since ABI 1.9: the world-space section planes the view is cut with (none for older
    /// hosts), each keeping `dot(n, p) + w >= 0`.
    pub fn section_planes(&self) -> &'a [[f64; 4]] {
        let end = std::mem::offset_of!(abi::CadrCullInput, section_planes)
            + std::mem::size_of::<[[f64; 4]; 6]>();
        if (self.raw.size as usize) < end {
            return &[];
        }
        let count = (self.raw.section_plane_count as usize).min(self.raw.section_planes.len());
        &self.raw.section_planes[..count]
    }
}

/// What culling writes.
#[derive(Debug)]
pub struct CullOutput<'a> {
    /// Bits of instances that pass.
    pub visible_bits: &'a mut [u64],
    /// Bits that changed since the last frame.
    pub changed_bits: &'a mut [u64],
}

impl<'a> CullOutput<'a> {
    /// Wraps the host's output.
    ///
    /// # Safety
    /// `raw` is a valid cull output for the call, its arrays not aliased.
    pub unsafe fn from_raw(raw: *mut abi::CadrCullOutput) -> Option<Self> {
        // SAFETY: per the contract.
        let raw = unsafe { raw.as_mut() }?;
        let words = raw.word_count as usize;
        if raw.visible_bits.is_null() || raw.changed_bits.is_null() {
            return None;
        }
        // SAFETY: `words` valid, unaliased words each.
        Some(unsafe {
            Self {
                visible_bits: std::slice::from_raw_parts_mut(raw.visible_bits, words),
                changed_bits: std::slice::from_raw_parts_mut(raw.changed_bits, words),
            }
        })
    }
}

/// What a GPU culler records with, for one phase of the frame (since ABI 1.3).
#[derive(Debug)]
pub struct GpuCull<'a> {
    raw: &'a abi::CadrGpuCullContext,
}

impl<'a> GpuCull<'a> {
    /// Wraps the host's context.
    ///
    /// # Safety
    /// `raw` is null or a valid context for the call, its `draws` writable.
    pub unsafe fn from_raw(raw: *const abi::CadrGpuCullContext) -> Option<Self> {
        // SAFETY: per the contract.
        unsafe { raw.as_ref() }.map(|raw| Self { raw })
    }

    /// The raw context: eye, planes, view-projection, target size and depth.
    pub fn raw(&self) -> &'a abi::CadrGpuCullContext {
        self.raw
    }

    /// The phase being recorded.
    pub fn phase(&self) -> u32 {
        self.raw.phase
    }

    /// The host's extension chain for this call: null from a host older than ABI 1.14, whose
    /// context ends before `extensions`.
    fn extensions(&self) -> *const abi::CadrExtension {
        let end = std::mem::offset_of!(abi::CadrGpuCullContext, extensions)
            + std::mem::size_of::<usize>();
        if (self.raw.size as usize) < end {
            std::ptr::null()
        } else {
            self.raw.extensions
        }
    }

    /// The cluster culling options ([`abi::CadrClusterCull`]), from a host of ABI 1.14 or
    /// later whose scene has clusters.
    pub fn cluster_cull(&self) -> Option<&'a abi::CadrClusterCull> {
        // SAFETY: the host's chain (or null) is valid for the call; an extension of this kind
        // is a `CadrClusterCull`.
        unsafe { extension(self.extensions(), abi::CADR_EXTENSION_CLUSTER_CULL) }
    }

    /// Per pass, whether the back faces of closed opaque parts cannot show in it (see
    /// [`abi::CadrClusterCull::back_faces_hidden`]); all false without the extension.
    pub fn back_faces_hidden(&self) -> Vec<bool> {
        let passes = self.passes().len();
        match self.cluster_cull() {
            Some(cull)
                if !cull.back_faces_hidden.is_null() && cull.pass_count as usize == passes =>
            {
                // SAFETY: the host's array of `pass_count` entries, valid for the call.
                unsafe { std::slice::from_raw_parts(cull.back_faces_hidden, passes) }
                    .iter()
                    .map(|&hidden| hidden != 0)
                    .collect()
            }
            _ => vec![false; passes],
        }
    }

    /// Per pass, which instances it takes by whether their back faces are culled
    /// ([`abi::CadrBackFacePasses`], `CADR_FACES_*`); all [`abi::CADR_FACES_ANY`] without the
    /// extension (a host that splits no pass).
    pub fn face_routes(&self) -> Vec<abi::CadrFaceRoute> {
        let passes = self.passes().len();
        // SAFETY: the host's chain (or null) is valid for the call; an extension of this kind
        // is a `CadrBackFacePasses`.
        let split: Option<&abi::CadrBackFacePasses> =
            unsafe { extension(self.extensions(), abi::CADR_EXTENSION_BACK_FACE_PASSES) };
        match split {
            Some(split) if !split.routes.is_null() && split.pass_count as usize == passes => {
                // SAFETY: the host's array of `pass_count` entries, valid for the call.
                unsafe { std::slice::from_raw_parts(split.routes, passes) }.to_vec()
            }
            _ => vec![abi::CADR_FACES_ANY; passes],
        }
    }

    /// Whether the host asks that each split's two passes share one stream whose commands name
    /// their pass ([`abi::CadrSharedFaceStreams`], since ABI 1.19).
    pub fn shares_face_streams(&self) -> bool {
        // SAFETY: the host's chain (or null) is valid for the call; an extension of this kind
        // is a `CadrSharedFaceStreams`.
        let shared: Option<&abi::CadrSharedFaceStreams> =
            unsafe { extension(self.extensions(), abi::CADR_EXTENSION_SHARED_FACE_STREAMS) };
        shared.is_some()
    }

    /// Whether the host asks that every command past each pass's count draw nothing, as the
    /// submission draws the commands by their capacity ([`abi::CadrEmptyCommandTails`], since
    /// ABI 1.24).
    pub fn empties_command_tails(&self) -> bool {
        // SAFETY: the host's chain (or null) is valid for the call; an extension of this kind
        // is a `CadrEmptyCommandTails`.
        let tails: Option<&abi::CadrEmptyCommandTails> =
            unsafe { extension(self.extensions(), abi::CADR_EXTENSION_EMPTY_COMMAND_TAILS) };
        tails.is_some()
    }

    /// The sub-pixel threshold (projected diameter in pixels below which a part is culled);
    /// 0, culling nothing for its size, from a host older than ABI 1.5.
    pub fn min_pixels(&self) -> f32 {
        let end =
            std::mem::offset_of!(abi::CadrGpuCullContext, min_pixels) + std::mem::size_of::<f32>();
        if self.raw.size as usize >= end && self.raw.min_pixels.is_finite() {
            self.raw.min_pixels.max(0.0)
        } else {
            0.0
        }
    }

    /// The host's buffer and offset holding the view as shaders read it
    /// (`CadrGpuCullView`, since ABI 1.5), if the host passed one.
    pub fn view_buffer(&self) -> Option<(vk::Buffer, u64)> {
        let end =
            std::mem::offset_of!(abi::CadrGpuCullContext, view_offset) + std::mem::size_of::<u64>();
        (self.raw.size as usize >= end && self.raw.view_buffer != 0).then(|| {
            (
                vk::Buffer::from_raw(self.raw.view_buffer),
                self.raw.view_offset,
            )
        })
    }

    /// The primary command buffer, outside rendering.
    pub fn command_buffer(&self) -> vk::CommandBuffer {
        vk::CommandBuffer::from_raw(self.raw.command_buffer as u64)
    }

    /// The scene.
    pub fn scene(&self) -> Option<Scene<'a>> {
        // SAFETY: the host's view for the call.
        unsafe { Scene::from_raw(self.raw.scene) }
    }

    /// The passes the frame draws.
    pub fn passes(&self) -> &'a [abi::CadrPass] {
        slice(self.raw.passes, self.raw.pass_count as usize)
    }

    pass_filters_method!(abi::CadrGpuCullContext);

    /// Says where pass `index`'s commands and count lie for this phase.
    pub fn set_draws(&self, index: usize, draws: abi::CadrGpuDraws) {
        if index < self.raw.pass_count as usize && !self.raw.draws.is_null() {
            // SAFETY: the host gives `pass_count` writable entries for the call.
            unsafe { *self.raw.draws.add(index) = draws };
        }
    }
}
