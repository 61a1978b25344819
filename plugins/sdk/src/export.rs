//! The `extern "C"` shims [`technique_library!`](crate::technique_library) builds vtables from.
//! Every shim catches panics: a panic never unwinds into the host.

use std::ffi::{c_void, CStr};
use std::marker::PhantomData;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::OnceLock;

use ash::vk;
use ash::vk::Handle;
use cadr_plugin_abi as abi;

use crate::gpu::Gpu;
use crate::views::{Bind, CullInput, CullOutput, GpuCull, Record, Scene};
use crate::{Culling, GpuCulling, ParameterPath, Submission, Technique, Transparency, VertexPath};

/// How a technique describes itself (strings NUL-terminated).
#[derive(Clone, Copy, Debug)]
pub struct Describe {
    /// Name.
    pub name: &'static str,
    /// Description.
    pub description: &'static str,
    /// `CADR_FEATURE_*` bits needed.
    pub features: abi::CadrFeatureBits,
    /// `CADR_TRAIT_*` bits provided.
    pub provides: abi::CadrTraitBits,
    /// `CADR_TRAIT_*` bits needed.
    pub needs: abi::CadrTraitBits,
}

struct Library(abi::CadrPluginLibrary);
// SAFETY: the library's pointers are to leaked, immutable data.
unsafe impl Send for Library {}
// SAFETY: as above.
unsafe impl Sync for Library {}

/// The description of one technique library, built on its first entry call and kept for the
/// life of the process ([`technique_library!`](crate::technique_library) makes one per library).
#[derive(Default)]
pub struct DescribedLibrary(OnceLock<Library>);

impl DescribedLibrary {
    /// Not described yet.
    pub const fn new() -> Self {
        Self(OnceLock::new())
    }
}

fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| (*s).to_owned())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic without a message".into())
}

/// Runs `f`, turning its error into a message and a panic into [`abi::CADR_STATUS_PANICKED`].
fn guarded(
    message: *mut abi::CadrMessage,
    f: impl FnOnce() -> Result<(), String>,
) -> abi::CadrStatus {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(())) => abi::CADR_STATUS_OK,
        Ok(Err(text)) => {
            // SAFETY: the host passes a valid message buffer or null.
            unsafe { abi::CadrMessage::write(message, &text) };
            abi::CADR_STATUS_ERROR
        }
        Err(payload) => {
            // SAFETY: as above.
            unsafe {
                abi::CadrMessage::write(message, &format!("panicked: {}", panic_text(&*payload)))
            };
            abi::CADR_STATUS_PANICKED
        }
    }
}

/// The body of `cadr_plugin_entry`.
///
/// # Safety
/// `library` is null or writable.
pub unsafe fn entry(
    described: &'static DescribedLibrary,
    library: *mut abi::CadrPluginLibrary,
    name: &'static str,
    techniques: impl FnOnce() -> Vec<abi::CadrTechniqueInfo>,
) -> abi::CadrStatus {
    if library.is_null() {
        return abi::CADR_STATUS_ERROR;
    }
    let built = catch_unwind(AssertUnwindSafe(|| {
        described.0.get_or_init(|| {
            let techniques: &'static [abi::CadrTechniqueInfo] = Vec::leak(techniques());
            Library(abi::CadrPluginLibrary {
                size: std::mem::size_of::<abi::CadrPluginLibrary>() as u32,
                abi_major: abi::CADR_PLUGIN_ABI_MAJOR,
                abi_minor: abi::CADR_PLUGIN_ABI_MINOR,
                name: name.as_ptr().cast(),
                technique_count: techniques.len() as u32,
                techniques: techniques.as_ptr(),
            })
        })
    }));
    let Ok(built) = built else {
        return abi::CADR_STATUS_PANICKED;
    };
    // SAFETY: checked non-null; the host set `size` to what it can hold.
    unsafe {
        let room = ((*library).size as usize).min(std::mem::size_of::<abi::CadrPluginLibrary>());
        std::ptr::copy_nonoverlapping(
            (&built.0 as *const abi::CadrPluginLibrary).cast::<u8>(),
            library.cast::<u8>(),
            room,
        );
        (*library).size = room as u32;
    }
    abi::CADR_STATUS_OK
}

fn info<V>(kind: abi::CadrTechniqueKind, describe: Describe, vtable: V) -> abi::CadrTechniqueInfo {
    abi::CadrTechniqueInfo {
        size: std::mem::size_of::<abi::CadrTechniqueInfo>() as u32,
        kind,
        name: describe.name.as_ptr().cast(),
        description: describe.description.as_ptr().cast(),
        required_features: describe.features,
        provides: describe.provides,
        needs: describe.needs,
        vtable: Box::leak(Box::new(vtable)) as *const V as *const c_void,
        extensions: std::ptr::null(),
        required_extensions: std::ptr::null(),
        required_extension_count: 0,
    }
}

fn common<T: Technique, V>() -> abi::CadrCommonVtable {
    abi::CadrCommonVtable {
        size: std::mem::size_of::<V>() as u32,
        create: Some(create::<T>),
        destroy: Some(destroy::<T>),
    }
}

unsafe extern "C" fn create<T: Technique>(
    info: *const abi::CadrCreateInfo,
    instance: *mut *mut c_void,
    message: *mut abi::CadrMessage,
) -> abi::CadrStatus {
    guarded(message, || {
        // SAFETY: the host passes a valid create info or null.
        let info = unsafe { info.as_ref() }.ok_or("no create info")?;
        if instance.is_null() {
            return Err("no place for the instance".into());
        }
        // SAFETY: the create info is the host's.
        let gpu = unsafe { Gpu::from_create_info(info) }?;
        let created = T::create(gpu)?;
        // SAFETY: checked non-null above.
        unsafe { *instance = Box::into_raw(Box::new(created)).cast() };
        Ok(())
    })
}

unsafe extern "C" fn destroy<T: Technique>(instance: *mut c_void) {
    if instance.is_null() {
        return;
    }
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: the instance came from `create::<T>` and is destroyed once.
        drop(unsafe { Box::from_raw(instance.cast::<T>()) })
    }));
}

/// # Safety
/// `instance` came from `create::<T>`; the host does not call `&mut` functions concurrently.
unsafe fn this<'a, T>(instance: *mut c_void) -> &'a mut T {
    // SAFETY: per the contract.
    unsafe { &mut *instance.cast::<T>() }
}

fn count_failure(context: *const abi::CadrBindContext) {
    // SAFETY: the context is valid for the call; its counters belong to this recording.
    if let Some(stats) = unsafe { context.as_ref().and_then(|c| c.stats.as_mut()) } {
        stats.failures += 1;
    }
}

/// What vertex and parameter paths have in common (snippet, prepare, bind_pass), so that one
/// set of shims serves both kinds.
trait PathKind {
    type Path: Technique;
    fn snippet(path: &Self::Path) -> &CStr;
    fn prepare(
        path: &mut Self::Path,
        scene: &Scene<'_>,
        command_buffer: vk::CommandBuffer,
    ) -> Result<(), String>;
    fn bind_pass(path: &Self::Path, bind: &Bind<'_>, state: &mut abi::CadrBindState);
}

struct VertexKind<T>(PhantomData<T>);
struct ParameterKind<T>(PhantomData<T>);

impl<T: VertexPath> PathKind for VertexKind<T> {
    type Path = T;
    fn snippet(path: &T) -> &CStr {
        path.shader_snippet()
    }
    fn prepare(
        path: &mut T,
        scene: &Scene<'_>,
        command_buffer: vk::CommandBuffer,
    ) -> Result<(), String> {
        path.prepare(scene, command_buffer)
    }
    fn bind_pass(path: &T, bind: &Bind<'_>, state: &mut abi::CadrBindState) {
        path.bind_pass(bind, state)
    }
}

impl<T: ParameterPath> PathKind for ParameterKind<T> {
    type Path = T;
    fn snippet(path: &T) -> &CStr {
        path.shader_snippet()
    }
    fn prepare(
        path: &mut T,
        scene: &Scene<'_>,
        command_buffer: vk::CommandBuffer,
    ) -> Result<(), String> {
        path.prepare(scene, command_buffer)
    }
    fn bind_pass(path: &T, bind: &Bind<'_>, state: &mut abi::CadrBindState) {
        path.bind_pass(bind, state)
    }
}

unsafe extern "C" fn snippet<K: PathKind>(instance: *mut c_void) -> *const std::ffi::c_char {
    // SAFETY: see `this`.
    catch_unwind(AssertUnwindSafe(|| {
        K::snippet(unsafe { this::<K::Path>(instance) }).as_ptr()
    }))
    .unwrap_or(std::ptr::null())
}

unsafe extern "C" fn prepare<K: PathKind>(
    instance: *mut c_void,
    scene: *const abi::CadrSceneView,
    command_buffer: *mut c_void,
    message: *mut abi::CadrMessage,
) -> abi::CadrStatus {
    guarded(message, || {
        // SAFETY: the host's scene view for the frame.
        let scene = unsafe { Scene::from_raw(scene) }.ok_or("no scene")?;
        let command_buffer = vk::CommandBuffer::from_raw(command_buffer as u64);
        // SAFETY: see `this`.
        K::prepare(unsafe { this::<K::Path>(instance) }, &scene, command_buffer)
    })
}

unsafe extern "C" fn bind_pass<K: PathKind>(
    instance: *mut c_void,
    context: *const abi::CadrBindContext,
    state: *mut abi::CadrBindState,
) {
    let result = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: valid for the call; the instance is only read (a thread-safe function).
        unsafe {
            if let (Some(bind), Some(state)) = (Bind::from_raw(context), state.as_mut()) {
                K::bind_pass(&*instance.cast::<K::Path>(), &bind, state);
            }
        }
    }));
    if result.is_err() {
        count_failure(context);
    }
}

/// Runs a per-draw bind, counting a panic as a failure and answering `fallback` instead.
fn bind_guarded<R>(context: *const abi::CadrBindContext, fallback: R, f: impl FnOnce() -> R) -> R {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|_| {
        count_failure(context);
        fallback
    })
}

/// The technique info of a vertex path.
pub fn vertex<T: VertexPath>(describe: Describe) -> abi::CadrTechniqueInfo {
    unsafe extern "C" fn input<T: VertexPath>(
        instance: *mut c_void,
        out: *mut abi::CadrVertexInput,
    ) {
        let _ = catch_unwind(AssertUnwindSafe(|| {
            // SAFETY: see `this`; `out` is the host's.
            unsafe { *out = this::<T>(instance).vertex_input() }
        }));
    }
    unsafe extern "C" fn set_layout<T: VertexPath>(instance: *mut c_void) -> u64 {
        // SAFETY: see `this`.
        catch_unwind(AssertUnwindSafe(|| {
            unsafe { this::<T>(instance) }.set_layout().as_raw()
        }))
        .unwrap_or(0)
    }
    unsafe extern "C" fn bind_draw<T: VertexPath>(
        instance: *mut c_void,
        context: *const abi::CadrBindContext,
        drawn: *const abi::CadrInstance,
        state: *mut abi::CadrBindState,
    ) -> abi::CadrDrawBase {
        bind_guarded(context, abi::CadrDrawBase::default(), || {
            // SAFETY: valid for the call; the instance is only read (a thread-safe function).
            unsafe {
                match (Bind::from_raw(context), drawn.as_ref(), state.as_mut()) {
                    (Some(bind), Some(drawn), Some(state)) => {
                        (*instance.cast::<T>()).bind_draw(&bind, drawn, state)
                    }
                    _ => abi::CadrDrawBase::default(),
                }
            }
        })
    }
    info(
        abi::CADR_KIND_VERTEX_PATH,
        describe,
        abi::CadrVertexPathVtable {
            common: common::<T, abi::CadrVertexPathVtable>(),
            shader_snippet: Some(snippet::<VertexKind<T>>),
            vertex_input: Some(input::<T>),
            set_layout: Some(set_layout::<T>),
            prepare: Some(prepare::<VertexKind<T>>),
            bind_pass: Some(bind_pass::<VertexKind<T>>),
            bind_draw: Some(bind_draw::<T>),
        },
    )
}

/// The technique info of a parameter path.
pub fn parameters<T: ParameterPath>(describe: Describe) -> abi::CadrTechniqueInfo {
    unsafe extern "C" fn layout<T: ParameterPath>(
        instance: *mut c_void,
        sets: *mut u64,
        push: *mut u32,
    ) {
        let _ = catch_unwind(AssertUnwindSafe(|| {
            // SAFETY: see `this`; the host passes room for two layouts and one count.
            unsafe {
                let (layouts, bytes) = this::<T>(instance).layout();
                *sets = layouts[0].as_raw();
                *sets.add(1) = layouts[1].as_raw();
                *push = bytes;
            }
        }));
    }
    unsafe extern "C" fn bind_draw<T: ParameterPath>(
        instance: *mut c_void,
        context: *const abi::CadrBindContext,
        id: u32,
        drawn: *const abi::CadrInstance,
        state: *mut abi::CadrBindState,
    ) -> u32 {
        bind_guarded(context, id, || {
            // SAFETY: valid for the call; the instance is only read (a thread-safe function).
            unsafe {
                match (Bind::from_raw(context), drawn.as_ref(), state.as_mut()) {
                    (Some(bind), Some(drawn), Some(state)) => {
                        (*instance.cast::<T>()).bind_draw(&bind, id, drawn, state)
                    }
                    _ => id,
                }
            }
        })
    }
    info(
        abi::CADR_KIND_PARAMETER_PATH,
        describe,
        abi::CadrParameterPathVtable {
            common: common::<T, abi::CadrParameterPathVtable>(),
            shader_snippet: Some(snippet::<ParameterKind<T>>),
            layout: Some(layout::<T>),
            prepare: Some(prepare::<ParameterKind<T>>),
            bind_pass: Some(bind_pass::<ParameterKind<T>>),
            bind_draw: Some(bind_draw::<T>),
        },
    )
}

/// The technique info of a submission.
pub fn submission<T: Submission>(describe: Describe) -> abi::CadrTechniqueInfo {
    unsafe extern "C" fn prepare<T: Submission>(
        instance: *mut c_void,
        context: *const abi::CadrRecordContext,
        message: *mut abi::CadrMessage,
    ) -> abi::CadrStatus {
        guarded(message, || {
            // SAFETY: the host's context for the call.
            let record = unsafe { Record::from_raw(context) }.ok_or("no record context")?;
            // SAFETY: see `this`.
            unsafe { this::<T>(instance) }.prepare(&record)
        })
    }
    unsafe extern "C" fn record<T: Submission>(
        instance: *mut c_void,
        context: *const abi::CadrRecordContext,
        message: *mut abi::CadrMessage,
    ) -> abi::CadrStatus {
        guarded(message, || {
            // SAFETY: the host's context for the call.
            let record = unsafe { Record::from_raw(context) }.ok_or("no record context")?;
            // SAFETY: see `this`.
            unsafe { this::<T>(instance) }.record(&record)
        })
    }
    requiring(
        T::REQUIRED_EXTENSIONS,
        info(
            abi::CADR_KIND_SUBMISSION,
            describe,
            abi::CadrSubmissionVtable {
                common: common::<T, abi::CadrSubmissionVtable>(),
                prepare: Some(prepare::<T>),
                record: Some(record::<T>),
            },
        ),
    )
}

/// `info` listing `required` as the extensions its technique cannot work without.
fn requiring(
    required: &'static [abi::CadrExtensionKind],
    info: abi::CadrTechniqueInfo,
) -> abi::CadrTechniqueInfo {
    abi::CadrTechniqueInfo {
        required_extensions: if required.is_empty() {
            std::ptr::null()
        } else {
            required.as_ptr()
        },
        required_extension_count: required.len() as u32,
        ..info
    }
}

/// The technique info of a culling technique.
pub fn culling<T: Culling>(describe: Describe) -> abi::CadrTechniqueInfo {
    unsafe extern "C" fn cull<T: Culling>(
        instance: *mut c_void,
        input: *const abi::CadrCullInput,
        output: *mut abi::CadrCullOutput,
        message: *mut abi::CadrMessage,
    ) -> abi::CadrStatus {
        guarded(message, || {
            // SAFETY: the host's input and output for the call.
            let (input, mut output) = unsafe {
                (
                    CullInput::from_raw(input).ok_or("no cull input")?,
                    CullOutput::from_raw(output).ok_or("no cull output")?,
                )
            };
            // SAFETY: see `this`.
            unsafe { this::<T>(instance) }.cull(&input, &mut output)
        })
    }
    info(
        abi::CADR_KIND_CULLING,
        describe,
        abi::CadrCullingVtable {
            common: common::<T, abi::CadrCullingVtable>(),
            cull: Some(cull::<T>),
            record_gpu: None,
            phase_count: None,
            gpu_counts: None,
        },
    )
}

/// The technique info of a GPU culling technique (ABI 1.3).
pub fn gpu_culling<T: GpuCulling>(describe: Describe) -> abi::CadrTechniqueInfo {
    unsafe extern "C" fn record_gpu<T: GpuCulling>(
        instance: *mut c_void,
        context: *const abi::CadrGpuCullContext,
        message: *mut abi::CadrMessage,
    ) -> abi::CadrStatus {
        guarded(message, || {
            // SAFETY: the host's context for the call.
            let cull = unsafe { GpuCull::from_raw(context) }.ok_or("no GPU cull context")?;
            // SAFETY: see `this`.
            unsafe { this::<T>(instance) }.record(&cull)
        })
    }
    unsafe extern "C" fn phase_count<T: GpuCulling>(instance: *mut c_void) -> u32 {
        // SAFETY: see `this`.
        catch_unwind(AssertUnwindSafe(|| {
            unsafe { this::<T>(instance) }.phase_count()
        }))
        .unwrap_or(1)
    }
    unsafe extern "C" fn gpu_counts<T: GpuCulling>(
        instance: *mut c_void,
        stats: *mut abi::CadrStats,
    ) {
        // SAFETY: see `this`.
        let counts = catch_unwind(AssertUnwindSafe(|| unsafe { this::<T>(instance) }.counts()));
        // SAFETY: the host passes its counters or null.
        if let (Ok(counts), Some(stats)) = (counts, unsafe { stats.as_mut() }) {
            stats.draws += counts.draws;
            stats.primitives += counts.primitives;
        }
    }
    requiring(
        T::REQUIRED_EXTENSIONS,
        info(
            abi::CADR_KIND_CULLING,
            describe,
            abi::CadrCullingVtable {
                common: common::<T, abi::CadrCullingVtable>(),
                cull: None,
                record_gpu: Some(record_gpu::<T>),
                phase_count: Some(phase_count::<T>),
                gpu_counts: Some(gpu_counts::<T>),
            },
        ),
    )
}

/// The technique info of a transparency method (ABI 1.7).
pub fn transparency<T: Transparency>(describe: Describe) -> abi::CadrTechniqueInfo {
    unsafe extern "C" fn method<T: Transparency>(
        instance: *mut c_void,
        method: *mut abi::CadrTransparencyMethod,
        message: *mut abi::CadrMessage,
    ) -> abi::CadrStatus {
        guarded(message, || {
            // SAFETY: see `this`.
            let this = unsafe { this::<T>(instance) };
            // SAFETY: the host passes its struct, valid and unaliased for the call.
            let method = unsafe { method.as_mut() }.ok_or("no method to describe")?;
            if (method.size as usize) < std::mem::size_of::<abi::CadrTransparencyMethod>() {
                return Err("the host's transparency method struct is too small".into());
            }
            let targets = this.targets();
            if targets.len() > method.targets.len() {
                return Err(format!("{} targets: at most 2", targets.len()));
            }
            method.target_count = targets.len() as u32;
            method.targets[..targets.len()].copy_from_slice(&targets);
            let (header, per_pixel, cleared) = this.storage_words();
            method.storage_header_words = header;
            method.storage_words_per_pixel = per_pixel;
            method.storage_cleared_words_per_pixel = cleared;
            method.fragment_snippet = this.fragment_snippet().as_ptr();
            method.merge_snippet = this.merge_snippet().as_ptr();
            Ok(())
        })
    }
    info(
        abi::CADR_KIND_TRANSPARENCY,
        describe,
        abi::CadrTransparencyVtable {
            common: common::<T, abi::CadrTransparencyVtable>(),
            method: Some(method::<T>),
        },
    )
}
