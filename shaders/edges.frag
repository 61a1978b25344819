#version 460
// The edge lines of the edge display modes: a dark line colour, unlit.
#include "frame.glsl"
layout(location = 0) in vec3 in_view_position;
layout(location = 1) in vec3 in_view_normal;
layout(location = 2) flat in vec4 in_base_color;
layout(location = 3) flat in vec2 in_surface;

layout(location = 0) out vec4 out_color;

void main() {
    out_color = vec4(CADR_EDGE_COLOR, 1.0);
}
