// The per-pixel keys (frame set binding 7): planes of one uint per pixel of the picture, pixel
// (x, y) of plane p at p * width * height + y * width + x, which the surface shaders record
// with atomicMin and the passes over the finished picture read. A plane is cleared (every bit
// set: no surface) in each frame that uses it:
// - plane 0, the outline keys (CADR_DISPLAY_HIGHLIGHT_OUTLINE, frame.glsl): the nearest
//   surface's depth (float bits, non-negative, so they order as the floats) with its lowest
//   bit 0 where that surface is highlighted and 1 where not; outline.frag draws the band
//   around highlighted parts from them;
// - plane 1, the nearest depth (CADR_DISPLAY_NEAREST_DEPTH): the nearest surface's depth,
//   translucent surfaces included, which write none to the depth buffer; silhouettes.frag
//   finds X-ray's silhouettes in it.
// Recording needs fragmentStoresAndAtomics: the host defines CADR_PIXEL_KEYS_WRITTEN for the
// surface shaders where the device has it (the renderer asks for neither plane elsewhere), and
// without it recording does nothing. A pass that only reads defines CADR_PIXEL_KEYS_READ.
#if defined(CADR_PIXEL_KEYS_WRITTEN)
layout(set = 0, binding = 7, std430) buffer CadrPixelKeys {
    uint cadr_pixel_keys[];
};
#elif defined(CADR_PIXEL_KEYS_READ)
layout(set = 0, binding = 7, std430) readonly buffer CadrPixelKeys {
    uint cadr_pixel_keys[];
};
#endif

const uint CADR_PIXEL_KEY_NOTHING = 0xffffffffu;
const uint CADR_OUTLINE_PLANE = 0u;
const uint CADR_NEAREST_DEPTH_PLANE = 1u;

// Where the key of `pixel` in `plane` lies.
uint cadr_pixel_key_index(uint plane, uvec2 pixel) {
    return (plane * frame.target.y + pixel.y) * frame.target.x + pixel.x;
}

#if defined(CADR_PIXEL_KEYS_WRITTEN)
// Records a surface fragment in the outline keys (the caller checks the display bit).
void cadr_record_outline(bool highlighted) {
    uint key = (floatBitsToUint(max(gl_FragCoord.z, 0.0)) & ~1u) | (highlighted ? 0u : 1u);
    atomicMin(cadr_pixel_keys[cadr_pixel_key_index(CADR_OUTLINE_PLANE, uvec2(gl_FragCoord.xy))], key);
}

// Records a surface fragment's depth in the nearest depth (the caller checks the display bit).
void cadr_record_nearest_depth() {
    uint key = floatBitsToUint(max(gl_FragCoord.z, 0.0));
    atomicMin(cadr_pixel_keys[cadr_pixel_key_index(CADR_NEAREST_DEPTH_PLANE, uvec2(gl_FragCoord.xy))], key);
}
#else
void cadr_record_outline(bool highlighted) {
}
void cadr_record_nearest_depth() {
}
#endif
