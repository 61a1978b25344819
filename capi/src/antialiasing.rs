//! Anti-aliasing: how many samples per pixel a renderer's colour pass draws (MSAA).

use crate::args::write;
use crate::error::{guard, CadrResult};
use crate::renderer::{with_renderer, CadrRenderer};

/// Sets the samples per pixel of the renderer's colour pass: 1 (the default) draws one, 2, 4
/// or 8 smooth the edges of triangles and lines (MSAA), resolved into the picture at the end of
/// the pass, for offscreen and window renderers alike. Picking is unchanged: the pick pass
/// always draws one sample per pixel. The next frame draws with it; the renderer's targets and
/// pipelines are remade for the new count.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_INVALID_ARGUMENT` (a count the device does not offer:
/// the message lists those it does; `cadr_renderer_msaa` gives them as a mask),
/// `CADR_RESULT_PLUGIN_FAILED` at the next frame when the active submission records secondary
/// command buffers and was built before plugin ABI 1.8, `CADR_RESULT_VULKAN` or a handle error.
/// Ownership: nothing changes hands. Thread-safety: as `cadr_renderer_create`.
#[no_mangle]
pub extern "C" fn cadr_renderer_set_msaa(renderer: CadrRenderer, samples: u32) -> CadrResult {
    guard(|| {
        with_renderer(renderer, |state| {
            Ok(state.view.renderer_mut().set_msaa(samples)?)
        })
    })
}

/// Writes the samples per pixel the colour pass draws (`*samples`: 1 without MSAA) and the
/// counts this renderer's device offers (`*offered`: a mask with bit value N set for each
/// offered count N, as `VkSampleCountFlags`: 1 always, 0x5 for 1 and 4). Either output may be
/// NULL.
///
/// Returns `CADR_RESULT_OK` or a handle error. Ownership: the outputs are the caller's; cadr
/// keeps no pointer to them. Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `samples` and `offered` are each null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_msaa(
    renderer: CadrRenderer,
    samples: *mut u32,
    offered: *mut u32,
) -> CadrResult {
    guard(|| {
        let (current, mask) = with_renderer(renderer, |state| {
            let renderer = state.view.renderer();
            let mask = renderer
                .device()
                .sample_counts()
                .iter()
                .fold(0u32, |mask, count| mask | count);
            Ok((renderer.msaa(), mask))
        })?;
        for (out, value) in [(samples, current), (offered, mask)] {
            if !out.is_null() {
                // SAFETY: non-null; writable by contract.
                unsafe { write(out, value) };
            }
        }
        Ok(())
    })
}
