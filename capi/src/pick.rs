//! Picking: what lies under a pixel, or every pickable part with a visible pixel in a
//! rectangle, found by the pick pass of the renderer's current techniques.

use cadr_core::render::pick::PixelRect;
use cadr_core::view::PickHit;

use crate::args::{check_owning_size, deliver_sized, non_null, read_sized};
use crate::camera::CadrCamera;
use crate::error::{guard, CadrResult, Failure};
use crate::handles::lock;
use crate::renderer::{with_renderer, CadrRenderer};
use crate::scene::{node_value, CadrNode, CadrScene, SCENES};

/// The size of `CadrPickResult` in version 1.0: every later header's is at least this, and
/// holds its arrays.
const FIRST_SIZE: usize = 24;
const _: () = assert!(std::mem::size_of::<CadrPickResult>() >= FIRST_SIZE);

/// One picked occurrence of a part.
///
/// Frozen: hits lie in an array the host indexes with its own `sizeof(CadrPickHit)`, so this
/// struct never changes within a major version; facts a later version adds about each hit come
/// as arrays of their own in `CadrPickResult`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrPickHit {
    /// The geo node drawn.
    pub node: CadrNode,
    /// The part of its geometry.
    pub part: u32,
    /// The pixel's column (for a rectangle: the part's nearest pixel in it).
    pub x: u32,
    /// The pixel's row.
    pub y: u32,
    /// Depth at the pixel: 0 at the near plane, 1 at the far plane.
    pub depth: f32,
    /// The surface point under the pixel's centre, in world space (double precision). On a
    /// section cap, the point where the plane cuts the part (and `depth` is its depth).
    pub position: [f64; 3],
    /// The occurrence: the nodes from the scene's root to `node` (a shared subgraph is drawn
    /// once per path; this says which). Owned by the result.
    pub path: *const CadrNode,
    /// Number of nodes in `path`.
    pub path_length: usize,
}

/// What a pick found: hits nearest first (none where only background or parts that cannot be
/// picked are). Filled by `cadr_renderer_pick` or `cadr_renderer_pick_rect`, released by
/// `cadr_pick_result_free`.
///
/// The struct grows by appending fields: the host sets `size` to `sizeof(CadrPickResult)`;
/// cadr fills the fields within it and zeroes those of a newer header it does not know.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrPickResult {
    /// `sizeof(CadrPickResult)`, set by the host.
    pub size: u32,
    /// The hits, nearest first.
    pub hits: *mut CadrPickHit,
    /// Number of `hits`.
    pub hit_count: usize,
}

fn result_of(hits: Vec<PickHit>) -> CadrPickResult {
    if hits.is_empty() {
        return CadrPickResult {
            size: std::mem::size_of::<CadrPickResult>() as u32,
            hits: std::ptr::null_mut(),
            hit_count: 0,
        };
    }
    let hits: Box<[CadrPickHit]> = hits
        .into_iter()
        .map(|hit| {
            let path: Box<[CadrNode]> = hit.path.iter().map(|&n| node_value(n)).collect();
            let path_length = path.len();
            CadrPickHit {
                node: node_value(hit.node),
                part: hit.part,
                x: hit.pixel.0,
                y: hit.pixel.1,
                depth: hit.depth,
                position: hit.position.to_array(),
                path: Box::into_raw(path).cast::<CadrNode>().cast_const(),
                path_length,
            }
        })
        .collect();
    let hit_count = hits.len();
    CadrPickResult {
        size: std::mem::size_of::<CadrPickResult>() as u32,
        hits: Box::into_raw(hits).cast::<CadrPickHit>(),
        hit_count,
    }
}

/// Picks `rect` of `scene` seen by `camera` and delivers the result.
///
/// # Safety
/// `camera` is null or readable; `result` is null or writable for its `size`.
unsafe fn pick(
    renderer: CadrRenderer,
    scene: CadrScene,
    camera: *const CadrCamera,
    rect: PixelRect,
    result: *mut CadrPickResult,
) -> Result<(), Failure> {
    non_null(camera, "camera")?;
    // SAFETY: null or writable for its size (the caller's contract).
    unsafe { check_owning_size(result, ("result", "CadrPickResult"), FIRST_SIZE) }?;
    // SAFETY: non-null and readable by contract.
    let camera = unsafe { *camera }.to_core()?;
    let scene_object = SCENES.get(scene as u64, "scene")?;
    let hits = with_renderer(renderer, |state| {
        let (width, height) = state.view.renderer().size();
        if u64::from(rect.x) + u64::from(rect.width) > u64::from(width)
            || u64::from(rect.y) + u64::from(rect.height) > u64::from(height)
            || rect.width == 0
            || rect.height == 0
        {
            return Err(Failure::invalid(format!(
                "pixels {rect} are not inside the renderer's {width}x{height} image"
            )));
        }
        let mut scene_state = lock(&scene_object);
        scene_state.sync(&mut state.view)?;
        state
            .view
            .pick(&scene_state.tree, &camera, rect)
            .map_err(Failure::from)
    })?;
    // SAFETY: result is writable for its size, checked to hold the hits (the caller's
    // contract).
    unsafe { deliver_sized(result, "result", result_of(hits)) }
}

/// Picks what lies under pixel (`x`, `y`) of the renderer's image (column, row from the top
/// left) when drawing `scene` seen by `camera` with the current techniques: at most one hit,
/// with the geo node, part, occurrence path, depth and world position. Parts that are hidden
/// are not drawn; parts that are not pickable (`CADR_NODE_PICKABLE` cleared on a node of their
/// path) let the click through to what is behind them; so do translucent parts (material
/// opacity under 1) while the renderer's `pick_through_translucent` setting is on.
///
/// Returns `CADR_RESULT_OK` and writes `*result` (no hits over background),
/// `CADR_RESULT_NULL_ARGUMENT`, `CADR_RESULT_INVALID_ARGUMENT` (a pixel outside the image, a
/// camera that is not finite), `CADR_RESULT_VULKAN`, `CADR_RESULT_PLUGIN_FAILED` or a handle
/// error. Ownership: the result's arrays are cadr's until `cadr_pick_result_free`; the camera
/// is read during the call. Thread-safety: as `cadr_renderer_render` (the scene is locked
/// during the call).
///
/// # Safety
/// `camera` is null or readable; `result` is null or writable for its `size`.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_pick(
    renderer: CadrRenderer,
    scene: CadrScene,
    camera: *const CadrCamera,
    x: u32,
    y: u32,
    result: *mut CadrPickResult,
) -> CadrResult {
    // SAFETY: forwarded contract.
    guard(|| unsafe { pick(renderer, scene, camera, PixelRect::pixel(x, y), result) })
}

/// Box selection: every pickable part with a visible pixel in the `width` × `height`
/// rectangle whose top-left pixel is (`x`, `y`), one hit per occurrence and part (at its
/// nearest pixel), nearest first.
///
/// Returns as `cadr_renderer_pick` (`CADR_RESULT_INVALID_ARGUMENT` also for an empty
/// rectangle or one that leaves the image). Ownership and thread-safety: as
/// `cadr_renderer_pick`.
///
/// # Safety
/// As `cadr_renderer_pick`.
#[no_mangle]
#[allow(clippy::too_many_arguments)] // A C function: the rectangle is four plain integers.
pub unsafe extern "C" fn cadr_renderer_pick_rect(
    renderer: CadrRenderer,
    scene: CadrScene,
    camera: *const CadrCamera,
    x: u32,
    y: u32,
    width: u32,
    height: u32,
    result: *mut CadrPickResult,
) -> CadrResult {
    let rect = PixelRect {
        x,
        y,
        width,
        height,
    };
    // SAFETY: forwarded contract.
    guard(|| unsafe { pick(renderer, scene, camera, rect, result) })
}

/// Frees the arrays of a pick result and zeroes it. NULL, or a zeroed result, is a no-op.
///
/// Ownership: takes back what `cadr_renderer_pick` or `cadr_renderer_pick_rect` handed out;
/// free each result once. Thread-safety: callable from any thread.
///
/// # Safety
/// `result` is null or a result filled by a pick (or zeroed).
#[no_mangle]
pub unsafe extern "C" fn cadr_pick_result_free(result: *mut CadrPickResult) {
    if result.is_null() {
        return;
    }
    // SAFETY: non-null, readable for its size and filled by a pick or zeroed (the caller's
    // contract); zero bytes are a CadrPickResult (no hits).
    let Ok(taken) =
        (unsafe { read_sized(result, ("result", "CadrPickResult"), std::mem::zeroed()) })
    else {
        log::error!(
            "cadr_pick_result_free: the result's size is not one a pick filled; nothing freed"
        );
        return;
    };
    if !taken.hits.is_null() {
        // SAFETY: made by Box::into_raw of a boxed slice of `hit_count` hits in `result_of`,
        // freed once (the result is zeroed below).
        let hits = unsafe {
            Box::from_raw(std::ptr::slice_from_raw_parts_mut(
                taken.hits,
                taken.hit_count,
            ))
        };
        for hit in hits.iter() {
            if !hit.path.is_null() {
                // SAFETY: made by Box::into_raw of a boxed slice of `path_length` nodes.
                drop(unsafe {
                    Box::from_raw(std::ptr::slice_from_raw_parts_mut(
                        hit.path.cast_mut(),
                        hit.path_length,
                    ))
                });
            }
        }
    }
    // SAFETY: non-null and writable for its size; zero bytes are a CadrPickResult.
    let _ = unsafe { deliver_sized(result, "result", std::mem::zeroed()) };
}
