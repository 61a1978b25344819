//! Textures of the scene model: decoded base-colour images with their sampling, the reference a
//! material makes to one (with its texture-coordinate transform), and how a material's alpha
//! is used.

use std::sync::Arc;

/// How texture coordinates outside 0..1 are wrapped (glTF sampler `wrapS`/`wrapT`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// The image repeats.
    #[default]
    Repeat,
    /// The edge texels extend outwards.
    ClampToEdge,
    /// The image repeats, every other copy mirrored.
    MirroredRepeat,
}

impl Wrap {
    /// Its code in the shaders (`shaders/texturing.glsl`).
    pub fn code(self) -> u32 {
        match self {
            Wrap::Repeat => 0,
            Wrap::ClampToEdge => 1,
            Wrap::MirroredRepeat => 2,
        }
    }
}

/// How a texture is sampled.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Sampler {
    /// Wrapping of the first texture coordinate.
    pub wrap_s: Wrap,
    /// Wrapping of the second texture coordinate.
    pub wrap_t: Wrap,
    /// Magnification picks the nearest texel (glTF `magFilter` NEAREST) instead of blending
    /// the four nearest. Minification always blends mip levels.
    pub magnify_nearest: bool,
}

/// A decoded image: 8-bit RGBA texels, sRGB-encoded colour and linear alpha (as glTF's
/// base-colour textures are), rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Name from the file (the image's name or URI) or the host.
    pub name: String,
    /// Width in texels (at least 1).
    pub width: u32,
    /// Height in texels (at least 1).
    pub height: u32,
    /// `width × height × 4` bytes, shared: scenes, graphs and copies of them hold one image.
    pub texels: Arc<Vec<u8>>,
    /// How materials sample it.
    pub sampler: Sampler,
}

impl Texture {
    /// Whether any texel is less than fully opaque.
    pub fn has_translucent_texels(&self) -> bool {
        self.texels.chunks_exact(4).any(|t| t[3] < 255)
    }

    /// Checks the texel count against the size; `t` numbers the texture in messages.
    pub fn validate(&self, t: usize) -> Result<(), super::SceneError> {
        let expected = u64::from(self.width) * u64::from(self.height) * 4;
        if self.width == 0 || self.height == 0 || self.texels.len() as u64 != expected {
            return Err(super::SceneError(format!(
                "texture {t} ('{}') is {}×{} texels but holds {} bytes ({expected} expected, at least 1×1)",
                self.name,
                self.width,
                self.height,
                self.texels.len()
            )));
        }
        Ok(())
    }
}

/// An affine map of texture coordinates, `uv' = [u_row · (u, v, 1), v_row · (u, v, 1)]`
/// (glTF `KHR_texture_transform`: offset, rotation and scale in one matrix).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    /// The row giving the new first coordinate.
    pub u_row: [f32; 3],
    /// The row giving the new second coordinate.
    pub v_row: [f32; 3],
}

impl Default for UvTransform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl UvTransform {
    /// Coordinates unchanged.
    pub const IDENTITY: Self = Self {
        u_row: [1.0, 0.0, 0.0],
        v_row: [0.0, 1.0, 0.0],
    };

    /// `KHR_texture_transform`'s matrix: translation × rotation × scale, where the rotation
    /// turns by `rotation` radians counter-clockwise in UV space.
    pub fn from_offset_rotation_scale(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> Self {
        let (sin, cos) = rotation.sin_cos();
        Self {
            u_row: [cos * scale[0], sin * scale[1], offset[0]],
            v_row: [-sin * scale[0], cos * scale[1], offset[1]],
        }
    }

    /// The transformed coordinates.
    pub fn apply(&self, uv: [f32; 2]) -> [f32; 2] {
        let row = |r: [f32; 3]| r[0] * uv[0] + r[1] * uv[1] + r[2];
        [row(self.u_row), row(self.v_row)]
    }

    /// Whether every entry is finite.
    pub fn is_finite(&self) -> bool {
        self.u_row.iter().chain(&self.v_row).all(|c| c.is_finite())
    }
}

/// A material's base-colour texture: which texture and how its coordinates are transformed.
/// The texture coordinates are the geometry's ([`super::VertexAttributes::uv`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    /// In a [`super::Scene`], an index in its textures; in a
    /// [`crate::graph::SceneGraph`], the texture's slot.
    pub texture: u32,
    /// Applied to the texture coordinates before sampling.
    pub transform: UvTransform,
}

/// How the alpha of the texture and of the vertex colours is used (glTF `alphaMode`); the
/// material's own opacity is the base colour's alpha in every mode.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum AlphaMode {
    /// Texture and vertex alpha are ignored.
    Opaque,
    /// A fragment whose texture alpha × vertex alpha × base alpha is under `cutoff` is
    /// discarded, the rest is opaque (glTF MASK with `alphaCutoff`); picking goes through the
    /// holes too.
    Mask {
        /// Fragments under it are discarded.
        cutoff: f32,
    },
    /// Texture alpha × vertex alpha multiply the opacity (glTF BLEND; what a host's material
    /// gets by default). A texture with any translucent texel makes the material translucent.
    #[default]
    Blend,
}

impl AlphaMode {
    /// Its code in the shaders (`shaders/texturing.glsl`).
    pub fn code(self) -> u32 {
        match self {
            AlphaMode::Opaque => 0,
            AlphaMode::Mask { .. } => 1,
            AlphaMode::Blend => 2,
        }
    }
}
