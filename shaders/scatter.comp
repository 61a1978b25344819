#version 460
// Sparse upload (seed 000: "gathers all updates, uploads them as compact buffer and scatters on
// the GPU"): the CPU packs only the changed items of one array, each as its slot followed by
// its words; this moves every word into place. One shader serves every array of the GPU scene
// (matrices, materials, instance records): the item size is a push constant.
layout(local_size_x = 64) in;

layout(set = 0, binding = 0, std430) readonly buffer Updates { uint update_words[]; };
layout(set = 0, binding = 1, std430) writeonly buffer Target { uint target_words[]; };

layout(push_constant) uniform Scatter {
    uint item_count;       // items in this dispatch
    uint item_words;       // 32-bit words per item (without its slot)
    uint first_word;       // where this dispatch's items start in update_words
} scatter;

void main() {
    uint word = gl_GlobalInvocationID.x;
    uint item = word / scatter.item_words;
    if (item >= scatter.item_count) {
        return;
    }
    uint within = word % scatter.item_words;
    uint source = scatter.first_word + item * (scatter.item_words + 1u);
    // The top bit of a slot word is a mark for later passes (the transform hierarchy's moved
    // roots), not part of the slot.
    uint slot = update_words[source] & 0x7fffffffu;
    target_words[slot * scatter.item_words + within] = update_words[source + 1u + within];
}
