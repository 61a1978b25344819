//! The host side of GPU culling (plugin ABI 1.3): a culler whose vtable has `record_gpu`
//! records compute work into the frame that writes each pass's indirect commands and count;
//! the submission draws from them. The CPU does no per-instance work: a moving camera costs
//! what a still one does.

use std::ffi::c_void;

use crate::error::RenderResult;
use crate::vk::raw::{self as vk, Handle};
use cadr_plugin_abi as abi;

use crate::render::{split_f64, Camera, Section};
use crate::technique::{status, Active, Message, PassFilters, TechniqueKind, Techniques};

/// The active GPU culler of a frame and the draw sources it wrote for the current phase.
pub(crate) struct GpuCuller<'a> {
    active: &'a Active,
    record_gpu: unsafe extern "C" fn(
        *mut c_void,
        *const abi::CadrGpuCullContext,
        *mut abi::CadrMessage,
    ) -> abi::CadrStatus,
    /// Phases of the frame (at least 1).
    pub(crate) phases: u32,
    /// Per pass, where this phase's commands lie (zeroed before each phase).
    pub(crate) draws: Vec<abi::CadrGpuDraws>,
    /// The level-of-detail threshold in pixels, for cluster cullers.
    lod_error: f32,
    /// Whether the submission draws the commands by their capacity, so that what lies past the
    /// counts must draw nothing (plugin ABI 1.24, `CadrEmptyCommandTails`).
    empty_command_tails: bool,
}

/// Bytes of a [`abi::CadrGpuCullView`] as shaders read it (std140: it has no padding).
pub(crate) const CULL_VIEW_BYTES: usize = std::mem::size_of::<abi::CadrGpuCullView>();

/// What a GPU culler needs of the view, relative to the eye: the camera's frustum planes and
/// projection for points given relative to the eye (the plane `n·p + d` becomes
/// `n·q + (d + n·eye)` for `q = p - eye`, computed in f64), the target size, and the
/// sub-pixel threshold (parts projecting under `min_pixels` across are culled).
pub(crate) fn cull_view(
    camera: &Camera,
    (width, height): (u32, u32),
    min_pixels: f32,
    section: &Section,
) -> abi::CadrGpuCullView {
    let eye = camera.eye();
    let (high, low) = split_f64(eye);
    let planes = camera.frustum_planes().map(|[x, y, z, d]| {
        let shifted = d + x * eye.x + y * eye.y + z * eye.z;
        [x as f32, y as f32, z as f32, shifted as f32]
    });
    let mut rotation = camera.view;
    rotation.w_axis = glam::DVec4::W;
    let view_projection = camera.projection * rotation;
    // Pixels per unit of size at clip w = 1: the x and y rows' scales over half the target.
    let scale = |row: usize, pixels: u32| {
        view_projection.row(row).truncate().length() * f64::from(pixels) * 0.5
    };
    let pixels_per_unit = scale(0, width).max(scale(1, height)) as f32;
    abi::CadrGpuCullView {
        eye_high: [high[0], high[1], high[2], 0.0],
        eye_low: [low[0], low[1], low[2], 0.0],
        planes,
        view_projection: view_projection.as_mat4().to_cols_array(),
        target: [width, height, 0, 0],
        sub_pixel: [min_pixels, pixels_per_unit, 0.0, 0.0],
        section_planes: section.eye_relative(eye),
        section: [section.planes().len() as u32, 0, 0, 0],
    }
}

/// The view's bytes as the culler's shaders read them (std140, little-endian), without
/// allocating: the host writes them every frame.
pub(crate) fn cull_view_bytes(view: &abi::CadrGpuCullView) -> [u8; CULL_VIEW_BYTES] {
    let floats = view
        .eye_high
        .iter()
        .chain(&view.eye_low)
        .chain(view.planes.iter().flatten())
        .chain(&view.view_projection);
    let words = floats
        .map(|f| f.to_bits())
        .chain(view.target)
        .chain(view.sub_pixel.iter().map(|f| f.to_bits()))
        .chain(view.section_planes.iter().flatten().map(|f| f.to_bits()))
        .chain(view.section);
    let mut bytes = [0u8; CULL_VIEW_BYTES];
    for (chunk, word) in bytes.chunks_exact_mut(4).zip(words) {
        chunk.copy_from_slice(&word.to_le_bytes());
    }
    bytes
}

/// The frame's depth as a later phase reads it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PhaseDepth {
    pub(crate) image: vk::Image,
    pub(crate) view: vk::ImageView,
    pub(crate) layout: vk::ImageLayout,
}

impl<'a> GpuCuller<'a> {
    /// The active culler if it culls on the GPU (a library of ABI 1.3 or later with
    /// `record_gpu`), with room for `pass_count` draw sources.
    pub(crate) fn of(techniques: &'a Techniques, pass_count: usize) -> RenderResult<Option<Self>> {
        let active = techniques.get(TechniqueKind::Culling)?;
        let vtable = active.vtable::<abi::CadrCullingVtable>();
        let Some(record_gpu) = vtable.record_gpu else {
            return Ok(None);
        };
        // SAFETY: a live instance of this vtable.
        let phases = vtable
            .phase_count
            .map_or(1, |count| unsafe { count(active.instance) })
            .max(1);
        Ok(Some(Self {
            active,
            record_gpu,
            phases,
            draws: vec![abi::CadrGpuDraws::default(); pass_count],
            lod_error: techniques.lod_error(),
            empty_command_tails: techniques.empty_command_tails(),
        }))
    }

    /// Whether the active culler culls on the GPU.
    /// Records `phase` of the culling into `command_buffer` (outside rendering), for `passes`
    /// with their filters (one each).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn record(
        &mut self,
        phase: u32,
        command_buffer: vk::CommandBuffer,
        scene: &abi::CadrSceneView,
        (passes, filters): (&[abi::CadrPass], &PassFilters),
        gpu_view: &abi::CadrGpuCullView,
        (view_buffer, view_offset): (vk::Buffer, u64),
        depth: Option<PhaseDepth>,
    ) -> RenderResult<()> {
        self.draws.fill(abi::CadrGpuDraws::default());
        debug_assert_eq!(passes.len(), filters.filters.len());
        debug_assert_eq!(passes.len(), filters.exclusions.len());
        debug_assert_eq!(passes.len(), filters.back_faces_hidden.len());
        debug_assert_eq!(passes.len(), filters.face_routes.len());
        // Where the submission picks the pipeline per command, the split's passes share a
        // stream.
        let shared_streams = abi::CadrSharedFaceStreams {
            header: abi::CadrExtension {
                size: std::mem::size_of::<abi::CadrSharedFaceStreams>() as u32,
                kind: abi::CADR_EXTENSION_SHARED_FACE_STREAMS,
                next: std::ptr::null(),
            },
        };
        let back_face_passes = abi::CadrBackFacePasses {
            header: abi::CadrExtension {
                size: std::mem::size_of::<abi::CadrBackFacePasses>() as u32,
                kind: abi::CADR_EXTENSION_BACK_FACE_PASSES,
                next: if filters.shared_face_stream {
                    &shared_streams.header
                } else {
                    std::ptr::null()
                },
            },
            pass_count: passes.len() as u32,
            routes: filters.face_routes.as_ptr(),
        };
        let clusters = abi::CadrClusterCull {
            header: abi::CadrExtension {
                size: std::mem::size_of::<abi::CadrClusterCull>() as u32,
                kind: abi::CADR_EXTENSION_CLUSTER_CULL,
                // Only where the passes are split: pass set planning asked the culler first.
                next: if filters.routes_faces() {
                    &back_face_passes.header
                } else {
                    std::ptr::null()
                },
            },
            lod_error: self.lod_error,
            pass_count: passes.len() as u32,
            back_faces_hidden: filters.back_faces_hidden.as_ptr(),
        };
        let empty_tails = abi::CadrEmptyCommandTails {
            header: abi::CadrExtension {
                size: std::mem::size_of::<abi::CadrEmptyCommandTails>() as u32,
                kind: abi::CADR_EXTENSION_EMPTY_COMMAND_TAILS,
                next: &clusters.header,
            },
        };
        let context = abi::CadrGpuCullContext {
            size: std::mem::size_of::<abi::CadrGpuCullContext>() as u32,
            phase,
            command_buffer: command_buffer.as_raw() as *mut c_void,
            scene,
            pass_count: passes.len() as u32,
            passes: passes.as_ptr(),
            draws: self.draws.as_mut_ptr(),
            eye_high: gpu_view.eye_high,
            eye_low: gpu_view.eye_low,
            planes: gpu_view.planes,
            view_projection: gpu_view.view_projection,
            width: gpu_view.target[0],
            height: gpu_view.target[1],
            depth_image: depth.map_or(0, |d| d.image.as_raw()),
            depth_view: depth.map_or(0, |d| d.view.as_raw()),
            depth_layout: depth.map_or(0, |d| d.layout.as_raw()),
            min_pixels: gpu_view.sub_pixel[0],
            view_buffer: view_buffer.as_raw(),
            view_offset,
            pass_filters: filters.filters.as_ptr(),
            section_plane_count: gpu_view.section[0],
            section_planes: gpu_view.section_planes,
            pass_exclusions: filters.exclusions.as_ptr(),
            extensions: if self.empty_command_tails {
                &empty_tails.header
            } else {
                &clusters.header
            },
        };
        let mut message = Message::new();
        // SAFETY: a live instance; the context and the arrays it points at are valid for the
        // call, `draws` holds `pass_count` writable entries.
        let result = unsafe { (self.record_gpu)(self.active.instance, &context, message.raw()) };
        status(&self.active.entry, "record_gpu", result, &message)
    }

    /// What the GPU drew in the last finished frame (draws and triangles).
    pub(crate) fn counts(&self) -> abi::CadrStats {
        let mut stats = abi::CadrStats::default();
        if let Some(counts) = self.active.vtable::<abi::CadrCullingVtable>().gpu_counts {
            // SAFETY: a live instance; `stats` is writable for the call.
            unsafe { counts(self.active.instance, &mut stats) };
        }
        stats
    }
}
