//! Where cadr's time went in this process: the phases of start-up and of first pictures, and a
//! renderer's last frame pass by pass on the GPU (`cadr render --timings` reports the same
//! figures).

use std::ffi::{c_char, CStr, CString};
use std::sync::{Mutex, OnceLock};

use cadr_core::timings::{self, Phase};

use crate::args::{deliver, deliver_sized};
use crate::error::{guard, CadrResult, Failure};
use crate::renderer::{with_renderer, CadrRenderer};

/// Milliseconds cadr spent in each phase of its work in this process, since it was loaded or
/// since `cadr_timings_reset`, over every context, scene and renderer. A phase that runs
/// inside another (pipelines built during a first frame) counts only for itself.
///
/// The struct grows by appending fields: the host sets `size` to `sizeof(CadrTimings)`; cadr
/// fills the fields within it and zeroes those of a newer header it does not know.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CadrTimings {
    /// `sizeof(CadrTimings)`, set by the host.
    pub size: u32,
    /// Vulkan instance and device creation (`cadr_context_create`).
    pub device_ms: f64,
    /// Reading and parsing scene files, or generating scenes (`cadr_scene_load`).
    pub load_ms: f64,
    /// Building scene graphs and trees from loaded scenes.
    pub scene_build_ms: f64,
    /// Uploading scenes to the GPU and bringing them up to date.
    pub upload_ms: f64,
    /// Compiling shaders, or reading them from the disk cache.
    pub shader_compile_ms: f64,
    /// Creating pipelines.
    pub pipeline_creation_ms: f64,
    /// Each renderer's first frame, less the shaders and pipelines it built.
    pub first_frame_ms: f64,
    /// Reading pictures back (`cadr_renderer_read_pixels`, `cadr_renderer_save_png`).
    pub readback_ms: f64,
    /// Encoding and writing PNG files.
    pub png_encode_ms: f64,
}

impl CadrTimings {
    fn now() -> Self {
        let spent = timings::snapshot();
        Self {
            size: std::mem::size_of::<Self>() as u32,
            device_ms: spent.ms(Phase::Device),
            load_ms: spent.ms(Phase::Load),
            scene_build_ms: spent.ms(Phase::SceneBuild),
            upload_ms: spent.ms(Phase::Upload),
            shader_compile_ms: spent.ms(Phase::ShaderCompile),
            pipeline_creation_ms: spent.ms(Phase::PipelineCreation),
            first_frame_ms: spent.ms(Phase::FirstFrame),
            readback_ms: spent.ms(Phase::Readback),
            png_encode_ms: spent.ms(Phase::PngEncode),
        }
    }
}

/// Writes the time cadr spent in each phase so far (see `CadrTimings`).
///
/// Returns `CADR_RESULT_OK` or `CADR_RESULT_NULL_ARGUMENT`.
/// Ownership: the output is the caller's; cadr keeps no pointer to it.
/// Thread-safety: any thread, at any time; phases still running are not yet counted.
///
/// # Safety
/// `timings` is null or writable for its `size`.
#[no_mangle]
pub unsafe extern "C" fn cadr_timings(timings: *mut CadrTimings) -> CadrResult {
    guard(|| {
        let value = CadrTimings::now();
        // SAFETY: timings is null or writable for its size (the caller's contract).
        unsafe { deliver_sized(timings, "timings", value) }
    })
}

/// Sets every phase's total to zero, for a host that measures one stretch of its run.
///
/// Ownership: nothing changes hands. Thread-safety: any thread; work running meanwhile may be
/// counted on either side of the reset.
#[no_mangle]
pub extern "C" fn cadr_timings_reset() {
    timings::reset();
}

/// The GPU time of one pass of a frame (`cadr_renderer_gpu_pass_times`).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrGpuPassTime {
    /// The pass's name, NUL-terminated: "uploads", "prepare and cull" (the techniques'
    /// preparation with a GPU culler's first phase), "surfaces phase N", "cull phase N", each
    /// pass over the picture by its name ("background", "silhouettes", "ambient occlusion",
    /// ...), "pick surfaces", "pick readback", "depth to host", and "techniques after the
    /// passes". Ownership: cadr's, valid until the process ends; do not free.
    pub name: *const c_char,
    /// Its GPU time in microseconds.
    pub us: f64,
}

/// The NUL-terminated copy of a pass name, made once per name and kept for the process (the
/// names are a small fixed set).
fn pass_name(name: &'static str) -> Result<*const c_char, Failure> {
    static NAMES: OnceLock<Mutex<Vec<(&'static str, &'static CStr)>>> = OnceLock::new();
    let mut names = NAMES
        .get_or_init(|| Mutex::new(Vec::new()))
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    if let Some((_, text)) = names.iter().find(|(known, _)| *known == name) {
        return Ok(text.as_ptr());
    }
    let text: &'static CStr = Box::leak(
        CString::new(name)
            .map_err(|_| Failure::invalid(format!("pass name {name:?} holds a NUL")))?
            .into_boxed_c_str(),
    );
    names.push((name, text));
    Ok(text.as_ptr())
}

/// Writes the GPU time of each pass of the frame whose time the renderer's last
/// `CadrFrameStats::gpu_us` reported (its last frame, rendered or replayed, with one frame in
/// flight; the latest finished one with more) into `times`, in the order drawn, and their
/// number into `*count`. Together they make that `gpu_us`. None (`*count` 0) while no frame's
/// time is known, or where the device's queue has no timestamps.
///
/// Returns `CADR_RESULT_OK` (with no passes, whatever `times` and `capacity`);
/// `CADR_RESULT_BUFFER_TOO_SMALL` with `times` NULL or `capacity` under the number of passes,
/// having written only that number into `*count` (call again with room for it); `CADR_RESULT_NULL_ARGUMENT` with `count` NULL; or a handle error.
/// Ownership: the entries are the caller's; their names are cadr's (see
/// `CadrGpuPassTime::name`). Thread-safety: as `cadr_renderer_render`; it waits for no frame
/// (the times were read when that frame's were).
///
/// # Safety
/// `times` is null or writable for `capacity` entries; `count` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_renderer_gpu_pass_times(
    renderer: CadrRenderer,
    times: *mut CadrGpuPassTime,
    capacity: usize,
    count: *mut usize,
) -> CadrResult {
    guard(|| {
        crate::args::non_null(count, "count")?;
        let passes = with_renderer(renderer, |state| {
            Ok(state.view.renderer().gpu_pass_times().to_vec())
        })?;
        // SAFETY: count is non-null and writable (the caller's contract).
        unsafe { deliver(count, "count", passes.len()) }?;
        if !passes.is_empty() && (times.is_null() || capacity < passes.len()) {
            return Err(Failure::new(
                CadrResult::BufferTooSmall,
                format!(
                    "the last frame has {} passes, the buffer holds {capacity}",
                    passes.len()
                ),
            ));
        }
        for (index, (name, us)) in passes.into_iter().enumerate() {
            let entry = CadrGpuPassTime {
                name: pass_name(name)?,
                us,
            };
            // SAFETY: times is writable for capacity >= passes.len() entries (the caller's
            // contract).
            unsafe { times.add(index).write(entry) };
        }
        Ok(())
    })
}
