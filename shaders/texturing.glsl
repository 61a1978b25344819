// A surface's base colour: the material's, times the vertex colour, times its base-colour
// texture. The vertex shader hands over the transformed texture coordinate and the material's
// texture description (CadrMaterialTexture: texture slot + 1, 0 for none; sampling bits;
// alpha mode; the mask's cutoff).
//
// Where the device has descriptor indexing (CADR_BINDLESS_TEXTURES, with
// GL_EXT_nonuniform_qualifier enabled by the host), each texture is an image of its own size
// in a table indexed by slot (binding 9), sampled with one of two samplers (bindings 5 and 6).
// Elsewhere every texture is a layer of one sRGB array (bindings 5 and 6, one per sampler).
#ifdef CADR_BINDLESS_TEXTURES
layout(set = 0, binding = 5) uniform sampler cadr_sampler_trilinear;
layout(set = 0, binding = 6) uniform sampler cadr_sampler_nearest;
layout(set = 0, binding = 9) uniform texture2D cadr_texture_table[];
#else
layout(set = 0, binding = 5) uniform sampler2DArray cadr_textures_trilinear;
layout(set = 0, binding = 6) uniform sampler2DArray cadr_textures_nearest;
#endif

// CadrMaterialTexture sampling bits: wrap S (bits 0-1) and T (bits 2-3): 0 repeat, 1 clamp to
// edge, 2 mirrored repeat; nearest-texel magnification; the texture has translucent texels.
const uint CADR_SAMPLING_NEAREST = 16u;
const uint CADR_SAMPLING_TRANSLUCENT = 32u;
// Alpha modes (glTF alphaMode).
const uint CADR_ALPHA_OPAQUE = 0u;
const uint CADR_ALPHA_MASK = 1u;
const uint CADR_ALPHA_BLEND = 2u;

float cadr_wrap(float coordinate, uint mode) {
    if (mode == 1u) {
        return clamp(coordinate, 0.0, 1.0);
    }
    if (mode == 2u) {
        float period = mod(coordinate, 2.0);
        return period > 1.0 ? 2.0 - period : period;
    }
    return fract(coordinate);
}

// The texel of texture `slot` at the wrapped coordinate `uv`, with the unwrapped coordinate's
// derivatives.
vec4 cadr_texel(uint slot, uint sampling, vec2 uv, vec2 uv_dx, vec2 uv_dy) {
    bool nearest = (sampling & CADR_SAMPLING_NEAREST) != 0u;
#ifdef CADR_BINDLESS_TEXTURES
    // The slot may differ between the fragments of one invocation group (parts of several
    // materials in one draw).
    return nearest
        ? textureGrad(sampler2D(cadr_texture_table[nonuniformEXT(slot)], cadr_sampler_nearest), uv, uv_dx, uv_dy)
        : textureGrad(sampler2D(cadr_texture_table[nonuniformEXT(slot)], cadr_sampler_trilinear), uv, uv_dx, uv_dy);
#else
    vec3 coordinate = vec3(uv, float(slot));
    return nearest
        ? textureGrad(cadr_textures_nearest, coordinate, uv_dx, uv_dy)
        : textureGrad(cadr_textures_trilinear, coordinate, uv_dx, uv_dy);
#endif
}

// texture: x texture slot + 1 (0: no texture, or textures off), y sampling bits, z alpha mode.
vec4 cadr_surface_color(vec4 base, vec4 vertex_color, vec2 uv, uvec4 texture_info) {
    // Derivatives of the unwrapped coordinate: the mip level does not jump where it wraps.
    vec2 uv_dx = dFdx(uv);
    vec2 uv_dy = dFdy(uv);
    vec4 color = base * vertex_color;
    if (texture_info.x != 0u) {
        uint sampling = texture_info.y;
        vec2 wrapped = vec2(cadr_wrap(uv.x, sampling & 3u), cadr_wrap(uv.y, (sampling >> 2) & 3u));
        color *= cadr_texel(texture_info.x - 1u, sampling, wrapped, uv_dx, uv_dy);
    }
    return color;
}

// The vertex colour and texture coordinate the surface, pick and translucent shaders read:
// interpolated only where the frame shows vertex colours or textures (the host defines
// CADR_SURFACE_ATTRIBUTES); elsewhere the vertex shader writes white and no texture is sampled,
// so constants stand in and the rasterizer interpolates six values fewer per triangle (with the
// cap offset left out too, 6-17 % less GPU time for a large frame on lavapipe;
// docs/BENCHMARKS.md).
#ifdef CADR_SURFACE_ATTRIBUTES
#define CADR_SURFACE_VERTEX_COLOR in_vertex_color
#define CADR_SURFACE_UV in_uv
#else
#define CADR_SURFACE_VERTEX_COLOR vec4(1.0)
#define CADR_SURFACE_UV vec2(0.0)
#endif

// Whether a fragment of this colour is cut away by its material's alpha mask.
bool cadr_masked_out(vec4 color, uvec4 texture_info) {
    return texture_info.z == CADR_ALPHA_MASK && color.a < uintBitsToFloat(texture_info.w);
}
