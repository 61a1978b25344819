#version 460
// One level of the depth pyramid for gpu-occlusion. Level 0 is the depth image itself, a texel
// a pixel: parts a few pixels across, seen through gaps a few pixels wide, are tested against
// each pixel's depth. Each texel of a level above keeps the farthest depth of the 2 × 2 texels
// below it; edges of odd sizes are clamped so that every texel below is covered. Levels lie one
// after the other in one buffer.
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform sampler2D depth;
layout(set = 0, binding = 1, std430) buffer Pyramid { float pyramid[]; };

layout(push_constant) uniform Level {
    uvec2 source_size;   // size of the level below (the depth image's for level 0)
    uvec2 size;          // size of this level
    uint source_offset;  // where the level below starts (unused for level 0)
    uint offset;         // where this level starts
    uint from_depth;     // 1 for level 0, the depth image copied
} level;

float source(uvec2 texel) {
    texel = min(texel, level.source_size - 1u);
    if (level.from_depth != 0u) {
        return texelFetch(depth, ivec2(texel), 0).r;
    }
    return pyramid[level.source_offset + texel.y * level.source_size.x + texel.x];
}

void main() {
    uvec2 texel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(texel, level.size))) {
        return;
    }
    if (level.from_depth != 0u) {
        pyramid[level.offset + texel.y * level.size.x + texel.x] = source(texel);
        return;
    }
    uvec2 base = texel * 2u;
    float farthest = max(max(source(base), source(base + uvec2(1u, 0u))),
                         max(source(base + uvec2(0u, 1u)), source(base + uvec2(1u, 1u))));
    pyramid[level.offset + texel.y * level.size.x + texel.x] = farthest;
}
