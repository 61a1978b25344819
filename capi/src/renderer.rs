//! Renderers: an offscreen target or a host window's swapchain, the techniques that draw into
//! it, frames and their statistics, pixels and PNGs.

use std::ffi::c_char;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use cadr_core::technique::{Combination, TechniqueKind};
use cadr_core::view::View;
use cadr_core::vk::{raw, raw::Handle, HostImage, ImageOutput, PresentOutcome, Swapchain};

use crate::args::{
    deliver, deliver_sized, non_null, optional_str, read_sized, required_str, write,
};
use crate::camera::CadrCamera;
use crate::context::{context_state, CadrContext, CadrTechniqueKind, ContextState};
use crate::error::{guard, CadrResult, Failure};
use crate::export::ExportOutput;
use crate::handles::{lock, Registry};
use crate::scene::{CadrScene, SCENES};

/// Opaque type behind [`CadrRenderer`].
pub struct CadrRendererObject {
    _private: (),
}

/// A renderer: draws scenes with the chosen techniques into an offscreen image, or into a host
/// window through a swapchain. Created by `cadr_renderer_create` or
/// `cadr_renderer_create_for_surface`, released by `cadr_renderer_destroy`.
pub type CadrRenderer = *mut CadrRendererObject;

/// One technique name per kind; NULL keeps the renderer's current technique of that kind.
///
/// The struct grows by appending fields (a kind added later, NULL when an older host does not
/// know it): the host sets `size` to `sizeof(CadrTechniqueSelection)`; a newer host's fields
/// this library does not know must be NULL.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrTechniqueSelection {
    /// `sizeof(CadrTechniqueSelection)`, set by the host.
    pub size: u32,
    /// Vertex path, e.g. "arena".
    pub vertex: *const c_char,
    /// Parameter path, e.g. "ssbo-index".
    pub parameters: *const c_char,
    /// Submission, e.g. "groups-mdi-replay".
    pub submission: *const c_char,
    /// Culling, e.g. "frustum".
    pub culling: *const c_char,
}

/// What one frame cost and drew: the figures `cadr bench` prints.
///
/// The struct grows by appending fields (`size` first, set by the host to
/// `sizeof(CadrFrameStats)`): cadr fills the fields within the host's `size` and zeroes those
/// of a newer header it does not know.
///
/// Its many fields: one per figure, as `cadr bench` prints them.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CadrFrameStats {
    /// `sizeof(CadrFrameStats)`, set by the host.
    pub size: u32,
    /// Whether the frame was drawn and, for a window, presented (false while minimized or
    /// while the swapchain was being recreated).
    pub presented: bool,
    /// CPU time of the frame: culling, the techniques' preparation, recording, submission.
    pub cpu_us: f64,
    /// CPU time spent recording commands.
    pub cpu_record_us: f64,
    /// CPU time of the queue submission.
    pub cpu_submit_us: f64,
    /// CPU time to bring the scene tree and the GPU scene up to date with the host's edits.
    pub scene_update_us: f64,
    /// CPU time to hand the image to the window (0 offscreen).
    pub present_us: f64,
    /// GPU time of the frame, or -1 where the device has no timestamps.
    pub gpu_us: f64,
    /// Draw calls (an indirect or multi-draw call counts once).
    pub draw_calls: u64,
    /// Parts or index ranges drawn.
    pub draws: u64,
    /// Triangles drawn: of the parts drawn, once each; with a GPU culler, what it let through
    /// in every surface pass.
    pub triangles: u64,
    /// Triangles the surface passes handed to the rasteriser, each pass counted (edge passes
    /// draw lines and are not counted), the same way for every culler.
    pub triangles_rasterized: u64,
    /// Pipeline binds.
    pub pipeline_binds: u64,
    /// Vertex and index buffer binds.
    pub vertex_binds: u64,
    /// Parameter updates (push constants, descriptor binds).
    pub parameter_updates: u64,
    /// Bytes uploaded for this frame.
    pub bytes_uploaded: u64,
    /// Whether the frame resubmitted the renderer's last recording (frame replay): recording
    /// cost nothing.
    pub replayed: bool,
    /// Whether the frame was recorded while earlier frames could still run on the GPU (more
    /// than one frame in flight, only the view changed, every active technique keeps its
    /// per-frame data per slot): it waited only for the frame that last used its slot.
    pub overlapped: bool,
    /// Device bytes the scene's copy on the GPU holds (geometry arenas, instances, matrices,
    /// materials, textures).
    pub resident_bytes: u64,
    /// The most full-detail geometry bytes the GPU may hold where the scene streams under the
    /// memory budget (`CADR_MEMORY_BUDGET`); 0 where it does not stream.
    pub streaming_budget: u64,
    /// Where the scene streams: full-detail geometry bytes on the GPU now (the rest is drawn in
    /// its coarse form).
    pub full_detail_bytes: u64,
    /// Where the scene streams: full-detail bytes of every geometry of the scene.
    pub total_full_detail_bytes: u64,
    /// Where the scene streams: bytes brought to the GPU by streaming since the scene was put
    /// there.
    pub streamed_bytes: u64,
    /// Where the scene streams: reads of full detail from the scene's page file that failed
    /// (each logged; the geometry stays coarse and is read again later).
    pub failed_page_reads: u64,
}

/// What a renderer holds: the view (its GPU scene, techniques and target), the window's
/// swapchain or the host's image its frames go to, and the context that keeps the device
/// alive. The outputs come first: dropped first, they wait for their blits, which read the
/// view's picture.
pub(crate) struct RendererState {
    pub(crate) swapchain: Option<Swapchain>,
    /// The host's image every frame is blitted into (`cadr_renderer_create_for_image`).
    pub(crate) image_output: Option<ImageOutput>,
    /// The exported memory every frame is copied into (`cadr_renderer_create_for_export`).
    pub(crate) frame_export: Option<ExportOutput>,
    pub(crate) view: View,
    context: Arc<ContextState>,
}

/// A renderer's state, movable between threads.
struct ThreadBound(RendererState);

// SAFETY: the raw pointers inside (plugin instances and the Vulkan description handed to
// plugins) are only used while the renderer's mutex is held, so by one thread at a time, which
// the plugin ABI allows ("all others are called from one thread at a time", cadr_plugin.h);
// the renderer's Vulkan objects are externally synchronised by the same mutex, and the shared
// queue by the device's own lock.
unsafe impl Send for ThreadBound {}

static RENDERERS: Registry<ThreadBound> = Registry::new(0xC3, "renderer");

/// Technique combinations tried for a new renderer, fastest first; the first the device and
/// the plugins can run is chosen, else the renderer keeps the built-in combination.
const PREFERRED: [[&str; 4]; 3] = [
    ["arena", "ssbo-index", "groups-mdi-replay", "frustum"],
    ["per-geometry", "push", "groups-replay", "frustum"],
    ["per-geometry", "push", "individual", "frustum"],
];

fn combination(names: [&str; 4]) -> Combination {
    Combination {
        vertex: names[0].into(),
        parameters: names[1].into(),
        submission: names[2].into(),
        culling: names[3].into(),
        ..Combination::built_in()
    }
}

fn check_size(width: u32, height: u32) -> Result<(), Failure> {
    if width == 0 || height == 0 || width > 16384 || height > 16384 {
        return Err(Failure::invalid(format!(
            "size {width}x{height}: each side must be 1 to 16384"
        )));
    }
    Ok(())
}

/// Where a new renderer's frames go besides its own picture.
pub(crate) enum Output {
    /// Nowhere: the host reads them back.
    Offscreen,
    /// A window: a swapchain on the host's surface.
    Surface(raw::SurfaceKHR),
    /// A host's image.
    Image(HostImage),
    /// Memory exported for another API (`cadr_renderer_create_for_export`).
    Export,
}

pub(crate) fn new_renderer(
    context: CadrContext,
    (width, height): (u32, u32),
    output: Output,
    renderer: *mut CadrRenderer,
) -> Result<(), Failure> {
    let context = context_state(context)?;
    non_null(renderer, "renderer")?;
    check_size(width, height)?;
    if matches!(output, Output::Surface(_)) && !context.presentation {
        return Err(Failure::new(
            CadrResult::Unsupported,
            "the context cannot present: create it with the window system's instance extensions (VK_KHR_surface and the platform's, e.g. from glfwGetRequiredInstanceExtensions)".into(),
        ));
    }
    let device = &context.device;
    let mut view = View::new(device, Arc::clone(&context.registry), width, height)?;
    // The view starts with the built-in combination, which needs no plugin library; a faster
    // one replaces it when the plugins and the device offer one.
    let techniques = view.techniques_mut();
    if let Some(faster) = PREFERRED
        .iter()
        .map(|&names| combination(names))
        .find(|c| techniques.check(c).is_ok())
    {
        techniques.select(&faster)?;
    }
    let (mut swapchain, mut image_output, mut frame_export) = (None, None, None);
    match output {
        Output::Offscreen => {}
        Output::Surface(surface) => {
            swapchain = Some(Swapchain::new(device, surface, width, height)?)
        }
        Output::Image(image) => image_output = Some(ImageOutput::new(device, image)?),
        Output::Export => frame_export = Some(ExportOutput::new(device, (width, height))?),
    }
    if swapchain.is_some() || image_output.is_some() {
        // A window's or a host image's frames go to the GPU without waiting for the last one
        // (see CadrRendererSettings::frames_in_flight); offscreen frames are read back at once
        // anyway.
        view.renderer_mut().set_frames_in_flight(2)?;
    }
    let state = RendererState {
        swapchain,
        image_output,
        frame_export,
        view,
        context: Arc::clone(&context),
    };
    let handle = RENDERERS.insert(ThreadBound(state))?;
    // SAFETY: renderer is null or writable (the caller's contract).
    unsafe { deliver(renderer, "renderer", handle as CadrRenderer) }
}

/// Runs `body` on a renderer's state, the renderer locked for it.
pub(crate) fn with_renderer<R>(
    renderer: CadrRenderer,
    body: impl FnOnce(&mut RendererState) -> Result<R, Failure>,
) -> Result<R, Failure> {
    let object = RENDERERS.get(renderer as u64, "renderer")?;
    let mut guard = lock(&object);
    body(&mut guard.0)
}

/// Creates a renderer that draws into an offscreen `width` × `height` image, with the fastest
/// technique combination the device and plugins allow, or the built-in combination when no
/// plugin library was found (see `cadr_renderer_technique`).
///
/// Returns `CADR_RESULT_OK` and writes `*renderer`, `CADR_RESULT_NULL_ARGUMENT`,
/// `CADR_RESULT_INVALID_ARGUMENT` (size 0 or above 16384), `CADR_RESULT_PLUGIN_FAILED` (a
/// technique failed to create its instance), `CADR_RESULT_VULKAN` or a handle error.
/// Ownership: the renderer is the caller's until `cadr_renderer_destroy`; it keeps the
/// context's device alive. Thread-safety: callable from any thread; one renderer is used by
/// one call at a time (an internal lock), and renderers of one context take turns on its queue.
///
/// # Safety
/// `renderer` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_create(
    context: CadrContext,
    width: u32,
    height: u32,
    renderer: *mut CadrRenderer,
) -> CadrResult {
    guard(|| new_renderer(context, (width, height), Output::Offscreen, renderer))
}

/// Creates a renderer that presents into a host window: `surface` is a `VkSurfaceKHR` the host
/// created on the context's instance (`cadr_context_vulkan_instance`), e.g. with
/// `glfwCreateWindowSurface`; pass it as `(uint64_t)surface`. cadr owns the swapchain,
/// recreates it when the window's size changes (call `cadr_renderer_resize` from the host's
/// resize callback) and presents nothing while the window is minimized.
///
/// Returns as `cadr_renderer_create`, and `CADR_RESULT_UNSUPPORTED` when the context was made
/// without the window system's instance extensions or cannot present to this surface.
/// Ownership: on success the renderer owns the surface and destroys it with itself; on failure
/// the surface stays the caller's. Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `surface` is 0 or a live surface of the context's instance not used by another swapchain;
/// `renderer` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_create_for_surface(
    context: CadrContext,
    surface: u64,
    width: u32,
    height: u32,
    renderer: *mut CadrRenderer,
) -> CadrResult {
    guard(|| {
        if surface == 0 {
            return Err(Failure::new(
                CadrResult::NullArgument,
                "surface is VK_NULL_HANDLE".into(),
            ));
        }
        new_renderer(
            context,
            (width, height),
            Output::Surface(raw::SurfaceKHR::from_raw(surface)),
            renderer,
        )
    })
}

/// Destroys a renderer (waiting for its last frame) and, for a window renderer, its swapchain
/// and surface. NULL is a no-op.
///
/// Returns `CADR_RESULT_OK` or a handle error.
/// Ownership: the handle (or item) is given back to cadr and invalid afterwards.
/// Thread-safety: any thread. A call another thread is making with this renderer finishes
/// first (the renderer goes when it returns); later calls with the handle are refused with
/// `CADR_RESULT_DESTROYED_HANDLE`.
#[no_mangle]
pub extern "C" fn cadr_renderer_destroy(renderer: CadrRenderer) -> CadrResult {
    guard(|| {
        let Some(object) = RENDERERS.remove(renderer as u64, "renderer")? else {
            return Ok(());
        };
        drop(object);
        Ok(())
    })
}

/// Gives the renderer a new size: for a window, call it from the framebuffer-size callback
/// (0 × 0 while minimized is accepted: frames are skipped until the window has area again).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_INVALID_ARGUMENT` (above 16384, or 0 offscreen),
/// `CADR_RESULT_VULKAN` or a handle error.
/// Ownership: nothing changes hands; the arguments are read during the call only.
/// Thread-safety: as `cadr_renderer_create`.
#[no_mangle]
pub extern "C" fn cadr_renderer_resize(
    renderer: CadrRenderer,
    width: u32,
    height: u32,
) -> CadrResult {
    guard(|| {
        with_renderer(renderer, |state| {
            if state.image_output.is_some() {
                return Err(Failure::invalid(
                    "the renderer draws at the size of the host's image: give it another image with cadr_renderer_set_image",
                ));
            }
            match &mut state.swapchain {
                Some(swapchain) => {
                    if width > 16384 || height > 16384 {
                        check_size(width, height)?;
                    }
                    swapchain.resize(width, height)?;
                    let extent = swapchain.extent();
                    if extent.width > 0 && extent.height > 0 {
                        state
                            .view
                            .renderer_mut()
                            .resize(extent.width, extent.height)?;
                    }
                }
                None => {
                    check_size(width, height)?;
                    state.view.renderer_mut().resize(width, height)?;
                }
            }
            if let Some(output) = &mut state.frame_export {
                // New memory now, so that the host imports it right after this call.
                let renderer = state.view.renderer();
                let extent = cadr_core::vk::raw::Extent2D { width, height };
                output.reshape(renderer.device(), extent, renderer.depth_to_host())?;
            }
            Ok(())
        })
    })
}

/// Writes the size of the renderer's image (for a window: of the swapchain, 0 × 0 while
/// minimized).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the outputs are the caller's; cadr keeps no pointer to them.
/// Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `width` and `height` are null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_size(
    renderer: CadrRenderer,
    width: *mut u32,
    height: *mut u32,
) -> CadrResult {
    guard(|| {
        non_null(width, "width")?;
        non_null(height, "height")?;
        let (w, h) = with_renderer(renderer, |state| {
            Ok(match &state.swapchain {
                Some(swapchain) => (swapchain.extent().width, swapchain.extent().height),
                None => state.view.renderer().size(),
            })
        })?;
        // SAFETY: checked non-null; writable by contract.
        unsafe {
            write(width, w);
            write(height, h);
        }
        Ok(())
    })
}

/// The combination `selection` asks for, with the current techniques where it says NULL.
///
/// # Safety
/// `selection` is null or valid with null or valid strings.
unsafe fn requested(
    state: &RendererState,
    selection: *const CadrTechniqueSelection,
) -> Result<Combination, Failure> {
    // SAFETY: null or valid for its size (the caller's contract); zero bytes are a
    // CadrTechniqueSelection (every kind NULL).
    let selection = unsafe {
        read_sized(
            selection,
            ("selection", "CadrTechniqueSelection"),
            std::mem::zeroed(),
        )
    }?;
    let mut wanted = state.view.techniques().combination();
    for (kind, pointer, name) in [
        (TechniqueKind::Vertex, selection.vertex, "selection.vertex"),
        (
            TechniqueKind::Parameters,
            selection.parameters,
            "selection.parameters",
        ),
        (
            TechniqueKind::Submission,
            selection.submission,
            "selection.submission",
        ),
        (
            TechniqueKind::Culling,
            selection.culling,
            "selection.culling",
        ),
    ] {
        // SAFETY: forwarded contract.
        if let Some(text) = unsafe { optional_str(pointer, name) }? {
            wanted.set(kind, text);
        }
    }
    Ok(wanted)
}

/// Why `combination` cannot be used, as a result code: an unknown name, a technique the
/// device cannot run, or techniques that do not fit together.
fn refusal(state: &RendererState, combination: &Combination) -> Result<(), Failure> {
    let registry = state.view.techniques().registry();
    for kind in TechniqueKind::ALL {
        let name = combination.get(kind);
        match registry.find(kind, name) {
            None => {
                let known: Vec<&str> = registry.of_kind(kind).map(|t| t.name.as_str()).collect();
                return Err(Failure::new(
                    CadrResult::NotFound,
                    format!(
                        "no {} technique named '{name}' (known: {})",
                        kind.name(),
                        known.join(", ")
                    ),
                ));
            }
            Some(entry) => {
                if let Err(why) = &entry.support {
                    return Err(Failure::new(
                        CadrResult::Unsupported,
                        format!(
                            "{} technique '{name}' cannot run on this device: {why}",
                            kind.name()
                        ),
                    ));
                }
            }
        }
    }
    state.view.techniques().check(combination).map_err(|why| {
        Failure::new(
            CadrResult::InvalidCombination,
            format!("{combination}: {why}"),
        )
    })
}

fn select(state: &mut RendererState, combination: &Combination) -> Result<(), Failure> {
    refusal(state, combination)?;
    state
        .view
        .techniques_mut()
        .select(combination)
        .map_err(Failure::from)
}

/// Checks whether a technique selection would work, without changing anything.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NOT_FOUND` (unknown name), `CADR_RESULT_UNSUPPORTED`
/// (the device cannot run a technique), `CADR_RESULT_INVALID_COMBINATION` (techniques that do
/// not fit; the message says which need is unmet), `CADR_RESULT_NULL_ARGUMENT` or a handle
/// error. Ownership: the strings are read during the call.
/// Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `selection` is null or valid with null or valid strings.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_check_techniques(
    renderer: CadrRenderer,
    selection: *const CadrTechniqueSelection,
) -> CadrResult {
    guard(|| {
        with_renderer(renderer, |state| {
            // SAFETY: forwarded contract.
            let wanted = unsafe { requested(state, selection) }?;
            refusal(state, &wanted)
        })
    })
}

/// Switches to a technique selection at run time. A refused selection keeps the current one;
/// a plugin that fails to create its instance also keeps it (`CADR_RESULT_PLUGIN_FAILED`).
///
/// Returns as `cadr_renderer_check_techniques`, and `CADR_RESULT_PLUGIN_FAILED`.
/// Ownership and thread-safety: as `cadr_renderer_check_techniques`.
///
/// # Safety
/// As `cadr_renderer_check_techniques`.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_set_techniques(
    renderer: CadrRenderer,
    selection: *const CadrTechniqueSelection,
) -> CadrResult {
    guard(|| {
        with_renderer(renderer, |state| {
            // SAFETY: forwarded contract.
            let wanted = unsafe { requested(state, selection) }?;
            select(state, &wanted)
        })
    })
}

/// Replaces the technique of one kind (`CADR_TECHNIQUE_KIND_*`) by name.
///
/// Returns as `cadr_renderer_set_techniques`, and `CADR_RESULT_INVALID_ARGUMENT` for an
/// unknown kind.
/// Ownership: nothing changes hands; the arguments are read during the call only.
/// Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `name` is null or a valid string.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_set_technique(
    renderer: CadrRenderer,
    kind: u32,
    name: *const c_char,
) -> CadrResult {
    guard(|| {
        let kind = CadrTechniqueKind::from_raw(kind)?.core();
        // SAFETY: forwarded contract.
        let name = unsafe { required_str(name, "name") }?;
        with_renderer(renderer, |state| {
            let mut wanted = state.view.techniques().combination();
            wanted.set(kind, name);
            select(state, &wanted)
        })
    })
}

/// Writes the name of the renderer's current technique of `kind` (`CADR_TECHNIQUE_KIND_*`).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_INVALID_ARGUMENT` (unknown kind),
/// `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the string belongs to the context (valid while it or a renderer of it lives).
/// Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `name` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_technique(
    renderer: CadrRenderer,
    kind: u32,
    name: *mut *const c_char,
) -> CadrResult {
    guard(|| {
        let kind = CadrTechniqueKind::from_raw(kind)?.core();
        let value = with_renderer(renderer, |state| {
            let current = state.view.techniques().combination();
            Ok(state.context.technique_name(kind, current.get(kind)))
        })?;
        // SAFETY: name is null or writable (the caller's contract).
        unsafe { deliver(name, "name", value) }
    })
}

/// Renders one frame of `scene` seen by `camera`: applies the host's edits since the last
/// frame (incrementally), culls, draws with the current techniques and, for a window, presents.
/// `stats` may be NULL; otherwise its `size` says how much of it the host has.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_INVALID_ARGUMENT`
/// (non-finite camera), `CADR_RESULT_VULKAN`, `CADR_RESULT_PLUGIN_FAILED` or a handle error.
/// Ownership: the camera is read during the call. Thread-safety: as `cadr_renderer_create`; the
/// scene is locked while the host's edits are applied. The renderers of one context drawing
/// one scene share its copy on the GPU (geometry, instances, matrices, materials; made at the
/// first frame, then brought up to date with the edits once, by whichever renderer draws
/// next); each keeps only its own picture, culling and uniforms (renderers of one size share
/// their depth, MSAA and transparency attachments, which a frame uses only until it ends,
/// unless `CadrRendererSettings::depth_to_host` keeps the depth their own).
///
/// # Safety
/// `camera` is null or readable; `stats` null or writable for its `size`.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_render(
    renderer: CadrRenderer,
    scene: CadrScene,
    camera: *const CadrCamera,
    stats: *mut CadrFrameStats,
) -> CadrResult {
    guard(|| {
        non_null(camera, "camera")?;
        // SAFETY: non-null and readable by contract.
        let camera = unsafe { *camera }.to_core()?;
        let scene_object = SCENES.get(scene as u64, "scene")?;
        let value = with_renderer(renderer, |state| {
            let mut frame = CadrFrameStats::default();
            if let Some(swapchain) = &mut state.swapchain {
                if swapchain.extent().width == 0 || swapchain.extent().height == 0 {
                    // Minimized until now: ask the surface again.
                    swapchain.recreate()?;
                }
                let extent = swapchain.extent();
                if extent.width == 0 || extent.height == 0 {
                    return Ok(frame); // still minimized: draw nothing
                }
                state
                    .view
                    .renderer_mut()
                    .resize(extent.width, extent.height)?;
            }
            if let Some(output) = &mut state.frame_export {
                output.wait_for_release()?;
            }
            let mut scene_state = lock(&scene_object);
            let update_start = Instant::now();
            scene_state.sync(&mut state.view)?;
            frame.scene_update_us = update_start.elapsed().as_secs_f64() * 1e6;
            drop(scene_state);
            let drawn = state.view.draw(&camera).map_err(Failure::from)?;
            frame.presented = true;
            if let Some(swapchain) = &mut state.swapchain {
                let present_start = Instant::now();
                frame.presented = swapchain.present(state.view.renderer().color_image())?
                    == PresentOutcome::Presented;
                frame.present_us = present_start.elapsed().as_secs_f64() * 1e6;
            }
            if let Some(output) = &mut state.image_output {
                let copy_start = Instant::now();
                output.copy(state.view.renderer().color_image())?;
                frame.present_us = copy_start.elapsed().as_secs_f64() * 1e6;
            }
            if let Some(output) = &mut state.frame_export {
                let copy_start = Instant::now();
                let renderer = state.view.renderer();
                output.copy(
                    renderer.device(),
                    renderer.color_image(),
                    renderer.depth_for_host(),
                )?;
                frame.present_us = copy_start.elapsed().as_secs_f64() * 1e6;
            }
            frame.cpu_us = drawn.cpu_us();
            frame.cpu_record_us = drawn.cpu_record_us;
            frame.cpu_submit_us = drawn.cpu_submit_us;
            frame.gpu_us = drawn.gpu_us.unwrap_or(-1.0);
            frame.draw_calls = drawn.draw_calls;
            frame.draws = drawn.draws;
            frame.triangles = drawn.triangles;
            frame.triangles_rasterized = drawn.triangles_rasterized;
            frame.pipeline_binds = drawn.pipeline_binds;
            frame.vertex_binds = drawn.vertex_binds;
            frame.parameter_updates = drawn.parameter_updates;
            frame.bytes_uploaded = drawn.bytes_uploaded;
            frame.replayed = drawn.replayed;
            frame.overlapped = drawn.overlapped;
            if let Some(gpu_scene) = state.view.scene() {
                frame.resident_bytes = gpu_scene.resident_bytes();
                if let Some(report) = gpu_scene.streaming() {
                    frame.streaming_budget = report.budget;
                    frame.full_detail_bytes = report.full_bytes;
                    frame.total_full_detail_bytes = report.total_full_bytes;
                    frame.streamed_bytes = report.streamed_bytes;
                    frame.failed_page_reads = report.failed_reads;
                }
            }
            Ok(frame)
        })?;
        if stats.is_null() {
            return Ok(());
        }
        // SAFETY: non-null and writable for its size (the caller's contract).
        unsafe { deliver_sized(stats, "stats", value) }
    })
}

/// Copies the last frame into `rgba` as tightly packed RGBA8 rows, top row first
/// (width × height × 4 bytes; see `cadr_renderer_size`).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_BUFFER_TOO_SMALL`
/// (nothing is written; the message gives the size needed), `CADR_RESULT_VULKAN` or a handle
/// error. Ownership: `rgba` is the caller's. Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `rgba` is null or writable for `capacity` bytes.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_read_pixels(
    renderer: CadrRenderer,
    rgba: *mut u8,
    capacity: usize,
) -> CadrResult {
    guard(|| {
        non_null(rgba, "rgba")?;
        with_renderer(renderer, |state| {
            let (width, height) = state.view.renderer().size();
            let needed = width as usize * height as usize * 4;
            if capacity < needed {
                return Err(Failure::new(
                    CadrResult::BufferTooSmall,
                    format!("capacity {capacity} is below the {needed} bytes of a {width}x{height} RGBA8 image"),
                ));
            }
            let image = state.view.renderer().read_rgba8()?;
            let bytes = image.as_raw();
            // SAFETY: rgba is writable for capacity >= needed == bytes.len() bytes; the image is
            // our own allocation, so the regions do not overlap.
            unsafe { std::ptr::copy_nonoverlapping(bytes.as_ptr(), rgba, bytes.len().min(needed)) };
            Ok(())
        })
    })
}

/// Copies the depth of the last frame into `depth`: width × height 32-bit floats (4 bytes
/// each), top row first, 0 at the near plane and 1 at the far plane and where nothing is drawn
/// (the opaque surfaces' depth: translucent surfaces, and X-ray's, write none). The renderer
/// keeps its frames' depth only with `CadrRendererSettings::depth_to_host` on; a host that
/// shares memory gets it in the exported frame instead (`CadrExportedFrame::depth_offset`).
/// Since 1.1.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_INVALID_ARGUMENT` (the
/// setting is off), `CADR_RESULT_BUFFER_TOO_SMALL` (nothing is written; the message gives the
/// size needed), `CADR_RESULT_VULKAN` or a handle error. Ownership: `depth` is the caller's.
/// Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `depth` is null or writable for `capacity` bytes, aligned for `float`.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_read_depth(
    renderer: CadrRenderer,
    depth: *mut f32,
    capacity: usize,
) -> CadrResult {
    guard(|| {
        non_null(depth, "depth")?;
        with_renderer(renderer, |state| {
            let renderer = state.view.renderer();
            if !renderer.depth_to_host() {
                return Err(Failure::invalid(
                    "the renderer keeps no depth: turn CadrRendererSettings::depth_to_host on",
                ));
            }
            let (width, height) = renderer.size();
            let needed = width as usize * height as usize * 4;
            if capacity < needed {
                return Err(Failure::new(
                    CadrResult::BufferTooSmall,
                    format!("capacity {capacity} is below the {needed} bytes of a {width}x{height} depth (4 bytes a pixel)"),
                ));
            }
            let values = renderer.read_depth()?;
            let count = values.len().min(needed / 4);
            // SAFETY: depth is writable for capacity >= needed bytes, that is `count` floats;
            // the values are our own allocation, so the regions do not overlap.
            unsafe { std::ptr::copy_nonoverlapping(values.as_ptr(), depth, count) };
            Ok(())
        })
    })
}

/// Writes the last frame to a PNG file.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_IO` (the message names
/// the file), `CADR_RESULT_VULKAN` or a handle error. Ownership: `path` is read during the call.
/// Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `path` is null or a valid string.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_save_png(
    renderer: CadrRenderer,
    path: *const c_char,
) -> CadrResult {
    guard(|| {
        // SAFETY: forwarded contract.
        let path = unsafe { required_str(path, "path") }?;
        with_renderer(renderer, |state| {
            state
                .view
                .renderer()
                .save_png(Path::new(path))
                .map_err(|e| match e {
                    cadr_core::frame::SaveError::Write { .. } => {
                        Failure::new(CadrResult::Io, e.to_string())
                    }
                    cadr_core::frame::SaveError::Render(render) => render.into(),
                })
        })
    })
}
