//! How a renderer's frames reach the GPU and the window: frames in flight and the present
//! mode.

use cadr_core::vk::PresentMode;

use crate::args::deliver;
use crate::error::{guard, CadrResult, Failure};
use crate::renderer::{with_renderer, CadrRenderer};

/// Frames paced to the display, never torn; every window offers it (the default).
pub const CADR_PRESENT_FIFO: u32 = 0;
/// The newest frame replaces one waiting to be shown: not torn, not paced.
pub const CADR_PRESENT_MAILBOX: u32 = 1;
/// Frames shown as soon as they are drawn, possibly torn.
pub const CADR_PRESENT_IMMEDIATE: u32 = 2;

fn present_mode(code: u32) -> Result<PresentMode, Failure> {
    match code {
        CADR_PRESENT_FIFO => Ok(PresentMode::Fifo),
        CADR_PRESENT_MAILBOX => Ok(PresentMode::Mailbox),
        CADR_PRESENT_IMMEDIATE => Ok(PresentMode::Immediate),
        other => Err(Failure::invalid(format!(
            "present mode {other} is not 0 (fifo), 1 (mailbox) or 2 (immediate)"
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

/// Sets how many frames the GPU may have: 1 waits for each frame before
/// `cadr_renderer_render` returns (its GPU time is then that frame's). 2 or 3 return once the
/// frame is submitted, so the host's work and the next frames' scene updates overlap the GPU's
/// drawing; its pixels or a pick wait for it when read. Each frame in flight has its own
/// command buffers and uniforms: a frame waits only for the one that used its slot before
/// when nothing but the camera changed since the last frame and every active technique keeps
/// its per-frame data per slot (cadr's own do, but the `-threads` submissions); otherwise it
/// waits for every earlier frame. The statistics' GPU time is then that of the latest frame
/// known to have finished. Window renderers start with 2, offscreen ones with 1.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_INVALID_ARGUMENT` (not 1 to 3), `CADR_RESULT_VULKAN`
/// or a handle error. Ownership: nothing changes hands. Thread-safety: as
/// `cadr_renderer_create`.
#[no_mangle]
pub extern "C" fn cadr_renderer_set_frames_in_flight(
    renderer: CadrRenderer,
    frames: u32,
) -> CadrResult {
    guard(|| {
        with_renderer(renderer, |state| {
            // An out-of-range count is the renderer's invalid use (CADR_RESULT_INVALID_ARGUMENT);
            // waiting for a frame may fail as Vulkan does.
            Ok(state.view.renderer_mut().set_frames_in_flight(frames)?)
        })
    })
}

/// Writes how many frames the GPU may have (see `cadr_renderer_set_frames_in_flight`).
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or a handle error.
/// Ownership: the output is the caller's; cadr keeps no pointer to it.
/// Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `frames` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_frames_in_flight(
    renderer: CadrRenderer,
    frames: *mut u32,
) -> CadrResult {
    guard(|| {
        let value = with_renderer(renderer, |state| {
            Ok(state.view.renderer().frames_in_flight())
        })?;
        // SAFETY: frames is null or writable (the caller's contract).
        unsafe { deliver(frames, "frames", value) }
    })
}

/// Sets how a window renderer's frames reach its window: `CADR_PRESENT_FIFO` (the default),
/// `CADR_PRESENT_MAILBOX` or `CADR_PRESENT_IMMEDIATE`. The swapchain is recreated; a mode the
/// window's surface does not offer is refused, naming those it does.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_INVALID_ARGUMENT` (unknown mode),
/// `CADR_RESULT_UNSUPPORTED` (not offered, or an offscreen renderer), `CADR_RESULT_VULKAN` or a
/// handle error. Ownership: nothing changes hands. Thread-safety: as `cadr_renderer_create`.
#[no_mangle]
pub extern "C" fn cadr_renderer_set_present_mode(renderer: CadrRenderer, mode: u32) -> CadrResult {
    guard(|| {
        let mode = present_mode(mode)?;
        with_renderer(renderer, |state| match &mut state.swapchain {
            Some(swapchain) => Ok(swapchain.set_present_mode(mode)?),
            None => Err(Failure::new(
                CadrResult::Unsupported,
                "an offscreen renderer presents nothing: present modes are for window renderers"
                    .into(),
            )),
        })
    })
}

/// Writes a window renderer's present mode (`*mode`) and the modes its surface offers
/// (`*offered`: bit `1 << CADR_PRESENT_*` set for each). Either output may be NULL.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_UNSUPPORTED` (an offscreen renderer),
/// `CADR_RESULT_VULKAN` or a handle error.
/// Ownership: the outputs are the caller's; cadr keeps no pointer to them.
/// Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `mode` and `offered` are each null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_present_mode(
    renderer: CadrRenderer,
    mode: *mut u32,
    offered: *mut u32,
) -> CadrResult {
    guard(|| {
        let (current, mask) = with_renderer(renderer, |state| match &state.swapchain {
            Some(swapchain) => {
                let mask = swapchain
                    .present_modes()?
                    .into_iter()
                    .fold(0u32, |mask, m| mask | 1 << present_code(m));
                Ok((present_code(swapchain.present_mode()), mask))
            }
            None => Err(Failure::new(
                CadrResult::Unsupported,
                "an offscreen renderer presents nothing: it has no present mode".into(),
            )),
        })?;
        for (out, value) in [(mode, current), (offered, mask)] {
            if !out.is_null() {
                // SAFETY: non-null; writable by contract.
                unsafe { crate::args::write(out, value) };
            }
        }
        Ok(())
    })
}
