//! The background a renderer draws its pictures over: a vertical gradient from a top colour
//! to a bottom one (one colour when they agree).

use cadr_core::render::Background;

use crate::args::{deliver, non_null, slice};
use crate::error::{guard, CadrResult};
use crate::renderer::{with_renderer, CadrRenderer};

/// Sets the background: `top_rgb` at the picture's top row blending to `bottom_rgb` at its
/// bottom row, three floats each, as display values in 0..1 (what a PNG stores; the default
/// is a light grey-blue gradient). Pass the same colour twice for a flat background. The
/// next frame draws it, in every display mode, under translucent parts too.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_INVALID_ARGUMENT` (a
/// value outside 0..1 or not finite) or a handle error. Ownership: both arrays are read during
/// the call only. Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `top_rgb` and `bottom_rgb` are null or point to three readable floats each.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_set_background(
    renderer: CadrRenderer,
    top_rgb: *const f32,
    bottom_rgb: *const f32,
) -> CadrResult {
    guard(|| {
        // SAFETY: each is null or holds three floats (the caller's contract).
        let top = unsafe { slice(top_rgb, 3, "top_rgb") }?;
        // SAFETY: as above.
        let bottom = unsafe { slice(bottom_rgb, 3, "bottom_rgb") }?;
        let background = Background {
            top: [top[0], top[1], top[2]],
            bottom: [bottom[0], bottom[1], bottom[2]],
        };
        with_renderer(renderer, |state| {
            Ok(state.view.renderer_mut().set_background(background)?)
        })
    })
}

/// Writes the background's top and bottom colours (three floats each, display values in
/// 0..1; see `cadr_renderer_set_background`).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error. Ownership: the
/// arrays are the caller's; cadr keeps no pointer to them. Thread-safety: as
/// `cadr_renderer_create`.
///
/// # Safety
/// `top_rgb` and `bottom_rgb` are null or point to three writable floats each.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_background(
    renderer: CadrRenderer,
    top_rgb: *mut f32,
    bottom_rgb: *mut f32,
) -> CadrResult {
    guard(|| {
        non_null(top_rgb, "top_rgb")?;
        non_null(bottom_rgb, "bottom_rgb")?;
        let background = with_renderer(renderer, |state| Ok(state.view.renderer().background()))?;
        // SAFETY: both are non-null and hold three writable floats (the caller's contract);
        // [f32; 3] has the alignment of f32.
        unsafe {
            deliver(top_rgb.cast::<[f32; 3]>(), "top_rgb", background.top)?;
            deliver(
                bottom_rgb.cast::<[f32; 3]>(),
                "bottom_rgb",
                background.bottom,
            )
        }
    })
}
