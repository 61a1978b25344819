// The vertex shader every technique combination shares. The host assembles it: the vertex
// path's snippet (cadr_vertex_position, cadr_vertex_normal) and the parameter path's snippet
// (cadr_object) replace the two markers below. Positions are made relative to the eye with
// the translation split into f32 high and low parts.
#include "frame.glsl"

struct CadrObject {
    mat4 world;            // column 3: translation high part; w of columns 0-2: low part
    vec4 base_color;
    vec2 surface;
    uint flags;            // CADR_INSTANCE_* bits
    uint instance;
};

const uint CADR_INSTANCE_HIGHLIGHTED = 1u;
const uint CADR_INSTANCE_PICKABLE = 2u;
const vec3 HIGHLIGHT_COLOR = vec3(1.0, 0.55, 0.05);

// Push constants: bytes 0-95 belong to the parameter path, 96-127 to the vertex path.
layout(push_constant) uniform CadrPushConstants {
    mat4 matrix;
    vec4 vectors[2];
    uvec4 words[2];
} cadr_push;

//@VERTEX_PATH@

//@PARAMETER_PATH@

layout(location = 0) out vec3 out_view_position;
layout(location = 1) out vec3 out_view_normal;
layout(location = 2) flat out vec4 out_base_color;
layout(location = 3) flat out vec2 out_surface;
layout(location = 4) flat out uint out_pick_id;
// Section caps: the world-space offset from the eye, and how the part closes as seen through
// the winding of this draw: +1 closed, -1 closed but wound the other way (inside out, or
// mirrored by its matrix), 0 open.
layout(location = 5) out vec3 out_eye_offset;
layout(location = 6) flat out float out_closure;

out float gl_ClipDistance[6];

const uint CADR_INSTANCE_CLOSED = 16u;
const uint CADR_INSTANCE_INSIDE_OUT = 32u;

// Which surfaces the pipeline draws: every one, only the opaque ones (the opaque pass of a
// frame with translucent surfaces) or only the translucent ones (the transparency method's
// pass). A part the pipeline does not draw has its triangles clipped away whole.
const uint CADR_DRAW_ALL = 0u;
const uint CADR_DRAW_OPAQUE = 1u;
const uint CADR_DRAW_TRANSLUCENT = 2u;
layout(constant_id = 0) const uint CADR_DRAW_ROLE = CADR_DRAW_ALL;

void main() {
    CadrObject object = cadr_object();
    // Translucent: a material opacity under 1, or X-ray on a part not highlighted.
    bool highlighted = (object.flags & CADR_INSTANCE_HIGHLIGHTED) != 0u;
    if ((frame.target.z & CADR_DISPLAY_XRAY) != 0u && !highlighted) {
        object.base_color.a = min(object.base_color.a, CADR_XRAY_OPACITY);
    }
    bool translucent = object.base_color.a < 1.0;
    if (CADR_DRAW_ROLE != CADR_DRAW_ALL && translucent != (CADR_DRAW_ROLE == CADR_DRAW_TRANSLUCENT)) {
        gl_Position = vec4(0.0, 0.0, 2.0, 1.0);
        for (int i = 0; i < 6; ++i) {
            gl_ClipDistance[i] = -1.0;
        }
        return;
    }
    mat4 world = object.world;
    vec3 translation_low = vec3(world[0].w, world[1].w, world[2].w);
    mat3 linear_world = mat3(world[0].xyz, world[1].xyz, world[2].xyz);
    precise vec3 eye_relative = (world[3].xyz - frame.eye_high.xyz) + (translation_low - frame.eye_low.xyz);
    vec3 world_offset = linear_world * cadr_vertex_position() + eye_relative;
    vec4 view_position = frame.view_rotation * vec4(world_offset, 1.0);
    mat3 linear = mat3(frame.view_rotation) * linear_world;
    mat3 cofactor = mat3(cross(linear[1], linear[2]), cross(linear[2], linear[0]), cross(linear[0], linear[1]));
    out_view_position = view_position.xyz;
    out_view_normal = cofactor * cadr_vertex_normal();
    out_base_color = object.base_color;
    if (highlighted) {
        out_base_color.rgb = mix(out_base_color.rgb, HIGHLIGHT_COLOR, 0.65);
    }
    out_surface = object.surface;
    // The pick pass writes instance + 1; 0 (nothing) lets the click through unpickable parts.
    out_pick_id = (object.flags & CADR_INSTANCE_PICKABLE) != 0u ? object.instance + 1u : 0u;
    gl_Position = frame.projection * view_position;
    for (int i = 0; i < 6; ++i) {
        gl_ClipDistance[i] = dot(frame.section_planes[i].xyz, world_offset) + frame.section_planes[i].w;
    }
    out_eye_offset = world_offset;
    float closure = 0.0;
    if ((object.flags & CADR_INSTANCE_CLOSED) != 0u) {
        bool inside_out = (object.flags & CADR_INSTANCE_INSIDE_OUT) != 0u;
        bool mirrored = determinant(linear_world) < 0.0;
        closure = inside_out != mirrored ? -1.0 : 1.0;
    }
    out_closure = closure;
}
