//! The C ABI between cadr (the host) and its technique plugins.
//!
//! Only `#[repr(C)]` types, plain integers and function pointers cross the boundary; Rust trait
//! objects never do. The order of events:
//!
//! 1. The host opens a library and calls [`CADR_PLUGIN_VERSION_SYMBOL`]
//!    (a [`CadrPluginVersionFn`]) before reading any struct. A library whose major version
//!    differs from [`CADR_PLUGIN_ABI_MAJOR`] is refused. A library of a newer minor is loaded
//!    by hosts of ABI 1.13 and later (older hosts refuse it) unless one of its techniques
//!    requires an extension the host does not know (see "Versions" below).
//! 2. The host calls [`CADR_PLUGIN_ENTRY_SYMBOL`] (a [`CadrPluginEntryFn`]), which fills a
//!    [`CadrPluginLibrary`]: the techniques it offers, each a [`CadrTechniqueInfo`] with the
//!    device features it needs and a vtable for its kind.
//! 3. Per technique instance the host calls the vtable's `create` with a [`CadrCreateInfo`]
//!    (raw Vulkan handles, `vkGetInstanceProcAddr`, and host services), then the kind's
//!    functions every frame, and `destroy` once the GPU has finished with the instance.
//!
//! Rules on both sides: every struct that carries a step of the protocol (library and
//! technique descriptions, vtables, create info, Vulkan handles, host API, scene view, bind,
//! record and cull contexts) starts with its `size` in bytes (a reader ignores fields beyond the
//! size the writer gave, and defaults fields the writer did not know); the small value records
//! laid out in arrays or passed by value ([`CadrInstance`], [`CadrMatrix`], [`CadrMaterial`],
//! [`CadrInstanceRecord`], [`CadrCullEntry`], [`CadrPass`], [`CadrPassFilter`],
//! [`CadrPassExclusion`], [`CadrBuffer`], [`CadrBufferRef`], [`CadrStats`], [`CadrBindState`],
//! [`CadrDrawBase`], [`CadrGpuDraws`], [`CadrVertexInput`], [`CadrMessage`],
//! [`CadrParameterBlock`]) are fixed for a major version; whoever allocates frees (buffers a
//! plugin asks the host for go back through the host); strings are NUL-terminated UTF-8 owned by the side that returns them, valid as
//! long as the library (descriptions) or the instance (shader snippets); no function unwinds
//! across the boundary (the SDK's shims catch panics and return [`CADR_STATUS_PANICKED`]);
//! libraries are never unloaded. Functions marked "thread-safe" may be called from several
//! threads at once on the same instance; all others are called from one thread at a time.
//!
//! # Versions
//!
//! - A new **major** version is the only way to remove or change anything: a struct's layout
//!   below its size, a function's signature, the meaning of a constant or a flag. Flags and
//!   constants keep their meaning for the whole of a major version.
//! - A new **minor** version adds; readers of the older minor are not disturbed. Up to 1.13,
//!   minors added fields at the end of size-prefixed structs. From 1.13 on, features are
//!   added as **extensions** instead: structs that start with a [`CadrExtension`] header
//!   (`size`, `kind`, `next`) and are chained from a struct's `extensions` pointer, as Vulkan
//!   chains `pNext`. The core structs stay as 1.13 left them (1.14 gave the two per-frame
//!   structs that lacked one, [`CadrSceneView`] and [`CadrGpuCullContext`], their
//!   `extensions` pointer, the last field added by size), a reader skips the kinds it does
//!   not know, and a technique lists in `required_extensions` the kinds it cannot work
//!   without.
//! - The host accepts a library of any minor of its major: an older one's structs are read by
//!   their size (what a later minor added takes its default); a newer one's by the prefix the
//!   host knows. A technique that requires an extension the host does not know is refused,
//!   naming the extension.

#![allow(non_camel_case_types)]

use std::ffi::{c_char, c_void};

/// Major version of this ABI: a library built for another major version is refused.
pub const CADR_PLUGIN_ABI_MAJOR: u32 = 1;
/// Minor version of this ABI: additions that older readers may ignore.
pub const CADR_PLUGIN_ABI_MINOR: u32 = 25;
/// `(major << 16) | minor`, what [`CadrPluginVersionFn`] returns.
pub const CADR_PLUGIN_ABI_VERSION: u32 = (CADR_PLUGIN_ABI_MAJOR << 16) | CADR_PLUGIN_ABI_MINOR;

/// Name of the version-negotiation symbol every plugin library exports.
pub const CADR_PLUGIN_VERSION_SYMBOL: &str = "cadr_plugin_abi_version";
/// Name of the entry point every plugin library exports.
pub const CADR_PLUGIN_ENTRY_SYMBOL: &str = "cadr_plugin_entry";

/// Returns the ABI version the library was built for, `(major << 16) | minor`. Called first,
/// before any struct is exchanged.
pub type CadrPluginVersionFn = unsafe extern "C" fn() -> u32;

/// Fills `library` (whose `size` the host has set) with what the library offers. The pointers
/// written stay valid for the life of the process.
pub type CadrPluginEntryFn = unsafe extern "C" fn(library: *mut CadrPluginLibrary) -> CadrStatus;

/// Result of a plugin function: one of the `CADR_STATUS_*` constants.
pub type CadrStatus = i32;
/// Success.
pub const CADR_STATUS_OK: CadrStatus = 0;
/// Failure; the plugin wrote a message into the [`CadrMessage`] it was given.
pub const CADR_STATUS_ERROR: CadrStatus = 1;
/// The plugin panicked (or threw); the SDK's shim caught it. The instance must not be used again.
pub const CADR_STATUS_PANICKED: CadrStatus = 2;

/// Technique kind: one of the `CADR_KIND_*` constants.
pub type CadrTechniqueKind = u32;
/// How vertices and indices reach the vertex shader ([`CadrVertexPathVtable`]).
pub const CADR_KIND_VERTEX_PATH: CadrTechniqueKind = 1;
/// How matrices and materials reach the shaders ([`CadrParameterPathVtable`]).
pub const CADR_KIND_PARAMETER_PATH: CadrTechniqueKind = 2;
/// Which draws are issued and how ([`CadrSubmissionVtable`]).
pub const CADR_KIND_SUBMISSION: CadrTechniqueKind = 3;
/// Which instances are drawn at all ([`CadrCullingVtable`]).
pub const CADR_KIND_CULLING: CadrTechniqueKind = 4;
/// Since ABI 1.7: how translucent surfaces are blended, whatever their order
/// ([`CadrTransparencyVtable`]).
pub const CADR_KIND_TRANSPARENCY: CadrTechniqueKind = 5;

/// Device features, as bits of a `u64`: what a technique needs ([`CadrTechniqueInfo`]) and
/// what the host's device has enabled ([`CadrVulkan::features`]).
pub type CadrFeatureBits = u64;
/// `multiDrawIndirect`.
pub const CADR_FEATURE_MULTI_DRAW_INDIRECT: CadrFeatureBits = 1 << 0;
/// `drawIndirectFirstInstance`.
pub const CADR_FEATURE_DRAW_INDIRECT_FIRST_INSTANCE: CadrFeatureBits = 1 << 1;
/// `drawIndirectCount` (Vulkan 1.2).
pub const CADR_FEATURE_DRAW_INDIRECT_COUNT: CadrFeatureBits = 1 << 2;
/// `VK_EXT_multi_draw`.
pub const CADR_FEATURE_MULTI_DRAW: CadrFeatureBits = 1 << 3;
/// `bufferDeviceAddress` (Vulkan 1.2).
pub const CADR_FEATURE_BUFFER_DEVICE_ADDRESS: CadrFeatureBits = 1 << 4;
/// `shaderDrawParameters` (Vulkan 1.1).
pub const CADR_FEATURE_SHADER_DRAW_PARAMETERS: CadrFeatureBits = 1 << 5;
/// `VK_EXT_mesh_shader` with task and mesh shaders (set by hosts since ABI 1.12's
/// `VK_EXT_mesh_shader` support; no built-in technique needs it yet).
pub const CADR_FEATURE_MESH_SHADER: CadrFeatureBits = 1 << 6;
/// `VK_NV_device_generated_commands`: never set by any host (reserved; see
/// [`CADR_FEATURE_DEVICE_GENERATED_COMMANDS_EXT`] for the cross-vendor extension).
pub const CADR_FEATURE_DEVICE_GENERATED_COMMANDS: CadrFeatureBits = 1 << 7;
/// Since ABI 1.7: `fragmentStoresAndAtomics` (fragment shaders write storage buffers).
pub const CADR_FEATURE_FRAGMENT_STORES_AND_ATOMICS: CadrFeatureBits = 1 << 8;
/// `VK_EXT_device_generated_commands` with `VK_KHR_maintenance5`, both enabled on the device,
/// and `bufferDeviceAddress`. Added within ABI 1.12: a host that does not know the bit never
/// sets it, so a technique that needs it is refused there as on a device without the
/// extension. Load the functions with the SDK's `dgc::Device`.
pub const CADR_FEATURE_DEVICE_GENERATED_COMMANDS_EXT: CadrFeatureBits = 1 << 9;

/// What a technique offers to, or needs from, the techniques it is combined with, as bits of
/// a `u64` ([`CadrTechniqueInfo::provides`], [`CadrTechniqueInfo::needs`]). The host refuses a
/// combination where some technique needs a bit that none of the others provides.
pub type CadrTraitBits = u64;
/// Vertex path: the parts of one geometry share one binding (draws differ only in
/// `firstIndex`), so one draw call may cover several parts of a geometry.
pub const CADR_TRAIT_GEOMETRY_SHARES_BINDING: CadrTraitBits = 1 << 0;
/// Vertex path: every geometry shares one binding (offsets in the draw), so one call may
/// cover the whole scene (multi-draw-indirect).
pub const CADR_TRAIT_SCENE_SHARES_BINDING: CadrTraitBits = 1 << 1;
/// Parameter path: the shader finds a draw's parameters from `gl_InstanceIndex` (the draw's
/// `firstInstance` is the instance id), so draws need no per-draw commands.
pub const CADR_TRAIT_PARAMETERS_FROM_INSTANCE_INDEX: CadrTraitBits = 1 << 2;
/// Parameter path: per-draw commands carry the parameters' values (push constants), so
/// recorded command buffers go stale when a matrix or material changes.
pub const CADR_TRAIT_PARAMETERS_IN_COMMANDS: CadrTraitBits = 1 << 3;
/// Submission: records into secondary command buffers; the host begins rendering with
/// `VK_RENDERING_CONTENTS_SECONDARY_COMMAND_BUFFERS_BIT` and records nothing inline.
pub const CADR_TRAIT_SECONDARY_COMMAND_BUFFERS: CadrTraitBits = 1 << 4;
/// Since ABI 1.3. Submission: when the record context carries GPU-written draws
/// ([`CadrRecordContext::gpu_draws`]), draws each pass from them with
/// `vkCmdDrawIndexedIndirectCount` instead of its own lists. GPU culling needs it.
pub const CADR_TRAIT_DRAWS_GPU_COMMANDS: CadrTraitBits = 1 << 5;
/// Since ABI 1.4. Any kind, an announcement rather than an offer (no technique needs it): the
/// technique reads world matrices on the host ([`CadrSceneView::matrices`],
/// [`CadrSceneView::dirty_matrices`] or [`CadrCullInput::world_matrices`]). While no active
/// technique sets it (and every one comes from a library of ABI 1.4 or later), the host keeps
/// the transform hierarchy on the GPU: a moved assembly node uploads only its local matrix and a
/// compute pass updates the world matrices of its subtree in [`CadrSceneView::matrix_buffer`];
/// the host arrays then lag behind for moved subtrees and `dirty_matrices` lists only the slots
/// the host itself wrote. A technique that reads matrices from the matrix buffer on the GPU
/// leaves it clear.
pub const CADR_TRAIT_READS_HOST_MATRICES: CadrTraitBits = 1 << 6;
/// Since ABI 1.5. Any kind, an announcement: the technique's per-frame calls (`prepare`,
/// `record`, `record_gpu`) record the same commands, and change nothing else, for a frame
/// whose commands key ([`CadrRecordContext::commands_key`]) and scene generations equal the
/// last recorded frame's, whatever the camera (a GPU culler reads the camera from
/// [`CadrGpuCullContext::view_buffer`] on the GPU, not from its values). When every active
/// technique sets it and the frame uploads nothing, the host resubmits the last frame's
/// command buffer without calling them: a frame with nothing changed costs one submission.
pub const CADR_TRAIT_REPLAYABLE: CadrTraitBits = 1 << 7;
/// Since ABI 1.10. Any kind, an announcement that widens [`CADR_TRAIT_REPLAYABLE`]: the
/// technique's per-frame calls (`prepare`, `record`, `record_gpu`) read no parameter values on
/// the host ([`CadrSceneView::matrices`], [`CadrSceneView::materials`],
/// [`CadrSceneView::dirty_matrices`], [`CadrSceneView::dirty_materials`]), so what they record
/// stays right when only [`CadrSceneView::parameters_generation`] changed: the shaders read the
/// values from the scene's buffers. When every active technique sets it and
/// [`CADR_TRAIT_REPLAYABLE`], a frame in which parts moved or materials changed resubmits the
/// last recording, after a command buffer of the host's own with the frame's uploads (the
/// sparse upload and the transform hierarchy): moving parts cost the CPU what a still camera
/// costs, plus the upload. A culler that sets it and not [`CADR_TRAIT_READS_HOST_MATRICES`]
/// reads no parameter values in `cull` either, so the host does not cull again when only they
/// changed. A technique that puts parameter values in its commands
/// ([`CADR_TRAIT_PARAMETERS_IN_COMMANDS`]) or copies them on the host leaves it clear.
pub const CADR_TRAIT_REPLAYS_PARAMETER_CHANGES: CadrTraitBits = 1 << 8;
/// Since ABI 1.11. Culling, an announcement: what `cull` writes depends on the scene (its
/// candidates and instances) only, never on the view ([`CadrCullInput::planes`],
/// [`CadrCullInput::section_planes`]): the host calls it again only when the scene changed, not
/// every frame of an orbiting camera (`none`, which draws every candidate, sets it).
pub const CADR_TRAIT_CULLS_WHATEVER_THE_VIEW: CadrTraitBits = 1 << 9;
/// Since ABI 1.15. Any kind, an announcement: the technique keeps what it writes for a frame
/// once per frame slot ([`CadrFrameSlot`]). In a frame whose
/// [`CadrFrameSlot::earlier_frames_finished`] is 0 it writes no host-visible memory, updates no
/// descriptor set and records no secondary command buffer that a frame of another slot may
/// still read on the GPU, except its copies for [`CadrFrameSlot::slot`] (a technique that writes
/// nothing per frame announces it as it is). Where an active technique does not announce it,
/// the host waits for every earlier frame before each frame (one frame's work at a time, as
/// hosts before 1.15 did), so it never has more than one frame to keep.
pub const CADR_TRAIT_FRAME_SLOTS: CadrTraitBits = 1 << 10;
/// Since ABI 1.18. Culling on the GPU, an announcement: the culler honours
/// [`CadrBackFacePasses`], writing each instance into only the passes whose route takes it. The
/// host draws closed parts in passes whose rasterizer culls back faces only for a culler that
/// announces it: one that ignored the routes would draw open parts with their back faces culled
/// (holes), and the other parts twice.
pub const CADR_TRAIT_ROUTES_BACK_FACES: CadrTraitBits = 1 << 11;
/// Since ABI 1.19. Submission, an announcement: it draws a shared stream of GPU-written
/// commands in which each command names the pass whose pipeline draws it
/// ([`CadrSharedFaceStreams`]; the `dgc` submission does it with an execution set
/// of the two passes' pipelines, the GPU picking one per command). Where the active submission
/// announces it and the culler routes back faces ([`CADR_TRAIT_ROUTES_BACK_FACES`], ABI 1.19 or
/// later), the host asks the culler for shared streams and makes the two passes' pipelines
/// bindable by the GPU (`VK_PIPELINE_CREATE_2_INDIRECT_BINDABLE_BIT_EXT`).
pub const CADR_TRAIT_SWITCHES_PIPELINES: CadrTraitBits = 1 << 12;
/// Since ABI 1.20. Vertex or parameter path, a promise: every instance of the technique on one
/// device gives the same shader snippet, vertex input and push-constant bytes, and set layouts
/// of the same definition (the same bindings, types, counts, stages and flags). The renderers of
/// one device then draw with the pipelines built once, from the layouts of whichever instance
/// was first (Vulkan's "identically defined" layouts are compatible): a second view of a scene
/// neither compiles its pipelines again nor holds a copy of them. Without it, each renderer
/// builds its own.
pub const CADR_TRAIT_SHARES_PIPELINES: CadrTraitBits = 1 << 13;
/// Since ABI 1.22. Parameter blocks ([`CadrParameterBlock`]), one announcement per kind:
/// - a parameter path promises that its shaders read a draw's parameters from nothing but the
///   block pushed at offset 0 of the vertex stage's push constants (it pushes the block per draw
///   itself; the built-in `push` does);
/// - a submission pushes each GPU-written command's block with its draw where the host asks for
///   blocks ([`CadrParameterBlocks`]; `dgc` does it with a push-constant token per sequence);
/// - a GPU culler writes each command's block before it where the host asks.
///
/// Where the active parameter path, submission and GPU culler all announce it, the host asks
/// the culler and the submission for blocks in every frame, and counts
/// [`CADR_TRAIT_PARAMETERS_FROM_INSTANCE_INDEX`] as offered to them: the culler finds each
/// draw's parameters from its instance id on the GPU. The parameter path then pushes nothing
/// and reads no parameter values on the host: the host counts it as announcing
/// [`CADR_TRAIT_REPLAYS_PARAMETER_CHANGES`], and neither [`CADR_TRAIT_PARAMETERS_IN_COMMANDS`]
/// nor [`CADR_TRAIT_READS_HOST_MATRICES`], whatever it announces for drawing alone (so moving
/// parts replay the recorded frame, and the transform hierarchy may stay on the GPU). A
/// parameter path and submission that announce it with a CPU culler are refused (nothing would
/// write the blocks).
pub const CADR_TRAIT_PARAMETER_BLOCKS: CadrTraitBits = 1 << 14;
/// Since ABI 1.23. Mesh shading (`VK_EXT_mesh_shader`), one announcement per kind:
/// - a vertex or parameter path promises that its snippet also runs in a mesh shader: it reads
///   the vertex and the instance only through `gl_VertexIndex` and `gl_InstanceIndex` (the host
///   puts the corner's values in their place there), declares no vertex input and pushes no
///   constants (`pulling` and `ssbo-index` do so);
/// - a submission draws GPU-written commands ([`CadrGpuDraws`]) with mesh workgroups in the
///   passes of kinds [`CADR_PASS_MESH_TRIANGLES`] and [`CADR_PASS_MESH_PICK`].
///
/// Where the active submission announces it, the host builds every triangle pass but the
/// hidden silhouettes' (a geometry shader, which mesh pipelines lack) as a mesh pipeline: the
/// host's task shader reads one command per draw, and its mesh shader draws each command's
/// triangles in chunks, every vertex computed as the vertex shader computes it, so the picture
/// is the vertex pipeline's. The pipeline layout then has one push-constant range of 152 bytes
/// for the vertex, task and mesh stages: the paths' 128, then the submission's
/// [`CadrMeshTaskPush`]. The host refuses such a submission unless both paths announce it, the
/// culler is a GPU culler and the device has mesh shaders and buffer device addresses.
pub const CADR_TRAIT_MESH_SHADING: CadrTraitBits = 1 << 15;
/// Since ABI 1.24. GPU-written commands drawn past their count, one announcement per kind:
/// - a submission that draws GPU-written commands ([`CADR_TRAIT_DRAWS_GPU_COMMANDS`]) says
///   that it may draw any of each pass's [`CadrGpuDraws::max_draws`] commands, whatever the
///   count says: `individual-mdi` draws them all with `vkCmdDrawIndexedIndirect` and never
///   reads the count (for devices without `drawIndirectCount`, such as SwiftShader); `dgc` runs
///   a pass in chunks that each read the count from their own first command;
/// - a GPU culler promises to honour [`CadrEmptyCommandTails`].
///
/// Where the active submission announces it and the culler culls on the GPU, the host chains
/// [`CadrEmptyCommandTails`] on every [`CadrGpuCullContext`] of the frame; a GPU culler that
/// does not announce it is refused with such a submission (what lies past its counts would be
/// drawn).
pub const CADR_TRAIT_EMPTY_COMMAND_TAILS: CadrTraitBits = 1 << 16;

/// Since ABI 1.23: where a mesh-shading submission ([`CADR_TRAIT_MESH_SHADING`]) pushes its
/// [`CadrMeshTaskPush`], for the task and mesh stages (the vertex stage too, as the range is one).
pub const CADR_MESH_TASK_PUSH_OFFSET: u32 = 128;

/// Since ABI 1.23: what a mesh-shading submission pushes at [`CADR_MESH_TASK_PUSH_OFFSET`]
/// before drawing a pass of kind [`CADR_PASS_MESH_TRIANGLES`] or [`CADR_PASS_MESH_PICK`] (the
/// host's task and mesh shaders read it). It then draws the pass with
/// `vkCmdDrawMeshTasksIndirectCountEXT`: the culler's count ([`CadrGpuDraws::count_buffer`] at
/// `count_offset`), at most [`CadrGpuDraws::max_draws`] draws, each a
/// `VkDrawMeshTasksIndirectCommandEXT` of `{1, 1, 1}` from a buffer of its own: the one task
/// workgroup of draw `i` (`gl_DrawID`) reads the pass's command `i` and launches a mesh
/// workgroup per 32 of its triangles. Device addresses of buffers made with
/// `SHADER_DEVICE_ADDRESS` usage: a GPU culler's commands, the scene's index buffer
/// ([`CadrSceneView::index_buffer`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CadrMeshTaskPush {
    /// Address of the pass's first command (`VkDrawIndexedIndirectCommand`, `firstInstance` the
    /// instance id): [`CadrGpuDraws::commands`] plus `commands_offset`.
    pub commands: u64,
    /// Address of the scene's triangle indices (u32).
    pub indices: u64,
    /// Words (4 bytes) between commands ([`CadrGpuDraws::stride`] / 4).
    pub stride_words: u32,
    /// 0.
    pub reserved: u32,
}

impl CadrMeshTaskPush {
    /// Its bytes as pushed (little-endian, as every Vulkan device cadr runs on).
    pub fn to_le_bytes(&self) -> [u8; 24] {
        let mut bytes = [0u8; 24];
        bytes[0..8].copy_from_slice(&self.commands.to_le_bytes());
        bytes[8..16].copy_from_slice(&self.indices.to_le_bytes());
        bytes[16..20].copy_from_slice(&self.stride_words.to_le_bytes());
        bytes[20..24].copy_from_slice(&self.reserved.to_le_bytes());
        bytes
    }
}

/// A message buffer the host hands to functions that can fail: the plugin writes a
/// NUL-terminated UTF-8 message of at most `capacity` bytes (including the NUL).
#[repr(C)]
#[derive(Debug)]
pub struct CadrMessage {
    /// Where to write.
    pub text: *mut c_char,
    /// Bytes available at `text`.
    pub capacity: usize,
}

impl CadrMessage {
    /// Writes `text`, cut at a character boundary to fit, NUL-terminated. Used by both sides
    /// (the Rust SDK and the host); C authors write the buffer directly.
    ///
    /// # Safety
    /// `message` is null or points at a message whose `text` has `capacity` writable bytes.
    pub unsafe fn write(message: *mut CadrMessage, text: &str) {
        // SAFETY: per the contract.
        let Some(message) = (unsafe { message.as_mut() }) else {
            return;
        };
        if message.text.is_null() || message.capacity == 0 {
            return;
        }
        let mut length = text.len().min(message.capacity - 1);
        while !text.is_char_boundary(length) {
            length -= 1;
        }
        // SAFETY: length + 1 <= capacity bytes are writable at `text`.
        unsafe {
            std::ptr::copy_nonoverlapping(text.as_ptr(), message.text.cast::<u8>(), length);
            *message.text.add(length) = 0;
        }
    }
}

/// What an extension is: one of the `CADR_EXTENSION_*` kinds. Kinds are never reused within a
/// major version.
pub type CadrExtensionKind = u32;

/// Since ABI 1.13: the header every extension struct starts with. Extensions are chained
/// through `next` from a struct's `extensions` pointer; a reader walks the chain and skips the
/// kinds it does not know (`size` says how long the whole extension struct is). Whoever writes
/// a chain owns it and keeps it valid as long as the struct it hangs from. Hosts of ABI 1.13
/// know no kind, so they skip every extension a technique offers and refuse a technique that
/// requires one; ABI 1.14 defines [`CADR_EXTENSION_SCENE_CLUSTERS`] and
/// [`CADR_EXTENSION_CLUSTER_CULL`], ABI 1.15 [`CADR_EXTENSION_FRAME_SLOT`], ABI 1.18
/// [`CADR_EXTENSION_BACK_FACE_PASSES`], ABI 1.19 [`CADR_EXTENSION_SHARED_FACE_STREAMS`], ABI
/// 1.20 the scene's cluster and part boxes, ABI 1.21 [`CADR_EXTENSION_SCENE_STREAMING`], ABI
/// 1.22 [`CADR_EXTENSION_PARAMETER_BLOCKS`], ABI 1.24 [`CADR_EXTENSION_EMPTY_COMMAND_TAILS`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrExtension {
    /// Size of the whole extension struct, this header included.
    pub size: u32,
    /// Which extension this is (`CADR_EXTENSION_*`).
    pub kind: CadrExtensionKind,
    /// The next extension of the chain, or null.
    pub next: *const CadrExtension,
}

/// What a library offers, filled by [`CadrPluginEntryFn`]. The host owns the struct; the
/// library owns everything it points at, which lives as long as the process.
#[repr(C)]
#[derive(Debug)]
pub struct CadrPluginLibrary {
    /// Size of this struct as the writer knows it.
    pub size: u32,
    /// The ABI major version the library was built for.
    pub abi_major: u32,
    /// The ABI minor version the library was built for.
    pub abi_minor: u32,
    /// The library's name (its family of techniques).
    pub name: *const c_char,
    /// Number of entries at `techniques`.
    pub technique_count: u32,
    /// The techniques: `technique_count` entries, each `size` bytes long (the size of
    /// [`CadrTechniqueInfo`] in the library's minor version), one after the other.
    pub techniques: *const CadrTechniqueInfo,
}

/// One technique a library offers. Owned by the library, with its strings and vtable; they
/// live as long as the process. The host copies the vtable (the `size` bytes its library
/// wrote) into its own layout; functions added by later minors are none for older libraries.
#[repr(C)]
#[derive(Debug)]
pub struct CadrTechniqueInfo {
    /// Size of this struct as the writer knows it.
    pub size: u32,
    /// One of the `CADR_KIND_*` constants; says which vtable `vtable` points at.
    pub kind: CadrTechniqueKind,
    /// Short unique name within its kind (what `--vertex NAME` and friends take).
    pub name: *const c_char,
    /// One sentence saying what it does (what `cadr techniques` prints).
    pub description: *const c_char,
    /// `CADR_FEATURE_*` bits the device must have enabled.
    pub required_features: CadrFeatureBits,
    /// `CADR_TRAIT_*` bits this technique offers its partners.
    pub provides: CadrTraitBits,
    /// `CADR_TRAIT_*` bits this technique needs from its partners.
    pub needs: CadrTraitBits,
    /// The kind's vtable: [`CadrVertexPathVtable`], [`CadrParameterPathVtable`],
    /// [`CadrSubmissionVtable`], [`CadrCullingVtable`] or [`CadrTransparencyVtable`].
    pub vtable: *const c_void,
    /// Since ABI 1.13: the technique's extension structs for the host (a chain of
    /// [`CadrExtension`]s, or null), owned by the library and living as long as the process.
    pub extensions: *const CadrExtension,
    /// Since ABI 1.13: `required_extension_count` extension kinds the technique cannot work
    /// without (null when the count is 0). A host that does not know one of them refuses the
    /// technique, naming it.
    pub required_extensions: *const CadrExtensionKind,
    /// Since ABI 1.13: the number of kinds at `required_extensions`.
    pub required_extension_count: u32,
}

/// `vkGetInstanceProcAddr`, from which a plugin loads every other Vulkan function.
pub type CadrGetInstanceProcAddr = Option<
    unsafe extern "system" fn(
        instance: *mut c_void,
        name: *const c_char,
    ) -> Option<unsafe extern "system" fn()>,
>;

/// The host's Vulkan objects, as raw handles (dispatchable ones as pointers, the others as
/// 64-bit integers, as in `vulkan_core.h`). Owned by the host; the struct and the objects
/// outlive every technique instance. Plugins destroy only objects they created.
#[repr(C)]
#[derive(Debug)]
pub struct CadrVulkan {
    /// Size of this struct.
    pub size: u32,
    /// The instance's API version (`VK_MAKE_API_VERSION`).
    pub api_version: u32,
    /// `VkInstance`.
    pub instance: *mut c_void,
    /// `VkPhysicalDevice`.
    pub physical_device: *mut c_void,
    /// `VkDevice`.
    pub device: *mut c_void,
    /// The queue family the host renders on.
    pub queue_family: u32,
    /// `VkFormat` of the colour target.
    pub color_format: i32,
    /// `VkFormat` of the depth target.
    pub depth_format: i32,
    /// Loader for every Vulkan function.
    pub get_instance_proc_addr: CadrGetInstanceProcAddr,
    /// `CADR_FEATURE_*` bits enabled on the device.
    pub features: CadrFeatureBits,
    /// `minUniformBufferOffsetAlignment`.
    pub min_uniform_buffer_offset_alignment: u64,
    /// `maxPushConstantsSize`.
    pub max_push_constants_size: u32,
    /// `VkAllocationCallbacks*` to pass to every `vkCreate*`/`vkDestroy*` (the host counts
    /// live objects with them); may be null.
    pub allocation_callbacks: *const c_void,
    /// Since ABI 1.5 (read it only when `size` covers it): the host's `VkPipelineCache`, kept on
    /// disk between runs; pass it to `vkCreate*Pipelines` so that a plugin's pipelines build
    /// fast the second time. Internally synchronised (any thread); owned by the host; may be 0.
    pub pipeline_cache: u64,
}

/// Where a host buffer lives.
pub type CadrMemoryLocation = u32;
/// Device-local; written by transfers or shaders.
pub const CADR_MEMORY_GPU_ONLY: CadrMemoryLocation = 0;
/// Host-visible and mapped; written by the CPU, read by the GPU.
pub const CADR_MEMORY_CPU_TO_GPU: CadrMemoryLocation = 1;

/// A buffer the host created for a plugin ([`CadrHostApi::create_buffer`]).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrBuffer {
    /// `VkBuffer` (0 for none).
    pub buffer: u64,
    /// Size in bytes.
    pub size_bytes: u64,
    /// Device address, when the buffer was created with `SHADER_DEVICE_ADDRESS` usage.
    pub address: u64,
    /// Host pointer to its memory for [`CADR_MEMORY_CPU_TO_GPU`]; null otherwise.
    pub mapped: *mut c_void,
    /// The host's id for it (passed back to destroy it).
    pub id: u64,
}

/// Services the host offers a plugin instance. Thread-safe.
#[repr(C)]
#[derive(Debug)]
pub struct CadrHostApi {
    /// Size of this struct.
    pub size: u32,
    /// Passed back to every function here.
    pub user: *mut c_void,
    /// Creates a buffer of `size_bytes` with `VkBufferUsageFlags` `usage` in `location`, named
    /// `name` for debuggers. The host owns its memory; give it back with `destroy_buffer`.
    pub create_buffer: Option<
        unsafe extern "C" fn(
            user: *mut c_void,
            size_bytes: u64,
            usage: u32,
            location: CadrMemoryLocation,
            name: *const c_char,
            buffer: *mut CadrBuffer,
            message: *mut CadrMessage,
        ) -> CadrStatus,
    >,
    /// Destroys a buffer from `create_buffer` (the caller makes sure the GPU is done with it).
    pub destroy_buffer: Option<unsafe extern "C" fn(user: *mut c_void, buffer: *const CadrBuffer)>,
    /// Since ABI 1.3 (read it only when `size` covers it): compiles GLSL `source` (NUL-terminated,
    /// `#version 460`) for the stage `stage` (a `VkShaderStageFlagBits` value: vertex, fragment
    /// or compute) and creates a `VkShaderModule` from it into `*module`. The plugin owns the
    /// module and destroys it with `vkDestroyShaderModule` and the host's allocation callbacks.
    /// `name` names the source in error messages. On failure writes the compiler's message.
    pub create_shader_module: Option<
        unsafe extern "C" fn(
            user: *mut c_void,
            stage: u32,
            source: *const c_char,
            name: *const c_char,
            module: *mut u64,
            message: *mut CadrMessage,
        ) -> CadrStatus,
    >,
}

/// What `create` receives. Owned by the host; the struct is valid for the call, the `vulkan`
/// and `host` structs it points at for the life of the instance.
#[repr(C)]
#[derive(Debug)]
pub struct CadrCreateInfo {
    /// Size of this struct.
    pub size: u32,
    /// The device and its loader.
    pub vulkan: *const CadrVulkan,
    /// Host services.
    pub host: *const CadrHostApi,
    /// Worker threads the technique may use (at least 1).
    pub worker_threads: u32,
    /// Since ABI 1.13: the host's extension structs for this instance (a chain of
    /// [`CadrExtension`]s, or null), valid for the call. Hosts of ABI 1.13 offer none.
    pub extensions: *const CadrExtension,
}

/// The extension of `kind` in the chain that starts at `chain`, if there is one.
///
/// # Safety
/// `chain` is null or the first of a chain of valid extension structs, as the ABI's
/// `extensions` pointers are.
pub unsafe fn find_extension<'chain>(
    chain: *const CadrExtension,
    kind: CadrExtensionKind,
) -> Option<&'chain CadrExtension> {
    let mut next = chain;
    while !next.is_null() {
        // SAFETY: the caller promises a chain of valid extension structs, alive for 'chain.
        let extension = unsafe { &*next };
        if extension.kind == kind {
            return Some(extension);
        }
        next = extension.next;
    }
    None
}

/// A buffer of the scene the host keeps on the GPU.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CadrBufferRef {
    /// `VkBuffer`.
    pub buffer: u64,
    /// Size in bytes.
    pub size_bytes: u64,
    /// Device address (0 without `bufferDeviceAddress`).
    pub address: u64,
}

/// Flag bits of [`CadrInstance::flags`].
pub type CadrInstanceFlags = u32;
/// Drawn with a highlight tint.
pub const CADR_INSTANCE_HIGHLIGHTED: CadrInstanceFlags = 1 << 0;
/// Drawn by the pick pass.
pub const CADR_INSTANCE_PICKABLE: CadrInstanceFlags = 1 << 1;
/// The instance id is alive.
pub const CADR_INSTANCE_ALIVE: CadrInstanceFlags = 1 << 2;
/// Since ABI 1.3, set in [`CadrCullEntry::flags`] only: the instance is drawn unless culled
/// (alive, visible in the scene tree, with triangles).
pub const CADR_INSTANCE_CANDIDATE: CadrInstanceFlags = 1 << 3;
/// Since ABI 1.6: the part's triangles enclose a volume (watertight and consistently wound,
/// counter-clockwise seen from outside); a section plane's cut through it is capped.
pub const CADR_INSTANCE_CLOSED: CadrInstanceFlags = 1 << 4;
/// Since ABI 1.6: with [`CADR_INSTANCE_CLOSED`], the part's triangles wind clockwise seen from
/// outside (an inside-out mesh).
pub const CADR_INSTANCE_INSIDE_OUT: CadrInstanceFlags = 1 << 5;
/// Since ABI 1.9: the part's material is translucent (blended with an opacity under 1, or with
/// a base-colour texture that has translucent texels), so frames with translucency draw it in
/// the transparency method's pass. Textures turned off make such a part opaque again where its
/// opacity is 1: [`CADR_INSTANCE_TRANSLUCENT_BY_TEXTURE`] says which (before ABI 1.11 the flag
/// then said "may be translucent").
pub const CADR_INSTANCE_TRANSLUCENT: CadrInstanceFlags = 1 << 6;
/// Since ABI 1.11, with [`CADR_INSTANCE_TRANSLUCENT`]: the part is translucent only through
/// its base-colour texture's texels (its material's opacity is 1), so with textures turned off
/// it is opaque.
pub const CADR_INSTANCE_TRANSLUCENT_BY_TEXTURE: CadrInstanceFlags = 1 << 7;
/// Since ABI 1.12: some triangle of the part has vertex normals that differ (the shared
/// normals of a curved surface, where a silhouette can run across a triangle). The hidden-line
/// mode's hidden silhouettes pass needs only such parts: a part whose every triangle has one
/// normal yields no silhouette segment there.
pub const CADR_INSTANCE_CURVED: CadrInstanceFlags = 1 << 8;
/// Since ABI 1.18: the part's material cuts texels out (the alpha mode MASK with a base-colour
/// texture): through the holes its inside, its back faces, may show.
pub const CADR_INSTANCE_CUTOUT: CadrInstanceFlags = 1 << 9;
/// Since ABI 1.25, where the scene view has [`CadrSceneClusters`]: the part's feature edges have
/// coarser levels, records in the cluster buffer right after the part's clusters (from
/// [`CadrCullEntry::first_cluster`] plus [`CadrCluster::part_clusters`]), finest first, each
/// in a group of depth [`CADR_CLUSTER_EDGE_DEPTH`]. A culler with a level-of-detail threshold
/// may draw, in an edge pass, the coarsest level whose error projects at or under it instead
/// of the part's edges (`first_wire_index`, `wire_index_count`).
pub const CADR_INSTANCE_EDGE_LEVELS: CadrInstanceFlags = 1 << 10;

/// One drawable part on one path of the scene tree (the unit of "individual" drawing). Index
/// positions are absolute element offsets in the scene's index buffers; indices are relative
/// to the geometry's first vertex, `vertex_base`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CadrInstance {
    /// Matrix slot (the scene tree node placing it).
    pub matrix: u32,
    /// Material slot.
    pub material: u32,
    /// Geometry slot.
    pub geometry: u32,
    /// Part index within the geometry.
    pub part: u32,
    /// `CADR_INSTANCE_*` bits.
    pub flags: CadrInstanceFlags,
    /// The geometry's first vertex in the vertex buffer.
    pub vertex_base: u32,
    /// The geometry's first index in the index buffer.
    pub geometry_first_index: u32,
    /// The geometry's first index in the wire index buffer.
    pub geometry_first_wire_index: u32,
    /// The part's first triangle index (absolute).
    pub first_index: u32,
    /// The part's triangle index count.
    pub index_count: u32,
    /// The part's first edge index (absolute) in the wire index buffer.
    pub first_wire_index: u32,
    /// The part's edge index count (line list).
    pub wire_index_count: u32,
    /// The part's bounding sphere in object space: centre xyz, radius w.
    pub sphere: [f32; 4],
}

/// A matrix slot as the host keeps it on the CPU and in [`CadrSceneView::matrix_buffer`]:
/// column-major, the translation (column 3) split into an f32 high part (in column 3) and the
/// f32 remainder (in the `w` of columns 0–2), so that positions relative to the eye keep f64
/// precision on the GPU.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CadrMatrix {
    /// Columns.
    pub columns: [[f32; 4]; 4],
}

impl CadrMatrix {
    /// The GPU layout: 16 little-endian f32, column after column.
    pub fn to_le_bytes(&self) -> [u8; 64] {
        let mut bytes = [0; 64];
        for (i, value) in self.columns.iter().flatten().enumerate() {
            bytes[i * 4..i * 4 + 4].copy_from_slice(&value.to_le_bytes());
        }
        bytes
    }
}

/// Since ABI 1.22: every parameter a draw's shaders read, as the vertex stage's push constants
/// hold them from offset 0 under [`CADR_TRAIT_PARAMETER_BLOCKS`] (96 bytes, std430: a
/// column-major mat4, then two vec4s). The values are the instance's: its world matrix
/// ([`CadrSceneView::matrix_buffer`] at its matrix slot), its material's base colour and
/// surface, its `CADR_INSTANCE_*` flags and its instance id (the draw's `firstInstance`), as
/// [`CadrInstanceRecord`] names them.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CadrParameterBlock {
    /// The world matrix.
    pub matrix: CadrMatrix,
    /// The material's linear RGBA base colour.
    pub base_color: [f32; 4],
    /// The material's metallic and roughness.
    pub surface: [f32; 2],
    /// `CADR_INSTANCE_*` bits.
    pub flags: u32,
    /// The instance id.
    pub instance: u32,
}

impl CadrParameterBlock {
    /// The block for `instance` drawn with `matrix`, `material` and `flags`.
    pub fn new(matrix: &CadrMatrix, material: &CadrMaterial, flags: u32, instance: u32) -> Self {
        Self {
            matrix: *matrix,
            base_color: material.base_color,
            surface: [material.surface[0], material.surface[1]],
            flags,
            instance,
        }
    }

    /// The GPU layout: 24 little-endian words.
    pub fn to_le_bytes(&self) -> [u8; 96] {
        let mut bytes = [0; 96];
        bytes[..64].copy_from_slice(&self.matrix.to_le_bytes());
        let words = self
            .base_color
            .iter()
            .chain(&self.surface)
            .map(|v| v.to_bits())
            .chain([self.flags, self.instance]);
        for (i, word) in words.enumerate() {
            bytes[64 + i * 4..68 + i * 4].copy_from_slice(&word.to_le_bytes());
        }
        bytes
    }
}

/// A material slot as kept on the CPU and in [`CadrSceneView::material_buffer`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CadrMaterial {
    /// Linear RGBA.
    pub base_color: [f32; 4],
    /// x: metallic, y: roughness.
    pub surface: [f32; 4],
}

impl CadrMaterial {
    /// The GPU layout: base colour then surface, 8 little-endian f32.
    pub fn to_le_bytes(&self) -> [u8; 32] {
        let mut bytes = [0; 32];
        for (i, value) in self.base_color.iter().chain(&self.surface).enumerate() {
            bytes[i * 4..i * 4 + 4].copy_from_slice(&value.to_le_bytes());
        }
        bytes
    }
}

/// The per-instance record in [`CadrSceneView::instance_buffer`], indexed by instance id
/// (what `gl_InstanceIndex` finds under [`CADR_TRAIT_PARAMETERS_FROM_INSTANCE_INDEX`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CadrInstanceRecord {
    /// Matrix slot.
    pub matrix: u32,
    /// Material slot.
    pub material: u32,
    /// `CADR_INSTANCE_*` bits.
    pub flags: u32,
    /// The instance id.
    pub instance: u32,
}

/// Since ABI 1.3: what a GPU culler reads per instance id from [`CadrSceneView::cull_buffer`]
/// (48 bytes, little-endian, std430-compatible): the bounding sphere and the ranges each pass
/// draws, so that a compute shader can test an instance and write its indirect command.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CadrCullEntry {
    /// The part's bounding sphere in object space: centre xyz, radius w.
    pub sphere: [f32; 4],
    /// First triangle index (absolute in the index buffer).
    pub first_index: u32,
    /// Triangle index count.
    pub index_count: u32,
    /// First edge index (absolute in the wire index buffer).
    pub first_wire_index: u32,
    /// Edge index count.
    pub wire_index_count: u32,
    /// The geometry's first vertex (the draw's `vertexOffset`).
    pub vertex_base: u32,
    /// Matrix slot.
    pub matrix: u32,
    /// `CADR_INSTANCE_*` bits, with [`CADR_INSTANCE_CANDIDATE`].
    pub flags: u32,
    /// Since ABI 1.14, where the scene view has [`CadrSceneClusters`]: the part's first
    /// cluster in its cluster buffer (before, zero).
    pub first_cluster: u32,
}

impl CadrCullEntry {
    /// The GPU layout: 12 little-endian 32-bit words.
    pub fn to_le_bytes(&self) -> [u8; 48] {
        let mut bytes = [0; 48];
        let words = self.sphere.map(f32::to_bits).into_iter().chain([
            self.first_index,
            self.index_count,
            self.first_wire_index,
            self.wire_index_count,
            self.vertex_base,
            self.matrix,
            self.flags,
            self.first_cluster,
        ]);
        for (i, word) in words.enumerate() {
            bytes[i * 4..i * 4 + 4].copy_from_slice(&word.to_le_bytes());
        }
        bytes
    }
}

/// The scene as techniques see it during one frame. Owned by the host, read-only for plugins;
/// everything it points at stays valid and unchanged until the frame's last call (copy what
/// must outlive the frame).
///
/// Its many fields are the ABI as it stood before extension chains: it keeps them, and grows
/// only through `extensions`.
#[repr(C)]
#[derive(Debug)]
pub struct CadrSceneView {
    /// Size of this struct.
    pub size: u32,
    /// Instance ids in use are below this.
    pub instance_count: u32,
    /// Per instance id (`instance_count` entries; dead ids lack [`CADR_INSTANCE_ALIVE`]).
    pub instances: *const CadrInstance,
    /// One bit per instance id: drawn this frame (alive, visible, not culled, has triangles).
    pub drawn_bits: *const u64,
    /// Changes whenever an instance or a drawn bit changed (structure, materials, culling).
    pub draws_generation: u64,
    /// Changes whenever a matrix or material value changed.
    pub parameters_generation: u64,
    /// Number of matrix slots.
    pub matrix_count: u32,
    /// The matrices on the CPU (`matrix_count`); behind the GPU for moved subtrees unless an
    /// active technique sets [`CADR_TRAIT_READS_HOST_MATRICES`].
    pub matrices: *const CadrMatrix,
    /// Number of material slots.
    pub material_count: u32,
    /// The materials on the CPU (`material_count`).
    pub materials: *const CadrMaterial,
    /// Matrix slots changed since the last frame (the host's writes only, unless an active
    /// technique sets [`CADR_TRAIT_READS_HOST_MATRICES`]).
    pub dirty_matrices: *const u32,
    /// Number of entries at `dirty_matrices`.
    pub dirty_matrix_count: u32,
    /// Material slots changed since the last frame.
    pub dirty_materials: *const u32,
    /// Number of entries at `dirty_materials`.
    pub dirty_material_count: u32,
    /// Changes whenever one of the buffers below was replaced.
    pub buffers_generation: u64,
    /// Vertices: position xyz and normal xyz as f32, `vertex_stride` bytes each.
    pub vertex_buffer: CadrBufferRef,
    /// Bytes per vertex.
    pub vertex_stride: u32,
    /// Triangle indices (u32).
    pub index_buffer: CadrBufferRef,
    /// Edge indices (u32 line list).
    pub wire_index_buffer: CadrBufferRef,
    /// [`CadrMatrix`] per matrix slot, the world matrix of every tree node (with the GPU
    /// transform hierarchy, written by its compute pass before the frame's techniques run).
    pub matrix_buffer: CadrBufferRef,
    /// [`CadrMaterial`] per material slot.
    pub material_buffer: CadrBufferRef,
    /// [`CadrInstanceRecord`] per instance id.
    pub instance_buffer: CadrBufferRef,
    /// Since ABI 1.3 (read it only when `size` covers it): [`CadrCullEntry`] per instance id.
    pub cull_buffer: CadrBufferRef,
    /// Since ABI 1.14 (read it only when `size` covers it): the host's extension structs for
    /// this view (a chain of [`CadrExtension`]s, or null), valid as long as the view:
    /// [`CadrSceneClusters`] where the scene has clusters, since 1.20 their
    /// [`CadrSceneClusterBoxes`] and the parts' [`CadrScenePartBoxes`], and since 1.21
    /// [`CadrSceneStreaming`] where the scene streams its geometry.
    pub extensions: *const CadrExtension,
}

/// Since ABI 1.14: the kind of [`CadrSceneClusters`], chained on [`CadrSceneView::extensions`].
pub const CADR_EXTENSION_SCENE_CLUSTERS: CadrExtensionKind = 1;
/// Since ABI 1.14: the kind of [`CadrClusterCull`], chained on
/// [`CadrGpuCullContext::extensions`].
pub const CADR_EXTENSION_CLUSTER_CULL: CadrExtensionKind = 2;
/// Since ABI 1.15: the kind of [`CadrFrameSlot`], chained on [`CadrSceneView::extensions`] of
/// the views the host gives to `prepare`, `record` and a GPU culler's `record`.
pub const CADR_EXTENSION_FRAME_SLOT: CadrExtensionKind = 3;
/// Since ABI 1.18: the kind of [`CadrBackFacePasses`], chained on
/// [`CadrGpuCullContext::extensions`].
pub const CADR_EXTENSION_BACK_FACE_PASSES: CadrExtensionKind = 4;
/// Since ABI 1.19: the kind of [`CadrSharedFaceStreams`], chained on
/// [`CadrGpuCullContext::extensions`].
pub const CADR_EXTENSION_SHARED_FACE_STREAMS: CadrExtensionKind = 5;
/// Since ABI 1.20: the kind of [`CadrSceneClusterBoxes`], chained on
/// [`CadrSceneView::extensions`] beside [`CadrSceneClusters`].
pub const CADR_EXTENSION_SCENE_CLUSTER_BOXES: CadrExtensionKind = 6;
/// Since ABI 1.20: the kind of [`CadrScenePartBoxes`], chained on
/// [`CadrSceneView::extensions`].
pub const CADR_EXTENSION_SCENE_PART_BOXES: CadrExtensionKind = 7;
/// Since ABI 1.21: the kind of [`CadrSceneStreaming`], chained on [`CadrSceneView::extensions`].
pub const CADR_EXTENSION_SCENE_STREAMING: CadrExtensionKind = 8;
/// Since ABI 1.22: the kind of [`CadrParameterBlocks`], chained on [`CadrSceneView::extensions`]
/// of the views the host gives to a frame's `prepare`, `record` and GPU culler's `record`.
pub const CADR_EXTENSION_PARAMETER_BLOCKS: CadrExtensionKind = 9;
/// Since ABI 1.24: the kind of [`CadrEmptyCommandTails`], chained on
/// [`CadrGpuCullContext::extensions`].
pub const CADR_EXTENSION_EMPTY_COMMAND_TAILS: CadrExtensionKind = 10;

/// Since ABI 1.15 ([`CADR_EXTENSION_FRAME_SLOT`]): which of the host's frames in flight is being
/// recorded. The host lets the GPU work on up to `slot_count` frames while it records the next;
/// frame `n` uses slot `n % slot_count`, and a recording made for a slot is submitted again
/// (replayed) only by later frames of the same slot. A technique that announces
/// [`CADR_TRAIT_FRAME_SLOTS`] keeps one copy per slot of what it writes for a frame on the host
/// (host-visible buffers, descriptor sets, secondary command buffers) and writes only the
/// copy of `slot` while `earlier_frames_finished` is 0. Owned by the host; valid as long as
/// the view it hangs from.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrFrameSlot {
    /// `kind` = [`CADR_EXTENSION_FRAME_SLOT`].
    pub header: CadrExtension,
    /// The slot of the frame being recorded, `0..slot_count`.
    pub slot: u32,
    /// How many frames the host may have in flight (1 to 3): the copies a technique keeps.
    pub slot_count: u32,
    /// 1 when the GPU has finished every earlier frame, so that the technique may write any of
    /// its memory and descriptor sets; 0 when frames of other slots may still run. (A
    /// recording made for another slot is submitted again only while every frame since has
    /// recorded the same commands, as a host of one slot replays its one recording.) The host waits, and sets 1, whenever the
    /// scene view's generations, the frame's passes, the active techniques or the target
    /// changed since the last frame, when the frame uploads scene data, for pick frames, and
    /// in every frame where an active technique does not announce [`CADR_TRAIT_FRAME_SLOTS`].
    pub earlier_frames_finished: u32,
    /// Zero.
    pub reserved: u32,
}

/// Since ABI 1.14 ([`CADR_EXTENSION_SCENE_CLUSTERS`]): every part's triangles as clusters of
/// at most 128 triangles and 128 vertices, with the coarser clusters of its level-of-detail
/// DAG. A part's clusters are contiguous in `cluster_buffer` from its cull entry's
/// [`CadrCullEntry::first_cluster`]; its original clusters ([`CADR_CLUSTER_ORIGINAL`]) come
/// first, and their index ranges tile the part's own range (`first_index`, `index_count` of the
/// instance) in order, so drawing them all draws exactly the part's triangles. The coarser
/// clusters' indices lie after the geometry's own, in the same index buffer, and name the
/// same vertices. Written by the host with the geometry; owned by the host.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrSceneClusters {
    /// `kind` = [`CADR_EXTENSION_SCENE_CLUSTERS`].
    pub header: CadrExtension,
    /// [`CadrCluster`] per cluster (storage buffer).
    pub cluster_buffer: CadrBufferRef,
    /// Number of clusters in `cluster_buffer`.
    pub cluster_count: u32,
    /// Number of groups in `group_buffer`.
    pub group_count: u32,
    /// [`CadrClusterGroup`] per group of the level-of-detail DAGs (storage buffer).
    pub group_buffer: CadrBufferRef,
    /// The clusters of the candidate instances, summed ([`CadrCluster::part_clusters`] of each
    /// candidate's part): a bound on the cluster draws one pass of a frame can need.
    pub candidate_clusters: u64,
    /// The clusters of the candidates' coarsest cuts (those in groups of error `f32::MAX`),
    /// summed: the room that draws every candidate at its coarsest. A culler with less room
    /// than `candidate_clusters` keeps this much for parts whose cut does not fit its budget,
    /// so that no part is left out.
    pub candidate_coarsest_clusters: u64,
}

/// Since ABI 1.20 ([`CADR_EXTENSION_SCENE_CLUSTER_BOXES`]): every cluster's box, one
/// [`CadrBox`] per cluster of [`CadrSceneClusters::cluster_buffer`], at the same index.
/// The box holds the cluster's triangles in object space, as the sphere does; placed by the
/// instance's matrix it is an oriented box, much tighter than the sphere around flat or long
/// clusters (panels, plates, shafts), so a culler that tests it against a depth pyramid finds
/// more of them hidden. Written by the host with the geometry; owned by the host.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrSceneClusterBoxes {
    /// `kind` = [`CADR_EXTENSION_SCENE_CLUSTER_BOXES`].
    pub header: CadrExtension,
    /// [`CadrBox`] per cluster (storage buffer), as many as
    /// [`CadrSceneClusters::cluster_count`].
    pub box_buffer: CadrBufferRef,
}

/// Since ABI 1.20 ([`CADR_EXTENSION_SCENE_PART_BOXES`]): the box of every instance's part, one
/// [`CadrBox`] per instance id, beside its cull entry ([`CadrSceneView::cull_buffer`]), in the
/// same object space as the entry's sphere and as tight as the part's triangles allow. Placed by
/// the instance's matrix it is an oriented box, far tighter than the sphere around a panel, a
/// plate or a shaft: a culler that tests it against the frustum, the section planes and a depth
/// pyramid finds more of them outside or hidden. Written by the host with the cull entries (the
/// entries of ids not in use are zero); owned by the host.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrScenePartBoxes {
    /// `kind` = [`CADR_EXTENSION_SCENE_PART_BOXES`].
    pub header: CadrExtension,
    /// [`CadrBox`] per instance id (storage buffer), as many as the cull buffer has entries.
    pub box_buffer: CadrBufferRef,
}

/// Since ABI 1.21 ([`CADR_EXTENSION_SCENE_STREAMING`]): the scene streams its geometry under a
/// memory budget. A geometry whose full detail the GPU does not hold is drawn in a coarse form
/// (a coarse cut of each part's level-of-detail DAG, about an eighth of its triangles), and the
/// part boxes ([`CadrScenePartBoxes`]) of its instances carry that form's error
/// ([`CadrBox::coarse_error`]) and the geometry's request bit ([`CadrBox::request_bit`]). A
/// GPU culler that draws an instance whose part box carries an error, and finds it projecting
/// over its threshold in pixels (its level-of-detail threshold, or 0 for a culler that draws
/// full detail), sets that bit in `request_buffer` (an atomic or); the host reads the bits after
/// the frame and brings the geometries asked for to full detail (or keeps them there), within
/// its budget, those least recently asked for back to coarse first. Only the GPU sets bits;
/// the host clears them between frames. Owned by the host; the buffer may be replaced, with
/// the view's `buffers_generation` moved.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrSceneStreaming {
    /// `kind` = [`CADR_EXTENSION_SCENE_STREAMING`].
    pub header: CadrExtension,
    /// One bit per geometry (bit `b % 32` of 32-bit word `b / 32` for request bit `b`), storage
    /// buffer.
    pub request_buffer: CadrBufferRef,
    /// Words in `request_buffer`: a bit past them asks for nothing.
    pub request_word_count: u32,
    /// Zero.
    pub reserved: u32,
}

/// Since ABI 1.20: a box in object space, as [`CadrSceneClusterBoxes::box_buffer`] and
/// [`CadrScenePartBoxes::box_buffer`] hold them (32 bytes, little-endian, std430-compatible: two
/// `vec4`s): the smallest box along the object's axes that holds a cluster's or a part's
/// vertices, a hair larger so that rounding leaves none outside.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CadrBox {
    /// The box's centre in object space.
    pub center: [f32; 3],
    /// Since ABI 1.21, in part boxes only ([`CadrScenePartBoxes`]), where the scene streams
    /// ([`CadrSceneStreaming`]): the object-space error of the part's coarse form against its
    /// full detail, positive while the GPU holds the coarse form and negated while it holds
    /// the full detail (a culler asks for either where the error projects over its
    /// threshold: to get the full detail, or to keep it); zero where the scene does not stream
    /// (and always zero in cluster boxes).
    pub coarse_error: f32,
    /// Half its size along each object axis (zero or more).
    pub half_extent: [f32; 3],
    /// Since ABI 1.21, in part boxes only, where the scene streams: the bit of
    /// [`CadrSceneStreaming::request_buffer`] that asks for the part's geometry (one per
    /// geometry, shared by all its parts and instances); zero elsewhere (the 1.20 `reserved1`,
    /// always zero).
    pub request_bit: u32,
}

impl CadrBox {
    /// The GPU layout: 7 little-endian f32 and a little-endian u32.
    pub fn to_le_bytes(&self) -> [u8; 32] {
        let mut bytes = [0; 32];
        let words = self
            .center
            .iter()
            .chain([&self.coarse_error])
            .chain(&self.half_extent)
            .map(|value| value.to_bits())
            .chain([self.request_bit]);
        for (i, word) in words.enumerate() {
            bytes[i * 4..i * 4 + 4].copy_from_slice(&word.to_le_bytes());
        }
        bytes
    }
}

/// [`CadrCluster::refined`] of a part's original clusters: its own triangles, made by no
/// simplification.
pub const CADR_CLUSTER_ORIGINAL: u32 = u32::MAX;

/// Since ABI 1.16: [`CadrClusterGroup::depth`] of a part's proxy groups, its last. Each such
/// group holds one cluster standing for the whole part (since 1.17 a part may have several:
/// simplifications of the whole part, coarser one after the other, the last often an
/// octahedron through its extreme vertices) and a finite `error` (no less than any error
/// before it in the part) measured from one sphere that holds every other group's. A culler
/// that knows proxies draws the last proxy whose error projects at or under its threshold,
/// alone, in place of the part's cut (and none at threshold 0, nor in place of a part's
/// coarsest clusters when a budget runs out). A proxy cluster's `refined` names one of the
/// part's terminal groups (error `f32::MAX`), so that a culler that does not know proxies
/// never draws it; a 1.16 culler draws only the last proxy, as before.
pub const CADR_CLUSTER_PROXY_DEPTH: u32 = u32::MAX;

/// Since ABI 1.25: [`CadrClusterGroup::depth`] of a group holding one coarser level of a
/// part's feature edges (see [`CADR_INSTANCE_EDGE_LEVELS`]). Its one record in the cluster
/// buffer is a [`CadrCluster`] whose `first_index` and `index_count` name a line list in the
/// wire index buffer (absolute, like [`CadrCullEntry::first_wire_index`]; the same vertices as
/// the part's edges, a subset of them), whose `sphere` holds those lines, whose `refined`
/// is the number of edge levels the part has (the same in each), and whose `part_clusters` is
/// the part's. The group's `error` is the farthest any of the part's edges lies from the
/// level's lines (object space; never less than a finer level's) and its sphere the record's. The
/// levels lie outside every part's clusters, so a culler that does not know them never meets
/// them.
pub const CADR_CLUSTER_EDGE_DEPTH: u32 = u32::MAX - 1;

/// Since ABI 1.14: one cluster of [`CadrSceneClusters::cluster_buffer`] (64 bytes,
/// little-endian, std430-compatible). Which clusters make a picture at a given error: those
/// whose own group's error ([`CadrCluster::group`]) projects over the threshold and whose
/// `refined` group's error projects at or under it (an original cluster's error is 0); each
/// group's error and sphere are the same for all its clusters, and errors only grow from the
/// refined to the coarser, so the chosen clusters tile the surface without cracks or overlaps.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CadrCluster {
    /// Bounding sphere of the cluster's triangles in object space: centre xyz, radius w.
    pub sphere: [f32; 4],
    /// Apex of the normal cone (object space).
    pub cone_apex: [f32; 3],
    /// The cone's cutoff: seen from an eye at `e`, every triangle faces away when
    /// `dot(normalize(cone_apex - e), cone_axis) >= cone_cutoff` (orthographic views:
    /// `dot(view_direction, cone_axis) >= cone_cutoff`). Above 1 when the triangles face too
    /// many ways for any test. Valid only for a transform that keeps angles (a rotation, a
    /// uniform scale, a mirror) and a part whose back faces cannot show.
    pub cone_cutoff: f32,
    /// Axis of the normal cone (object space, unit length; triangles wound counter-clockwise).
    pub cone_axis: [f32; 3],
    /// First triangle index (absolute in the index buffer).
    pub first_index: u32,
    /// Triangle index count (a multiple of 3).
    pub index_count: u32,
    /// The group the cluster belongs to (an index into the group buffer): its error is what
    /// drawing the coarser clusters instead would cost.
    pub group: u32,
    /// The group whose simplification made this cluster (its error is this cluster's), or
    /// [`CADR_CLUSTER_ORIGINAL`].
    pub refined: u32,
    /// How many clusters the part has (the same in each of its clusters).
    pub part_clusters: u32,
}

impl CadrCluster {
    /// The GPU layout: 16 little-endian 32-bit words.
    pub fn to_le_bytes(&self) -> [u8; 64] {
        let floats = self
            .sphere
            .into_iter()
            .chain(self.cone_apex)
            .chain([self.cone_cutoff])
            .chain(self.cone_axis)
            .map(f32::to_bits);
        let words = floats.chain([
            self.first_index,
            self.index_count,
            self.group,
            self.refined,
            self.part_clusters,
        ]);
        let mut bytes = [0; 64];
        for (i, word) in words.enumerate() {
            bytes[i * 4..i * 4 + 4].copy_from_slice(&word.to_le_bytes());
        }
        bytes
    }
}

/// Since ABI 1.14: one group of a level-of-detail DAG in [`CadrSceneClusters::group_buffer`]
/// (32 bytes, std430-compatible): neighbouring clusters simplified together, their shared
/// border kept.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CadrClusterGroup {
    /// The sphere the error is measured from (object space): centre xyz, radius w. It holds
    /// the spheres of the groups it was made from.
    pub sphere: [f32; 4],
    /// The object-space error of the coarser clusters made from this group (the largest
    /// distance their surface may lie from the original); `f32::MAX` for a group that was
    /// not simplified further (its clusters are the part's coarsest).
    pub error: f32,
    /// Level in the DAG: 0 for groups of original clusters; [`CADR_CLUSTER_PROXY_DEPTH`] for a
    /// part's proxies (since 1.16); [`CADR_CLUSTER_EDGE_DEPTH`] for a level of its feature
    /// edges (since 1.25).
    pub depth: u32,
    /// The group's first cluster in the cluster buffer: a group's clusters are contiguous,
    /// and a part's groups, in the group buffer, cover its clusters in order (a culler may
    /// walk a part group by group, skipping the clusters of a group its cut leaves out).
    pub first_cluster: u32,
    /// How many clusters the group has.
    pub cluster_count: u32,
}

impl CadrClusterGroup {
    /// The GPU layout: 8 little-endian 32-bit words.
    pub fn to_le_bytes(&self) -> [u8; 32] {
        let words = self
            .sphere
            .into_iter()
            .chain([self.error])
            .map(f32::to_bits)
            .chain([self.depth, self.first_cluster, self.cluster_count]);
        let mut bytes = [0; 32];
        for (i, word) in words.enumerate() {
            bytes[i * 4..i * 4 + 4].copy_from_slice(&word.to_le_bytes());
        }
        bytes
    }
}

/// Since ABI 1.14 ([`CADR_EXTENSION_CLUSTER_CULL`]): what a cluster culler needs of the frame
/// beyond [`CadrGpuCullContext`]. Owned by the host, valid for the call.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrClusterCull {
    /// `kind` = [`CADR_EXTENSION_CLUSTER_CULL`].
    pub header: CadrExtension,
    /// The level-of-detail threshold in pixels: the clusters drawn are the coarsest whose error
    /// projects at or under it. 0 draws every part at full detail (its original clusters).
    pub lod_error: f32,
    /// Number of entries at `back_faces_hidden` (the cull context's `pass_count`).
    pub pass_count: u32,
    /// Per pass, nonzero when the pass draws surfaces with depth test and depth writes, so
    /// that the back faces of a closed opaque part never show in it: the culler may drop
    /// clusters that face away from the eye, for closed parts
    /// ([`CADR_INSTANCE_CLOSED`]) that are not translucent and that no section plane cuts.
    pub back_faces_hidden: *const u32,
}

/// Since ABI 1.18: which instances a pass takes by whether the rasterizer may cull their back
/// faces ([`CadrBackFacePasses`]).
pub type CadrFaceRoute = u32;
/// Every instance the pass's filter keeps (what passes without a route draw).
pub const CADR_FACES_ANY: CadrFaceRoute = 0;
/// Only the instances whose back faces can never show, which the pass's pipeline culls: closed
/// ([`CADR_INSTANCE_CLOSED`]), wound counter-clockwise seen from outside (not
/// [`CADR_INSTANCE_INSIDE_OUT`]), neither [`CADR_INSTANCE_TRANSLUCENT`] nor
/// [`CADR_INSTANCE_CUTOUT`], placed by a matrix that
/// keeps handedness (a positive determinant: a mirroring matrix turns the winding), with the
/// bounding sphere wholly on the inner side of the near plane (the eye cannot look into the
/// part) and crossed by no section plane (a cut part shows its inside).
pub const CADR_FACES_CULLED: CadrFaceRoute = 1;
/// Only the instances [`CADR_FACES_CULLED`] does not take.
pub const CADR_FACES_KEPT: CadrFaceRoute = 2;

/// Since ABI 1.18 ([`CADR_EXTENSION_BACK_FACE_PASSES`]): the host draws opaque surfaces in two
/// passes, one whose pipeline culls back faces for the closed parts and one that draws both
/// faces for the rest; the route of each pass says which instances it takes. A
/// [`CADR_FACES_CULLED`] pass is always followed by its [`CADR_FACES_KEPT`] pass. The host
/// chains it only for a culler that announces [`CADR_TRAIT_ROUTES_BACK_FACES`], and such a
/// culler writes every instance into exactly one of the two passes (the route is decided per
/// instance, the same way in every phase of a frame). Owned by the host, valid for the call.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrBackFacePasses {
    /// `kind` = [`CADR_EXTENSION_BACK_FACE_PASSES`].
    pub header: CadrExtension,
    /// Number of entries at `routes` (the cull context's `pass_count`).
    pub pass_count: u32,
    /// Per pass, a `CADR_FACES_*` route.
    pub routes: *const CadrFaceRoute,
}

/// Since ABI 1.19 ([`CADR_EXTENSION_SHARED_FACE_STREAMS`], chained beside
/// [`CadrBackFacePasses`] where the active submission announces
/// [`CADR_TRAIT_SWITCHES_PIPELINES`]): the submission draws each split's two passes from one
/// stream. A culler that honours it writes the commands of each [`CADR_FACES_CULLED`] pass
/// and of the [`CADR_FACES_KEPT`] pass after it into one stream with one count, each command
/// preceded by a `u32` naming its pass (0 the culled pass, whose pipeline culls back faces; 1
/// the kept pass): commands 24 bytes apart (`stride` 24 or more), the word at each command's
/// start, the `VkDrawIndexedIndirectCommand` 4 bytes after it. It sets the draws of both
/// passes to that same stream ([`CadrGpuDraws`] equal field for field, `commands_offset` at the
/// first command's word): a submission sees a shared stream as two consecutive passes with
/// equal draws. A culler that does not know the kind writes two streams as in ABI 1.18, which
/// a submission that announces the trait draws as two. Owned by the host, valid for the call.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrSharedFaceStreams {
    /// `kind` = [`CADR_EXTENSION_SHARED_FACE_STREAMS`]; the kind says it all.
    pub header: CadrExtension,
}

/// Since ABI 1.24 ([`CADR_EXTENSION_EMPTY_COMMAND_TAILS`], chained on the cull context of every
/// phase where the active submission announces [`CADR_TRAIT_EMPTY_COMMAND_TAILS`]): the
/// submission may draw any of the [`CadrGpuDraws::max_draws`] commands of each pass, whatever
/// the count says. A culler that honours it leaves every command past a pass's count drawing
/// nothing (`instanceCount` 0; `vkCmdFillBuffer` with zeros does) by the time the pass's draws
/// read it, in every phase, and still writes the counts. Owned by the host, valid for the call.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrEmptyCommandTails {
    /// `kind` = [`CADR_EXTENSION_EMPTY_COMMAND_TAILS`]; the kind says it all.
    pub header: CadrExtension,
}

/// Since ABI 1.22 ([`CADR_EXTENSION_PARAMETER_BLOCKS`], chained on the frame's scene views where
/// the active parameter path, submission and GPU culler announce
/// [`CADR_TRAIT_PARAMETER_BLOCKS`]): the draws carry their parameters. The GPU culler writes each
/// command after the [`CadrParameterBlock`] of its instance: the 96-byte block, then the
/// `VkDrawIndexedIndirectCommand` (and, in a shared stream, the word naming the pass before
/// both), `stride` 116 bytes or more (120 or more in a shared stream). [`CadrGpuDraws`] still
/// points at the first command's start (the block, or the word). The submission pushes each
/// block at offset 0 of the vertex stage's push constants before its draw. Owned by the host,
/// valid as long as the view it hangs from.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrParameterBlocks {
    /// `kind` = [`CADR_EXTENSION_PARAMETER_BLOCKS`]; the kind says it all.
    pub header: CadrExtension,
}

/// What a draw pass draws.
pub type CadrPassKind = u32;
/// Triangles (solid shading).
pub const CADR_PASS_TRIANGLES: CadrPassKind = 0;
/// Edge lines from the wire index buffer.
pub const CADR_PASS_EDGES: CadrPassKind = 1;
/// Since ABI 1.2: the pick pass. Triangles, as [`CADR_PASS_TRIANGLES`], but every pixel must
/// name its own part: draw each part with its own instance's parameters (never join several
/// parts into one range or one parameter binding; sorting is fine). The host passes it only
/// when every active technique was built for ABI 1.2 or later; older libraries get
/// [`CADR_PASS_TRIANGLES`] for the pick pass instead.
pub const CADR_PASS_PICK: CadrPassKind = 2;
/// Since ABI 1.23: triangles drawn by a mesh pipeline (the host's task and mesh shaders),
/// given only where the active submission announces [`CADR_TRAIT_MESH_SHADING`], for every
/// triangle pass but the hidden silhouettes' and the pick pass. Bind the pipeline, bind the
/// paths, push [`CadrMeshTaskPush`] and draw a task workgroup per command (see there). Cullers
/// treat it as [`CADR_PASS_TRIANGLES`].
pub const CADR_PASS_MESH_TRIANGLES: CadrPassKind = 3;
/// Since ABI 1.23: the pick pass drawn by a mesh pipeline, as [`CADR_PASS_MESH_TRIANGLES`]
/// (each command draws its own instance, as [`CADR_PASS_PICK`] asks). Cullers treat it as
/// [`CADR_PASS_PICK`].
pub const CADR_PASS_MESH_PICK: CadrPassKind = 4;

/// One pass of the frame: its pipeline and what it draws.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrPass {
    /// `VkPipeline` to bind.
    pub pipeline: u64,
    /// `CADR_PASS_*`.
    pub kind: CadrPassKind,
}

/// Since ABI 1.9: which instances a pass needs, by their flags: those whose
/// `flags & mask == value` ([`CadrInstance::flags`], the same bits in [`CadrCullEntry::flags`]).
/// The pass's pipeline clips every other instance away whole, so drawing them too is correct,
/// only wasted work: a submission or GPU culler that honours the filter skips them (the X-ray
/// mode's opaque pass needs only highlighted parts, the transparency method's pass only
/// translucent ones, the section caps' pass only closed ones); one that ignores it draws
/// everything as before. `mask` 0 is every instance.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct CadrPassFilter {
    /// The `CADR_INSTANCE_*` bits the filter looks at.
    pub mask: CadrInstanceFlags,
    /// What those bits must be.
    pub value: CadrInstanceFlags,
    /// Nonzero: only parts whose bounding sphere some section plane passes through (the
    /// section caps' pass: a part no plane cuts shows no cap). Only a culler that knows the
    /// planes and where the parts are can tell: a GPU culler honours it, a submission drawing
    /// its own lists does not.
    pub section_cut: u32,
}

impl CadrPassFilter {
    /// Whether an instance with `flags` is needed.
    pub fn keeps(&self, flags: CadrInstanceFlags) -> bool {
        flags & self.mask == self.value
    }
}

/// Since ABI 1.11: the instances a pass does not need although its [`CadrPassFilter`] keeps
/// them: those whose `flags & mask == value`; `mask` 0 excludes none. A filter says what a
/// needed instance is, an exclusion what it is not: the X-ray mode's translucent pass needs
/// every instance except the highlighted opaque ones its opaque pass draws, which no single
/// filter can say. As with the filter, the pass's pipeline clips the excluded instances away
/// whole, so drawing them is correct, only wasted work.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct CadrPassExclusion {
    /// The `CADR_INSTANCE_*` bits the exclusion looks at; 0 excludes nothing.
    pub mask: CadrInstanceFlags,
    /// What those bits are in an instance the pass does not need.
    pub value: CadrInstanceFlags,
}

impl CadrPassExclusion {
    /// Whether an instance with `flags` is not needed.
    pub fn excludes(&self, flags: CadrInstanceFlags) -> bool {
        self.mask != 0 && flags & self.mask == self.value
    }
}

/// Counters a frame's recording adds to.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CadrStats {
    /// Draw commands recorded (`vkCmdDraw*` calls, each indirect or multi-draw call counts once).
    pub draw_calls: u64,
    /// Parts or ranges those commands draw.
    pub draws: u64,
    /// Primitives (triangles or lines) drawn.
    pub primitives: u64,
    /// Pipeline binds.
    pub pipeline_binds: u64,
    /// Vertex and index buffer binds (and vertex-pulling descriptor or address changes).
    pub vertex_binds: u64,
    /// Parameter binds: push constants, descriptor sets, buffer updates.
    pub parameter_binds: u64,
    /// Bind calls that panicked (their shims caught it); the host treats the frame as failed.
    pub failures: u64,
}

/// What a vertex or parameter path binds with: the command buffer being recorded and the pass.
/// Owned by its caller (the submission), valid for the call.
#[repr(C)]
#[derive(Debug)]
pub struct CadrBindContext {
    /// Size of this struct.
    pub size: u32,
    /// `VkCommandBuffer` being recorded (primary or secondary).
    pub command_buffer: *mut c_void,
    /// `VkPipelineLayout` of the pass's pipeline.
    pub pipeline_layout: u64,
    /// `CADR_PASS_*`.
    pub pass_kind: CadrPassKind,
    /// The scene.
    pub scene: *const CadrSceneView,
    /// Counters to add to (one per recording thread).
    pub stats: *mut CadrStats,
}

/// Scratch a recording keeps per command buffer so that a path re-issues a binding only when
/// it changes. Zeroed (`valid == 0`) at the start of each command buffer.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CadrBindState {
    /// 0 until the path has bound something in this command buffer.
    pub valid: u32,
    /// Free for the path.
    pub words: [u64; 3],
}

/// Element offsets the vertex path's current binding starts at: a draw of an instance uses
/// `firstIndex = first_index - index_base` and `vertexOffset = vertex_base - vertex_base_bound`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CadrDrawBase {
    /// First index element of the bound index buffer range.
    pub index_base: u32,
    /// First vertex of the bound vertex range.
    pub vertex_base: u32,
    /// 0 when the instance cannot be drawn (nothing bound).
    pub ok: u32,
}

/// Vertex input a pipeline is built with.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CadrVertexInput {
    /// Stride of binding 0, or 0 for no vertex input (vertex pulling).
    pub stride: u32,
    /// Number of attributes (at most 4): location i has format `formats[i]` at `offsets[i]`.
    pub attribute_count: u32,
    /// `VkFormat` per attribute.
    pub formats: [i32; 4],
    /// Byte offset per attribute.
    pub offsets: [u32; 4],
}

/// Functions every technique has at the start of its vtable.
#[repr(C)]
#[derive(Debug)]
pub struct CadrCommonVtable {
    /// Size of the whole vtable.
    pub size: u32,
    /// Creates an instance into `*instance`. On failure writes `message`.
    pub create: Option<
        unsafe extern "C" fn(
            info: *const CadrCreateInfo,
            instance: *mut *mut c_void,
            message: *mut CadrMessage,
        ) -> CadrStatus,
    >,
    /// Destroys an instance (the GPU has finished with everything it recorded).
    pub destroy: Option<unsafe extern "C" fn(instance: *mut c_void)>,
}

/// GLSL the host pastes into the vertex shader (`shaders/technique.vert`). The host declares
/// `struct CadrObject` and the push-constant block `cadr_push { mat4 matrix; vec4 vectors[2];
/// uvec4 words[2]; }`: `matrix` and `vectors` (bytes 0–95) belong to the parameter path,
/// `words` (bytes 96–127) to the vertex path; descriptor sets 1 and 2 belong to the parameter
/// path, set 3 to the vertex path (set 0 is the host's frame uniforms). Lines starting with
/// `#extension` are moved to the top of the shader.
pub type CadrShaderSnippetFn = Option<unsafe extern "C" fn(instance: *mut c_void) -> *const c_char>;

/// Prepares for a frame before the pass (uploads, descriptor writes); may record transfer or
/// compute commands into `command_buffer` (a primary outside rendering).
pub type CadrPrepareFn = Option<
    unsafe extern "C" fn(
        instance: *mut c_void,
        scene: *const CadrSceneView,
        command_buffer: *mut c_void,
        message: *mut CadrMessage,
    ) -> CadrStatus,
>;

/// Vertex path vtable ([`CADR_KIND_VERTEX_PATH`]). Its snippet defines
/// `vec3 cadr_vertex_position()` and `vec3 cadr_vertex_normal()`.
#[repr(C)]
#[derive(Debug)]
pub struct CadrVertexPathVtable {
    /// Size, create, destroy.
    pub common: CadrCommonVtable,
    /// The GLSL snippet.
    pub shader_snippet: CadrShaderSnippetFn,
    /// The vertex input state.
    pub vertex_input:
        Option<unsafe extern "C" fn(instance: *mut c_void, input: *mut CadrVertexInput)>,
    /// `VkDescriptorSetLayout` for set 3, or 0.
    pub set_layout: Option<unsafe extern "C" fn(instance: *mut c_void) -> u64>,
    /// Before the pass.
    pub prepare: CadrPrepareFn,
    /// Binds what stays bound for the whole pass. Thread-safe.
    pub bind_pass: Option<
        unsafe extern "C" fn(
            instance: *mut c_void,
            context: *const CadrBindContext,
            state: *mut CadrBindState,
        ),
    >,
    /// Binds what the draw of `drawn` needs unless `state` says it is bound; returns where
    /// the binding starts. Thread-safe.
    pub bind_draw: Option<
        unsafe extern "C" fn(
            instance: *mut c_void,
            context: *const CadrBindContext,
            drawn: *const CadrInstance,
            state: *mut CadrBindState,
        ) -> CadrDrawBase,
    >,
}

/// Parameter path vtable ([`CADR_KIND_PARAMETER_PATH`]). Its snippet defines
/// `CadrObject cadr_object()` (the host declares `struct CadrObject { mat4 world; vec4
/// base_color; vec2 surface; uint flags; uint instance; }`, `world` laid out as
/// [`CadrMatrix`]).
#[repr(C)]
#[derive(Debug)]
pub struct CadrParameterPathVtable {
    /// Size, create, destroy.
    pub common: CadrCommonVtable,
    /// The GLSL snippet.
    pub shader_snippet: CadrShaderSnippetFn,
    /// `VkDescriptorSetLayout`s for sets 1 and 2 (0 for none), and the push-constant bytes used.
    pub layout: Option<
        unsafe extern "C" fn(
            instance: *mut c_void,
            set_layouts: *mut u64,
            push_constant_bytes: *mut u32,
        ),
    >,
    /// Before the pass.
    pub prepare: CadrPrepareFn,
    /// Binds what stays bound for the whole pass. Thread-safe.
    pub bind_pass: Option<
        unsafe extern "C" fn(
            instance: *mut c_void,
            context: *const CadrBindContext,
            state: *mut CadrBindState,
        ),
    >,
    /// Binds the parameters of instance `id` unless `state` says they are bound; returns the
    /// `firstInstance` the draw must use. Thread-safe.
    pub bind_draw: Option<
        unsafe extern "C" fn(
            instance: *mut c_void,
            context: *const CadrBindContext,
            id: u32,
            drawn: *const CadrInstance,
            state: *mut CadrBindState,
        ) -> u32,
    >,
}

/// A technique the submission drives: instance and vtable.
#[repr(C)]
#[derive(Debug)]
pub struct CadrPathRef<V> {
    /// The path's instance.
    pub instance: *mut c_void,
    /// The path's vtable.
    pub vtable: *const V,
}

impl<V> Clone for CadrPathRef<V> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<V> Copy for CadrPathRef<V> {}

/// What a submission records with. Owned by the host, valid for the call; the command
/// buffer is the host's (secondary command buffers the submission records are its own).
///
/// Its many fields are the ABI as it stood before extension chains: it keeps them, and what
/// is new reaches the submission through the scene view's chain (`scene.extensions`).
#[repr(C)]
#[derive(Debug)]
pub struct CadrRecordContext {
    /// Size of this struct.
    pub size: u32,
    /// The primary `VkCommandBuffer`, inside dynamic rendering during `record`.
    pub command_buffer: *mut c_void,
    /// `VkPipelineLayout` shared by the passes.
    pub pipeline_layout: u64,
    /// `VkDescriptorSet` of the frame uniforms, for set 0.
    pub frame_set: u64,
    /// Number of passes.
    pub pass_count: u32,
    /// The passes, in order.
    pub passes: *const CadrPass,
    /// Target width and height (viewport and scissor of secondary command buffers).
    pub width: u32,
    /// Target height.
    pub height: u32,
    /// The scene.
    pub scene: *const CadrSceneView,
    /// The vertex path.
    pub vertex: CadrPathRef<CadrVertexPathVtable>,
    /// The parameter path.
    pub parameters: CadrPathRef<CadrParameterPathVtable>,
    /// Changes whenever anything recorded commands depend on changed (draws, passes, target,
    /// and parameter values under [`CADR_TRAIT_PARAMETERS_IN_COMMANDS`]): a technique that
    /// replays recorded commands re-records when it differs from last time.
    pub commands_key: u64,
    /// Counters to add to.
    pub stats: *mut CadrStats,
    /// Since ABI 1.1: the `VkFormat` of the pass's colour attachment (the pick pass draws
    /// instance ids into `VK_FORMAT_R32_UINT`); secondary command buffers must inherit it.
    /// Read it only when `size` covers it; 0 means [`CadrVulkan::color_format`].
    pub color_format: i32,
    /// Since ABI 1.3 (read it only when `size` covers it): null, or `pass_count` draw sources a
    /// GPU culler wrote for this phase of the frame, one per pass: a submission that provides
    /// [`CADR_TRAIT_DRAWS_GPU_COMMANDS`] draws each pass from its source.
    pub gpu_draws: *const CadrGpuDraws,
    /// Since ABI 1.3: the phase of the frame being recorded (0 unless a GPU culler splits the
    /// frame into phases, see [`CadrCullingVtable::phase_count`]).
    pub phase: u32,
    /// Since ABI 1.7 (read it only when `size` covers it): how many colour attachments the
    /// rendering has after the first (`color_format`): the transparency method's targets
    /// ([`CadrTransparencyMethod::targets`]) while the frame draws translucent surfaces, else 0.
    /// Secondary command buffers inherit all of them, in order.
    pub extra_color_count: u32,
    /// Since ABI 1.7: the `VkFormat`s of those attachments (`extra_color_count` of them).
    pub extra_color_formats: [i32; 2],
    /// Since ABI 1.8 (read it only when `size` covers it; absent means 1): the samples per
    /// pixel of every attachment of the rendering, a `VkSampleCountFlagBits` (1 without MSAA;
    /// the pick pass always has 1). Secondary command buffers inherit it as their
    /// `rasterizationSamples`. The host draws with MSAA through a submission of
    /// [`CADR_TRAIT_SECONDARY_COMMAND_BUFFERS`] only when its library is of ABI 1.8 or later.
    pub rasterization_samples: u32,
    /// Since ABI 1.9 (read it only when `size` covers it): null, or `pass_count` filters, one
    /// per pass: the instances each pass needs ([`CadrPassFilter`]). Part of what
    /// `commands_key` covers.
    pub pass_filters: *const CadrPassFilter,
    /// Since ABI 1.11 (read it only when `size` covers it): null, or `pass_count` exclusions,
    /// one per pass: the instances each pass does not need although its filter keeps them
    /// ([`CadrPassExclusion`]). Part of what `commands_key` covers.
    pub pass_exclusions: *const CadrPassExclusion,
}

/// Submission vtable ([`CADR_KIND_SUBMISSION`]).
#[repr(C)]
#[derive(Debug)]
pub struct CadrSubmissionVtable {
    /// Size, create, destroy.
    pub common: CadrCommonVtable,
    /// Before the pass (outside rendering): e.g. writes indirect commands.
    pub prepare: Option<
        unsafe extern "C" fn(
            instance: *mut c_void,
            context: *const CadrRecordContext,
            message: *mut CadrMessage,
        ) -> CadrStatus,
    >,
    /// Inside rendering: records (or replays) the passes' draws, pass by pass: every draw of a
    /// pass comes before any draw of the next (the translucent surfaces' pass, last, must see
    /// every opaque surface's depth), also when several threads record.
    pub record: Option<
        unsafe extern "C" fn(
            instance: *mut c_void,
            context: *const CadrRecordContext,
            message: *mut CadrMessage,
        ) -> CadrStatus,
    >,
}

/// What culling reads. Owned by the host, read-only, valid for the call.
#[repr(C)]
#[derive(Debug)]
pub struct CadrCullInput {
    /// Size of this struct.
    pub size: u32,
    /// The scene (instances with their spheres, candidates in `drawn_bits` before culling).
    pub scene: *const CadrSceneView,
    /// Candidate bits: alive, visible in the tree, with triangles.
    pub candidate_bits: *const u64,
    /// World matrices in f64 per matrix slot (column-major, 16 each). Null while the host
    /// keeps the transform hierarchy on the GPU (no active technique announces
    /// [`CADR_TRAIT_READS_HOST_MATRICES`]): a culler that reads them announces it.
    pub world_matrices: *const f64,
    /// World-space frustum planes (xyz normal pointing inside, w distance): a point p is
    /// inside when `dot(n, p) + w >= 0` for all six.
    pub planes: [[f64; 4]; 6],
    /// Since ABI 1.9 (read it only when `size` covers it): how many of `section_planes` the
    /// view is cut with.
    pub section_plane_count: u32,
    /// Since ABI 1.9: world-space section planes (xyz unit normal, w distance), each keeping
    /// the points with `dot(n, p) + w >= 0`: a part whose sphere lies wholly outside one is
    /// cut away, and a culler may cull it like one outside the frustum.
    pub section_planes: [[f64; 4]; 6],
}

/// What culling writes: `word_count` words each. The host owns both arrays; the culler
/// writes every word during the call and keeps no pointer to them.
#[repr(C)]
#[derive(Debug)]
pub struct CadrCullOutput {
    /// Size of this struct.
    pub size: u32,
    /// Words at each pointer.
    pub word_count: u32,
    /// Bit per instance id: passes culling (the culler keeps these between frames).
    pub visible_bits: *mut u64,
    /// Bits that differ from the last frame's `visible_bits` (the XOR), so the host applies
    /// only the changes.
    pub changed_bits: *mut u64,
}

/// Since ABI 1.3: where the indirect commands of one pass lie, written by a GPU culler
/// during the frame: `VkDrawIndexedIndirectCommand`s (20 bytes each, `firstInstance` the
/// instance id) and their count (a u32). The culler owns the buffers. Since ABI 1.19, two
/// consecutive passes with equal draws share one stream whose commands each start with the
/// word that names their pass ([`CadrSharedFaceStreams`]); only a submission that
/// announces [`CADR_TRAIT_SWITCHES_PIPELINES`] is given such draws.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CadrGpuDraws {
    /// `VkBuffer` of the commands (0: the pass draws nothing).
    pub commands: u64,
    /// Byte offset of the first command.
    pub commands_offset: u64,
    /// `VkBuffer` holding the count.
    pub count_buffer: u64,
    /// Byte offset of the count.
    pub count_offset: u64,
    /// The most commands the count can say (`maxDrawCount`).
    pub max_draws: u32,
    /// Bytes between commands (20 or more, a multiple of 4).
    pub stride: u32,
}

/// Since ABI 1.3: what a GPU culler records with, once per phase of the frame. Owned by the
/// host, valid for the call; the culler writes `draws`.
///
/// Positions are relative to the eye so that precision holds far from the origin: the GPU
/// matrices keep their translation as an f32 high part and remainder ([`CadrMatrix`]), and a
/// point `p` relative to the eye is `(t_high - eye_high) + (t_low - eye_low) + R * x`.
///
/// Its many fields are the ABI as it stood before extension chains: it keeps them, and grows
/// only through `extensions`.
#[repr(C)]
#[derive(Debug)]
pub struct CadrGpuCullContext {
    /// Size of this struct.
    pub size: u32,
    /// The phase being recorded, `0..phase_count`.
    pub phase: u32,
    /// The primary `VkCommandBuffer`, outside rendering. The host has made the frame's scene
    /// uploads visible to compute shaders; the culler makes its own writes visible to
    /// `DRAW_INDIRECT` and vertex shaders with a barrier before it returns.
    pub command_buffer: *mut c_void,
    /// The scene (its `cull_buffer`, `instance_buffer` and `matrix_buffer` hold the data).
    pub scene: *const CadrSceneView,
    /// Number of passes.
    pub pass_count: u32,
    /// The passes the frame draws, in order (their kinds say which ranges: triangles, edges,
    /// or pickable triangles for the pick pass).
    pub passes: *const CadrPass,
    /// Where the culler writes the draw source of each pass for this phase (`pass_count`
    /// entries, zeroed by the host).
    pub draws: *mut CadrGpuDraws,
    /// The eye position's f32 high part (xyz, w = 0).
    pub eye_high: [f32; 4],
    /// The eye position's f32 remainder (xyz, w = 0).
    pub eye_low: [f32; 4],
    /// Frustum planes relative to the eye (xyz normal pointing inside, w distance): a point `q`
    /// relative to the eye is inside when `dot(n, q) + w >= 0` for all six.
    pub planes: [[f32; 4]; 6],
    /// Projection times the view's rotation, column-major: clip coordinates of a point
    /// relative to the eye (Vulkan depth 0..1).
    pub view_projection: [f32; 16],
    /// Target width in pixels.
    pub width: u32,
    /// Target height in pixels.
    pub height: u32,
    /// The frame's depth image (`VkImage`), readable in phases after the first: the host has
    /// ended rendering, and the image is in `depth_layout` with its writes visible to compute
    /// shaders; the culler leaves it in that layout. 0 in phase 0.
    pub depth_image: u64,
    /// A `VkImageView` of the depth image (depth aspect), 0 in phase 0.
    pub depth_view: u64,
    /// `VkImageLayout` of the depth image during the call.
    pub depth_layout: i32,
    /// Since ABI 1.5 (read it only when `size` covers it): the smallest projected diameter, in
    /// pixels, of a part's bounding sphere that is still drawn; a part whose sphere projects
    /// smaller is culled from every pass (pick included, so what is picked is what is seen).
    /// 0 (the default) culls nothing for its size: CAD users count small parts. A part whose
    /// sphere holds the eye is never culled for its size.
    pub min_pixels: f32,
    /// Since ABI 1.5: a `VkBuffer` (uniform-buffer usage, host-written before each submission
    /// of the frame, also one that resubmits it) holding a [`CadrGpuCullView`] at
    /// `view_offset`: the same view as the fields above, for shaders. A culler that reads the
    /// view from here rather than recording its values can be replayed
    /// ([`CADR_TRAIT_REPLAYABLE`]). Owned by the host; valid while the frame runs.
    pub view_buffer: u64,
    /// Byte offset of the [`CadrGpuCullView`] in `view_buffer` (a multiple of 256).
    pub view_offset: u64,
    /// Since ABI 1.9 (read it only when `size` covers it): null, or `pass_count` filters, one
    /// per pass: the instances each pass needs ([`CadrPassFilter`]); a culler that honours
    /// them writes no commands for the others.
    pub pass_filters: *const CadrPassFilter,
    /// Since ABI 1.9: how many of `section_planes` the view is cut with.
    pub section_plane_count: u32,
    /// Since ABI 1.9: the section planes relative to the eye (xyz unit normal, w distance),
    /// each keeping the points `q` (relative to the eye) with `dot(n, q) + w >= 0`: a part
    /// whose sphere lies wholly outside one is cut away, and the culler may cull it like one
    /// outside the frustum. Also in [`CadrGpuCullView::section_planes`].
    pub section_planes: [[f32; 4]; 6],
    /// Since ABI 1.11 (read it only when `size` covers it): null, or `pass_count` exclusions,
    /// one per pass ([`CadrPassExclusion`]); a culler that honours them writes no commands for
    /// the instances they exclude.
    pub pass_exclusions: *const CadrPassExclusion,
    /// Since ABI 1.14 (read it only when `size` covers it): the host's extension structs for
    /// this call (a chain of [`CadrExtension`]s, or null), valid for the call:
    /// [`CadrClusterCull`] where the scene has clusters; since ABI 1.18 [`CadrBackFacePasses`]
    /// where the culler announces [`CADR_TRAIT_ROUTES_BACK_FACES`]; since ABI 1.19
    /// [`CadrSharedFaceStreams`] beside it where the submission announces
    /// [`CADR_TRAIT_SWITCHES_PIPELINES`]; since ABI 1.24 [`CadrEmptyCommandTails`] where the
    /// submission announces [`CADR_TRAIT_EMPTY_COMMAND_TAILS`].
    pub extensions: *const CadrExtension,
}

/// Since ABI 1.5: the view of a GPU-culled frame as shaders read it (std140: vec4s, then a
/// column-major mat4, a uvec4 and a vec4; since ABI 1.9 six vec4s and a uvec4 more, which an
/// older culler's shaders do not declare), in [`CadrGpuCullContext::view_buffer`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CadrGpuCullView {
    /// The eye position's f32 high part (xyz, w = 0).
    pub eye_high: [f32; 4],
    /// The eye position's f32 remainder (xyz, w = 0).
    pub eye_low: [f32; 4],
    /// Frustum planes relative to the eye, as [`CadrGpuCullContext::planes`].
    pub planes: [[f32; 4]; 6],
    /// Projection times the view's rotation, column-major, as
    /// [`CadrGpuCullContext::view_projection`].
    pub view_projection: [f32; 16],
    /// Target width and height in pixels, then two zeros.
    pub target: [u32; 4],
    /// The sub-pixel threshold ([`CadrGpuCullContext::min_pixels`]); the pixels one unit of
    /// size covers at clip w = 1 (the larger of the x and y scales: a sphere of radius r at
    /// clip w spans about `2 r k / w` pixels); two zeros.
    pub sub_pixel: [f32; 4],
    /// Since ABI 1.9: the section planes relative to the eye, as
    /// [`CadrGpuCullContext::section_planes`] (the unused ones keep everything: 0, 0, 0, 1).
    pub section_planes: [[f32; 4]; 6],
    /// Since ABI 1.9: the number of section planes, then three zeros.
    pub section: [u32; 4],
}

/// Culling vtable ([`CADR_KIND_CULLING`]).
#[repr(C)]
#[derive(Debug)]
pub struct CadrCullingVtable {
    /// Size, create, destroy.
    pub common: CadrCommonVtable,
    /// Culls on the CPU before the frame is recorded.
    pub cull: Option<
        unsafe extern "C" fn(
            instance: *mut c_void,
            input: *const CadrCullInput,
            output: *mut CadrCullOutput,
            message: *mut CadrMessage,
        ) -> CadrStatus,
    >,
    /// GPU culling (reserved and null before ABI 1.3; a culler has `cull` or this): records,
    /// for one phase of the frame, compute work that tests the instances on the GPU and writes
    /// each pass's indirect commands and count, and says where in `context.draws`. The host
    /// then records the phase's rendering with the submission drawing from them.
    pub record_gpu: Option<
        unsafe extern "C" fn(
            instance: *mut c_void,
            context: *const CadrGpuCullContext,
            message: *mut CadrMessage,
        ) -> CadrStatus,
    >,
    /// Since ABI 1.3: how many phases a frame has with this GPU culler (none or 0 means 1).
    /// Between phases the host ends rendering and hands the culler the depth so far (two-phase
    /// occlusion: draw what was visible last frame, test the rest against that depth, draw
    /// what became visible).
    pub phase_count: Option<unsafe extern "C" fn(instance: *mut c_void) -> u32>,
    /// Since ABI 1.3: adds to `stats` what the GPU drew (`draws`, `primitives`) in the last
    /// frame whose work has finished. Called by the host after waiting for a frame.
    pub gpu_counts: Option<unsafe extern "C" fn(instance: *mut c_void, stats: *mut CadrStats)>,
}

/// Since ABI 1.7: how a colour target of a transparency method is blended, as the fields of
/// `VkPipelineColorBlendAttachmentState` (blending is always enabled; all four components are
/// written).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CadrBlend {
    /// `VkBlendFactor` for the colour source.
    pub src_color: i32,
    /// `VkBlendFactor` for the colour destination.
    pub dst_color: i32,
    /// `VkBlendOp` for colour.
    pub color_op: i32,
    /// `VkBlendFactor` for the alpha source.
    pub src_alpha: i32,
    /// `VkBlendFactor` for the alpha destination.
    pub dst_alpha: i32,
    /// `VkBlendOp` for alpha.
    pub alpha_op: i32,
}

/// Since ABI 1.7: one colour target a transparency method draws translucent fragments into.
/// The host creates it at the frame's size, clears it when the frame begins and lets the merge
/// read it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CadrTransparencyTarget {
    /// `VkFormat`: one every device blends into and samples, which the host accepts:
    /// `VK_FORMAT_R16G16B16A16_SFLOAT`, `VK_FORMAT_R16G16_SFLOAT`, `VK_FORMAT_R16_SFLOAT` or
    /// `VK_FORMAT_R8G8B8A8_UNORM` (another is refused when the technique is selected).
    pub format: i32,
    /// How fragments are blended into it.
    pub blend: CadrBlend,
    /// The value it is cleared to.
    pub clear: [f32; 4],
}

/// Since ABI 1.7: what a transparency method is, as the host builds it into every frame that
/// draws translucent surfaces (parts whose material's opacity is under 1, or every part not
/// highlighted in the X-ray display mode). Opaque surfaces are drawn first, as without
/// translucency; then, in the same rendering and with the same submission and culling, the
/// translucent surfaces are drawn with depth testing against the opaque ones but no depth
/// writes, each fragment handed to `fragment_snippet`; after rendering, a full-screen pass
/// runs `merge_snippet` per pixel and blends what it returns over the opaque picture.
///
/// Written by the plugin into the host's struct; the strings belong to the instance and stay
/// valid as long as it lives.
///
/// The host declares, for both snippets, the frame uniforms (`frame`) and:
/// - `uint cadr_pixel_index()`: the pixel's index, `y * width + x`;
/// - `uint cadr_pixel_count()`: width × height of the target;
/// - with `storage_words_per_pixel` > 0, `buffer CadrTransparencyStorage { uint
///   cadr_storage[]; }`: `storage_header_words + storage_words_per_pixel × pixels` words, of
///   which the first `storage_header_words + storage_cleared_words_per_pixel × pixels` are
///   zero when the frame's translucent surfaces begin (the rest keeps what it held);
/// - in the fragment snippet, `layout(location = 1 + i) out vec4 cadr_target_i` for each
///   target (`cadr_target_0`, `cadr_target_1`); fragment tests run early, so a fragment that
///   reaches the snippet is in front of every opaque surface;
/// - in the merge snippet, `vec4 cadr_target_texel(int i)`: target i at this pixel.
#[repr(C)]
#[derive(Debug)]
pub struct CadrTransparencyMethod {
    /// Size of this struct as the host knows it (the host sets it; the plugin writes fields
    /// it covers).
    pub size: u32,
    /// Number of colour targets (0 to 2) at `targets`.
    pub target_count: u32,
    /// The targets.
    pub targets: [CadrTransparencyTarget; 2],
    /// Words of storage at the start of the buffer, zeroed every frame (counters).
    pub storage_header_words: u32,
    /// Words of storage per pixel (0: no storage buffer).
    pub storage_words_per_pixel: u32,
    /// Of those, the words per pixel zeroed every frame (they lie first, right after the
    /// header: `cadr_storage[storage_header_words + i]` for i below this times the pixels).
    pub storage_cleared_words_per_pixel: u32,
    /// GLSL defining `void cadr_transparent_fragment(vec4 color, float view_depth)`: `color`
    /// is the shaded colour premultiplied by its opacity (gamma-encoded, as the picture),
    /// `view_depth` the distance along the view direction (positive, in scene units). It
    /// writes the targets and the storage.
    pub fragment_snippet: *const c_char,
    /// GLSL defining `vec4 cadr_merge()`: the pixel's translucent colour, premultiplied, with
    /// its coverage in alpha; the host blends it over the opaque picture
    /// (`rgb + picture × (1 − a)`).
    pub merge_snippet: *const c_char,
}

/// Since ABI 1.7: transparency vtable ([`CADR_KIND_TRANSPARENCY`]).
#[repr(C)]
#[derive(Debug)]
pub struct CadrTransparencyVtable {
    /// Size, create, destroy.
    pub common: CadrCommonVtable,
    /// Describes the method into `method` (whose `size` the host set; the host owns the struct
    /// and copies the snippets, which stay the instance's). Called once per instance, after
    /// `create`, from one thread; on failure writes `message`.
    pub method: Option<
        unsafe extern "C" fn(
            instance: *mut c_void,
            method: *mut CadrTransparencyMethod,
            message: *mut CadrMessage,
        ) -> CadrStatus,
    >,
}

impl CadrInstanceRecord {
    /// The GPU layout: 4 little-endian u32.
    pub fn to_le_bytes(&self) -> [u8; 16] {
        let mut bytes = [0; 16];
        for (i, value) in [self.matrix, self.material, self.flags, self.instance]
            .iter()
            .enumerate()
        {
            bytes[i * 4..i * 4 + 4].copy_from_slice(&value.to_le_bytes());
        }
        bytes
    }
}

/// Makes sure the structs really are what the C side sees.
#[cfg(test)]
mod tests {
    use super::*;

    /// The push lands where `shaders/mesh_tasks.glsl` reads it: two addresses, then the
    /// stride, after the paths' 128 bytes.
    #[test]
    fn the_mesh_task_push_has_the_shaders_layout() {
        let push = CadrMeshTaskPush {
            commands: 0x0102_0304_0506_0708,
            indices: 9,
            stride_words: 5,
            reserved: 0,
        };
        let bytes = push.to_le_bytes();
        assert_eq!(bytes[0..8], 0x0102_0304_0506_0708u64.to_le_bytes());
        assert_eq!(bytes[8], 9);
        assert_eq!(bytes[16], 5);
        assert_eq!(bytes.len(), std::mem::size_of::<CadrMeshTaskPush>());
        assert_eq!(CADR_MESH_TASK_PUSH_OFFSET as usize + bytes.len(), 152);
    }

    #[test]
    fn structs_have_their_c_sizes() {
        assert_eq!(std::mem::size_of::<CadrInstance>(), 64);
        assert_eq!(std::mem::size_of::<CadrMatrix>(), 64);
        assert_eq!(std::mem::size_of::<CadrMaterial>(), 32);
        assert_eq!(std::mem::size_of::<CadrInstanceRecord>(), 16);
        assert_eq!(std::mem::size_of::<CadrBindState>(), 32);
        assert_eq!(std::mem::size_of::<CadrCullEntry>(), 48);
        assert_eq!(std::mem::size_of::<CadrParameterBlock>(), 96);
        assert_eq!(std::mem::size_of::<CadrGpuDraws>(), 40);
        assert_eq!(std::mem::size_of::<CadrMeshTaskPush>(), 24);
        assert_eq!(std::mem::size_of::<CadrPassFilter>(), 12);
        assert_eq!(std::mem::size_of::<CadrPassExclusion>(), 8);
        assert_eq!(CADR_PLUGIN_ABI_VERSION >> 16, CADR_PLUGIN_ABI_MAJOR);
        assert_eq!(std::mem::size_of::<CadrExtension>(), 16);
    }

    #[test]
    fn a_parameter_block_is_laid_out_as_the_push_constants_read_it() {
        let mut matrix = CadrMatrix::default();
        matrix.columns[3] = [1.0, 2.0, 3.0, 1.0];
        let material = CadrMaterial {
            base_color: [0.1, 0.2, 0.3, 0.4],
            surface: [0.5, 0.6, 0.7, 0.8],
        };
        let bytes = CadrParameterBlock::new(&matrix, &material, 0x12, 77).to_le_bytes();
        assert_eq!(bytes[..64], matrix.to_le_bytes());
        // The material's base colour and first two surface values; not the rest of the slot.
        assert_eq!(bytes[64..88], material.to_le_bytes()[..24]);
        assert_eq!(bytes[88..92], 0x12u32.to_le_bytes());
        assert_eq!(bytes[92..], 77u32.to_le_bytes());
    }

    #[test]
    fn an_extension_is_found_by_its_kind_anywhere_in_its_chain() {
        let last = CadrExtension {
            size: 16,
            kind: 7,
            next: std::ptr::null(),
        };
        let first = CadrExtension {
            size: 16,
            kind: 3,
            next: &last,
        };
        // SAFETY: a chain of two live extensions, then the empty chain.
        unsafe {
            assert_eq!(find_extension(&first, 7).map(|e| e.kind), Some(7));
            assert_eq!(find_extension(&first, 3).map(|e| e.kind), Some(3));
            assert!(
                find_extension(&first, 5).is_none(),
                "a kind not in the chain"
            );
            assert!(
                find_extension(std::ptr::null(), 3).is_none(),
                "the empty chain"
            );
        }
    }

    #[test]
    fn messages_are_cut_at_a_character_boundary() {
        let mut bytes = [0xffu8; 5];
        let mut message = CadrMessage {
            text: bytes.as_mut_ptr().cast(),
            capacity: bytes.len(),
        };
        // SAFETY: the message points at 5 writable bytes.
        unsafe { CadrMessage::write(&mut message, "ab→c") };
        assert_eq!(
            &bytes[..3],
            b"ab\0",
            "the 3-byte arrow does not fit in 2 bytes"
        );
    }
}
