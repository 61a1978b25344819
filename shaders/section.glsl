// Section caps. A closed part cut by a section plane shows its inside through the cut: the
// back faces of its far side. Such a back face is visible only where the cut removed what was
// in front of it, so a visible back face of a closed part is painted as the cap: the view ray
// is followed back to where it entered the kept region (the last plane it crossed into), and
// the fragment takes that plane's cap colour, lit with the plane's normal.
// Needs frame.glsl and shading.glsl.

// The plane whose cut the fragment at world offset `eye_offset` from the eye is seen through
// (-1 when none: the eye is on the kept side of every plane, so no cut lies in front).
int section_cap_plane(vec3 eye_offset) {
    uint count = min(frame.section.x & 0xffu, 6u);
    float entry = 0.0;
    int plane = -1;
    for (uint i = 0u; i < count; ++i) {
        vec4 p = frame.section_planes[i];
        float along = dot(p.xyz, eye_offset);
        // The eye is on the cut side of this plane and the ray crosses into the kept side.
        if (p.w < 0.0 && along > 0.0) {
            float t = -p.w / along;
            if (t > entry) {
                entry = t;
                plane = int(i);
            }
        }
    }
    return plane;
}

// How much farther than another surface, as a fraction of that surface's distance, the face a
// cap is found on may lie and still tie with it (the bottom of a cut part standing on a plate
// lies in the plate's top): far under any part's thickness, far over the depth buffer's steps.
const float CADR_CAP_TIE = 1e-4;

// The distance along the view (view space looks down -z) of what lies at depth `depth`:
// depth = (a z + b) / (c z + d) from the projection, solved for z.
float cadr_view_distance(float depth) {
    float a = frame.projection[2][2];
    float b = frame.projection[3][2];
    float c = frame.projection[2][3];
    float d = frame.projection[3][3];
    return -(b - depth * d) / (depth * c - a);
}

// The depth of what lies at `distance` along the view (the inverse of cadr_view_distance).
float cadr_depth_at(float distance) {
    vec4 clip = frame.projection * vec4(0.0, 0.0, -distance, 1.0);
    return clip.z / clip.w;
}

// The world offset from the eye the surface and pick shaders give section_cap_of: interpolated
// only where caps can show (the host defines CADR_SURFACE_CAPS: caps on and some plane active);
// elsewhere section_cap_of finds no plane whatever the offset.
#ifdef CADR_SURFACE_CAPS
#define CADR_SURFACE_EYE_OFFSET in_eye_offset
#else
#define CADR_SURFACE_EYE_OFFSET vec3(0.0)
#endif

// The plane whose cap a fragment of a part closing as `closure` (in_closure) shows at world
// offset `eye_offset` from the eye: with caps on, a closed part seen from inside through a cut
// (-1 for every other fragment).
int section_cap_of(float closure, vec3 eye_offset) {
    bool seen_from_inside = closure * (gl_FrontFacing ? 1.0 : -1.0) < 0.0;
    if ((frame.section.x & CADR_SECTION_CAPS) == 0u || !seen_from_inside) {
        return -1;
    }
    return section_cap_plane(eye_offset);
}

// The colour of the cap of `plane` seen at world offset `eye_offset` from the eye
// (gamma-encoded, like shade_headlight).
vec3 section_cap_color(int plane, vec3 eye_offset) {
    vec3 view_normal = mat3(frame.view_rotation) * frame.section_planes[plane].xyz;
    vec3 view_position = (frame.view_rotation * vec4(eye_offset, 1.0)).xyz;
    vec3 color = shade_headlight(view_position, view_normal, frame.section_colors[plane], vec2(0.0, 0.7), frame.light,
                                 frame.view_rotation[1].xyz);
    if ((frame.section.x & CADR_SECTION_HATCHED) != 0u && mod(gl_FragCoord.x + gl_FragCoord.y, 8.0) < 2.0) {
        color *= 0.35;
    }
    return color;
}
