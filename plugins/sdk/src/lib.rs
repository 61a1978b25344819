//! The SDK for writing cadr technique plugins in Rust.
//!
//! Implement [`Technique`] and one kind trait ([`VertexPath`], [`ParameterPath`],
//! [`Submission`], [`Culling`], [`GpuCulling`] or [`Transparency`]) per technique, then list them in [`technique_library!`], which
//! generates the `extern "C"` shims (each catching panics) that the host calls, and export the
//! library from a dynamic library with [`export_plugin!`] (the two symbols the host looks for).
//! A library that is not exported can be linked into a host statically: cadr's built-in
//! techniques are such a library. The views ([`Scene`], [`Bind`], [`Record`], …) turn the ABI's raw pointers
//! into slices and safe calls.

pub mod export;
mod gpu;
mod message;
mod views;

pub use ash;
pub use ash::vk;
pub use cadr_plugin_abi as abi;
pub use cadr_vk_ext::device_generated_commands as dgc;
pub use gpu::{grown_capacity, Gpu, HostBuffer};
pub use views::{buffer, Bind, CullInput, CullOutput, GpuCull, PassFilter, Path, Record, Scene};

use std::ffi::CStr;
use std::sync::Arc;

/// What every technique is: created on the host's device, dropped when the host destroys it.
pub trait Technique: Sized + Send + Sync + 'static {
    /// Creates an instance on `gpu`.
    fn create(gpu: Arc<Gpu>) -> Result<Self, String>;
}

/// A vertex path: how vertices and indices reach the vertex shader.
pub trait VertexPath: Technique {
    /// GLSL defining `vec3 cadr_vertex_position()` and `vec3 cadr_vertex_normal()` (set 3 and
    /// push-constant bytes 96–127 are the vertex path's).
    fn shader_snippet(&self) -> &CStr;
    /// The pipeline's vertex input.
    fn vertex_input(&self) -> abi::CadrVertexInput;
    /// The layout of set 3, if the path uses one.
    fn set_layout(&self) -> vk::DescriptorSetLayout {
        vk::DescriptorSetLayout::null()
    }
    /// Before the pass (outside rendering).
    fn prepare(
        &mut self,
        _scene: &Scene<'_>,
        _command_buffer: vk::CommandBuffer,
    ) -> Result<(), String> {
        Ok(())
    }
    /// Binds what stays bound for the pass. Called from several threads at once.
    fn bind_pass(&self, _bind: &Bind<'_>, _state: &mut abi::CadrBindState) {}
    /// Binds what the draw of `drawn` needs unless `state` says it is bound. Called from
    /// several threads at once.
    fn bind_draw(
        &self,
        bind: &Bind<'_>,
        drawn: &abi::CadrInstance,
        state: &mut abi::CadrBindState,
    ) -> abi::CadrDrawBase;
}

/// A parameter path: how matrices and materials reach the shaders.
pub trait ParameterPath: Technique {
    /// GLSL defining `CadrObject cadr_object()` (sets 1 and 2 and push-constant bytes 0–95 are
    /// the parameter path's).
    fn shader_snippet(&self) -> &CStr;
    /// Layouts of sets 1 and 2 (null for none) and the push-constant bytes used.
    fn layout(&self) -> ([vk::DescriptorSetLayout; 2], u32);
    /// Before the pass (outside rendering): uploads.
    fn prepare(
        &mut self,
        _scene: &Scene<'_>,
        _command_buffer: vk::CommandBuffer,
    ) -> Result<(), String> {
        Ok(())
    }
    /// Binds what stays bound for the pass. Called from several threads at once.
    fn bind_pass(&self, _bind: &Bind<'_>, _state: &mut abi::CadrBindState) {}
    /// Binds instance `id`'s parameters unless `state` says they are bound; returns the
    /// `firstInstance` to draw with. Called from several threads at once.
    fn bind_draw(
        &self,
        bind: &Bind<'_>,
        id: u32,
        drawn: &abi::CadrInstance,
        state: &mut abi::CadrBindState,
    ) -> u32;
}

/// A draw submission: which draws are issued and how.
pub trait Submission: Technique {
    /// The plugin ABI extensions (`CADR_EXTENSION_*`) the submission cannot work without: a
    /// host that does not know one refuses the technique, naming it. None by default.
    const REQUIRED_EXTENSIONS: &'static [abi::CadrExtensionKind] = &[];
    /// Before the pass (outside rendering).
    fn prepare(&mut self, _record: &Record<'_>) -> Result<(), String> {
        Ok(())
    }
    /// Inside rendering: records (or replays) the passes.
    fn record(&mut self, record: &Record<'_>) -> Result<(), String>;
}

/// Culling: which candidate instances are drawn.
pub trait Culling: Technique {
    /// Writes the visible bits and their XOR with the last frame's.
    fn cull(&mut self, input: &CullInput<'_>, output: &mut CullOutput<'_>) -> Result<(), String>;
}

/// Culling on the GPU (since ABI 1.3): compute work recorded into the frame that tests the
/// instances and writes each pass's indirect commands and count, which a submission providing
/// `CADR_TRAIT_DRAWS_GPU_COMMANDS` draws. Listed as kind `gpu_culling`.
pub trait GpuCulling: Technique {
    /// The plugin ABI extensions (`CADR_EXTENSION_*`) the culler cannot work without: a host
    /// that does not know one refuses the technique, naming it. None by default.
    const REQUIRED_EXTENSIONS: &'static [abi::CadrExtensionKind] = &[];
    /// Phases of a frame (between them the host ends rendering and hands over the depth).
    fn phase_count(&self) -> u32 {
        1
    }
    /// Records phase `cull.phase()`: tests, writes the commands, sets each pass's draws.
    fn record(&mut self, cull: &GpuCull<'_>) -> Result<(), String>;
    /// What the GPU drew in the last finished frame: `draws` (ranges drawn, all passes: parts,
    /// or a cluster culler's clusters) and `primitives` (triangles of the triangle and pick
    /// passes).
    fn counts(&self) -> abi::CadrStats {
        abi::CadrStats::default()
    }
}

/// How translucent surfaces are blended (since ABI 1.7): a method the host builds into every
/// frame that draws translucent surfaces (see `abi::CadrTransparencyMethod`). Listed as kind
/// `transparency`.
pub trait Transparency: Technique {
    /// The colour targets (at most 2).
    fn targets(&self) -> Vec<abi::CadrTransparencyTarget>;
    /// Storage words: at the start (zeroed every frame), per pixel, and of those per pixel the
    /// ones zeroed every frame. None by default.
    fn storage_words(&self) -> (u32, u32, u32) {
        (0, 0, 0)
    }
    /// GLSL defining `void cadr_transparent_fragment(vec4 color, float view_depth)`.
    fn fragment_snippet(&self) -> &CStr;
    /// GLSL defining `vec4 cadr_merge()`.
    fn merge_snippet(&self) -> &CStr;
}

/// Defines a technique library: a Rust function `$entry` with the signature of
/// `cadr_plugin_entry` that describes the listed techniques. Nothing is exported, so several
/// libraries can be linked into one binary (the host's built-in techniques are one); hand the
/// function to [`export_plugin!`] to make a dynamic library of it.
///
/// ```ignore
/// cadr_plugin_sdk::technique_library! {
///     pub fn entry;
///     library: "my-techniques",
///     techniques: [
///         vertex MyVertexPath {
///             name: "mine", description: "what it does",
///             features: 0, provides: 0, needs: 0,
///         },
///     ]
/// }
/// ```
/// Kinds: `vertex`, `parameters`, `submission`, `culling`, `gpu_culling`, `transparency`.
#[macro_export]
macro_rules! technique_library {
    (
        $vis:vis fn $entry:ident;
        library: $library:literal,
        techniques: [
            $( $kind:ident $ty:ty {
                name: $name:literal,
                description: $description:literal,
                features: $features:expr,
                provides: $provides:expr,
                needs: $needs:expr $(,)?
            } ),* $(,)?
        ] $(,)?
    ) => {
        /// Fills `library` with this library's techniques (the body of `cadr_plugin_entry`).
        /// Any thread may call it; what it hands out lives as long as the process.
        ///
        /// # Safety
        /// `library` is null or points at a writable `CadrPluginLibrary` whose `size` says how
        /// much of it the caller can hold.
        $vis unsafe extern "C" fn $entry(
            library: *mut $crate::abi::CadrPluginLibrary,
        ) -> $crate::abi::CadrStatus {
            static DESCRIBED: $crate::export::DescribedLibrary =
                $crate::export::DescribedLibrary::new();
            // SAFETY: forwarded contract.
            unsafe {
                $crate::export::entry(&DESCRIBED, library, concat!($library, "\0"), || {
                    vec![$(
                        $crate::export::$kind::<$ty>($crate::export::Describe {
                            name: concat!($name, "\0"),
                            description: concat!($description, "\0"),
                            features: $features,
                            provides: $provides,
                            needs: $needs,
                        })
                    ),*]
                })
            }
        }
    };
}

/// Exports the two symbols the host looks for in a dynamic library: the ABI version and
/// `cadr_plugin_entry`, which forwards to a library defined by [`technique_library!`].
/// Use it once per dynamic library.
///
/// ```ignore
/// cadr_plugin_sdk::export_plugin!(entry: my_techniques::entry);
/// ```
///
/// The one-step form takes what [`technique_library!`] takes, without the `fn` line:
///
/// ```ignore
/// cadr_plugin_sdk::export_plugin! {
///     library: "my-techniques",
///     techniques: [
///         culling MyCulling {
///             name: "mine", description: "what it does",
///             features: 0, provides: 0, needs: 0,
///         },
///     ]
/// }
/// ```
#[macro_export]
macro_rules! export_plugin {
    (entry: $entry:path $(,)?) => {
        /// The ABI version this library was built for (see `cadr-plugin-abi`).
        #[no_mangle]
        pub extern "C" fn cadr_plugin_abi_version() -> u32 {
            $crate::abi::CADR_PLUGIN_ABI_VERSION
        }

        /// Fills `library` with this library's techniques.
        ///
        /// # Safety
        /// `library` is null or points at a writable `CadrPluginLibrary`.
        #[no_mangle]
        pub unsafe extern "C" fn cadr_plugin_entry(
            library: *mut $crate::abi::CadrPluginLibrary,
        ) -> $crate::abi::CadrStatus {
            // SAFETY: forwarded contract.
            unsafe { $entry(library) }
        }
    };
    (library: $($rest:tt)*) => {
        $crate::technique_library! {
            fn cadr_plugin_library_entry;
            library: $($rest)*
        }
        $crate::export_plugin!(entry: cadr_plugin_library_entry);
    };
}

/// How a plugin reports a failed Vulkan call: `vkCreateX: out of host memory` for the two
/// out-of-memory results (the words hosts and users look for), the result's own description
/// otherwise. For `map_err(vulkan_failure("vkCreateX"))`.
pub fn vulkan_failure(call: &'static str) -> impl Fn(vk::Result) -> String {
    move |result| match result {
        vk::Result::ERROR_OUT_OF_HOST_MEMORY => format!("{call}: out of host memory"),
        vk::Result::ERROR_OUT_OF_DEVICE_MEMORY => format!("{call}: out of device memory"),
        vk::Result::ERROR_DEVICE_LOST => format!("{call}: the device was lost"),
        other => format!("{call}: {other} ({other:?})"),
    }
}
