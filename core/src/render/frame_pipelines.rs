//! Pipelines and their layouts: the per-frame descriptor set shared by every technique and the
//! full-screen passes over the picture (which ones, and in what order, the frame's list of
//! passes says: `frame/passes.rs`).

use std::sync::{Arc, OnceLock};

use crate::error::RenderResult;
use crate::vk::raw as vk;

use crate::shaders::{self, ShaderSource};
use crate::vk::{
    Blend, Capabilities, DescriptorSetLayout, Device, LayoutBinding, Pipeline, PipelineLayout,
    Shared,
};

/// Format of the pick target: one instance id (+1) per pixel.
pub const PICK_FORMAT: vk::Format = vk::Format::R32_UINT;

/// Per-frame uniform data; mirrors `FrameUniforms` in `shaders/frame.glsl` (std140).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FrameUniforms {
    /// View to clip space.
    pub projection: [[f32; 4]; 4],
    /// World to view space without the translation (the eye at the origin).
    pub view_rotation: [[f32; 4]; 4],
    /// The eye's world position, f32 high part (xyz).
    pub eye_high: [f32; 4],
    /// The eye's world position, f32 remainder (xyz).
    pub eye_low: [f32; 4],
    /// Ambient, diffuse and specular strength of the head light.
    pub light: [f32; 4],
    /// Section planes relative to the eye (see [`super::Section`]).
    pub section_planes: [[f32; 4]; 6],
    /// Cap colour of each plane.
    pub section_colors: [[f32; 4]; 6],
    /// Plane count (bits 0-7), caps (bit 8), hatching (bit 9).
    pub section: [u32; 4],
    /// The target's width and height; display bits (`DISPLAY_XRAY`); zero.
    pub target: [u32; 4],
    /// The background's top colour (display RGB, alpha 1).
    pub background_top: [f32; 4],
    /// The background's bottom colour.
    pub background_bottom: [f32; 4],
    /// The edge lines' colour (display RGB, alpha 1; see [`super::Palette`]).
    pub edge_color: [f32; 4],
    /// The highlight colour (display RGB) and the outline band's width in pixels (w).
    pub highlight: [f32; 4],
}

/// [`FrameUniforms::target`]`[2]`: the X-ray display mode.
pub const DISPLAY_XRAY: u32 = 1;
/// [`FrameUniforms::target`]`[2]`: the scene has vertex attributes (texture coordinates and
/// colours) for the vertex shader to read.
pub const DISPLAY_VERTEX_ATTRIBUTES: u32 = 2;
/// [`FrameUniforms::target`]`[2]`: materials' textures are sampled (textures on, and the scene
/// has some).
pub const DISPLAY_TEXTURES: u32 = 4;
/// [`FrameUniforms::target`]`[2]`: some material has a texture or an alpha mode other than
/// BLEND, so the vertex shader reads the material descriptions.
pub const DISPLAY_MATERIAL_DESCRIPTIONS: u32 = 8;
/// [`FrameUniforms::target`]`[2]`: highlighted parts are outlined, not tinted; surfaces record
/// the outline keys (binding 7).
pub const DISPLAY_HIGHLIGHT_OUTLINE: u32 = 16;
/// [`FrameUniforms::target`]`[2]`: surfaces record themselves in the nearest surfaces
/// (binding 7), where the silhouettes pass finds X-ray's silhouettes and which silhouettes
/// outline highlighted parts (the renderer sets it).
pub const DISPLAY_NEAREST_SURFACES: u32 = 32;
/// [`FrameUniforms::target`]`[2]`: opaque surfaces record the cap keys (binding 7), from which
/// the cap ties pass paints the caps that tie with another part's surface (the renderer sets
/// it).
pub const DISPLAY_CAP_KEYS: u32 = 64;

/// The frame set's bindings (see [`Pipelines::frame_set_layout`]) on a device with
/// `capabilities`: the bindless texture table where it binds textures so
/// ([`Capabilities::bindless_textures`]), the frame uniforms seen by geometry shaders where it
/// has them (the hidden silhouettes' `shaders/silhouette_lines.geom`).
fn frame_set_bindings(capabilities: Capabilities) -> Vec<LayoutBinding> {
    use vk::DescriptorType as Type;
    use vk::ShaderStageFlags as Stage;
    let bindless_textures = capabilities.bindless_textures;
    // The technique mesh shader (mesh-shading submissions) reads what the vertex shader reads.
    let vertex_stages = if capabilities.mesh_shader {
        Stage::VERTEX | Stage::MESH_EXT
    } else {
        Stage::VERTEX
    };
    let mut uniform_stages = vertex_stages | Stage::FRAGMENT;
    if capabilities.geometry_shader {
        uniform_stages |= Stage::GEOMETRY;
    }
    let vertex_storage = LayoutBinding::one(Type::STORAGE_BUFFER, vertex_stages);
    let fragment_storage = LayoutBinding::one(Type::STORAGE_BUFFER, Stage::FRAGMENT);
    let texture_sampling = if bindless_textures > 0 {
        LayoutBinding::one(Type::SAMPLER, Stage::FRAGMENT)
    } else {
        LayoutBinding::one(Type::COMBINED_IMAGE_SAMPLER, Stage::FRAGMENT)
    };
    let mut bindings = vec![
        LayoutBinding::one(Type::UNIFORM_BUFFER, uniform_stages),
        fragment_storage,
        vertex_storage,
        vertex_storage,
        vertex_storage,
        texture_sampling,
        texture_sampling,
        fragment_storage,
        vertex_storage,
    ];
    if bindless_textures > 0 {
        bindings.push(LayoutBinding {
            ty: Type::SAMPLED_IMAGE,
            stages: Stage::FRAGMENT,
            count: bindless_textures,
            indexed_array: true,
        });
    }
    bindings
}

/// The frame set's binding of the bindless texture table.
pub const TEXTURE_TABLE_BINDING: u32 = 9;

/// Which descriptor sets a pass over the picture binds beside the frame set (set 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OverlaySets {
    /// The frame set alone.
    Frame,
    /// The frame set and the picture's depth (set 1, [`Pipelines::depth_set_layout`]).
    FrameAndDepth,
}

/// A pass over the picture as its pipeline is made: a full-screen triangle with this fragment
/// shader and blend, binding these sets.
#[derive(Clone, Copy, Debug)]
pub struct OverlayShader {
    /// The fragment shader.
    pub fragment: &'static ShaderSource,
    /// How its colour goes over the picture.
    pub blend: Blend,
    /// The sets it binds.
    pub sets: OverlaySets,
}

/// The sets of [`Pipelines::shared`], one per device and overlay count.
static SHARED_PIPELINES: Shared<Pipelines> = Shared::new();

/// The frame's layouts and the pipelines of the passes over the picture: made from the device
/// alone, so the renderers of one device share one set ([`Pipelines::shared`]).
pub struct Pipelines {
    device: Arc<Device>,
    /// Set 0: the frame uniform buffer and the transparency method's storage.
    frame_set_layout: DescriptorSetLayout,
    /// Set 1 of the transparency merge: the method's targets as sampled images.
    merge_set_layout: DescriptorSetLayout,
    /// The layout of the passes over the picture that read only the frame set.
    frame_overlay_layout: PipelineLayout,
    /// Set 1 of the passes over the picture that read its depth: the depth as a sampled image.
    depth_set_layout: DescriptorSetLayout,
    /// Their layout (the frame set, the depth set).
    depth_overlay_layout: PipelineLayout,
    /// The passes over the picture, each made on first use, by the index the frame gives it.
    overlays: Vec<OnceLock<Pipeline>>,
}

impl Pipelines {
    /// The set the renderers of `device` share, made with room for `overlay_count` passes over
    /// the picture when none is alive: a further view neither makes its layouts nor compiles
    /// its full-screen pipelines again.
    pub fn shared(device: &Arc<Device>, overlay_count: usize) -> RenderResult<Arc<Self>> {
        SHARED_PIPELINES.get_or_make(
            |held| Arc::ptr_eq(&held.device, device) && held.overlays.len() == overlay_count,
            || Self::new(device, overlay_count),
        )
    }

    /// Creates the layouts and room for `overlay_count` passes over the picture; pipelines are
    /// made on first use.
    pub fn new(device: &Arc<Device>, overlay_count: usize) -> RenderResult<Self> {
        let frame_set_layout = DescriptorSetLayout::with_bindings(
            device,
            "frame set layout",
            &frame_set_bindings(device.capabilities()),
        )?;
        let merge_set_layout = DescriptorSetLayout::new(
            device,
            "transparency merge set layout",
            &[(
                vk::DescriptorType::SAMPLED_IMAGE,
                vk::ShaderStageFlags::FRAGMENT,
            ); 2],
        )?;
        let frame_overlay_layout = PipelineLayout::new(
            device,
            "frame overlay layout",
            &[frame_set_layout.raw()],
            0,
            vk::ShaderStageFlags::FRAGMENT,
        )?;
        let depth_set_layout = DescriptorSetLayout::new(
            device,
            "picture depth set layout",
            &[(
                vk::DescriptorType::SAMPLED_IMAGE,
                vk::ShaderStageFlags::FRAGMENT,
            )],
        )?;
        let depth_overlay_layout = PipelineLayout::new(
            device,
            "picture depth overlay layout",
            &[frame_set_layout.raw(), depth_set_layout.raw()],
            0,
            vk::ShaderStageFlags::FRAGMENT,
        )?;
        Ok(Self {
            device: Arc::clone(device),
            depth_set_layout,
            depth_overlay_layout,
            frame_overlay_layout,
            frame_set_layout,
            merge_set_layout,
            overlays: (0..overlay_count).map(|_| OnceLock::new()).collect(),
        })
    }

    /// Set 0 of every graphics pipeline: the frame uniform buffer (binding 0; geometry shaders
    /// read it too where the device has them), the
    /// transparency method's storage (binding 1, fragment shaders), and for the shared vertex
    /// shader the GPU scene's instance records, material texture descriptions and vertex
    /// attributes (bindings 2–4), its textures sampled trilinear and with nearest
    /// magnification (bindings 5–6, fragment shaders: the texture array with each sampler, or
    /// with bindless textures the two samplers alone), the pixel keys (the outline highlight
    /// style's and the silhouettes' nearest surfaces; binding 7, fragment shaders), the GPU
    /// scene's cull entries, whose bounding spheres the section caps' pass reads (binding 8),
    /// and with bindless textures the table of textures (binding 9,
    /// [`TEXTURE_TABLE_BINDING`]: an update-after-bind, partially bound array of sampled
    /// images as long as the device binds textures).
    pub fn frame_set_layout(&self) -> &DescriptorSetLayout {
        &self.frame_set_layout
    }

    /// Set 1 of the transparency merge: the method's targets (bindings 0 and 1).
    pub fn merge_set_layout(&self) -> &DescriptorSetLayout {
        &self.merge_set_layout
    }

    /// The layouts technique pipelines are built with: the frame set's and the merge's.
    pub fn technique_set_layouts(&self) -> (vk::DescriptorSetLayout, vk::DescriptorSetLayout) {
        (self.frame_set_layout.raw(), self.merge_set_layout.raw())
    }

    /// Set 1 of the passes over the picture that read its depth (ambient occlusion,
    /// silhouettes): the frame's depth (binding 0).
    pub fn depth_set_layout(&self) -> &DescriptorSetLayout {
        &self.depth_set_layout
    }

    /// The pipeline of the pass over the picture at `index` (of the `overlay_count` this was
    /// made with), made from `shader` on first use, with its layout.
    pub fn overlay(
        &self,
        index: usize,
        shader: &OverlayShader,
    ) -> RenderResult<(vk::Pipeline, vk::PipelineLayout)> {
        let layout = match shader.sets {
            OverlaySets::Frame => &self.frame_overlay_layout,
            OverlaySets::FrameAndDepth => &self.depth_overlay_layout,
        };
        let slot = self.overlays.get(index).ok_or_else(|| {
            crate::error::RenderError::InvalidUse(format!(
                "pass over the picture {index} ({}): the renderer has room for {}",
                shader.fragment.name,
                self.overlays.len()
            ))
        })?;
        self.fullscreen(slot, layout, shader.fragment, shader.blend)
    }

    /// The full-screen pipeline in `slot`, made from `fragment` on first use.
    fn fullscreen(
        &self,
        slot: &OnceLock<Pipeline>,
        layout: &PipelineLayout,
        fragment: &ShaderSource,
        blend: Blend,
    ) -> RenderResult<(vk::Pipeline, vk::PipelineLayout)> {
        if let Some(pipeline) = slot.get() {
            return Ok((pipeline.raw(), layout.raw()));
        }
        let vertex = shaders::module(&self.device, &shaders::MERGE_VERT)?;
        let fragment_module = shaders::module(&self.device, fragment)?;
        let made = Pipeline::fullscreen(
            &self.device,
            layout,
            (&vertex, &fragment_module),
            blend,
            fragment.name,
        )?;
        // Another thread may have made one meanwhile: the first is kept, `made` is dropped.
        Ok((slot.get_or_init(|| made).raw(), layout.raw()))
    }
}
