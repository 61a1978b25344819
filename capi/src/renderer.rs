//! Renderers: an offscreen target or a host window's swapchain, the techniques that draw into
//! it, frames and their statistics, pixels and PNGs.

use std::ffi::c_char;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use cadr_core::render::HighlightStyle;
use cadr_core::technique::{Combination, ShadeMode, TechniqueKind};
use cadr_core::view::View;
use cadr_core::vk::{raw, raw::Handle, HostImage, ImageOutput, PresentOutcome, Swapchain};

use crate::args::{deliver, non_null, optional_str, required_str, write};
use crate::camera::CadrCamera;
use crate::context::{context_state, CadrContext, CadrTechniqueKind, ContextState};
use crate::error::{guard, CadrResult, Failure};
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

/// Shaded triangles only.
pub const CADR_SHADE_SOLID: u32 = 0;
/// Shaded triangles with their edges drawn as lines.
pub const CADR_SHADE_EDGES: u32 = 1;
/// Display mode: edge lines only, those hidden behind opaque surfaces removed (translucent
/// surfaces hide no lines); section caps are filled and hide the lines behind them.
pub const CADR_SHADE_HIDDEN_LINE: u32 = 2;
/// Display mode: every triangle's edges, hidden ones included.
pub const CADR_SHADE_WIREFRAME: u32 = 3;
/// Display mode: every part translucent with its edges, highlighted parts opaque (what is
/// inside an assembly shows through its housing).
pub const CADR_SHADE_XRAY: u32 = 4;

/// Highlight style: highlighted parts' colours mixed towards orange (the default).
pub const CADR_HIGHLIGHT_TINT: u32 = 0;
/// Highlight style: highlighted parts keep their colours, with an orange band two pixels wide
/// around them. Needs the device's `fragmentStoresAndAtomics`.
pub const CADR_HIGHLIGHT_OUTLINE: u32 = 1;

/// One technique name per kind; NULL keeps the renderer's current technique of that kind.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrTechniqueSelection {
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
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CadrFrameStats {
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
    /// Triangles drawn.
    pub triangles: u64,
    /// Pipeline binds.
    pub pipeline_binds: u64,
    /// Vertex and index buffer binds.
    pub vertex_binds: u64,
    /// Parameter updates (push constants, descriptor binds).
    pub parameter_updates: u64,
    /// Bytes uploaded for this frame.
    pub bytes_uploaded: u64,
}

/// What a renderer holds: the view (its GPU scene, techniques and target), the window's
/// swapchain or the host's image its frames go to, and the context that keeps the device
/// alive. The outputs come first: dropped first, they wait for their blits, which read the
/// view's picture.
pub(crate) struct RendererState {
    pub(crate) swapchain: Option<Swapchain>,
    /// The host's image every frame is blitted into (`cadr_renderer_create_for_image`).
    pub(crate) image_output: Option<ImageOutput>,
    pub(crate) view: View,
    context: Arc<ContextState>,
    /// Whether the last frame resubmitted the recording before it.
    last_frame_replayed: bool,
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
    let (swapchain, image_output) = match output {
        Output::Offscreen => (None, None),
        Output::Surface(surface) => (Some(Swapchain::new(device, surface, width, height)?), None),
        Output::Image(image) => (None, Some(ImageOutput::new(device, image)?)),
    };
    if swapchain.is_some() || image_output.is_some() {
        // A window's or a host image's frames go to the GPU without waiting for the last one
        // (see cadr_renderer_set_frames_in_flight); offscreen frames are read back at once
        // anyway.
        view.renderer_mut().set_frames_in_flight(2)?;
    }
    let state = RendererState {
        swapchain,
        image_output,
        view,
        context: Arc::clone(&context),
        last_frame_replayed: false,
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
    non_null(selection, "selection")?;
    // SAFETY: non-null and valid by contract.
    let selection = unsafe { *selection };
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

/// Sets the display mode: `CADR_SHADE_SOLID`, `CADR_SHADE_EDGES`, `CADR_SHADE_HIDDEN_LINE`,
/// `CADR_SHADE_WIREFRAME` or `CADR_SHADE_XRAY`.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_INVALID_ARGUMENT` (unknown mode), `CADR_RESULT_VULKAN`
/// or a handle error. Ownership: nothing changes hands; the arguments are read during the call
/// only. Thread-safety: as `cadr_renderer_create`.
#[no_mangle]
pub extern "C" fn cadr_renderer_set_shade_mode(renderer: CadrRenderer, mode: u32) -> CadrResult {
    guard(|| {
        let mode = match mode {
            CADR_SHADE_SOLID => ShadeMode::Solid,
            CADR_SHADE_EDGES => ShadeMode::Edges,
            CADR_SHADE_HIDDEN_LINE => ShadeMode::HiddenLine,
            CADR_SHADE_WIREFRAME => ShadeMode::Wireframe,
            CADR_SHADE_XRAY => ShadeMode::XRay,
            other => {
                return Err(Failure::invalid(format!(
                "shade mode {other} is not 0 (solid), 1 (edges), 2 (hidden line), 3 (wireframe) or 4 (X-ray)"
            )))
            }
        };
        with_renderer(renderer, |state| {
            Ok(state.view.techniques_mut().set_shade_mode(mode)?)
        })
    })
}

/// Writes the display mode (`CADR_SHADE_*`).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the outputs are the caller's; cadr keeps no pointer to them.
/// Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `mode` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_shade_mode(
    renderer: CadrRenderer,
    mode: *mut u32,
) -> CadrResult {
    guard(|| {
        let value = with_renderer(renderer, |state| {
            Ok(match state.view.techniques().shade_mode() {
                ShadeMode::Solid => CADR_SHADE_SOLID,
                ShadeMode::Edges => CADR_SHADE_EDGES,
                ShadeMode::HiddenLine => CADR_SHADE_HIDDEN_LINE,
                ShadeMode::Wireframe => CADR_SHADE_WIREFRAME,
                ShadeMode::XRay => CADR_SHADE_XRAY,
            })
        })?;
        // SAFETY: mode is null or writable (the caller's contract).
        unsafe { deliver(mode, "mode", value) }
    })
}

/// Turns screen-space ambient occlusion on or off (off by default): in the modes that fill
/// surfaces (solid, edges, X-ray), creases, corners and gaps between parts are darkened from
/// the frame's depth; the background and translucent surfaces are not. Applies from the next
/// frame; its cost is one full-screen pass.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_VULKAN` or a handle error. Ownership: nothing
/// changes hands. Thread-safety: as `cadr_renderer_create`.
#[no_mangle]
pub extern "C" fn cadr_renderer_set_ssao(renderer: CadrRenderer, on: bool) -> CadrResult {
    guard(|| {
        with_renderer(renderer, |state| {
            Ok(state.view.renderer_mut().set_ssao(on)?)
        })
    })
}

/// Writes whether screen-space ambient occlusion is on (see `cadr_renderer_set_ssao`).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the output is the caller's; cadr keeps no pointer to it.
/// Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `on` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_ssao(renderer: CadrRenderer, on: *mut bool) -> CadrResult {
    guard(|| {
        let value = with_renderer(renderer, |state| Ok(state.view.renderer().ssao()))?;
        // SAFETY: on is null or writable (the caller's contract).
        unsafe { deliver(on, "on", value) }
    })
}

/// Sets how highlighted parts (`CADR_NODE_HIGHLIGHTED`) are drawn: `CADR_HIGHLIGHT_TINT` (the
/// default) or `CADR_HIGHLIGHT_OUTLINE`, in every display mode. Applies from the next frame.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_INVALID_ARGUMENT` (an unknown style, or the outline
/// on a device without `fragmentStoresAndAtomics`; the message says which),
/// `CADR_RESULT_VULKAN` or a handle error. Ownership: nothing changes hands.
/// Thread-safety: as `cadr_renderer_create`.
#[no_mangle]
pub extern "C" fn cadr_renderer_set_highlight_style(
    renderer: CadrRenderer,
    style: u32,
) -> CadrResult {
    guard(|| {
        let style = match style {
            CADR_HIGHLIGHT_TINT => HighlightStyle::Tint,
            CADR_HIGHLIGHT_OUTLINE => HighlightStyle::Outline,
            other => {
                return Err(Failure::invalid(format!(
                    "highlight style {other} is not 0 (tint) or 1 (outline)"
                )))
            }
        };
        with_renderer(renderer, |state| {
            Ok(state.view.renderer_mut().set_highlight_style(style)?)
        })
    })
}

/// Writes the highlight style (`CADR_HIGHLIGHT_*`).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the output is the caller's; cadr keeps no pointer to it.
/// Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `style` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_highlight_style(
    renderer: CadrRenderer,
    style: *mut u32,
) -> CadrResult {
    guard(|| {
        let value = with_renderer(renderer, |state| {
            Ok(match state.view.renderer().highlight_style() {
                HighlightStyle::Tint => CADR_HIGHLIGHT_TINT,
                HighlightStyle::Outline => CADR_HIGHLIGHT_OUTLINE,
            })
        })?;
        // SAFETY: style is null or writable (the caller's contract).
        unsafe { deliver(style, "style", value) }
    })
}

/// Turns silhouette edges on (`on` true, the default) or off: in the display modes with
/// feature edges (edges, hidden-line, X-ray), the outlines of curved surfaces, which no
/// feature edge marks, are drawn with the feature edges, found where the frame's depth breaks
/// (in X-ray, where the nearest surface's depth breaks, translucent surfaces included), in the
/// edge lines' colour, or a highlighted part's in the highlight's line colour, as its feature
/// edges. On a device without `fragmentStoresAndAtomics` X-ray draws none and the other modes
/// draw every silhouette in the edge lines' colour. Applies from the next frame; its cost is
/// one full-screen pass in those modes, and in X-ray, or while some part is highlighted, an
/// atomic write per surface fragment.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_VULKAN` or a handle error. Ownership: nothing
/// changes hands. Thread-safety: as `cadr_renderer_create`.
#[no_mangle]
pub extern "C" fn cadr_renderer_set_silhouettes(renderer: CadrRenderer, on: bool) -> CadrResult {
    guard(|| {
        with_renderer(renderer, |state| {
            Ok(state.view.renderer_mut().set_silhouettes(on)?)
        })
    })
}

/// Writes whether silhouette edges are on (see `cadr_renderer_set_silhouettes`).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the output is the caller's; cadr keeps no pointer to it.
/// Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `on` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_silhouettes(
    renderer: CadrRenderer,
    on: *mut bool,
) -> CadrResult {
    guard(|| {
        let value = with_renderer(renderer, |state| Ok(state.view.renderer().silhouettes()))?;
        // SAFETY: on is null or writable (the caller's contract).
        unsafe { deliver(on, "on", value) }
    })
}

/// Turns the sampling of materials' base-colour textures on (`on` true, the default) or off:
/// off, materials show their base colour (times vertex colours, which stay). Applies from the
/// next frame; nothing is rebuilt.
///
/// Returns `CADR_RESULT_OK` or a handle error. Ownership: nothing changes hands.
/// Thread-safety: as `cadr_renderer_create`.
#[no_mangle]
pub extern "C" fn cadr_renderer_set_textures(renderer: CadrRenderer, on: bool) -> CadrResult {
    guard(|| {
        with_renderer(renderer, |state| {
            state.view.renderer_mut().set_textures(on);
            Ok(())
        })
    })
}

/// Writes whether materials' textures are sampled (see `cadr_renderer_set_textures`).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the output is the caller's; cadr keeps no pointer to it.
/// Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `on` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_textures(
    renderer: CadrRenderer,
    on: *mut bool,
) -> CadrResult {
    guard(|| {
        let value = with_renderer(renderer, |state| Ok(state.view.renderer().textures()))?;
        // SAFETY: on is null or writable (the caller's contract).
        unsafe { deliver(on, "on", value) }
    })
}

/// Shows the hidden edges in the `CADR_SHADE_HIDDEN_LINE` mode dashed, in a lighter shade of
/// the visible ones' colour (`dashed` true), or removes them (false, the default). With
/// silhouettes on (`cadr_renderer_set_silhouettes`), the silhouettes of hidden curved
/// surfaces (tessellated with shared vertex normals) are dashed too where the device has
/// geometry shaders. Other modes are not affected. Applies from the next frame. With the `gpu-occlusion` culler, parts it finds
/// entirely hidden are not drawn, so their dashed edges do not show.
///
/// Returns `CADR_RESULT_OK` or a handle error. Ownership: nothing changes hands.
/// Thread-safety: as `cadr_renderer_create`.
#[no_mangle]
pub extern "C" fn cadr_renderer_set_dashed_hidden_lines(
    renderer: CadrRenderer,
    dashed: bool,
) -> CadrResult {
    guard(|| {
        with_renderer(renderer, |state| {
            state.view.techniques_mut().set_dashed_hidden_lines(dashed);
            Ok(())
        })
    })
}

/// Writes whether the hidden-line mode shows hidden edges dashed (see
/// `cadr_renderer_set_dashed_hidden_lines`).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the output is the caller's; cadr keeps no pointer to it.
/// Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `dashed` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_dashed_hidden_lines(
    renderer: CadrRenderer,
    dashed: *mut bool,
) -> CadrResult {
    guard(|| {
        let value = with_renderer(renderer, |state| {
            Ok(state.view.techniques().dashed_hidden_lines())
        })?;
        // SAFETY: dashed is null or writable (the caller's contract).
        unsafe { deliver(dashed, "dashed", value) }
    })
}

/// Sets the sub-pixel culling threshold: with a GPU culler (`gpu-frustum`, `gpu-occlusion`)
/// active, parts whose bounding sphere projects smaller than `pixels` across are not drawn, in
/// any pass (picking included). 0, the default, keeps every part (CAD users count small parts);
/// CPU cullers ignore the threshold. Applies from the next frame.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_INVALID_ARGUMENT` (negative, infinite or NaN) or a
/// handle error. Ownership: nothing changes hands. Thread-safety: as `cadr_renderer_create`.
#[no_mangle]
pub extern "C" fn cadr_renderer_set_min_pixels(renderer: CadrRenderer, pixels: f32) -> CadrResult {
    guard(|| {
        if !pixels.is_finite() || pixels < 0.0 {
            return Err(Failure::invalid(format!(
                "sub-pixel threshold {pixels}: expected a finite number of pixels >= 0"
            )));
        }
        with_renderer(renderer, |state| {
            Ok(state.view.techniques_mut().set_min_pixels(pixels)?)
        })
    })
}

/// Writes the sub-pixel culling threshold in pixels (0: off).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the output is the caller's; cadr keeps no pointer to it.
/// Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `pixels` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_min_pixels(
    renderer: CadrRenderer,
    pixels: *mut f32,
) -> CadrResult {
    guard(|| {
        let value = with_renderer(renderer, |state| Ok(state.view.techniques().min_pixels()))?;
        // SAFETY: pixels is null or writable (the caller's contract).
        unsafe { deliver(pixels, "pixels", value) }
    })
}

/// Sets the level-of-detail threshold of the cluster culler (`gpu-clusters`), in pixels: each
/// part is drawn with the coarsest clusters whose simplification error projects at or under
/// `pixels` on screen (a part never vanishes for being far: it keeps its coarsest clusters).
/// 0 draws every part at full detail; the default is 1. Other cullers draw parts whole and
/// ignore it. Applies from the next frame.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_INVALID_ARGUMENT` (negative, infinite or NaN) or a
/// handle error. Ownership: nothing changes hands. Thread-safety: as `cadr_renderer_create`.
#[no_mangle]
pub extern "C" fn cadr_renderer_set_lod_error(renderer: CadrRenderer, pixels: f32) -> CadrResult {
    guard(|| {
        if !pixels.is_finite() || pixels < 0.0 {
            return Err(Failure::invalid(format!(
                "level-of-detail error {pixels}: expected a finite number of pixels >= 0"
            )));
        }
        with_renderer(renderer, |state| {
            Ok(state.view.techniques_mut().set_lod_error(pixels)?)
        })
    })
}

/// Writes the level-of-detail threshold of the cluster culler in pixels (0: full detail).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the output is the caller's; cadr keeps no pointer to it.
/// Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `pixels` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_lod_error(
    renderer: CadrRenderer,
    pixels: *mut f32,
) -> CadrResult {
    guard(|| {
        let value = with_renderer(renderer, |state| Ok(state.view.techniques().lod_error()))?;
        // SAFETY: pixels is null or writable (the caller's contract).
        unsafe { deliver(pixels, "pixels", value) }
    })
}

/// Turns frame replay on (the default) or off. With it on, a frame that would record what the
/// renderer's last frame recorded (only the camera moved, or nothing changed; also parts moved
/// or material values changed, when every active technique reads parameter values on the
/// GPU) resubmits that recording instead, after the frame's uploads, when every active
/// technique allows it; the picture is the same. Off,
/// every frame is recorded afresh (to measure recording, or to compare).
///
/// Returns `CADR_RESULT_OK` or a handle error. Ownership: nothing changes hands.
/// Thread-safety: as `cadr_renderer_create`.
#[no_mangle]
pub extern "C" fn cadr_renderer_set_frame_replay(
    renderer: CadrRenderer,
    enabled: bool,
) -> CadrResult {
    guard(|| {
        with_renderer(renderer, |state| {
            state.view.techniques_mut().set_frame_replay(enabled);
            Ok(())
        })
    })
}

/// Writes whether frame replay is on (`*enabled`) and whether the renderer's last frame was
/// a replay (`*last_frame_replayed`; false before the first frame). Either output may be NULL.
///
/// Returns `CADR_RESULT_OK` or a handle error.
/// Ownership: the outputs are the caller's; cadr keeps no pointer to them.
/// Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `enabled` and `last_frame_replayed` are each null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_frame_replay(
    renderer: CadrRenderer,
    enabled: *mut bool,
    last_frame_replayed: *mut bool,
) -> CadrResult {
    guard(|| {
        let (on, replayed) = with_renderer(renderer, |state| {
            Ok((
                state.view.techniques().frame_replay(),
                state.last_frame_replayed,
            ))
        })?;
        for (out, value) in [(enabled, on), (last_frame_replayed, replayed)] {
            if !out.is_null() {
                // SAFETY: non-null; writable by contract.
                unsafe { write(out, value) };
            }
        }
        Ok(())
    })
}

/// Renders one frame of `scene` seen by `camera`: applies the host's edits since the last
/// frame (incrementally), culls, draws with the current techniques and, for a window, presents.
/// `stats` may be NULL.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_INVALID_ARGUMENT`
/// (non-finite camera), `CADR_RESULT_VULKAN`, `CADR_RESULT_PLUGIN_FAILED` or a handle error.
/// Ownership: the camera is read during the call. Thread-safety: as `cadr_renderer_create`; the
/// scene is locked during the call. A scene drawn alternately by two renderers is uploaded
/// afresh at each change of renderer.
///
/// # Safety
/// `camera` is null or readable; `stats` null or writable.
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
            let mut scene_state = lock(&scene_object);
            let update_start = Instant::now();
            scene_state.update();
            let s = &mut *scene_state;
            state.view.sync(&s.graph, &mut s.tree)?;
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
            frame.cpu_us = drawn.cpu_us();
            frame.cpu_record_us = drawn.cpu_record_us;
            frame.cpu_submit_us = drawn.cpu_submit_us;
            frame.gpu_us = drawn.gpu_us.unwrap_or(-1.0);
            frame.draw_calls = drawn.draw_calls;
            frame.draws = drawn.draws;
            frame.triangles = drawn.triangles;
            frame.pipeline_binds = drawn.pipeline_binds;
            frame.vertex_binds = drawn.vertex_binds;
            frame.parameter_updates = drawn.parameter_updates;
            frame.bytes_uploaded = drawn.bytes_uploaded;
            state.last_frame_replayed = drawn.replayed;
            Ok(frame)
        })?;
        if !stats.is_null() {
            // SAFETY: non-null; writable by contract.
            unsafe { write(stats, value) };
        }
        Ok(())
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
