#version 460
// Screen-space ambient occlusion over the finished opaque picture: for each covered pixel, the
// view-space point under it (from the depth) and its normal (from the point's screen
// derivatives); nearby points of the depth buffer that stand above that surface, within a
// radius of a few percent of the picture's height, occlude it. The result darkens the
// picture's colour (blend: dst × (1 − a)), leaving its coverage alone: the background and
// the translucent surfaces merged after it are not darkened.
#extension GL_EXT_samplerless_texture_functions : require
#include "frame.glsl"

layout(set = 1, binding = 0) uniform texture2D depth_image;

layout(location = 0) out vec4 out_color;

// Samples per pixel, on a spiral out to the radius.
const int SAMPLES = 12;
// The radius, as a share of the picture's height.
const float RADIUS_SHARE = 0.025;
// How dark a fully occluded pixel gets.
const float STRENGTH = 0.9;

vec3 view_position(vec2 pixel, float depth, mat4 inverse_projection) {
    vec2 ndc = pixel / vec2(frame.target.xy) * 2.0 - 1.0;
    vec4 view = inverse_projection * vec4(ndc, depth, 1.0);
    return view.xyz / view.w;
}

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    float depth = texelFetch(depth_image, pixel, 0).r;
    mat4 inverse_projection = inverse(frame.projection);
    vec3 center = view_position(gl_FragCoord.xy, depth, inverse_projection);
    // Derivatives need every pixel of the quad, so background pixels return only now.
    vec3 normal = normalize(cross(dFdx(center), dFdy(center)));
    if (depth >= 1.0) {
        out_color = vec4(0.0);
        return;
    }
    if (dot(normal, -center) < 0.0) {
        normal = -normal;
    }
    float radius_pixels = RADIUS_SHARE * float(frame.target.y);
    // The radius in view units at this point's distance.
    float radius = radius_pixels * abs(center.z) * 2.0 / (abs(frame.projection[1][1]) * float(frame.target.y));
    float occlusion = 0.0;
    for (int i = 0; i < SAMPLES; ++i) {
        float t = (float(i) + 0.5) / float(SAMPLES);
        float angle = 2.399963 * float(i); // the golden angle: samples spread evenly
        vec2 offset = vec2(cos(angle), sin(angle)) * (t * radius_pixels);
        ivec2 sample_pixel = clamp(pixel + ivec2(offset), ivec2(0), ivec2(frame.target.xy) - 1);
        float sample_depth = texelFetch(depth_image, sample_pixel, 0).r;
        if (sample_depth >= 1.0) {
            continue;
        }
        vec3 point = view_position(vec2(sample_pixel) + 0.5, sample_depth, inverse_projection);
        vec3 to_point = point - center;
        float distance = length(to_point);
        if (distance < 1e-6 * abs(center.z)) {
            continue;
        }
        float above = dot(normal, to_point / distance) - 0.15;
        float near = 1.0 - smoothstep(0.5 * radius, radius, distance);
        occlusion += max(above, 0.0) * near;
    }
    float darkening = clamp(STRENGTH * occlusion / float(SAMPLES) * 2.0, 0.0, 0.7);
    out_color = vec4(0.0, 0.0, 0.0, darkening);
}
