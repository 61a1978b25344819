#version 460
// The pick pass: writes which instance covers each pixel (instance id + 1; 0 is nothing).
// Instances that cannot be picked come with id 0 and let the click through to what is behind,
// and so do the holes a material's alpha mask cuts. A cap (section.glsl) sets CADR_PICK_CAP
// in the id: the host moves such a hit from the far face the cap is painted on to the plane.
// Where that face ties with another part's surface (a cut part standing on a plate), the
// picture paints the cap (cap_ties.frag): the cap's depth is pulled nearer by the same tie
// margin, so that the click hits what the picture shows.
#include "frame.glsl"
#include "shading.glsl"
#include "section.glsl"
#include "texturing.glsl"

layout(location = 2) flat in vec4 in_base_color;
layout(location = 4) flat in uint in_pick_id;
layout(location = 5) in vec3 in_eye_offset;
layout(location = 6) flat in float in_closure;
layout(location = 7) in vec2 in_uv;
layout(location = 8) in vec4 in_vertex_color;
layout(location = 9) flat in uvec4 in_texture;

layout(location = 0) out uint out_id;

void main() {
    // Sampled before any discard: the texture's derivatives need the whole quad.
    vec4 surface = cadr_surface_color(in_base_color, CADR_SURFACE_VERTEX_COLOR, CADR_SURFACE_UV, in_texture);
    if (in_pick_id == 0u || cadr_masked_out(surface, in_texture)) {
        discard;
    }
    bool cap = section_cap_of(in_closure, CADR_SURFACE_EYE_OFFSET) >= 0;
    out_id = cap ? in_pick_id | CADR_PICK_CAP : in_pick_id;
    gl_FragDepth = cap
        ? cadr_depth_at(cadr_view_distance(gl_FragCoord.z) * (1.0 - CADR_CAP_TIE))
        : gl_FragCoord.z;
}
