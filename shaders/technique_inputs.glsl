// What the technique vertex and mesh shaders read before the paths' snippets: the host's
// buffers of the frame set, the object a parameter path returns and the push constants the
// paths own. Included by technique.vert and technique.mesh after frame.glsl.

// The GPU scene's instance records (matrix, material, flags, instance), by instance id.
layout(set = 0, binding = 2, std430) readonly buffer CadrHostInstanceRecords {
    uvec4 cadr_host_instance_records[];
};
// Per material slot: the texture-coordinate transform's rows (xyz), and layer + 1 (0: none),
// sampling bits, alpha mode, the mask's cutoff (float bits). See gpu_scene/textures.rs.
struct CadrMaterialTexture {
    vec4 u_row;
    vec4 v_row;
    uvec4 info;
};
layout(set = 0, binding = 3, std430) readonly buffer CadrHostMaterialTextures {
    CadrMaterialTexture cadr_host_material_textures[];
};
// Per vertex of the vertex arena (with CADR_DISPLAY_VERTEX_ATTRIBUTES): u, v (float bits),
// colour (RGBA8).
layout(set = 0, binding = 4, std430) readonly buffer CadrHostVertexAttributes {
    uint cadr_host_vertex_attributes[];
};

// The GPU scene's cull entries by instance id, three vec4 each: the first is the part's
// bounding sphere in object space (centre, radius). See CadrCullEntry in the plugin ABI.
layout(set = 0, binding = 8, std430) readonly buffer CadrHostCullEntries {
    vec4 cadr_host_cull_entries[];
};

struct CadrObject {
    mat4 world;            // column 3: translation high part; w of columns 0-2: low part
    vec4 base_color;
    vec2 surface;
    uint flags;            // CADR_INSTANCE_* bits
    uint instance;
};

const uint CADR_INSTANCE_HIGHLIGHTED = 1u;
const uint CADR_INSTANCE_PICKABLE = 2u;
