#version 460
// Translucent surfaces of every technique combination: shaded as in shaded.frag (without
// caps: a translucent part shows its inside anyway; with textures, vertex colours and alpha
// masks), premultiplied by the opacity (a BLEND material's alpha, at most the opacity limit
// X-ray sets; the limit itself for other alpha modes) and handed
// to the transparency method's snippet, which the host pastes below with the declarations of
// its targets and storage (CADR_TARGET_COUNT, CADR_STORAGE).
// Fragments behind an opaque surface never reach the method (which may write storage).
layout(early_fragment_tests) in;
#include "frame.glsl"
#include "shading.glsl"
#include "transparency.glsl"
#include "texturing.glsl"
#include "pixel_keys.glsl"

layout(location = 0) in vec3 in_view_position;
layout(location = 1) in vec3 in_view_normal;
layout(location = 2) flat in vec4 in_base_color;
layout(location = 3) flat in vec2 in_surface;
layout(location = 7) in vec2 in_uv;
layout(location = 8) in vec4 in_vertex_color;
layout(location = 9) flat in uvec4 in_texture;
layout(location = 10) flat in float in_opacity_limit;
layout(location = 11) flat in uint in_highlighted;

// The picture itself is written by the opaque pass and the merge only.
layout(location = 0) out vec4 out_color;
#if CADR_TARGET_COUNT > 0
layout(location = 1) out vec4 cadr_target_0;
#endif
#if CADR_TARGET_COUNT > 1
layout(location = 2) out vec4 cadr_target_1;
#endif

//@TRANSPARENCY@

void main() {
    vec4 surface = cadr_surface_color(in_base_color, CADR_SURFACE_VERTEX_COLOR, CADR_SURFACE_UV, in_texture);
    if (cadr_masked_out(surface, in_texture)) {
        discard;
    }
    // A highlighted translucent surface gets its outline; the others do not hide what is
    // outlined behind them (X-ray shows the highlighted parts inside a housing outlined).
    if ((frame.target.z & CADR_DISPLAY_HIGHLIGHT_OUTLINE) != 0u && in_highlighted != 0u) {
        cadr_record_surface(CADR_OUTLINE_PLANE, true);
    }
    // X-ray's silhouettes outline translucent surfaces too.
    if ((frame.target.z & CADR_DISPLAY_NEAREST_SURFACES) != 0u) {
        cadr_record_surface(CADR_NEAREST_SURFACES_PLANE, in_highlighted != 0u);
    }
    vec3 color = shade_headlight(in_view_position, in_view_normal, surface, in_surface, frame.light,
                          frame.view_rotation[1].xyz);
    float opacity = in_texture.z == CADR_ALPHA_BLEND ? min(surface.a, in_opacity_limit) : in_opacity_limit;
    opacity = clamp(opacity, 0.0, 1.0);
    out_color = vec4(0.0);
    cadr_transparent_fragment(vec4(color * opacity, opacity), -in_view_position.z);
}
