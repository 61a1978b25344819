// The vertex shader every technique combination shares. The host assembles it: the vertex
// path's snippet (cadr_vertex_position, cadr_vertex_normal, and where it defines
// CADR_VERTEX_INDEX, cadr_vertex_index) and the parameter path's snippet (cadr_object)
// replace the two markers below. Positions are made relative to the eye with the translation
// split into f32 high and low parts. Texture coordinates, vertex colours and each material's
// texture description come from the host's frame set (bindings 2-4), whatever the paths.
#include "frame.glsl"

// The GPU scene's instance records (matrix, material, flags, instance), by instance id.
layout(set = 0, binding = 2, std430) readonly buffer CadrHostInstanceRecords {
    uvec4 cadr_host_instance_records[];
};
// Per material slot: the texture-coordinate transform's rows (xyz), and layer + 1 (0: none),
// sampling bits, alpha mode, the mask's cutoff (float bits). See gpu_scene/textures.rs.
struct CadrMaterialTexture {
    vec4 u_row;
    vec4 v_row;
    uvec4 info;
};
layout(set = 0, binding = 3, std430) readonly buffer CadrHostMaterialTextures {
    CadrMaterialTexture cadr_host_material_textures[];
};
// Per vertex of the vertex arena (with CADR_DISPLAY_VERTEX_ATTRIBUTES): u, v (float bits),
// colour (RGBA8).
layout(set = 0, binding = 4, std430) readonly buffer CadrHostVertexAttributes {
    uint cadr_host_vertex_attributes[];
};

// The GPU scene's cull entries by instance id, three vec4 each: the first is the part's
// bounding sphere in object space (centre, radius). See CadrCullEntry in the plugin ABI.
layout(set = 0, binding = 8, std430) readonly buffer CadrHostCullEntries {
    vec4 cadr_host_cull_entries[];
};

struct CadrObject {
    mat4 world;            // column 3: translation high part; w of columns 0-2: low part
    vec4 base_color;
    vec2 surface;
    uint flags;            // CADR_INSTANCE_* bits
    uint instance;
};

const uint CADR_INSTANCE_HIGHLIGHTED = 1u;
const uint CADR_INSTANCE_PICKABLE = 2u;

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

const uint CADR_INSTANCE_CLOSED = 16u;
const uint CADR_INSTANCE_INSIDE_OUT = 32u;

// Which surfaces the pipeline draws: every one, only the opaque ones (the opaque pass of a
// frame with translucent surfaces) or only the translucent ones (the transparency method's
// pass). A part the pipeline does not draw has its triangles clipped away whole.
const uint CADR_DRAW_ALL = 0u;
const uint CADR_DRAW_OPAQUE = 1u;
const uint CADR_DRAW_TRANSLUCENT = 2u;
layout(constant_id = 0) const uint CADR_DRAW_ROLE = CADR_DRAW_ALL;
// The section caps' pass (caps.frag): only a closed part that a plane cuts can show a cap, so
// every other part has its triangles clipped away whole.
layout(constant_id = 1) const bool CADR_CAPS_PASS = false;

const uint CADR_TEXTURE_SAMPLING_TRANSLUCENT = 32u;
const uint CADR_TEXTURE_ALPHA_BLEND = 2u;

// Whether some section plane passes through the bounding sphere `sphere` (object space) of a
// part placed by `linear_world` with its origin at `eye_relative` from the eye.
bool cadr_cut_by_a_plane(vec4 sphere, mat3 linear_world, vec3 eye_relative) {
    vec3 center = linear_world * sphere.xyz + eye_relative;
    float scale = max(max(length(linear_world[0]), length(linear_world[1])), length(linear_world[2]));
    // With the rounding of f32 eye-relative positions as slack.
    float radius = sphere.w * scale + 1e-5 * length(center);
    uint count = min(frame.section.x & 0xffu, 6u);
    for (uint i = 0u; i < count; ++i) {
        vec4 plane = frame.section_planes[i];
        if (abs(dot(plane.xyz, center) + plane.w) <= radius) {
            return true;
        }
    }
    return false;
}

void main() {
    CadrObject object = cadr_object();
    // No texture, BLEND: what every material is while none is described otherwise.
    CadrMaterialTexture material_texture = CadrMaterialTexture(
        vec4(1.0, 0.0, 0.0, 0.0), vec4(0.0, 1.0, 0.0, 0.0), uvec4(0u, 0u, CADR_TEXTURE_ALPHA_BLEND, 0u));
    if ((frame.target.z & CADR_DISPLAY_MATERIAL_DESCRIPTIONS) != 0u) {
        uint material = cadr_host_instance_records[object.instance].y;
        material_texture = cadr_host_material_textures[material];
    }
    uvec4 texture_info = material_texture.info;
    if ((frame.target.z & CADR_DISPLAY_TEXTURES) == 0u) {
        texture_info.x = 0u;
    }
    // Translucent: a BLEND material with an opacity under 1 or a translucent texture, or
    // X-ray on a part not highlighted.
    bool highlighted = (object.flags & CADR_INSTANCE_HIGHLIGHTED) != 0u;
    bool blends = texture_info.z == CADR_TEXTURE_ALPHA_BLEND;
    bool translucent = blends && (object.base_color.a < 1.0
        || (texture_info.x != 0u && (texture_info.y & CADR_TEXTURE_SAMPLING_TRANSLUCENT) != 0u));
    out_opacity_limit = 1.0;
    if ((frame.target.z & CADR_DISPLAY_XRAY) != 0u && !highlighted) {
        translucent = true;
        out_opacity_limit = CADR_XRAY_OPACITY;
    }
    mat4 world = object.world;
    vec3 translation_low = vec3(world[0].w, world[1].w, world[2].w);
    mat3 linear_world = mat3(world[0].xyz, world[1].xyz, world[2].xyz);
    precise vec3 eye_relative = (world[3].xyz - frame.eye_high.xyz) + (translation_low - frame.eye_low.xyz);
    bool drawn = CADR_DRAW_ROLE == CADR_DRAW_ALL || translucent == (CADR_DRAW_ROLE == CADR_DRAW_TRANSLUCENT);
    if (CADR_CAPS_PASS && drawn) {
        drawn = (object.flags & CADR_INSTANCE_CLOSED) != 0u
            && cadr_cut_by_a_plane(cadr_host_cull_entries[object.instance * 3u], linear_world, eye_relative);
    }
    if (!drawn) {
        gl_Position = vec4(0.0, 0.0, 2.0, 1.0);
        for (int i = 0; i < 6; ++i) {
            gl_ClipDistance[i] = -1.0;
        }
        return;
    }
    vec3 world_offset = linear_world * cadr_vertex_position() + eye_relative;
    vec4 view_position = frame.view_rotation * vec4(world_offset, 1.0);
    mat3 linear = mat3(frame.view_rotation) * linear_world;
    mat3 cofactor = mat3(cross(linear[1], linear[2]), cross(linear[2], linear[0]), cross(linear[0], linear[1]));
    out_view_position = view_position.xyz;
    out_view_normal = cofactor * cadr_vertex_normal();
    out_base_color = object.base_color;
    if (highlighted && (frame.target.z & CADR_DISPLAY_HIGHLIGHT_OUTLINE) == 0u) {
        out_base_color.rgb = mix(out_base_color.rgb, frame.highlight.rgb, 0.65);
    }
    out_highlighted = highlighted ? 1u : 0u;
    out_surface = object.surface;
    out_texture = texture_info;
    vec2 uv = vec2(0.0);
    out_vertex_color = vec4(1.0);
#ifdef CADR_VERTEX_INDEX
    if ((frame.target.z & CADR_DISPLAY_VERTEX_ATTRIBUTES) != 0u) {
        uint at = cadr_vertex_index() * 3u;
        uv = vec2(uintBitsToFloat(cadr_host_vertex_attributes[at]),
                  uintBitsToFloat(cadr_host_vertex_attributes[at + 1u]));
        out_vertex_color = unpackUnorm4x8(cadr_host_vertex_attributes[at + 2u]);
    }
#endif
    vec3 homogeneous_uv = vec3(uv, 1.0);
    out_uv = vec2(dot(material_texture.u_row.xyz, homogeneous_uv),
                  dot(material_texture.v_row.xyz, homogeneous_uv));
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
