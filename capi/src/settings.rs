//! A renderer's settings as one sized struct the host reads, changes and applies
//! (`cadr_renderer_settings`, `cadr_renderer_apply_settings`), and what the renderer's device
//! and window offer (`cadr_renderer_capabilities`).

use cadr_core::render::{Background, HighlightStyle, Palette, MAX_SECTION_PLANES};
use cadr_core::technique::ShadeMode;
use cadr_core::vk::PresentMode;

use crate::args::{deliver_sized, read_sized};
use crate::error::{guard, CadrResult, Failure};
use crate::renderer::{with_renderer, CadrRenderer, RendererState};
use crate::section::{CADR_MAX_SECTION_PLANES, CADR_SECTION_CAPS, CADR_SECTION_HATCHED};

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

/// Highlight style: highlighted parts' colours mixed towards the highlight colour (the
/// default).
pub const CADR_HIGHLIGHT_TINT: u32 = 0;
/// Highlight style: highlighted parts keep their colours, with a band in the highlight colour
/// around them. Needs the device's `fragmentStoresAndAtomics`
/// (`CadrRendererCapabilities::highlight_outline`).
pub const CADR_HIGHLIGHT_OUTLINE: u32 = 1;

/// Frames paced to the display, never torn; every window offers it (the default).
pub const CADR_PRESENT_FIFO: u32 = 0;
/// The newest frame replaces one waiting to be shown: not torn, not paced.
pub const CADR_PRESENT_MAILBOX: u32 = 1;
/// Frames shown as soon as they are drawn, possibly torn.
pub const CADR_PRESENT_IMMEDIATE: u32 = 2;

/// A renderer's settings: how it draws, picks and presents. Read them with
/// `cadr_renderer_settings`, change the fields you need, and apply them with
/// `cadr_renderer_apply_settings`; a new renderer starts with the defaults each field names.
/// Colours are display values in 0..1 (what a PNG stores) unless a field says otherwise.
///
/// The struct grows by appending fields (`size` first, set by the host to
/// `sizeof(CadrRendererSettings)`); a field added later keeps its old behaviour at 0.
///
/// Its many fields: one per setting, so that a C host sets them one by one; nested structs
/// would freeze each group's size.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CadrRendererSettings {
    /// `sizeof(CadrRendererSettings)`, set by the host.
    pub size: u32,
    /// Display mode (`CADR_SHADE_*`; default `CADR_SHADE_SOLID`).
    pub shade_mode: u32,
    /// How highlighted parts (`CADR_NODE_HIGHLIGHTED`) are drawn, in every display mode
    /// (`CADR_HIGHLIGHT_*`; default `CADR_HIGHLIGHT_TINT`).
    pub highlight_style: u32,
    /// What highlighted parts are tinted towards or outlined in, and their edge lines' colour
    /// (a darker shade). Default orange: 1.0, 0.55, 0.05.
    pub highlight_color: [f32; 3],
    /// Width in pixels, 1 to 8, of the band `CADR_HIGHLIGHT_OUTLINE` draws (default 2).
    pub outline_width: u32,
    /// Colour of edge lines and silhouettes in every display mode that draws them (edges,
    /// hidden-line, wireframe, X-ray; dashed hidden lines take a lighter shade of it).
    /// Default near-black: 0.06, 0.07, 0.09.
    pub edge_color: [f32; 3],
    /// Silhouette edges (default true): in the display modes with feature edges (edges,
    /// hidden-line, X-ray), the outlines of curved surfaces, which no feature edge marks, are
    /// drawn where the frame's depth breaks (in X-ray, where the nearest surface's depth
    /// breaks, translucent surfaces included). On a device without `fragmentStoresAndAtomics`
    /// X-ray draws none and the other modes draw every silhouette in the edge colour. Costs one
    /// full-screen pass in those modes.
    pub silhouettes: bool,
    /// Hidden edges of `CADR_SHADE_HIDDEN_LINE` drawn dashed in a lighter shade of the edge
    /// colour (true), or removed (false, the default). With silhouettes on, hidden curved
    /// surfaces' silhouettes are dashed too where the device has geometry shaders. Parts the
    /// `gpu-occlusion` culler finds entirely hidden are not drawn, so their dashed edges do not
    /// show.
    pub dashed_hidden_lines: bool,
    /// Screen-space ambient occlusion (default false): in the modes that fill surfaces (solid,
    /// edges, X-ray), creases, corners and gaps between parts are darkened from the frame's
    /// depth; the background and translucent surfaces are not. Costs one full-screen pass.
    pub ssao: bool,
    /// Materials' base-colour textures sampled (default true); off, materials show their base
    /// colour (times vertex colours, which stay).
    pub textures: bool,
    /// The background's colour at the picture's top row, blending to `background_bottom` at
    /// its bottom row (the same colour twice is a flat background). Default 0.93, 0.95, 0.97.
    pub background_top: [f32; 3],
    /// The background's colour at the picture's bottom row. Default 0.64, 0.69, 0.76.
    pub background_bottom: [f32; 3],
    /// Samples per pixel of the colour pass: 1 (the default), or 2, 4 or 8 to smooth the edges
    /// of triangles and lines (MSAA), where the device offers the count
    /// (`CadrRendererCapabilities::msaa_sample_counts`). The pick pass always draws one sample.
    /// A change remakes the renderer's targets and pipelines; a submission that records
    /// secondary command buffers and was built before plugin ABI 1.8 then fails at the next
    /// frame with `CADR_RESULT_PLUGIN_FAILED`.
    pub msaa_samples: u32,
    /// Section flags: `CADR_SECTION_CAPS` (fill cuts through closed parts; without it the
    /// inside shows) and `CADR_SECTION_HATCHED` (hatch the caps). Default `CADR_SECTION_CAPS`.
    /// The planes themselves change with `cadr_renderer_set_section_planes`.
    pub section_flags: u32,
    /// Cap colour of each section plane, linear RGBA (finite values, clamped to 0..1), whether
    /// or not the plane is set.
    pub section_cap_colors: [[f32; 4]; CADR_MAX_SECTION_PLANES as usize],
    /// Sub-pixel culling threshold in pixels (default 0: keep every part, as CAD users count
    /// small parts): with a GPU culler (`gpu-frustum`, `gpu-occlusion`), parts whose bounding
    /// sphere projects smaller than this across are not drawn, in any pass (picking included).
    /// CPU cullers ignore it.
    pub min_pixels: f32,
    /// Level-of-detail threshold of the cluster culler (`gpu-clusters`) in pixels (default 1):
    /// each part is drawn with the coarsest clusters whose simplification error projects at or
    /// under it (a part keeps at least its coarsest clusters); 0 draws full detail. Other
    /// cullers draw parts whole and ignore it.
    pub lod_error: f32,
    /// Frame replay (default true): a frame that would record what the last frame recorded
    /// (only the camera moved, or nothing changed; also parts moved or material values
    /// changed, when every active technique reads parameter values on the GPU) resubmits that
    /// recording, when every active technique allows it; the picture is the same. Off, every
    /// frame is recorded afresh (to measure recording, or to compare).
    pub frame_replay: bool,
    /// Picking goes through translucent parts to what lies behind them (true), or picks them
    /// like opaque ones (false, the default: what is seen in front is picked). X-ray's
    /// see-through look is a display mode and does not count.
    pub pick_through_translucent: bool,
    /// Frames the GPU may have, 1 to 3. 1 waits for each frame before `cadr_renderer_render`
    /// returns (its GPU time is then that frame's); 2 or 3 return once the frame is submitted,
    /// so the host's work and the next frames' scene updates overlap the GPU's drawing (pixels
    /// and picks wait for the frame when read). A frame waits only for the one that used its
    /// slot before when nothing but the camera changed and every active technique keeps its
    /// per-frame data per slot (cadr's own do, but the `-threads` submissions); otherwise for
    /// every earlier frame. Default: 2 for window and host-image renderers, 1 offscreen.
    pub frames_in_flight: u32,
    /// How a window renderer's frames reach its window (`CADR_PRESENT_*`; default
    /// `CADR_PRESENT_FIFO`), among those its surface offers
    /// (`CadrRendererCapabilities::present_modes`); a change recreates the swapchain. Other
    /// renderers present nothing and take only `CADR_PRESENT_FIFO`.
    pub present_mode: u32,
    /// Each frame's depth kept for the host (default false), for a host that draws its own
    /// geometry into cadr's frame with a depth test (a grid, a manipulator, its own
    /// annotations): a renderer made by `cadr_renderer_create_for_export` exports it after the
    /// colour (`CadrExportedFrame::depth_offset`; applying a change gives the frames new
    /// memory, of a new `generation`: import it again), and any renderer's can be read back
    /// with `cadr_renderer_read_depth`. It costs a depth store (and a copy) per frame, and a
    /// depth image of the renderer's own (renderers of one size otherwise share one). Since
    /// 1.1.
    pub depth_to_host: bool,
}

/// What a renderer's device and output offer, for the choices of `CadrRendererSettings`.
/// The struct grows by appending fields (`size` first, set by the host).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CadrRendererCapabilities {
    /// `sizeof(CadrRendererCapabilities)`, set by the host.
    pub size: u32,
    /// The MSAA sample counts offered: bit value N set for each count N, as
    /// `VkSampleCountFlags` (1 always; 0x5 for 1 and 4).
    pub msaa_sample_counts: u32,
    /// The present modes a window renderer's surface offers: bit `1 << CADR_PRESENT_*` for
    /// each; 0 for a renderer without a window.
    pub present_modes: u32,
    /// Whether the device can draw `CADR_HIGHLIGHT_OUTLINE` and X-ray's silhouettes
    /// (`fragmentStoresAndAtomics`).
    pub highlight_outline: bool,
}

fn shade_mode(code: u32) -> Result<ShadeMode, Failure> {
    Ok(match code {
        CADR_SHADE_SOLID => ShadeMode::Solid,
        CADR_SHADE_EDGES => ShadeMode::Edges,
        CADR_SHADE_HIDDEN_LINE => ShadeMode::HiddenLine,
        CADR_SHADE_WIREFRAME => ShadeMode::Wireframe,
        CADR_SHADE_XRAY => ShadeMode::XRay,
        other => {
            return Err(Failure::invalid(format!(
                "settings.shade_mode {other} is not 0 (solid), 1 (edges), 2 (hidden line), 3 (wireframe) or 4 (X-ray)"
            )))
        }
    })
}

fn shade_code(mode: ShadeMode) -> u32 {
    match mode {
        ShadeMode::Solid => CADR_SHADE_SOLID,
        ShadeMode::Edges => CADR_SHADE_EDGES,
        ShadeMode::HiddenLine => CADR_SHADE_HIDDEN_LINE,
        ShadeMode::Wireframe => CADR_SHADE_WIREFRAME,
        ShadeMode::XRay => CADR_SHADE_XRAY,
    }
}

fn highlight_style(code: u32) -> Result<HighlightStyle, Failure> {
    match code {
        CADR_HIGHLIGHT_TINT => Ok(HighlightStyle::Tint),
        CADR_HIGHLIGHT_OUTLINE => Ok(HighlightStyle::Outline),
        other => Err(Failure::invalid(format!(
            "settings.highlight_style {other} is not 0 (tint) or 1 (outline)"
        ))),
    }
}

fn highlight_code(style: HighlightStyle) -> u32 {
    match style {
        HighlightStyle::Tint => CADR_HIGHLIGHT_TINT,
        HighlightStyle::Outline => CADR_HIGHLIGHT_OUTLINE,
    }
}

fn present_mode(code: u32) -> Result<PresentMode, Failure> {
    match code {
        CADR_PRESENT_FIFO => Ok(PresentMode::Fifo),
        CADR_PRESENT_MAILBOX => Ok(PresentMode::Mailbox),
        CADR_PRESENT_IMMEDIATE => Ok(PresentMode::Immediate),
        other => Err(Failure::invalid(format!(
            "settings.present_mode {other} is not 0 (fifo), 1 (mailbox) or 2 (immediate)"
        ))),
    }
}

fn present_code(mode: PresentMode) -> u32 {
    match mode {
        PresentMode::Fifo => CADR_PRESENT_FIFO,
        PresentMode::Mailbox => CADR_PRESENT_MAILBOX,
        PresentMode::Immediate => CADR_PRESENT_IMMEDIATE,
    }
}

/// Refuses a threshold in pixels that is negative, infinite or NaN.
fn pixels(field: &str, value: f32) -> Result<f32, Failure> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(Failure::invalid(format!(
            "settings.{field} {value}: expected a finite number of pixels >= 0"
        )))
    }
}

/// Prefixes a refusal of the core with the field it came from.
fn named<T>(field: &str, result: Result<T, impl Into<Failure>>) -> Result<T, Failure> {
    result.map_err(|e| e.into().named(&format!("settings.{field}")))
}

/// The renderer's settings as they are now.
fn current(state: &RendererState) -> CadrRendererSettings {
    let renderer = state.view.renderer();
    let techniques = state.view.techniques();
    let section = state.view.section();
    let (palette, background) = (renderer.palette(), renderer.background());
    let mut section_cap_colors = [[0.0; 4]; CADR_MAX_SECTION_PLANES as usize];
    for (index, color) in section_cap_colors.iter_mut().enumerate() {
        *color = section.cap_color(index).unwrap_or_default();
    }
    let section_flags = if section.caps() { CADR_SECTION_CAPS } else { 0 }
        | if section.hatched() {
            CADR_SECTION_HATCHED
        } else {
            0
        };
    CadrRendererSettings {
        size: std::mem::size_of::<CadrRendererSettings>() as u32,
        shade_mode: shade_code(techniques.shade_mode()),
        highlight_style: highlight_code(renderer.highlight_style()),
        highlight_color: palette.highlight,
        outline_width: palette.outline_width,
        edge_color: palette.edges,
        silhouettes: renderer.silhouettes(),
        dashed_hidden_lines: techniques.dashed_hidden_lines(),
        ssao: renderer.ssao(),
        textures: renderer.textures(),
        background_top: background.top,
        background_bottom: background.bottom,
        msaa_samples: renderer.msaa(),
        section_flags,
        section_cap_colors,
        min_pixels: techniques.min_pixels(),
        lod_error: techniques.lod_error(),
        frame_replay: techniques.frame_replay(),
        pick_through_translucent: techniques.pick_through_translucent(),
        frames_in_flight: renderer.frames_in_flight(),
        present_mode: state
            .swapchain
            .as_ref()
            .map_or(CADR_PRESENT_FIFO, |s| present_code(s.present_mode())),
        depth_to_host: renderer.depth_to_host(),
    }
}

/// Refuses unknown codes and flags and thresholds out of range before anything changes (the
/// renderer refuses the rest as it applies them, and the call undoes what it applied).
fn check(wanted: &CadrRendererSettings) -> Result<(), Failure> {
    shade_mode(wanted.shade_mode)?;
    highlight_style(wanted.highlight_style)?;
    present_mode(wanted.present_mode)?;
    pixels("min_pixels", wanted.min_pixels)?;
    pixels("lod_error", wanted.lod_error)?;
    let known = CADR_SECTION_CAPS | CADR_SECTION_HATCHED;
    if wanted.section_flags & !known != 0 {
        return Err(Failure::invalid(format!(
            "settings.section_flags {:#x} have unknown bits (known: CADR_SECTION_CAPS {CADR_SECTION_CAPS}, CADR_SECTION_HATCHED {CADR_SECTION_HATCHED})",
            wanted.section_flags
        )));
    }
    Ok(())
}

fn palette(settings: &CadrRendererSettings) -> Palette {
    Palette {
        edges: settings.edge_color,
        highlight: settings.highlight_color,
        outline_width: settings.outline_width,
    }
}

/// Applies the fields of `to` that differ from `from` (the renderer's settings now), in an
/// order where each change finds the ones it depends on done. A failure leaves the changes
/// before it applied.
fn apply_changes(
    state: &mut RendererState,
    from: &CadrRendererSettings,
    to: &CadrRendererSettings,
) -> Result<(), Failure> {
    let techniques = state.view.techniques_mut();
    if to.shade_mode != from.shade_mode {
        named(
            "shade_mode",
            techniques.set_shade_mode(shade_mode(to.shade_mode)?),
        )?;
    }
    if to.dashed_hidden_lines != from.dashed_hidden_lines {
        techniques.set_dashed_hidden_lines(to.dashed_hidden_lines);
    }
    if to.frame_replay != from.frame_replay {
        techniques.set_frame_replay(to.frame_replay);
    }
    if to.pick_through_translucent != from.pick_through_translucent {
        techniques.set_pick_through_translucent(to.pick_through_translucent);
    }
    if to.min_pixels != from.min_pixels {
        named("min_pixels", techniques.set_min_pixels(to.min_pixels))?;
    }
    if to.lod_error != from.lod_error {
        named("lod_error", techniques.set_lod_error(to.lod_error))?;
    }
    if to.depth_to_host != from.depth_to_host {
        named(
            "depth_to_host",
            state
                .view
                .renderer_mut()
                .set_depth_to_host(to.depth_to_host),
        )?;
        // The memory is made for the depth now, so that the host imports it once.
        let renderer = state.view.renderer();
        let (width, height) = renderer.size();
        if let Some(output) = &mut state.frame_export {
            let extent = cadr_core::vk::raw::Extent2D { width, height };
            output.reshape(renderer.device(), extent, to.depth_to_host)?;
        }
    }
    let renderer = state.view.renderer_mut();
    if to.highlight_style != from.highlight_style {
        named(
            "highlight_style",
            renderer.set_highlight_style(highlight_style(to.highlight_style)?),
        )?;
    }
    if palette(to) != palette(from) {
        named("palette", renderer.set_palette(palette(to)))?;
    }
    if (to.background_top, to.background_bottom) != (from.background_top, from.background_bottom) {
        let background = Background {
            top: to.background_top,
            bottom: to.background_bottom,
        };
        named("background", renderer.set_background(background))?;
    }
    if to.silhouettes != from.silhouettes {
        named("silhouettes", renderer.set_silhouettes(to.silhouettes))?;
    }
    if to.ssao != from.ssao {
        named("ssao", renderer.set_ssao(to.ssao))?;
    }
    if to.textures != from.textures {
        renderer.set_textures(to.textures);
    }
    if to.msaa_samples != from.msaa_samples {
        named("msaa_samples", renderer.set_msaa(to.msaa_samples))?;
    }
    if to.frames_in_flight != from.frames_in_flight {
        named(
            "frames_in_flight",
            renderer.set_frames_in_flight(to.frames_in_flight),
        )?;
    }
    if to.section_flags != from.section_flags || to.section_cap_colors != from.section_cap_colors {
        let mut section = state.view.section().clone();
        section.set_caps(to.section_flags & CADR_SECTION_CAPS != 0);
        section.set_hatched(to.section_flags & CADR_SECTION_HATCHED != 0);
        for (index, color) in to.section_cap_colors.iter().enumerate() {
            if !section.set_cap_color(index, *color) {
                return Err(Failure::invalid(format!(
                    "settings.section_cap_colors[{index}] {color:?}: every value must be finite"
                )));
            }
        }
        state.view.set_section(section);
    }
    if to.present_mode != from.present_mode {
        let mode = present_mode(to.present_mode)?;
        match &mut state.swapchain {
            Some(swapchain) => named("present_mode", swapchain.set_present_mode(mode))?,
            None => {
                return Err(Failure::new(
                    CadrResult::Unsupported,
                    "settings.present_mode: a renderer without a window presents nothing and takes only CADR_PRESENT_FIFO".into(),
                ))
            }
        }
    }
    Ok(())
}

const _: () = assert!(CADR_MAX_SECTION_PLANES as usize == MAX_SECTION_PLANES);

/// Writes the renderer's settings into `*settings`, up to the `settings->size` the host set
/// (`sizeof(CadrRendererSettings)`; a newer host's fields this library does not know are
/// zeroed).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_INVALID_ARGUMENT` (a
/// `size` below 4) or a handle error. Ownership: the struct is the caller's; cadr keeps no
/// pointer to it. Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `settings` is null or points to `settings->size` writable bytes.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_settings(
    renderer: CadrRenderer,
    settings: *mut CadrRendererSettings,
) -> CadrResult {
    guard(|| {
        let value = with_renderer(renderer, |state| Ok(current(state)))?;
        // SAFETY: null or `size` writable bytes (the caller's contract).
        unsafe { deliver_sized(settings, "settings", value) }
    })
}

/// Applies `*settings` to the renderer; the next frame and pick follow them. Read the
/// settings first with `cadr_renderer_settings` and change what you need. A host compiled
/// against an older header (a smaller `size`) keeps the renderer's current values of the
/// fields it does not know; a newer host's fields this library does not know must be 0.
///
/// All or nothing: a refused value (the message names the field) leaves every setting as it
/// was.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_INVALID_ARGUMENT` (a
/// value out of range, a sample count or highlight style the device does not offer, a
/// non-zero field this library does not know), `CADR_RESULT_UNSUPPORTED` (a present mode the
/// window does not offer, or another than FIFO without a window), `CADR_RESULT_VULKAN` or a
/// handle error. Ownership: `settings` is read during the call only. Thread-safety: as
/// `cadr_renderer_create`.
///
/// # Safety
/// `settings` is null or points to `settings->size` readable bytes.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_apply_settings(
    renderer: CadrRenderer,
    settings: *const CadrRendererSettings,
) -> CadrResult {
    guard(|| {
        with_renderer(renderer, |state| {
            let before = current(state);
            // SAFETY: null or `size` readable bytes (the caller's contract).
            let wanted =
                unsafe { read_sized(settings, ("settings", "CadrRendererSettings"), before) }?;
            check(&wanted)?;
            if let Err(failure) = apply_changes(state, &before, &wanted) {
                // Undo what was applied before the refusal; what was set before was valid.
                let partly = current(state);
                if let Err(undo) = apply_changes(state, &partly, &before) {
                    log::error!("restoring a renderer's settings after a refusal failed: {undo:?}");
                }
                return Err(failure);
            }
            Ok(())
        })
    })
}

/// Writes what the renderer's device and output offer into `*capabilities`, up to the
/// `capabilities->size` the host set.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_INVALID_ARGUMENT` (a
/// `size` below 4), `CADR_RESULT_VULKAN` (the window's surface could not be asked) or a
/// handle error. Ownership: the struct is the caller's. Thread-safety: as
/// `cadr_renderer_create`.
///
/// # Safety
/// `capabilities` is null or points to `capabilities->size` writable bytes.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_capabilities(
    renderer: CadrRenderer,
    capabilities: *mut CadrRendererCapabilities,
) -> CadrResult {
    guard(|| {
        let value = with_renderer(renderer, |state| {
            let device = state.view.renderer().device();
            let msaa_sample_counts = device
                .sample_counts()
                .iter()
                .fold(0u32, |mask, count| mask | count);
            let present_modes = match &state.swapchain {
                Some(swapchain) => swapchain
                    .present_modes()?
                    .into_iter()
                    .fold(0u32, |mask, m| mask | 1 << present_code(m)),
                None => 0,
            };
            Ok(CadrRendererCapabilities {
                size: std::mem::size_of::<CadrRendererCapabilities>() as u32,
                msaa_sample_counts,
                present_modes,
                highlight_outline: device.capabilities().fragment_stores_and_atomics,
            })
        })?;
        // SAFETY: null or `size` writable bytes (the caller's contract).
        unsafe { deliver_sized(capabilities, "capabilities", value) }
    })
}
