#version 460
// Sparse upload (seed 000: "gathers all updates, uploads them as compact buffer and scatters on
// the GPU"): the CPU packs only the changed matrices with their slots; this moves each into place.
layout(local_size_x = 64) in;

struct MatrixUpdate {
    uint slot;
    uint pad0;
    uint pad1;
    uint pad2;
    mat4 matrix;           // its translation: the f32 high part
    vec4 translation_low;  // the f32 remainder of the translation
};

layout(set = 0, binding = 0, std430) readonly buffer Updates { MatrixUpdate updates[]; };
layout(set = 0, binding = 1, std430) writeonly buffer Matrices { mat4 world_from_object[]; };
layout(set = 0, binding = 2, std430) writeonly buffer TranslationLows { vec4 translation_low[]; };

layout(push_constant) uniform Count { uint update_count; } pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i < pc.update_count) {
        world_from_object[updates[i].slot] = updates[i].matrix;
        translation_low[updates[i].slot] = updates[i].translation_low;
    }
}
