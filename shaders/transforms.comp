#version 460
// The transform hierarchy on the GPU (core/src/gpu_scene/hierarchy.rs): moved nodes' local
// matrices arrived through the sparse upload, each behind its slot word with the top bit set;
// these stages recompute the world matrices of their subtrees. One pipeline, four stages
// chosen by a push constant:
//   stamp:  every moved root marks itself with this frame's stamp;
//   roots:  one work group: a root below another stamped root gets an empty range, the others
//           their subtree's range; ranges are laid end to end (prefix sum);
//   leaves: one thread per node of the ranges multiplies the locals up to its root and the
//           root's parent's world matrix;
//   level:  one thread per node of the ranges; those `level` below their root multiply their
//           parent's world matrix (written by the previous level) by their local matrix.
// Matrices are affine: rotation and scale in f32, translations as f32 high + low parts, added
// with error-free sums (`precise`), so parts far from the origin keep their precision.
layout(local_size_x = 64) in;

const uint NONE = 0xffffffffu;
const uint MARK = 0x80000000u;
const uint STAGE_STAMP = 0u;
const uint STAGE_ROOTS = 1u;
const uint STAGE_LEAVES = 2u;
const uint STAGE_LEVEL = 3u;
const uint LOCAL_WORDS = 15u;

layout(set = 0, binding = 0, std430) readonly buffer Updates { uint update_words[]; };
layout(set = 0, binding = 1, std430) readonly buffer Locals { float local_words[]; };
// Per tree node: parent, first (position in depth-first order), depth, subtree size.
layout(set = 0, binding = 2, std430) readonly buffer Nodes { uvec4 nodes[]; };
layout(set = 0, binding = 3, std430) readonly buffer Order { uint order[]; };
layout(set = 0, binding = 4, std430) buffer Stamps { uint stamps[]; };
// Per moved root: node, first, size (0 when below another moved root), prefix.
layout(set = 0, binding = 5, std430) buffer Roots { uvec4 roots[]; };
// CadrMatrix per tree node: columns 0-2 rotation/scale with the translation's low part in w,
// column 3 the translation's high part.
layout(set = 0, binding = 6, std430) buffer Worlds { vec4 world_columns[]; };

layout(push_constant) uniform Hierarchy {
    uint stage;
    uint first_word;  // the locals' first item in update_words
    uint root_count;  // locals uploaded this frame (marked or not)
    uint stamp;
    uint total;       // nodes in the ranges
    uint level;
} pc;

struct Affine {
    mat3 r;
    vec3 high;
    vec3 low;
};

Affine load_local(uint n) {
    uint b = n * LOCAL_WORDS;
    Affine a;
    a.r = mat3(vec3(local_words[b], local_words[b + 1u], local_words[b + 2u]),
               vec3(local_words[b + 4u], local_words[b + 5u], local_words[b + 6u]),
               vec3(local_words[b + 8u], local_words[b + 9u], local_words[b + 10u]));
    a.low = vec3(local_words[b + 3u], local_words[b + 7u], local_words[b + 11u]);
    a.high = vec3(local_words[b + 12u], local_words[b + 13u], local_words[b + 14u]);
    return a;
}

Affine load_world(uint n) {
    vec4 c0 = world_columns[n * 4u];
    vec4 c1 = world_columns[n * 4u + 1u];
    vec4 c2 = world_columns[n * 4u + 2u];
    vec4 c3 = world_columns[n * 4u + 3u];
    Affine a;
    a.r = mat3(c0.xyz, c1.xyz, c2.xyz);
    a.low = vec3(c0.w, c1.w, c2.w);
    a.high = c3.xyz;
    return a;
}

void store_world(uint n, Affine a) {
    world_columns[n * 4u] = vec4(a.r[0], a.low.x);
    world_columns[n * 4u + 1u] = vec4(a.r[1], a.low.y);
    world_columns[n * 4u + 2u] = vec4(a.r[2], a.low.z);
    world_columns[n * 4u + 3u] = vec4(a.high, 1.0);
}

// a ∘ b: b's translation is turned by a's rotation and added to a's translation as a sum of
// two floats (Knuth's two-sum, then renormalized).
Affine compose(Affine a, Affine b) {
    Affine c;
    c.r = a.r * b.r;
    precise vec3 turned = a.r * b.high;
    precise vec3 sum = a.high + turned;
    precise vec3 virtual_b = sum - a.high;
    precise vec3 error = (a.high - (sum - virtual_b)) + (turned - virtual_b);
    precise vec3 low = error + a.low + a.r * b.low;
    precise vec3 high = sum + low;
    precise vec3 rest = low - (high - sum);
    c.high = high;
    c.low = rest;
    return c;
}

shared uint scan[64];

void stamp_roots() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.root_count) {
        return;
    }
    uint word = update_words[pc.first_word + i * (LOCAL_WORDS + 1u)];
    if ((word & MARK) != 0u) {
        stamps[word & ~MARK] = pc.stamp;
    }
}

void lay_out_roots() {
    uint lane = gl_LocalInvocationID.x;
    uint offset = 0u;
    for (uint base = 0u; base < pc.root_count; base += 64u) {
        uint i = base + lane;
        uint node = NONE;
        uint first = 0u;
        uint size = 0u;
        if (i < pc.root_count) {
            uint word = update_words[pc.first_word + i * (LOCAL_WORDS + 1u)];
            node = word & ~MARK;
            uvec4 info = nodes[node];
            first = info.y;
            if ((word & MARK) != 0u) {
                size = info.w;
                for (uint p = info.x; p != NONE; p = nodes[p].x) {
                    if (stamps[p] == pc.stamp) {
                        size = 0u;
                        break;
                    }
                }
            }
        }
        scan[lane] = size;
        barrier();
        for (uint d = 1u; d < 64u; d <<= 1u) {
            uint add = lane >= d ? scan[lane - d] : 0u;
            barrier();
            scan[lane] += add;
            barrier();
        }
        if (i < pc.root_count) {
            roots[i] = uvec4(node, first, size, offset + scan[lane] - size);
        }
        offset += scan[63];
        barrier();
    }
}

// The root range holding node number k of the frame, and that node.
uvec2 node_of(uint k, out uvec4 root) {
    uint lo = 0u;
    uint hi = pc.root_count - 1u;
    while (lo < hi) {
        uint mid = (lo + hi + 1u) / 2u;
        if (roots[mid].w <= k) {
            lo = mid;
        } else {
            hi = mid - 1u;
        }
    }
    root = roots[lo];
    return uvec2(root.x, order[root.y + (k - root.w)]);
}

void main() {
    if (pc.stage == STAGE_STAMP) {
        stamp_roots();
        return;
    }
    if (pc.stage == STAGE_ROOTS) {
        lay_out_roots();
        return;
    }
    uint k = gl_GlobalInvocationID.x;
    if (k >= pc.total) {
        return;
    }
    uvec4 root;
    uint node = node_of(k, root).y;
    if (pc.stage == STAGE_LEAVES) {
        Affine acc = load_local(node);
        uint p = node;
        while (p != root.x) {
            p = nodes[p].x;
            acc = compose(load_local(p), acc);
        }
        uint parent = nodes[root.x].x;
        if (parent != NONE) {
            acc = compose(load_world(parent), acc);
        }
        store_world(node, acc);
    } else {
        uvec4 info = nodes[node];
        if (info.z - nodes[root.x].z != pc.level) {
            return;
        }
        Affine local = load_local(node);
        store_world(node, info.x == NONE ? local : compose(load_world(info.x), local));
    }
}
