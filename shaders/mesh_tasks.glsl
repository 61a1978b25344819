// What the technique task and mesh shaders share (technique.task, technique.mesh): the
// submission's push constants after the paths' 128 bytes (the plugin ABI's CadrMeshTaskPush),
// the buffers they name by device address, and the payload a task workgroup hands its mesh
// workgroups.
// Needs GL_EXT_buffer_reference and GL_EXT_buffer_reference_uvec2, enabled by the includer.

// Commands a task workgroup reads, and triangles a mesh workgroup draws.
const uint CADR_MESH_COMMANDS_PER_TASK = 32u;
const uint CADR_MESH_TRIANGLES = 32u;
// Mesh workgroups launched per row (x); more take further rows (y).
const uint CADR_MESH_GROUPS_PER_ROW = 32768u;

layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer CadrMeshWords {
    uint values[];
};

// Push constants: bytes 0-127 belong to the paths (technique.vert's CadrPushConstants; a path
// that announces mesh shading pushes none), 128-159 to the submission.
layout(push_constant) uniform CadrPushConstants {
    mat4 matrix;
    vec4 vectors[2];
    uvec4 words[2];
    // The pass's first VkDrawIndexedIndirectCommand, its count, the scene's triangle indices.
    uvec2 commands;
    uvec2 count;
    uvec2 indices;
    uint max_draws;
    uint stride_words;
} cadr_push;

// Per task workgroup: its first command, and per command the end of its mesh workgroups
// (a running sum; the last is how many the task launched).
struct CadrMeshTaskPayload {
    uint first_command;
    uint chunk_ends[CADR_MESH_COMMANDS_PER_TASK];
};
taskPayloadSharedEXT CadrMeshTaskPayload cadr_payload;

// The mesh workgroups one command needs: its triangles in chunks, once per instance.
uint cadr_command_chunks(uint index_count, uint instance_count) {
    uint triangles = index_count / 3u;
    return (triangles + CADR_MESH_TRIANGLES - 1u) / CADR_MESH_TRIANGLES * instance_count;
}
