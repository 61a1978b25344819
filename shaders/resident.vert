#version 460
// GPU-resident parameters: world matrices and materials live in storage buffers, updated
// sparsely by scatter.comp; each draw pushes indices. Positions are made relative to the eye on
// the GPU with translations split into high and low f32 parts (from f64), so parts far from the
// world origin keep their precision whatever the scene's units.
#include "frame.glsl"

struct MaterialParameters {
    vec4 base_color;
    vec4 surface;          // x: metallic, y: roughness
};

layout(set = 1, binding = 0, std430) readonly buffer Matrices { mat4 world_from_object[]; };
layout(set = 1, binding = 1, std430) readonly buffer Materials { MaterialParameters materials[]; };
layout(set = 1, binding = 2, std430) readonly buffer TranslationLows { vec4 translation_low[]; };

layout(push_constant) uniform DrawIndices {
    uint matrix;
    uint material;
    uint flags;            // bit 0: highlighted
    uint instance;         // scene tree instance id, written by the pick pass
} draw;

const uint DRAW_HIGHLIGHTED = 1u;
const vec3 HIGHLIGHT_COLOR = vec3(1.0, 0.55, 0.05);

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;

layout(location = 0) out vec3 out_view_position;
layout(location = 1) out vec3 out_view_normal;
layout(location = 2) flat out vec4 out_base_color;
layout(location = 3) flat out vec2 out_surface;
layout(location = 4) flat out uint out_pick_id;  // instance + 1 (0 means nothing)

void main() {
    mat4 world = world_from_object[draw.matrix];
    // Subtract high from high and low from low: both differences are exact or tiny, and
    // `precise` keeps the compiler from reassociating them away.
    precise vec3 eye_relative = (world[3].xyz - frame.eye_high.xyz) + (translation_low[draw.matrix].xyz - frame.eye_low.xyz);
    vec3 world_offset = mat3(world) * in_position + eye_relative;
    vec4 view_position = frame.view_rotation * vec4(world_offset, 1.0);
    mat3 linear = mat3(frame.view_rotation) * mat3(world);
    mat3 cofactor = mat3(cross(linear[1], linear[2]), cross(linear[2], linear[0]), cross(linear[0], linear[1]));
    out_view_position = view_position.xyz;
    out_view_normal = cofactor * in_normal;
    MaterialParameters material = materials[draw.material];
    out_base_color = material.base_color;
    if ((draw.flags & DRAW_HIGHLIGHTED) != 0u) {
        out_base_color.rgb = mix(out_base_color.rgb, HIGHLIGHT_COLOR, 0.65);
    }

    out_surface = material.surface.xy;
    out_pick_id = draw.instance + 1u;
    gl_Position = frame.projection * view_position;
}
