#version 460
// The outline highlight style: over the finished picture, a band in the highlight colour
// (frame.highlight; its w is the band's width in pixels, 1 to 8, 2 by default) around every
// region where the nearest surface is a highlighted part's (from the outline keys its surfaces
// recorded, pixel_keys.glsl). The band lies outside the
// part, over what surrounds it; the part itself keeps its own colours.
#define CADR_PIXEL_KEYS_READ
#include "frame.glsl"
#include "pixel_keys.glsl"

layout(location = 0) out vec4 out_color;

// The widest band the host allows (Palette::MAX_OUTLINE_WIDTH): the search window's bound.
const int MAX_RADIUS = 8;

bool highlighted_at(ivec2 pixel) {
    return cadr_key_highlighted(cadr_pixel_keys[cadr_pixel_key_index(CADR_OUTLINE_PLANE, uvec2(pixel))]);
}

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    ivec2 size = ivec2(frame.target.xy);
    out_color = vec4(0.0);
    if (highlighted_at(pixel)) {
        return;
    }
    int radius = clamp(int(frame.highlight.w), 1, MAX_RADIUS);
    float nearest = 2.0 * float(radius);
    for (int dy = -radius; dy <= radius; ++dy) {
        for (int dx = -radius; dx <= radius; ++dx) {
            ivec2 other = pixel + ivec2(dx, dy);
            if (any(lessThan(other, ivec2(0))) || any(greaterThanEqual(other, size))) {
                continue;
            }
            if (highlighted_at(other)) {
                nearest = min(nearest, length(vec2(dx, dy)));
            }
        }
    }
    // Full inside the radius, half at the window's corners: rounded outer corners.
    float coverage = nearest <= float(radius) ? 1.0 : (nearest < 2.0 * float(radius) ? 0.5 : 0.0);
    out_color = vec4(frame.highlight.rgb * coverage, coverage);
}
