// The per-pixel keys (frame set binding 7): planes of one uint per pixel of the picture, pixel
// (x, y) of plane p at p * width * height + y * width + x, which the surface shaders record
// with atomicMin and the passes over the finished picture read. A key is the nearest surface's
// depth (float bits, non-negative, so they order as the floats) with its lowest bit 0 where
// that surface is a highlighted part's and 1 where not. A plane is cleared (every bit set: no
// surface) in each frame that uses it:
// - plane 0, the outline keys (CADR_DISPLAY_HIGHLIGHT_OUTLINE, frame.glsl): the opaque
//   surfaces and the highlighted translucent ones; outline.frag draws the band around
//   highlighted parts from them;
// - plane 1, the nearest surfaces (CADR_DISPLAY_NEAREST_SURFACES): every surface, translucent
//   ones included, which write no depth to the depth buffer; silhouettes.frag finds X-ray's
//   silhouettes in their depth, and in every edge mode draws the silhouettes of highlighted
//   parts in the highlight's line colour;
// - planes 2 and 3, the cap keys (CADR_DISPLAY_CAP_KEYS): in plane 2 the nearest opaque
//   fragment that shows a section cap, its lowest 3 bits the plane's index instead of the
//   highlight bit; in plane 3 the nearest opaque fragment that does not; cap_ties.frag paints
//   the caps that tie with another part's surface from them.
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
const uint CADR_NEAREST_SURFACES_PLANE = 1u;
const uint CADR_CAPS_PLANE = 2u;
const uint CADR_UNCAPPED_PLANE = 3u;

// Where the key of `pixel` in `plane` lies.
uint cadr_pixel_key_index(uint plane, uvec2 pixel) {
    return (plane * frame.target.y + pixel.y) * frame.target.x + pixel.x;
}

// Whether `key` is a highlighted part's surface (false where none was recorded).
bool cadr_key_highlighted(uint key) {
    return key != CADR_PIXEL_KEY_NOTHING && (key & 1u) == 0u;
}

// The depth of the surface `key` records (to within the lowest bit).
float cadr_key_depth(uint key) {
    return uintBitsToFloat(key & ~1u);
}

// A cap key (plane 2): the depth of the fragment (to within its lowest 3 bits) ...
float cadr_cap_key_depth(uint key) {
    return uintBitsToFloat(key & ~7u);
}

// ... and the index of the section plane whose cap it shows.
int cadr_cap_key_plane(uint key) {
    return int(key & 7u);
}

#if defined(CADR_PIXEL_KEYS_WRITTEN)
// Records a surface fragment in `plane` (the caller checks the plane's display bit).
void cadr_record_surface(uint plane, bool highlighted) {
    uint key = (floatBitsToUint(max(gl_FragCoord.z, 0.0)) & ~1u) | (highlighted ? 0u : 1u);
    atomicMin(cadr_pixel_keys[cadr_pixel_key_index(plane, uvec2(gl_FragCoord.xy))], key);
}

// Records a fragment that shows the cap of section plane `section_plane` in the caps plane.
void cadr_record_cap(int section_plane) {
    uint key = (floatBitsToUint(max(gl_FragCoord.z, 0.0)) & ~7u) | uint(section_plane);
    atomicMin(cadr_pixel_keys[cadr_pixel_key_index(CADR_CAPS_PLANE, uvec2(gl_FragCoord.xy))], key);
}
#else
void cadr_record_surface(uint plane, bool highlighted) {
}
void cadr_record_cap(int section_plane) {
}
#endif
