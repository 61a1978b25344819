#version 460
// The hidden edge lines of the hidden-line display mode, when they are shown dashed: a
// lighter shade of the visible lines' colour (a highlighted part's of the highlight's line
// colour, cadr_line_color), dashed by a checkerboard of 4 x 5 pixel cells in
// screen space: a line of any direction crosses cells in turn, so it shows dashes of 4 to 5
// pixels (cells of unequal sides, so that 45-degree lines do not run along cell corners).
#include "frame.glsl"
layout(location = 0) in vec3 in_view_position;
layout(location = 1) in vec3 in_view_normal;
layout(location = 2) flat in vec4 in_base_color;
layout(location = 3) flat in vec2 in_surface;
layout(location = 11) flat in uint in_highlighted;

layout(location = 0) out vec4 out_color;

void main() {
    ivec2 cell = ivec2(gl_FragCoord.xy) / ivec2(4, 5);
    if (((cell.x + cell.y) & 1) != 0) {
        discard;
    }
    out_color = vec4(mix(cadr_line_color(in_highlighted != 0u), vec3(1.0), 0.42), 1.0);
}
