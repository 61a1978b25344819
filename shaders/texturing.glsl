// A surface's base colour: the material's, times the vertex colour, times its base-colour
// texture (frame set bindings 5 and 6: every texture is a layer of one sRGB array, the path
// every device has). The vertex shader hands over the transformed texture coordinate and the
// material's texture description (CadrMaterialTexture: layer + 1, 0 for none; sampling bits;
// alpha mode; the mask's cutoff).
layout(set = 0, binding = 5) uniform sampler2DArray cadr_textures_trilinear;
layout(set = 0, binding = 6) uniform sampler2DArray cadr_textures_nearest;

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

// texture: x layer + 1 (0: no texture, or textures off), y sampling bits, z alpha mode.
vec4 cadr_surface_color(vec4 base, vec4 vertex_color, vec2 uv, uvec4 texture_info) {
    // Derivatives of the unwrapped coordinate: the mip level does not jump where it wraps.
    vec2 uv_dx = dFdx(uv);
    vec2 uv_dy = dFdy(uv);
    vec4 color = base * vertex_color;
    if (texture_info.x != 0u) {
        uint sampling = texture_info.y;
        vec3 coordinate = vec3(cadr_wrap(uv.x, sampling & 3u), cadr_wrap(uv.y, (sampling >> 2) & 3u),
                               float(texture_info.x - 1u));
        vec4 texel = (sampling & CADR_SAMPLING_NEAREST) != 0u
            ? textureGrad(cadr_textures_nearest, coordinate, uv_dx, uv_dy)
            : textureGrad(cadr_textures_trilinear, coordinate, uv_dx, uv_dy);
        color *= texel;
    }
    return color;
}

// Whether a fragment of this colour is cut away by its material's alpha mask.
bool cadr_masked_out(vec4 color, uvec4 texture_info) {
    return texture_info.z == CADR_ALPHA_MASK && color.a < uintBitsToFloat(texture_info.w);
}
