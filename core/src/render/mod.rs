//! The pieces a frame is drawn with: the camera, section planes, background, palette and
//! highlight style a host sets; the frame uniforms, the frame set's layout and the full-screen
//! pipelines over the picture (`frame_pipelines.rs`); the transparency method's targets
//! (`transparency.rs`); the pick target and its readback (`pick.rs`); the pixel keys the
//! outline, silhouette and cap-tie passes read (`pixel_keys.rs`); and what a frame cost
//! (`stats.rs`). [`crate::frame`] puts them together into a frame.

mod background;
mod camera;
mod frame_pipelines;
mod highlight;
mod palette;
pub mod pick;
pub(crate) mod pixel_keys;
mod section;
mod stats;
pub(crate) mod transparency;

pub use background::Background;
pub use camera::{split_f64, Camera, DEFAULT_DIRECTION, DEFAULT_FOV_DEGREES};
pub use frame_pipelines::{
    FrameUniforms, OverlaySets, OverlayShader, Pipelines, DISPLAY_CAP_KEYS,
    DISPLAY_HIGHLIGHT_OUTLINE, DISPLAY_MATERIAL_DESCRIPTIONS, DISPLAY_NEAREST_SURFACES,
    DISPLAY_TEXTURES, DISPLAY_VERTEX_ATTRIBUTES, DISPLAY_XRAY, PICK_FORMAT, TEXTURE_TABLE_BINDING,
};
pub use highlight::HighlightStyle;
pub use palette::{DisplayRgb, Palette};
pub use section::{Section, DEFAULT_CAP_COLORS, MAX_SECTION_PLANES};
pub use stats::FrameStats;
pub use transparency::TransparencyMethod;
