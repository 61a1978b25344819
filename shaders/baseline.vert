#version 460
// Baseline technique: one draw per part, its matrix and material pushed per draw.
#include "frame.glsl"

layout(push_constant) uniform DrawParameters {
    mat4 model_view;       // object -> view space, made relative to the camera in f64 on the CPU
    vec4 base_color;
    vec4 surface;          // x: metallic, y: roughness
} draw;

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;

layout(location = 0) out vec3 out_view_position;
layout(location = 1) out vec3 out_view_normal;

void main() {
    vec4 view_position = draw.model_view * vec4(in_position, 1.0);
    mat3 linear = mat3(draw.model_view);
    // The cofactor matrix transforms normals correctly under non-uniform scale.
    mat3 cofactor = mat3(cross(linear[1], linear[2]), cross(linear[2], linear[0]), cross(linear[0], linear[1]));
    out_view_position = view_position.xyz;
    out_view_normal = cofactor * in_normal;
    gl_Position = frame.projection * view_position;
}
