// What the host declares for a transparency method's snippets (see the plugin ABI's
// CadrTransparencyMethod): the pixel's index and the pixel count, and, when the method uses
// storage (CADR_STORAGE defined), its buffer at set 0, binding 1. Needs frame.glsl.

uint cadr_pixel_count() {
    return frame.target.x * frame.target.y;
}

uint cadr_pixel_index() {
    uvec2 pixel = uvec2(gl_FragCoord.xy);
    return pixel.y * frame.target.x + pixel.x;
}

#ifdef CADR_STORAGE
layout(set = 0, binding = 1, std430) buffer CadrTransparencyStorage {
    uint cadr_storage[];
};
#endif
