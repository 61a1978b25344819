//! The colours a renderer draws edge lines and highlights in, and the width of the outline
//! band (`cadr_core::render::Palette`): a host draws cadr's lines and selection feedback in
//! its own theme's colours.

use cadr_core::render::{DisplayRgb, Palette};

use crate::args::{deliver, slice};
use crate::error::{guard, CadrResult, Failure};
use crate::renderer::{with_renderer, CadrRenderer};

/// Changes the renderer's palette with `change` (a failed change or a refused palette leaves
/// it as it was).
fn change_palette(
    renderer: CadrRenderer,
    change: impl FnOnce(&mut Palette) -> Result<(), Failure>,
) -> CadrResult {
    guard(|| {
        with_renderer(renderer, |state| {
            let mut palette = state.view.renderer().palette();
            change(&mut palette)?;
            Ok(state.view.renderer_mut().set_palette(palette)?)
        })
    })
}

/// Sets the palette colour `slot` chooses to the three floats at `rgb`.
///
/// # Safety
/// `rgb` is null or points to three readable floats.
unsafe fn set_color(
    renderer: CadrRenderer,
    rgb: *const f32,
    slot: impl FnOnce(&mut Palette) -> &mut DisplayRgb,
) -> CadrResult {
    change_palette(renderer, |palette| {
        // SAFETY: null or three readable floats (the caller's contract).
        let values = unsafe { slice(rgb, 3, "rgb") }?;
        *slot(palette) = [values[0], values[1], values[2]];
        Ok(())
    })
}

/// Writes the palette colour `color` chooses to the three floats at `rgb`.
///
/// # Safety
/// `rgb` is null or points to three writable floats.
unsafe fn deliver_color(
    renderer: CadrRenderer,
    rgb: *mut f32,
    color: impl FnOnce(&Palette) -> DisplayRgb,
) -> CadrResult {
    guard(|| {
        let palette = with_renderer(renderer, |state| Ok(state.view.renderer().palette()))?;
        // SAFETY: null or three writable floats (the caller's contract); [f32; 3] has the
        // alignment of f32.
        unsafe { deliver(rgb.cast::<DisplayRgb>(), "rgb", color(&palette)) }
    })
}

/// Sets the colour of edge lines and silhouettes in every display mode that draws them
/// (edges, hidden-line, wireframe, X-ray; dashed hidden lines take a lighter shade of it):
/// three floats, display values in 0..1 (what a PNG stores; the default is near-black,
/// 0.06, 0.07, 0.09). The next frame draws with it.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_INVALID_ARGUMENT` (a
/// value outside 0..1 or not finite; the colour is kept) or a handle error. Ownership: `rgb`
/// is read during the call only. Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `rgb` is null or points to three readable floats.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_set_edge_color(
    renderer: CadrRenderer,
    rgb: *const f32,
) -> CadrResult {
    // SAFETY: null or three readable floats (the caller's contract).
    unsafe { set_color(renderer, rgb, |palette| &mut palette.edges) }
}

/// Writes the colour of edge lines (three floats; see `cadr_renderer_set_edge_color`).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error. Ownership: the
/// array is the caller's; cadr keeps no pointer to it. Thread-safety: as
/// `cadr_renderer_create`.
///
/// # Safety
/// `rgb` is null or points to three writable floats.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_edge_color(
    renderer: CadrRenderer,
    rgb: *mut f32,
) -> CadrResult {
    // SAFETY: null or three writable floats (the caller's contract).
    unsafe { deliver_color(renderer, rgb, |palette| palette.edges) }
}

/// Sets the highlight colour: what highlighted parts are tinted towards
/// (`CADR_HIGHLIGHT_TINT`) or outlined in (`CADR_HIGHLIGHT_OUTLINE`), and the colour of their
/// edge lines (a darker shade): three floats, display values in 0..1 (the default is orange,
/// 1.0, 0.55, 0.05). The next frame draws with it.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_INVALID_ARGUMENT` (a
/// value outside 0..1 or not finite; the colour is kept) or a handle error. Ownership: `rgb`
/// is read during the call only. Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `rgb` is null or points to three readable floats.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_set_highlight_color(
    renderer: CadrRenderer,
    rgb: *const f32,
) -> CadrResult {
    // SAFETY: null or three readable floats (the caller's contract).
    unsafe { set_color(renderer, rgb, |palette| &mut palette.highlight) }
}

/// Writes the highlight colour (three floats; see `cadr_renderer_set_highlight_color`).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error. Ownership: the
/// array is the caller's; cadr keeps no pointer to it. Thread-safety: as
/// `cadr_renderer_create`.
///
/// # Safety
/// `rgb` is null or points to three writable floats.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_highlight_color(
    renderer: CadrRenderer,
    rgb: *mut f32,
) -> CadrResult {
    // SAFETY: null or three writable floats (the caller's contract).
    unsafe { deliver_color(renderer, rgb, |palette| palette.highlight) }
}

/// Sets the width in pixels, 1 to 8 (default 2), of the band the `CADR_HIGHLIGHT_OUTLINE`
/// style draws around highlighted parts. The next frame draws with it.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_INVALID_ARGUMENT` (outside 1 to 8; the width is
/// kept) or a handle error. Ownership: nothing changes hands. Thread-safety: as
/// `cadr_renderer_create`.
#[no_mangle]
pub extern "C" fn cadr_renderer_set_outline_width(
    renderer: CadrRenderer,
    pixels: u32,
) -> CadrResult {
    change_palette(renderer, |palette| {
        palette.outline_width = pixels;
        Ok(())
    })
}

/// Writes the outline band's width in pixels (see `cadr_renderer_set_outline_width`).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error. Ownership: the
/// output is the caller's; cadr keeps no pointer to it. Thread-safety: as
/// `cadr_renderer_create`.
///
/// # Safety
/// `pixels` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_outline_width(
    renderer: CadrRenderer,
    pixels: *mut u32,
) -> CadrResult {
    guard(|| {
        let palette = with_renderer(renderer, |state| Ok(state.view.renderer().palette()))?;
        // SAFETY: pixels is null or writable (the caller's contract).
        unsafe { deliver(pixels, "pixels", palette.outline_width) }
    })
}
