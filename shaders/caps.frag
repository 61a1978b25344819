#version 460
// Section caps drawn again over the edge lines (the edges and hidden-line display modes with
// caps on). Drawn after the lines with the surfaces' own depth, tested for equality, so only
// the surface fragment each pixel shows passes; every fragment that is not a cap is
// discarded. What remains is the visible caps, painted again as shaded.frag paints them, over
// the lines that were drawn on the far faces the caps are painted on: at a visible cap pixel
// the ray runs inside the cut part from the plane to that face, so every line there lies
// inside the part and belongs under the cap. In the hidden-line mode, whose surfaces fill no
// colour, this is where the caps are painted at all.
#include "frame.glsl"
#include "shading.glsl"
#include "section.glsl"
#include "texturing.glsl"

layout(location = 2) flat in vec4 in_base_color;
layout(location = 5) in vec3 in_eye_offset;
layout(location = 6) flat in float in_closure;
layout(location = 7) in vec2 in_uv;
layout(location = 8) in vec4 in_vertex_color;
layout(location = 9) flat in uvec4 in_texture;

layout(location = 0) out vec4 out_color;

void main() {
    // Sampled before any discard: the texture's derivatives need the whole quad.
    vec4 surface = cadr_surface_color(in_base_color, in_vertex_color, in_uv, in_texture);
    int cap_plane = section_cap_of(in_closure, in_eye_offset);
    if (cap_plane < 0 || cadr_masked_out(surface, in_texture)) {
        discard;
    }
    out_color = vec4(section_cap_color(cap_plane, in_eye_offset), 1.0);
}
