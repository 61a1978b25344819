#version 460
#include "frame.glsl"
#include "shading.glsl"

layout(push_constant) uniform DrawParameters {
    mat4 model_view;
    vec4 base_color;
    vec4 surface;
} draw;

layout(location = 0) in vec3 in_view_position;
layout(location = 1) in vec3 in_view_normal;

layout(location = 0) out vec4 out_color;

void main() {
    out_color = vec4(shade_headlight(in_view_position, in_view_normal, draw.base_color, draw.surface.xy, frame.light), 1.0);
}
