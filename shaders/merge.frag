#version 460
// The transparency merge: the method's snippet (pasted below by the host) turns what its
// targets and storage gathered at this pixel into a premultiplied colour with its coverage,
// which the pipeline blends over the opaque picture (rgb + picture * (1 - a)).
#extension GL_EXT_samplerless_texture_functions : require
#include "frame.glsl"
#include "transparency.glsl"

#if CADR_TARGET_COUNT > 0
layout(set = 1, binding = 0) uniform texture2D cadr_target_image_0;
#endif
#if CADR_TARGET_COUNT > 1
layout(set = 1, binding = 1) uniform texture2D cadr_target_image_1;
#endif

vec4 cadr_target_texel(int i) {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
#if CADR_TARGET_COUNT > 1
    if (i == 1) {
        return texelFetch(cadr_target_image_1, pixel, 0);
    }
#endif
#if CADR_TARGET_COUNT > 0
    return texelFetch(cadr_target_image_0, pixel, 0);
#else
    return vec4(0.0);
#endif
}

layout(location = 0) out vec4 out_color;

//@TRANSPARENCY@

void main() {
    out_color = cadr_merge();
}
