#version 460
// Shaded triangles of every technique combination: a head light on the material colour (times
// the vertex colour and the texture; a material's alpha mask cuts holes). While
// section planes cut with caps on, a closed part seen through a cut shows the cap there (see
// section.glsl). Every surface fragment records itself in the outline keys with the highlight
// outline style, in the nearest surfaces for the silhouettes, and in the cap keys while caps
// are seen (pixel_keys.glsl).
#include "frame.glsl"
#include "shading.glsl"
#include "section.glsl"
#include "texturing.glsl"
#include "pixel_keys.glsl"

layout(location = 0) in vec3 in_view_position;
layout(location = 1) in vec3 in_view_normal;
layout(location = 2) flat in vec4 in_base_color;
layout(location = 3) flat in vec2 in_surface;
layout(location = 5) in vec3 in_eye_offset;
layout(location = 6) flat in float in_closure;
layout(location = 7) in vec2 in_uv;
layout(location = 8) in vec4 in_vertex_color;
layout(location = 9) flat in uvec4 in_texture;
layout(location = 11) flat in uint in_highlighted;

layout(location = 0) out vec4 out_color;

void main() {
    vec4 surface = cadr_surface_color(in_base_color, CADR_SURFACE_VERTEX_COLOR, CADR_SURFACE_UV, in_texture);
    if (cadr_masked_out(surface, in_texture)) {
        discard;
    }
    if ((frame.target.z & CADR_DISPLAY_HIGHLIGHT_OUTLINE) != 0u) {
        cadr_record_surface(CADR_OUTLINE_PLANE, in_highlighted != 0u);
    }
    if ((frame.target.z & CADR_DISPLAY_NEAREST_SURFACES) != 0u) {
        cadr_record_surface(CADR_NEAREST_SURFACES_PLANE, in_highlighted != 0u);
    }
    int cap_plane = section_cap_of(in_closure, CADR_SURFACE_EYE_OFFSET);
    if ((frame.target.z & CADR_DISPLAY_CAP_KEYS) != 0u) {
        if (cap_plane >= 0) {
            cadr_record_cap(cap_plane);
        } else {
            cadr_record_surface(CADR_UNCAPPED_PLANE, false);
        }
    }
    if (cap_plane >= 0) {
        out_color = vec4(section_cap_color(cap_plane, CADR_SURFACE_EYE_OFFSET), 1.0);
        return;
    }
    out_color = vec4(shade_headlight(in_view_position, in_view_normal, surface, in_surface, frame.light,
                          frame.view_rotation[1].xyz), 1.0);
}
