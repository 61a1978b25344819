// The vertex of the technique shaders, shared by technique.vert (one vertex per invocation)
// and technique.mesh (one per triangle corner): included after the paths' snippets.

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

// One vertex as the technique shaders compute it, whatever the stage: the position, the six
// clip distances (section planes) and what the fragment shaders interpolate (see the outputs of
// technique.vert).
struct CadrTechniqueVertex {
    vec4 position;
    float clip_distance[6];
    vec3 view_position;
    vec3 view_normal;
    vec4 base_color;
    vec2 surface;
    uint pick_id;
    vec3 eye_offset;
    float closure;
    vec2 uv;
    vec4 vertex_color;
    uvec4 texture;
    float opacity_limit;
    uint highlighted;
};

// The vertex the paths' snippets name (cadr_vertex_position, cadr_object, ...), placed,
// projected and described for the fragment shaders.
CadrTechniqueVertex cadr_technique_vertex() {
    CadrTechniqueVertex v;
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
    v.opacity_limit = 1.0;
    if ((frame.target.z & CADR_DISPLAY_XRAY) != 0u && !highlighted) {
        translucent = true;
        v.opacity_limit = CADR_XRAY_OPACITY;
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
        v.position = vec4(0.0, 0.0, 2.0, 1.0);
        for (int i = 0; i < 6; ++i) {
            v.clip_distance[i] = -1.0;
        }
        return v;
    }
    vec3 world_offset = linear_world * cadr_vertex_position() + eye_relative;
    vec4 view_position = frame.view_rotation * vec4(world_offset, 1.0);
    mat3 linear = mat3(frame.view_rotation) * linear_world;
    mat3 cofactor = mat3(cross(linear[1], linear[2]), cross(linear[2], linear[0]), cross(linear[0], linear[1]));
    v.view_position = view_position.xyz;
    v.view_normal = cofactor * cadr_vertex_normal();
    v.base_color = object.base_color;
    if (highlighted && (frame.target.z & CADR_DISPLAY_HIGHLIGHT_OUTLINE) == 0u) {
        v.base_color.rgb = mix(v.base_color.rgb, frame.highlight.rgb, 0.65);
    }
    v.highlighted = highlighted ? 1u : 0u;
    v.surface = object.surface;
    v.texture = texture_info;
    vec2 uv = vec2(0.0);
    v.vertex_color = vec4(1.0);
#ifdef CADR_VERTEX_INDEX
    if ((frame.target.z & CADR_DISPLAY_VERTEX_ATTRIBUTES) != 0u) {
        uint at = cadr_vertex_index() * 3u;
        uv = vec2(uintBitsToFloat(cadr_host_vertex_attributes[at]),
                  uintBitsToFloat(cadr_host_vertex_attributes[at + 1u]));
        v.vertex_color = unpackUnorm4x8(cadr_host_vertex_attributes[at + 2u]);
    }
#endif
    vec3 homogeneous_uv = vec3(uv, 1.0);
    v.uv = vec2(dot(material_texture.u_row.xyz, homogeneous_uv),
                  dot(material_texture.v_row.xyz, homogeneous_uv));
    // The pick pass writes instance + 1; 0 (nothing) lets the click through unpickable parts.
    v.pick_id = (object.flags & CADR_INSTANCE_PICKABLE) != 0u ? object.instance + 1u : 0u;
    v.position = frame.projection * view_position;
    for (int i = 0; i < 6; ++i) {
        v.clip_distance[i] = dot(frame.section_planes[i].xyz, world_offset) + frame.section_planes[i].w;
    }
    v.eye_offset = world_offset;
    float closure = 0.0;
    if ((object.flags & CADR_INSTANCE_CLOSED) != 0u) {
        bool inside_out = (object.flags & CADR_INSTANCE_INSIDE_OUT) != 0u;
        bool mirrored = determinant(linear_world) < 0.0;
        closure = inside_out != mirrored ? -1.0 : 1.0;
    }
    v.closure = closure;
    return v;
}
