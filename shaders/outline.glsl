// The outline keys of the highlight outline style (CADR_DISPLAY_HIGHLIGHT_OUTLINE, frame.glsl),
// for the fragment shaders that record surfaces in them and the outline pass that reads them.
// The keys are written only where CADR_OUTLINE_KEYS is defined: the host defines it where the
// device has fragmentStoresAndAtomics (a fragment shader may not write storage otherwise, and
// the renderer refuses the style there); without it, recording does nothing.
#ifdef CADR_OUTLINE_KEYS

// With CADR_DISPLAY_HIGHLIGHT_OUTLINE, per pixel of the picture: the nearest surface's depth
// (float bits, non-negative, so they order as the floats) with its lowest bit 0 where that
// surface is highlighted and 1 where not; all bits set where no surface was drawn. Cleared
// every frame, written with atomicMin by the surface shaders, read by outline.frag.
layout(set = 0, binding = 7, std430) buffer CadrOutlineKeys {
    uint cadr_outline_keys[];
};
const uint CADR_OUTLINE_NOTHING = 0xffffffffu;

// Records a surface fragment in the outline keys (the caller checks the display bit).
void cadr_record_outline(bool highlighted) {
    uint pixel = uint(gl_FragCoord.y) * frame.target.x + uint(gl_FragCoord.x);
    uint key = (floatBitsToUint(max(gl_FragCoord.z, 0.0)) & ~1u) | (highlighted ? 0u : 1u);
    atomicMin(cadr_outline_keys[pixel], key);
}
#else
void cadr_record_outline(bool highlighted) {
}
#endif
