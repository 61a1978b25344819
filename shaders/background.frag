#version 460
// The background: a vertical gradient, blended under what the frame drew. The picture's alpha
// is its coverage (opaque surfaces and lines 1, translucent ones what they cover, nothing 0),
// so the pipeline's blend is background * (1 - coverage) + picture.
#include "frame.glsl"

layout(location = 0) out vec4 out_color;

void main() {
    float down = gl_FragCoord.y / float(max(frame.target.y, 1u));
    out_color = vec4(mix(frame.background_top.rgb, frame.background_bottom.rgb, down), 1.0);
}
