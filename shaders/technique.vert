// The vertex shader every technique combination shares. The host assembles it: the vertex
// path's snippet (cadr_vertex_position, cadr_vertex_normal, and where it defines
// CADR_VERTEX_INDEX, cadr_vertex_index) and the parameter path's snippet (cadr_object)
// replace the two markers below. Positions are made relative to the eye with the translation
// split into f32 high and low parts. Texture coordinates, vertex colours and each material's
// texture description come from the host's frame set (bindings 2-4), whatever the paths.
// technique.mesh computes the same vertex (technique_vertex.glsl) in a mesh shader.
#include "frame.glsl"
#include "technique_inputs.glsl"

// Push constants: bytes 0-95 belong to the parameter path, 96-127 to the vertex path.
layout(push_constant) uniform CadrPushConstants {
    mat4 matrix;
    vec4 vectors[2];
    uvec4 words[2];
} cadr_push;

//@VERTEX_PATH@

//@PARAMETER_PATH@

#include "technique_vertex.glsl"

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
// Texturing (texturing.glsl): the transformed texture coordinate, the vertex colour, the
// material's texture description (layer + 1 or 0 with textures off, sampling, alpha mode,
// cutoff) and the opacity a translucent surface may have at most (X-ray lowers it).
layout(location = 7) out vec2 out_uv;
layout(location = 8) out vec4 out_vertex_color;
layout(location = 9) flat out uvec4 out_texture;
layout(location = 10) flat out float out_opacity_limit;
// 1 for a highlighted part (the outline style records it for its outline), else 0.
layout(location = 11) flat out uint out_highlighted;

// Only what every pass reads (the hidden silhouettes' geometry shader declares the same).
out gl_PerVertex {
    vec4 gl_Position;
    float gl_ClipDistance[6];
};
// The same position in every pipeline built from this shader, whatever its fragment shader: the
// section caps' second pass (caps.frag) finds the surface each pixel shows by depth equality.
invariant gl_Position;

void main() {
    CadrTechniqueVertex v = cadr_technique_vertex();
    gl_Position = v.position;
    for (int i = 0; i < 6; ++i) {
        gl_ClipDistance[i] = v.clip_distance[i];
    }
    out_view_position = v.view_position;
    out_view_normal = v.view_normal;
    out_base_color = v.base_color;
    out_surface = v.surface;
    out_pick_id = v.pick_id;
    out_eye_offset = v.eye_offset;
    out_closure = v.closure;
    out_uv = v.uv;
    out_vertex_color = v.vertex_color;
    out_texture = v.texture;
    out_opacity_limit = v.opacity_limit;
    out_highlighted = v.highlighted;
}
