#version 460
// Section caps where the face a cap is found on ties with another part's surface, over the
// finished opaque picture. A cap shows on the back faces of a closed part seen through the
// cut (section.glsl); where such a face lies in another part's surface (the bottom of a cut
// part standing on a plate, in the plate's top) the two are at one depth, and the depth test
// lets either win, pixel by pixel, so the plate would show through the cap in patches. From
// the cap keys the opaque surfaces recorded (CADR_DISPLAY_CAP_KEYS, pixel_keys.glsl): where
// the nearest cap fragment and the nearest other surface tie (their distances differ by under
// a relative CADR_CAP_TIE, section.glsl; the cap key's lowest bits hold the plane,
// so exact ties cannot be told from near ones), the cap is painted as shaded.frag paints it,
// at the position the cap fragment had. Where the cap lies clearly nearer, the surfaces
// painted it already (with their anti-aliasing), and where a surface lies clearly in front,
// the cap is hidden.
#define CADR_PIXEL_KEYS_READ
#include "frame.glsl"
#include "shading.glsl"
#include "section.glsl"
#include "pixel_keys.glsl"

layout(location = 0) out vec4 out_color;

void main() {
    uvec2 pixel = uvec2(gl_FragCoord.xy);
    out_color = vec4(0.0);
    uint cap = cadr_pixel_keys[cadr_pixel_key_index(CADR_CAPS_PLANE, pixel)];
    uint other = cadr_pixel_keys[cadr_pixel_key_index(CADR_UNCAPPED_PLANE, pixel)];
    if (cap == CADR_PIXEL_KEY_NOTHING || other == CADR_PIXEL_KEY_NOTHING) {
        return;
    }
    float cap_depth = cadr_cap_key_depth(cap);
    float other_depth = cadr_key_depth(other);
    float other_distance = cadr_view_distance(other_depth);
    if (abs(cadr_view_distance(cap_depth) - other_distance) > CADR_CAP_TIE * other_distance) {
        return;
    }
    vec2 ndc = gl_FragCoord.xy / vec2(frame.target.xy) * 2.0 - 1.0;
    vec4 view = inverse(frame.projection) * vec4(ndc, cap_depth, 1.0);
    vec3 eye_offset = transpose(mat3(frame.view_rotation)) * (view.xyz / view.w);
    out_color = vec4(section_cap_color(cadr_cap_key_plane(cap), eye_offset), 1.0);
}
