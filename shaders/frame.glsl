// Per-frame parameters (binding frequency "view"): set 0, binding 0.
// Mirrored by cadr_core::render::FrameUniforms; offsets are asserted in a test.
layout(set = 0, binding = 0, std140) uniform FrameUniforms {
    mat4 projection;       // view space -> clip space (Vulkan: y down, depth 0..1)
    mat4 view_rotation;    // world -> view space with the eye at the origin (no translation)
    vec4 eye_high;         // the eye's world position: f32 high part (xyz) ...
    vec4 eye_low;          // ... and the f32 remainder, split from f64 on the CPU
    vec4 light;            // x: ambient (sky and ground), y: diffuse, z: specular, w: unused
    // Section planes relative to the eye: n.xyz and d + n·eye (computed in f64 on the CPU);
    // a point at world offset o from the eye is kept where dot(n, o) + w >= 0. Unused: (0,0,0,1).
    vec4 section_planes[6];
    vec4 section_colors[6];  // cap colour of each plane (linear RGBA)
    uvec4 section;           // x: bits 0-7 plane count, bit 8 caps, bit 9 hatching
    uvec4 target;            // x, y: the target's width and height; z: CADR_DISPLAY_* bits
    vec4 background_top;     // the background at the top of the picture (display RGB) ...
    vec4 background_bottom;  // ... and at its bottom, blended linearly between
    vec4 edge_color;         // edge lines and silhouettes (display RGB)
    vec4 highlight;          // what highlighted parts are tinted towards or outlined in
                             // (display RGB); w: the outline band's width in pixels
} frame;

const uint CADR_SECTION_CAPS = 0x100u;
const uint CADR_SECTION_HATCHED = 0x200u;
// The pick pass's flag on ids whose pixel shows a cap (the host reads it as PICK_CAP_BIT).
const uint CADR_PICK_CAP = 0x80000000u;

// frame.target.z: the X-ray display mode (every part not highlighted drawn translucent).
const uint CADR_DISPLAY_XRAY = 1u;
// frame.target.z: the scene has vertex attributes (texture coordinates, colours) to read.
const uint CADR_DISPLAY_VERTEX_ATTRIBUTES = 2u;
// frame.target.z: materials' textures are sampled.
const uint CADR_DISPLAY_TEXTURES = 4u;
// frame.target.z: some material has a texture or an alpha mode other than BLEND (without, the
// vertex shader does not read the material descriptions).
const uint CADR_DISPLAY_MATERIAL_DESCRIPTIONS = 8u;
// The opacity of parts X-ray makes translucent.
const float CADR_XRAY_OPACITY = 0.2;
// frame.target.z: highlighted parts are outlined (their surfaces record themselves in the
// outline keys, binding 7) instead of tinted.
const uint CADR_DISPLAY_HIGHLIGHT_OUTLINE = 16u;
// frame.target.z: surfaces record themselves in the nearest surfaces (binding 7), where the
// silhouettes pass finds X-ray's silhouettes (its translucent surfaces write no depth) and
// which silhouettes outline highlighted parts.
const uint CADR_DISPLAY_NEAREST_SURFACES = 32u;
// frame.target.z: opaque surfaces record the cap keys (binding 7), from which cap_ties.frag
// paints the caps that tie with another part's surface (caps on, and seen).
const uint CADR_DISPLAY_CAP_KEYS = 64u;

// The colour of edge lines and silhouettes: a highlighted part's in a darker highlight
// colour, so that a highlight shows in the line-only modes too, and on a tinted surface.
vec3 cadr_line_color(bool highlighted) {
    return highlighted ? 0.7 * frame.highlight.rgb : frame.edge_color.rgb;
}
