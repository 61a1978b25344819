#version 460
// Shaded triangles of every technique combination: a head light on the material colour.
#include "frame.glsl"
#include "shading.glsl"

layout(location = 0) in vec3 in_view_position;
layout(location = 1) in vec3 in_view_normal;
layout(location = 2) flat in vec4 in_base_color;
layout(location = 3) flat in vec2 in_surface;

layout(location = 0) out vec4 out_color;

void main() {
    out_color = vec4(shade_headlight(in_view_position, in_view_normal, in_base_color, in_surface, frame.light), 1.0);
}
