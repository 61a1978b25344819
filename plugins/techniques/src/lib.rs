//! cadr's own techniques, written against the plugin SDK. Each module defines one technique
//! library (a `technique_library!` entry function, nothing exported): [`builtin`] is linked
//! into the host statically; the others are exported as the dynamic libraries in
//! `plugins/vertex`, `plugins/parameters`, `plugins/submission`, `plugins/culling` and `plugins/transparency`, which
//! the host finds and loads at run time.

pub mod builtin;
pub mod culling;
pub mod gpu_culling;
pub mod parameters;
pub mod submission;
pub mod transparency;
pub mod vertex;

use cadr_plugin_sdk::abi;

/// What cadr's techniques announce unless they read parameter values on the host (`push`,
/// `ubo-dynamic`): their frames may be replayed, also those in which only parameter values
/// changed (moved parts, new material values).
pub(crate) const REPLAYABLE: abi::CadrTraitBits =
    abi::CADR_TRAIT_REPLAYABLE | abi::CADR_TRAIT_REPLAYS_PARAMETER_CHANGES;

/// What cadr's techniques announce unless they record secondary command buffers every frame
/// (`individual-threads`, `groups-threads`): they write host memory and descriptor sets only
/// when the scene or the frame's passes changed (the host then waits for every frame in
/// flight) or into the copy of the frame's slot (the GPU cullers' cull sets), and their
/// secondary buffers, recorded once, may be pending in several frames at once.
pub(crate) const KEEPS_FRAME_SLOTS: abi::CadrTraitBits = abi::CADR_TRAIT_FRAME_SLOTS;
/// What cadr's vertex and parameter paths promise: their snippets, vertex input, push bytes and
/// set layouts are constants, the same for every instance, so renderers of one device share the
/// pipelines built with them.
pub(crate) const SHARES_PIPELINES: abi::CadrTraitBits = abi::CADR_TRAIT_SHARES_PIPELINES;
/// Bytes of a command of a stream two passes share (`CadrSharedFaceStreams`): the word naming
/// the command's pass, then its `VkDrawIndexedIndirectCommand`. The GPU cullers write such
/// commands, `dgc` reads them.
pub(crate) const NAMED_COMMAND_BYTES: u32 = 24;
