//! Section planes of a renderer: planes in world space (double precision) that cut the scene
//! away in every pass, picking included, and the caps that fill cuts through closed parts.

use cadr_core::render::{Section, MAX_SECTION_PLANES};
use glam::DVec4;

use crate::args::{deliver, non_null, slice};
use crate::error::{guard, CadrResult, Failure};
use crate::renderer::{with_renderer, CadrRenderer};

/// The most section planes a renderer takes at once.
pub const CADR_MAX_SECTION_PLANES: u32 = 6;
const _: () = assert!(CADR_MAX_SECTION_PLANES as usize == MAX_SECTION_PLANES);
/// Section flag: fill the cut of closed parts with the plane's cap colour (on by default).
pub const CADR_SECTION_CAPS: u32 = 1;
/// Section flag: hatch the caps (off by default).
pub const CADR_SECTION_HATCHED: u32 = 2;

fn with_section(
    renderer: CadrRenderer,
    change: impl FnOnce(&mut Section) -> Result<(), Failure>,
) -> Result<(), Failure> {
    with_renderer(renderer, |state| {
        let mut section = state.view.section().clone();
        change(&mut section)?;
        state.view.set_section(section);
        Ok(())
    })
}

/// Sets the renderer's section planes: `count` planes of four doubles each, `(nx, ny, nz, d)`,
/// each keeping the half-space `nx·x + ny·y + nz·z + d >= 0` of world space (the normal need not
/// be of unit length). 0 planes (`planes` may then be NULL) cuts nothing. The next frame and
/// pick apply them; what they cut away is neither drawn nor picked.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_INVALID_ARGUMENT` (more
/// than `CADR_MAX_SECTION_PLANES`, a zero normal or a value that is not finite; the message
/// names the plane, and the planes stay as they were) or a handle error. Ownership: `planes`
/// is read during the call only. Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `planes` is null or points to `4 * count` readable doubles.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_set_section_planes(
    renderer: CadrRenderer,
    planes: *const f64,
    count: u32,
) -> CadrResult {
    guard(|| {
        if count > CADR_MAX_SECTION_PLANES {
            return Err(Failure::invalid(format!(
                "{count} section planes given; at most {CADR_MAX_SECTION_PLANES}"
            )));
        }
        // SAFETY: `planes` is null or holds 4 * count doubles (the caller's contract).
        let values = unsafe { slice(planes, 4 * count as usize, "planes") }?;
        let planes: Vec<DVec4> = values.chunks_exact(4).map(DVec4::from_slice).collect();
        with_section(renderer, |section| {
            section.set_planes(&planes).map_err(Failure::invalid)
        })
    })
}

/// Writes the number of section planes into `*count` and, when `planes` is not NULL, up to
/// `capacity` of them (four doubles each, normals of unit length) into `planes`.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` (`count` NULL) or a handle error.
/// Ownership: the outputs are the caller's. Thread-safety: as `cadr_renderer_create`.
///
/// # Safety
/// `planes` is null or writable for `4 * capacity` doubles; `count` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_section_planes(
    renderer: CadrRenderer,
    planes: *mut f64,
    capacity: u32,
    count: *mut u32,
) -> CadrResult {
    guard(|| {
        non_null(count, "count")?;
        let current = with_renderer(renderer, |state| Ok(state.view.section().planes().to_vec()))?;
        if !planes.is_null() {
            for (i, plane) in current.iter().take(capacity as usize).enumerate() {
                // SAFETY: planes holds 4 * capacity doubles and i < capacity.
                unsafe {
                    std::ptr::copy_nonoverlapping(plane.to_array().as_ptr(), planes.add(4 * i), 4)
                };
            }
        }
        // SAFETY: count is non-null and writable (the caller's contract).
        unsafe { deliver(count, "count", current.len() as u32) }
    })
}
