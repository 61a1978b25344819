#version 460
// Silhouette edges over the finished picture of the edge display modes (edges, hidden-line,
// X-ray): the outlines of curved surfaces (a cylinder's sides, a sphere's rim), which no
// feature edge marks, found where the depth breaks: the depth buffer's, or in X-ray, whose
// translucent surfaces write none, the nearer of it and the nearest surface every fragment
// recorded (CADR_DISPLAY_NEAREST_SURFACES, pixel_keys.glsl): a surface's fragments under its
// own edge lines fail the depth test there and record nothing. A pixel is on a silhouette
// when a neighbour is uncovered, or lies farther than the surface through this pixel and the
// one opposite predicts by more than a few pixel widths (the depth buffer is linear in screen
// space across a plane, so the prediction is exact on planes and close on gently curved
// surfaces). The line goes on the near side, drawn over the picture (premultiplied), in the
// edge lines' colour, or where the nearest surfaces are recorded and the surface it outlines
// is a highlighted part's, in the highlight's line colour, as that part's edge lines.
#extension GL_EXT_samplerless_texture_functions : require
#define CADR_PIXEL_KEYS_READ
#include "frame.glsl"
#include "pixel_keys.glsl"

layout(set = 1, binding = 0) uniform texture2D depth_image;

layout(location = 0) out vec4 out_color;

// How much farther than predicted a neighbour must lie, in pixel widths at this pixel's
// distance, to break the surface.
const float BREAK_PIXELS = 3.0;

vec3 view_position(vec2 pixel, float depth, mat4 inverse_projection) {
    vec2 ndc = pixel / vec2(frame.target.xy) * 2.0 - 1.0;
    vec4 view = inverse_projection * vec4(ndc, depth, 1.0);
    return view.xyz / view.w;
}

// The nearest surface's (or line's) depth at `pixel`, 1 where none is.
const uint XRAY_SURFACES = CADR_DISPLAY_XRAY | CADR_DISPLAY_NEAREST_SURFACES;

// The nearest surface's key at `pixel`, nothing where the frame does not record them.
uint nearest_surface(ivec2 pixel) {
    if ((frame.target.z & CADR_DISPLAY_NEAREST_SURFACES) == 0u) {
        return CADR_PIXEL_KEY_NOTHING;
    }
    return cadr_pixel_keys[cadr_pixel_key_index(CADR_NEAREST_SURFACES_PLANE, uvec2(pixel))];
}

float depth_at(ivec2 pixel) {
    float depth = texelFetch(depth_image, pixel, 0).r;
    if ((frame.target.z & XRAY_SURFACES) == XRAY_SURFACES) {
        uint key = nearest_surface(pixel);
        if (key != CADR_PIXEL_KEY_NOTHING) {
            depth = min(depth, cadr_key_depth(key));
        }
    }
    return depth;
}

// The silhouette's line at `pixel`, in the colour of the surface it outlines.
vec4 line_at(ivec2 pixel) {
    return vec4(cadr_line_color(cadr_key_highlighted(nearest_surface(pixel))), 1.0);
}

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    ivec2 size = ivec2(frame.target.xy);
    float depth = depth_at(pixel);
    out_color = vec4(0.0);
    if (depth >= 1.0) {
        return;
    }
    mat4 inverse_projection = inverse(frame.projection);
    vec3 center = view_position(gl_FragCoord.xy, depth, inverse_projection);
    float pixel_width = length(view_position(gl_FragCoord.xy + vec2(1.0, 0.0), depth, inverse_projection) - center);
    const ivec2 directions[4] = ivec2[4](ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1));
    for (int i = 0; i < 4; ++i) {
        ivec2 neighbour = pixel + directions[i];
        if (any(lessThan(neighbour, ivec2(0))) || any(greaterThanEqual(neighbour, size))) {
            continue;
        }
        float neighbour_depth = depth_at(neighbour);
        if (neighbour_depth >= 1.0) {
            out_color = line_at(pixel);
            return;
        }
        ivec2 opposite = pixel - directions[i];
        float predicted = depth;
        if (all(greaterThanEqual(opposite, ivec2(0))) && all(lessThan(opposite, size))) {
            float opposite_depth = depth_at(opposite);
            if (opposite_depth < 1.0) {
                predicted = clamp(2.0 * depth - opposite_depth, 0.0, 1.0);
            }
        }
        vec2 at = vec2(neighbour) + 0.5;
        // View space looks down -z: the distance along the view is -z.
        float farther = view_position(at, predicted, inverse_projection).z
            - view_position(at, neighbour_depth, inverse_projection).z;
        if (farther > BREAK_PIXELS * pixel_width) {
            out_color = line_at(pixel);
            return;
        }
    }
}
