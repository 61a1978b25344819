//! What one frame cost and drew.

/// What one frame cost and drew.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameStats {
    /// CPU time spent recording the command buffer, in microseconds.
    pub cpu_record_us: f64,
    /// CPU time of the queue submission, in microseconds.
    pub cpu_submit_us: f64,
    /// GPU time between the frame's first and last command, in microseconds (if timestamps work);
    /// with more than one frame in flight, the latest finished frame's (read without waiting;
    /// `None` for the first).
    pub gpu_us: Option<f64>,
    /// Draw calls issued (an indirect or multi-draw call counts once).
    pub draw_calls: u64,
    /// Parts or index ranges those calls drew.
    pub draws: u64,
    /// Triangles drawn: of the parts drawn, once each; with a GPU culler, what it let through
    /// in every surface pass.
    pub triangles: u64,
    /// Triangles the surface passes handed to the rasteriser, each pass counted (edge passes
    /// draw lines, not counted), the same way for every culler: what submissions recorded
    /// from their lists, or what a GPU culler let through.
    pub triangles_rasterized: u64,
    /// Pipeline binds.
    pub pipeline_binds: u64,
    /// Vertex/index buffer binds.
    pub vertex_binds: u64,
    /// Parameter updates (push constant writes, descriptor binds).
    pub parameter_updates: u64,
    /// Bytes uploaded to the GPU for this frame (matrices, materials).
    pub bytes_uploaded: u64,
    /// Whether the frame resubmitted the last recorded command buffer (nothing had changed
    /// but the camera, and the techniques allow it): recording cost nothing.
    pub replayed: bool,
    /// Whether the frame was recorded while earlier frames could still run on the GPU: more
    /// than one frame in flight, nothing but the view changed since the last frame, and every
    /// active technique keeps its per-frame data per frame slot. It waited only for the frame
    /// that last used its slot.
    pub overlapped: bool,
}

impl FrameStats {
    /// CPU time of recording and submission.
    pub fn cpu_us(&self) -> f64 {
        self.cpu_record_us + self.cpu_submit_us
    }
}
