// What the technique task and mesh shaders share (technique.task, technique.mesh): the
// submission's push constants after the paths' 128 bytes (the plugin ABI's CadrMeshTaskPush),
// the buffers they name by device address, and the payload a task workgroup hands its mesh
// workgroups.
// Needs GL_EXT_buffer_reference and GL_EXT_buffer_reference_uvec2, enabled by the includer.

// Triangles a mesh workgroup draws.
const uint CADR_MESH_TRIANGLES = 32u;
// Mesh workgroups launched per row (x); more take further rows (y).
const uint CADR_MESH_GROUPS_PER_ROW = 32768u;

layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer CadrMeshWords {
    uint values[];
};

// Push constants: bytes 0-127 belong to the paths (technique.vert's CadrPushConstants; a path
// that announces mesh shading pushes none), 128-151 to the submission.
layout(push_constant) uniform CadrPushConstants {
    mat4 matrix;
    vec4 vectors[2];
    uvec4 words[2];
    // The pass's first VkDrawIndexedIndirectCommand and the scene's triangle indices.
    uvec2 commands;
    uvec2 indices;
    uint stride_words;
} cadr_push;

// What a task workgroup hands its mesh workgroups: the command they draw, and how many of them
// there are (a chunk of the command's triangles, for one of its instances, each).
struct CadrMeshTaskPayload {
    uint command;
    uint chunks;
};
taskPayloadSharedEXT CadrMeshTaskPayload cadr_payload;

// The mesh workgroups one command needs: its triangles in chunks, once per instance.
uint cadr_command_chunks(uint index_count, uint instance_count) {
    uint triangles = index_count / 3u;
    return (triangles + CADR_MESH_TRIANGLES - 1u) / CADR_MESH_TRIANGLES * instance_count;
}
