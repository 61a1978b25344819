//! Where cadr's time went in this process: the phases of start-up and of first pictures
//! (`cadr render --timings` reports the same figures).

use cadr_core::timings::{self, Phase};

use crate::args::deliver_sized;
use crate::error::{guard, CadrResult};

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
