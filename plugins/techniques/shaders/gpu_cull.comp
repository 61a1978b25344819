#version 460
#extension GL_EXT_control_flow_attributes : require
// GPU culling (gpu-frustum, gpu-occlusion): one invocation per instance id tests the part's
// bounding sphere, placed by its GPU matrix relative to the eye, against the frustum and, for
// occlusion, against the depth pyramid of what was drawn first; a part that passes gets an
// indirect command appended for this pass, and the count goes where
// vkCmdDrawIndexedIndirectCount reads it. Parts projecting under the host's sub-pixel
// threshold (off by default) and parts a section plane cuts away whole are culled too, and a
// pass gets no commands for the parts its filter leaves out (the X-ray mode's opaque pass
// draws only highlighted parts, the section caps' pass only closed parts a plane cuts).
//
// Where the host splits the opaque surfaces by their back faces (CadrBackFacePasses), each part
// goes to one of the two passes: the closed parts whose back faces cannot show to the pass whose
// rasterizer culls them, the others to the pass that draws both faces. Where the submission
// picks the pipeline per command (dgc), both passes write one stream, each command naming its
// pass.
//
// With CLUSTERS defined (gpu-clusters), a part that passes gets, in the triangle passes, its
// clusters instead of one command: those of its level-of-detail cut (the coarsest whose error
// projects at or under the threshold), each tested against the frustum, the section planes,
// its normal cone where back faces cannot show, and in phase 1 the depth pyramid; clusters
// that follow each other in the index buffer are drawn by one command. Edge passes draw the
// part's edges whole, or a coarser level of them whose error projects under half the
// threshold.
layout(local_size_x = 64) in;

const uint PASS_EDGES = 1u;
const uint PASS_PICK = 2u;
const uint INSTANCE_PICKABLE = 2u;
const uint INSTANCE_CANDIDATE = 8u;
const uint INSTANCE_CLOSED = 16u;
const uint INSTANCE_INSIDE_OUT = 32u;
const uint INSTANCE_TRANSLUCENT = 64u;
const uint INSTANCE_CUTOUT = 512u;
const uint INSTANCE_EDGE_LEVELS = 1024u;
// Edge levels are chosen at this share of the threshold: a line a pixel off has left its
// pixels, where a surface a pixel off has only moved its outline.
const float EDGE_ERROR_SHARE = 0.5;

// Which parts a pass takes by their back faces (CADR_FACES_*).
const uint FACES_ANY = 0u;
const uint FACES_CULLED = 1u;
const uint FACES_KEPT = 2u;

// What this dispatch does.
const uint MODE_FRUSTUM = 0u;          // frustum only
const uint MODE_LAST_VISIBLE = 1u;     // occlusion phase 0: what was visible last frame
const uint MODE_NEWLY_VISIBLE = 2u;    // occlusion phase 1: test the pyramid, draw what is new

struct CullEntry {
    vec4 sphere;
    uint first_index;
    uint index_count;
    uint first_wire_index;
    uint wire_index_count;
    uint vertex_base;
    uint matrix;
    uint flags;
    uint first_cluster;
};

struct Matrix {
    vec4 columns[4];
};

layout(set = 0, binding = 0, std430) readonly buffer Entries { CullEntry entries[]; };
layout(set = 0, binding = 1, std430) readonly buffer Matrices { Matrix matrices[]; };
layout(set = 0, binding = 2, std430) writeonly buffer Commands { uint commands[]; };
// [0..8): commands per pass slot; [8]: commands in all; [9]: triangles drawn; [10]: clusters
// drawn (gpu-clusters); [11..19): per pass slot, the cluster commands asked for (gpu-clusters'
// budget).
layout(set = 0, binding = 3, std430) buffer Counts { uint counts[]; };
const uint ASKED = 11u;
// The host's CadrGpuCullView, written before every submission of the frame.
layout(set = 0, binding = 4, std140) uniform View {
    vec4 eye_high;
    vec4 eye_low;
    vec4 planes[6];
    mat4 view_projection;
    // x, y: the target's (and depth image's) size; zw: unused.
    uvec4 target;
    // x: the sub-pixel threshold (projected diameter in pixels; 0: off); y: pixels per unit
    // of size at clip w = 1.
    vec4 sub_pixel;
    // The section planes relative to the eye (ABI 1.9), each keeping dot(n, q) + w >= 0; x of
    // `section`: how many.
    vec4 section_planes[6];
    uvec4 section;
} view;
// One bit per instance id: visible at the end of the last frame (read) and of this one
// (written by the first pass of phase 1).
layout(set = 0, binding = 5, std430) readonly buffer LastVisible { uint last_visible[]; };
layout(set = 0, binding = 6, std430) buffer NowVisible { uint now_visible[]; };
// The depth pyramid (see hiz.comp): level k holds the farthest depth of 2^k × 2^k
// depth texels, the levels one after the other.
layout(set = 0, binding = 7, std430) readonly buffer Pyramid { float pyramid[]; };

// The plugin ABI's CadrBox (ABI 1.20): a box along the object's axes.
struct ObjectBox {
    vec4 center;
    vec4 half_extent;
};
// The box of each instance's part (CadrScenePartBoxes), by instance id, after the cluster
// bindings. An older host has none: then a 4-byte buffer is bound here, holding fewer boxes
// than there are instances, and the spheres are tested.
#ifdef CLUSTERS
#define PART_BOX_BINDING 14
#else
#define PART_BOX_BINDING 8
#endif
layout(set = 0, binding = PART_BOX_BINDING, std430) readonly buffer PartBoxes { ObjectBox part_boxes[]; };
// The streaming requests (CadrSceneStreaming), one bit per geometry, after the part boxes: set
// for a part whose coarse form's error (its box's centre w, object space) projects over the
// threshold, at the bit its box's half-extent w names (ABI 1.21: the geometry's request bit).
// 4 unused bytes where the scene does not stream.
layout(set = 0, binding = PART_BOX_BINDING + 1, std430) buffer Requests { uint requests[]; };
// What parameter blocks are made of (CadrParameterBlocks, ABI 1.22): the scene's instance
// records (CadrInstanceRecord, by instance id) and material slots (CadrMaterial), read only
// where the host asks for blocks.
struct InstanceRecord {
    uint matrix;
    uint material;
    uint flags;
    uint instance;
};
struct MaterialValues {
    vec4 base_color;
    vec4 surface;
};
layout(set = 0, binding = PART_BOX_BINDING + 2, std430) readonly buffer Records { InstanceRecord records[]; };
layout(set = 0, binding = PART_BOX_BINDING + 3, std430) readonly buffer Materials { MaterialValues materials[]; };

#ifdef CLUSTERS
// The plugin ABI's CadrCluster and CadrClusterGroup (CadrSceneClusters).
struct Cluster {
    vec4 sphere;
    vec3 cone_apex;
    float cone_cutoff;
    vec3 cone_axis;
    uint first_index;
    uint index_count;
    uint group;
    uint refined;
    uint part_clusters;
};
struct Group {
    vec4 sphere;
    float error;
    uint depth;
    uint first_cluster;
    uint cluster_count;
};
const uint CLUSTER_ORIGINAL = 0xffffffffu;
// The depth of a part's stand-in groups (CADR_CLUSTER_PROXY_DEPTH): its last.
const uint PROXY_DEPTH = 0xffffffffu;
layout(set = 0, binding = 8, std430) readonly buffer Clusters { Cluster clusters[]; };
layout(set = 0, binding = 9, std430) readonly buffer Groups { Group groups[]; };
// Cluster visibility at the end of the last frame (read) and of this one (written by the first
// pass of phase 1): one bit per (instance, cluster) pair, found by hashing it into a table of
// cluster_bit_mask + 1 bits. Two pairs may share a bit: phase 0 then draws a hidden cluster,
// which costs time, never a cluster that phase 1 would then leave out (both phases read the
// same bits).
layout(set = 0, binding = 10, std430) readonly buffer LastClusters { uint last_clusters[]; };
layout(set = 0, binding = 11, std430) buffer NowClusters { uint now_clusters[]; };
// One bit per instance id, cleared every frame: phase 0 found no room for the part's cut in its
// budget and drew none of it, so phase 1 draws all of it that is visible.
layout(set = 0, binding = 12, std430) buffer Phase0Skipped { uint phase0_skipped[]; };
// The plugin ABI's CadrBox per cluster (CadrSceneClusterBoxes, ABI 1.20): the box along
// the object's axes that holds the cluster. An older host has none: then a 4-byte buffer is
// bound here, holding fewer boxes than there are clusters, and the spheres are tested.
layout(set = 0, binding = 13, std430) readonly buffer ClusterBoxes { ObjectBox cluster_boxes[]; };
// Whether the boxes are there (set once per invocation in main()).
bool boxes_bound;
#endif

layout(push_constant) uniform Dispatch {
    uint instance_count;
    uint pass_kind;
    uint pass_slot;
    uint first_command;
    uint mode;
    // What this dispatch records in the visibility tables of phase 1 (RECORDS_*).
    uint writes_visibility;
    uint pyramid_levels;
    // The pass's filter (CadrPassFilter): only instances with flags & mask == value are drawn.
    uint filter_mask;
    uint filter_value;
    // Nonzero: only parts some section plane passes through (the section caps' pass).
    uint filter_section_cut;
    // The pass's exclusion (CadrPassExclusion): of those, instances with flags & mask ==
    // value are not drawn (mask 0 excludes none).
    uint exclude_mask;
    uint exclude_value;
    // gpu-clusters: the level-of-detail threshold in pixels (0: full detail), whether this
    // pass hides the back faces of closed opaque parts, and the commands a pass slot holds.
    float lod_error;
    uint back_faces_hidden;
    uint command_capacity;
    // Of a pass slot's commands, how many the cuts at `lod_error` may take; past it, a part is
    // drawn at its coarsest, which the rest of the slot always has room for.
    uint cluster_budget;
    // The cluster visibility table's bits less one.
    uint cluster_bit_mask;
    // Which parts the pass takes by whether the rasterizer culls their back faces.
    uint face_route;
    // Words of each command: 5, or 6 where each starts with the word naming its pass (1 for
    // the pass that keeps back faces, else 0), the two passes of a split sharing one stream
    // (CadrSharedFaceStreams: one slot, one count).
    uint command_words;
    // Words of the streaming requests (CadrSceneStreaming, ABI 1.21); 0 where the scene does
    // not stream.
    uint request_words;
    // Nonzero where each command comes after its instance's parameter block (CadrParameterBlocks,
    // ABI 1.22: 24 words, after the word naming the pass where there is one); `command_words`
    // counts them.
    uint parameter_blocks;
} dispatch;

// The visibility a phase 1 dispatch records: the parts' (one dispatch records every part's, so
// the others test the pyramid only for the parts their pass takes) and the clusters' of the
// parts its pass takes.
const uint RECORDS_PARTS = 1u;
const uint RECORDS_CLUSTERS = 2u;

// Inside the frustum.
bool in_frustum(vec3 center, float radius) {
    for (int i = 0; i < 6; ++i) {
        if (dot(view.planes[i].xyz, center) + view.planes[i].w < -radius) {
            return false;
        }
    }
    return true;
}

// The half axes of `box` placed by `rotation`, the linear part of an instance's matrix (an
// oriented box, also under non-uniform scale).
mat3 placed_half_axes(ObjectBox box, mat3 rotation) {
    vec3 h = box.half_extent.xyz;
    return mat3(rotation[0] * h.x, rotation[1] * h.y, rotation[2] * h.z);
}

// How far the box of half axes `half_axes` reaches along the unit normal `normal`.
float box_reach(mat3 half_axes, vec3 normal) {
    return abs(dot(normal, half_axes[0])) + abs(dot(normal, half_axes[1]))
        + abs(dot(normal, half_axes[2]));
}

// Whether the box of `center` and half axes `half_axes` reaches into the frustum (as a plane's
// distance, its reach scales with the plane's normal: the test holds for unit normals or not).
bool box_in_frustum(vec3 center, mat3 half_axes) {
    for (int i = 0; i < 6; ++i) {
        vec4 plane = view.planes[i];
        if (dot(plane.xyz, center) + plane.w < -box_reach(half_axes, plane.xyz)) {
            return false;
        }
    }
    return true;
}

// Whether some section plane cuts the box away whole (with the slack `against_sections`
// gives spheres).
bool box_cut_away(vec3 center, mat3 half_axes) {
    uint sections = min(view.section.x, 6u);
    for (uint i = 0u; i < sections; ++i) {
        vec4 plane = view.section_planes[i];
        float slack = box_reach(half_axes, plane.xyz) + 1e-5 * length(center);
        if (dot(plane.xyz, center) + plane.w < -slack) {
            return true;
        }
    }
    return false;
}

// Where the sphere lies against the section planes: x, some plane cuts it away whole; y, some
// plane passes through it. With the rounding of f32 eye-relative positions as slack: the
// vertex shader clips against the same planes, and what it keeps must not be culled.
bvec2 against_sections(vec3 center, float radius) {
    float slack = radius + 1e-5 * length(center);
    bool cut_away = false;
    bool crossed = false;
    uint sections = min(view.section.x, 6u);
    for (uint i = 0u; i < sections; ++i) {
        float distance = dot(view.section_planes[i].xyz, center) + view.section_planes[i].w;
        cut_away = cut_away || distance < -slack;
        crossed = crossed || abs(distance) <= slack;
    }
    return bvec2(cut_away, crossed);
}

// The size of level `level` of the depth pyramid: the target halved `level` times, rounding
// up, at least 1 (as the host's levels are made).
uvec2 pyramid_level_size(uint level) {
    return max((view.target.xy + (1u << level) - 1u) >> level, uvec2(1u));
}

// An orthonormal frame of the view's axes (right, up, along the view), read off the
// projection's rows: a cube around a sphere with these axes projects to a smaller rect, with a
// nearer depth no nearer than the sphere's own, than one with the world's axes. Any orthonormal
// frame holds the sphere, so the test stays conservative whatever the projection.
mat3 view_axes_of_projection() {
    mat4 m = view.view_projection;
    vec3 row0 = vec3(m[0][0], m[1][0], m[2][0]);
    vec3 row2 = vec3(m[0][2], m[1][2], m[2][2]);
    vec3 row3 = vec3(m[0][3], m[1][3], m[2][3]);
    // Perspective: the bottom row is the view direction; orthographic: it is (0, 0, 0, 1) and
    // the depth row is.
    vec3 along = dot(row3, row3) > 1e-12 ? row3 : row2;
    if (dot(along, along) <= 1e-24) {
        return mat3(1.0);
    }
    along = normalize(along);
    vec3 right = row0 - dot(row0, along) * along;
    if (dot(right, right) <= 1e-24) {
        return mat3(1.0);
    }
    right = normalize(right);
    return mat3(right, cross(along, right), along);
}

// view_axes_of_projection(), the same for the whole dispatch: set once per invocation in
// main(), before any pyramid test (one per part, one per cluster of the walk).
mat3 view_axes;

// The planes that may part the screen-space hull of a box from a pyramid texel: for each face
// of the box, its plane; for each edge, the screen line along it (the hull's outline lies on
// such lines). Each keeps the range of the hull's corners along it, so the hull lies between
// those bounds whatever rounding did to the directions.
struct HullBounds {
    vec4 faces[6]; // xyz: the direction (NDC); w: the most any corner reaches along it
    float faces_least[6];
    vec4 edges[12]; // xy: the direction on screen; z, w: the least and most of the corners
};

// The hull bounds of the box whose corners lie at `corners` in NDC (corner k is the box's
// corner with bit a of k set where it lies on the + side of axis a).
HullBounds hull_bounds(vec3 corners[8]) {
    HullBounds hull;
    int edge = 0;
    [[unroll]] for (int axis = 0; axis < 3; ++axis) {
        int b = 1 << ((axis + 1) % 3);
        int c = 1 << ((axis + 2) % 3);
        [[unroll]] for (int side = 0; side < 2; ++side) {
            int first = side << axis;
            // Newell's diagonals: sound on a face that came out slightly warped.
            vec3 direction = cross(corners[first | b | c] - corners[first],
                                   corners[first | c] - corners[first | b]);
            vec2 along = vec2(-1.0 / 0.0, 1.0 / 0.0);
            [[unroll]] for (int k = 0; k < 8; ++k) {
                float reach = dot(direction, corners[k]);
                along = vec2(max(along.x, reach), min(along.y, reach));
            }
            hull.faces[2 * axis + side] = vec4(direction, along.x);
            hull.faces_least[2 * axis + side] = along.y;
        }
        [[unroll]] for (int k = 0; k < 8; ++k) {
            if ((k & (1 << axis)) != 0) {
                continue;
            }
            vec2 e = corners[k | (1 << axis)].xy - corners[k].xy;
            vec2 direction = vec2(-e.y, e.x);
            vec2 range = vec2(1.0 / 0.0, -1.0 / 0.0);
            [[unroll]] for (int j = 0; j < 8; ++j) {
                float reach = dot(direction, corners[j].xy);
                range = vec2(min(range.x, reach), max(range.y, reach));
            }
            hull.edges[edge++] = vec4(direction, range);
        }
    }
    return hull;
}

// Whether the NDC box `centre` ± `half_size` (a texel's screen square, from the hull's nearest
// depth to the farthest depth the texel keeps) lies wholly beyond one of the hull's bounds. A
// small slack keeps rounding from parting what touches.
bool parted_from_hull(HullBounds hull, vec3 centre, vec3 half_size) {
    [[unroll]] for (int face = 0; face < 6; ++face) {
        vec3 direction = hull.faces[face].xyz;
        float middle = dot(direction, centre);
        float spread = dot(abs(direction), half_size);
        float slack = 1e-5 * (abs(middle) + spread) + 1e-30;
        if (middle - spread > hull.faces[face].w + slack
            || middle + spread < hull.faces_least[face] - slack) {
            return true;
        }
    }
    [[unroll]] for (int edge = 0; edge < 12; ++edge) {
        vec4 bounds = hull.edges[edge];
        float middle = dot(bounds.xy, centre.xy);
        float spread = dot(abs(bounds.xy), half_size.xy);
        float slack = 1e-5 * (abs(middle) + spread) + 1e-30;
        if (middle - spread > bounds.w + slack || middle + spread < bounds.z - slack) {
            return true;
        }
    }
    return false;
}

// The texels of one pyramid level under a screen rect (`texel_lo`..`texel_hi` in target
// pixels), at most 9 per axis: where the level starts, its size, its texels per target pixel,
// and the first and last texel.
struct PyramidRect {
    uint offset;
    uvec2 dims;
    float scale;
    uvec2 a;
    uvec2 b;
};

PyramidRect pyramid_rect(uint level, vec2 texel_lo, vec2 texel_hi) {
    PyramidRect rect;
    // Each level's size is computed whole, not carried from one iteration to the next: Mesa
    // 22.3's lavapipe, with this inlined into the cluster walk, left the size one level further
    // on than the offset.
    rect.offset = 0u;
    for (uint finer = 0u; finer < level; ++finer) {
        uvec2 finer_dims = pyramid_level_size(finer);
        rect.offset += finer_dims.x * finer_dims.y;
    }
    rect.dims = pyramid_level_size(level);
    rect.scale = exp2(-float(level));
    rect.a = uvec2(clamp(ivec2(floor(texel_lo * rect.scale)), ivec2(0), ivec2(rect.dims) - 1));
    rect.b = uvec2(clamp(ivec2(floor(texel_hi * rect.scale)), ivec2(0), ivec2(rect.dims) - 1));
    rect.b = min(rect.b, rect.a + 8u);
    return rect;
}

// Whether any texel of `rect` keeps a depth no nearer than `nearest`.
bool reaches_in_front(PyramidRect rect, float nearest) {
    for (uint y = rect.a.y; y <= rect.b.y; ++y) {
        for (uint x = rect.a.x; x <= rect.b.x; ++x) {
            if (nearest <= pyramid[rect.offset + y * rect.dims.x + x]) {
                return true;
            }
        }
    }
    return false;
}

// Whether the box of `center` and half axes `half_axes` (its corners are center ± each column)
// may be visible over the depth drawn so far. Conservative: with every corner in front of the
// eye, the box's image in NDC is the hull of its corners' images (a projection keeps lines
// straight), and under each pyramid texel of its screen rect that hull is tested against the
// texel's column, from the nearest corner's depth to the farthest depth kept there. A box seen
// through a gap that its rect spans but its outline does not, or that only its far side
// reaches, is found hidden there.
bool passes_pyramid_box(vec3 center, mat3 half_axes) {
    vec3 corners[8];
    vec2 lo = vec2(1.0);
    vec2 hi = vec2(-1.0);
    float nearest = 1.0;
    [[unroll]] for (int corner = 0; corner < 8; ++corner) {
        vec3 offset = half_axes * vec3((corner & 1) != 0 ? 1.0 : -1.0,
                                       (corner & 2) != 0 ? 1.0 : -1.0,
                                       (corner & 4) != 0 ? 1.0 : -1.0);
        vec4 clip = view.view_projection * vec4(center + offset, 1.0);
        if (clip.w <= 1e-6) {
            return true; // reaches behind the eye: cannot be judged
        }
        vec3 ndc = clip.xyz / clip.w;
        corners[corner] = ndc;
        lo = min(lo, ndc.xy);
        hi = max(hi, ndc.xy);
        nearest = min(nearest, ndc.z);
    }
    lo = clamp(lo, vec2(-1.0), vec2(1.0));
    hi = clamp(hi, vec2(-1.0), vec2(1.0));
    if (nearest <= 0.0) {
        return true;
    }
    vec2 size = vec2(view.target.xy);
    vec2 texel_lo = (lo * 0.5 + 0.5) * size;
    vec2 texel_hi = (hi * 0.5 + 0.5) * size;
    vec2 extent = max(texel_hi - texel_lo, vec2(1.0));
    uint levels = max(dispatch.pyramid_levels, 1u);
    // First the level where the rect is at most 4 texels wide (so spans at most 5 per axis),
    // against the nearest corner alone: most hidden boxes are found hidden there, in few reads.
    uint level = uint(clamp(ceil(log2(max(extent.x, extent.y))) - 2.0, 0.0, float(levels - 1u)));
    PyramidRect rect = pyramid_rect(level, texel_lo, texel_hi);
    if (!reaches_in_front(rect, nearest)) {
        return false;
    }
    // Then one level finer (at most 8 texels wide), with the hull: fine enough that a part
    // hidden near a silhouette, or behind a row of parts with gaps between them, is still
    // found hidden.
    level = level > 0u ? level - 1u : 0u;
    rect = pyramid_rect(level, texel_lo, texel_hi);
    HullBounds hull = hull_bounds(corners);
    // A texel's half size in NDC.
    vec2 texel_half = vec2(1.0) / (rect.scale * size);
    // The texel under the box's centre first: the hull covers it, so a box in sight is most
    // often found there, at one test. Then every texel of the rect, row by row.
    vec4 centre_clip = view.view_projection * vec4(center, 1.0);
    vec2 centre_pixel = (centre_clip.xy / centre_clip.w * 0.5 + 0.5) * size;
    uvec2 centre_texel = uvec2(clamp(ivec2(floor(centre_pixel * rect.scale)), ivec2(rect.a),
                                     ivec2(rect.b)));
    uint columns = rect.b.x - rect.a.x + 1u;
    int texels = int(columns * (rect.b.y - rect.a.y + 1u));
    for (int k = -1; k < texels; ++k) {
        uvec2 texel = k < 0 ? centre_texel : rect.a + uvec2(uint(k) % columns, uint(k) / columns);
        float farthest = pyramid[rect.offset + texel.y * rect.dims.x + texel.x];
        if (nearest > farthest) {
            continue;
        }
        vec2 middle = (vec2(texel) + 0.5) * 2.0 * texel_half - 1.0;
        vec3 column_centre = vec3(middle, 0.5 * (nearest + farthest));
        vec3 column_half = vec3(texel_half, 0.5 * (farthest - nearest));
        if (!parted_from_hull(hull, column_centre, column_half)) {
            return true;
        }
    }
    return false;
}

// Whether the sphere projects at least the sub-pixel threshold across. A perspective view
// (clip w grows with distance) measures at w - radius, the sphere's nearest depth, which never
// underestimates the size on the axis; a sphere holding the eye is always large enough.
bool large_enough(vec3 center, float radius) {
    if (view.sub_pixel.x <= 0.0) {
        return true;
    }
    vec4 w_row = vec4(view.view_projection[0][3], view.view_projection[1][3],
                      view.view_projection[2][3], view.view_projection[3][3]);
    float w = dot(w_row, vec4(center, 1.0));
    bool perspective = w_row.w == 0.0;
    float nearest = perspective ? w - radius : w;
    if (nearest <= 0.0) {
        return true;
    }
    return 2.0 * radius * view.sub_pixel.y >= view.sub_pixel.x * nearest;
}

// Whether the rasterizer may cull the part's back faces (CADR_FACES_CULLED): closed, wound
// counter-clockwise outside, neither translucent nor cut out, placed without mirroring (which
// turns the winding), wholly on the inner side of the near plane (the eye cannot look into it)
// and crossed by no section plane (`cut`). Decided per part, the same in every phase.
bool back_faces_culled(uint flags, mat3 rotation, vec3 center, float radius, bool cut) {
    const uint SEEN_INSIDE = INSTANCE_INSIDE_OUT | INSTANCE_TRANSLUCENT | INSTANCE_CUTOUT;
    float slack = radius + 1e-5 * length(center);
    return (flags & (INSTANCE_CLOSED | SEEN_INSIDE)) == INSTANCE_CLOSED
        && determinant(rotation) > 0.0 && !cut
        && dot(view.planes[4].xyz, center) + view.planes[4].w > slack;
}

// Writes the parameter block of instance `id` (CadrParameterBlock: world matrix, base colour,
// surface, flags, instance id) at word `base` of the commands.
void write_parameter_block(uint base, uint id) {
    InstanceRecord record = records[id];
    Matrix world = matrices[record.matrix];
    for (uint column = 0u; column < 4u; ++column) {
        for (uint row = 0u; row < 4u; ++row) {
            commands[base + column * 4u + row] = floatBitsToUint(world.columns[column][row]);
        }
    }
    MaterialValues material = materials[record.material];
    for (uint i = 0u; i < 4u; ++i) {
        commands[base + 16u + i] = floatBitsToUint(material.base_color[i]);
    }
    commands[base + 20u] = floatBitsToUint(material.surface.x);
    commands[base + 21u] = floatBitsToUint(material.surface.y);
    commands[base + 22u] = record.flags;
    commands[base + 23u] = record.instance;
}

// Writes an indirect command for `count` indices from `first`, instance `id`, at `slot` of the
// pass's commands: the word naming the pass where the stream is shared, the instance's
// parameter block where the host asks for blocks, then the draw.
void write_command(uint slot, uint first, uint count, uint vertex_base, uint id) {
    if (slot >= dispatch.command_capacity) {
        return; // never, with the capacity the culler reserves; the count stays past it
    }
    uint base = (dispatch.first_command + slot) * dispatch.command_words;
    uint block_words = dispatch.parameter_blocks != 0u ? 24u : 0u;
    if (dispatch.command_words == 6u + block_words) {
        commands[base] = dispatch.face_route == FACES_KEPT ? 1u : 0u;
        base += 1u;
    }
    if (block_words != 0u) {
        write_parameter_block(base, id);
        base += block_words;
    }
    commands[base] = count;
    commands[base + 1u] = 1u;
    commands[base + 2u] = first;
    commands[base + 3u] = vertex_base;
    commands[base + 4u] = id;
    atomicAdd(counts[8], 1u);
    if (dispatch.pass_kind != PASS_EDGES) {
        atomicAdd(counts[9], count / 3u);
    }
}

// Whether instance `id` was visible at the end of the last frame.
bool bit(uint id) {
    return (last_visible[id >> 5] >> (id & 31u) & 1u) != 0u;
}

// Appends an indirect command for `count` indices from `first`, instance `id`.
void append(uint first, uint count, uint vertex_base, uint id) {
    write_command(atomicAdd(counts[dispatch.pass_slot], 1u), first, count, vertex_base, id);
}

#ifdef CLUSTERS
// Where the instance's matrix puts things, relative to the eye.
struct Placement {
    mat3 rotation;
    vec3 translation;
    float scale;
};

// The error of `group` in pixels, as seen from the eye (at least the true projection: the
// group's sphere is measured at its nearest depth). A sphere holding the eye projects without
// bound; a group never simplified further has infinite error.
float projected_error(Group group, Placement place) {
    if (group.error >= 3.0e38) {
        return 1.0 / 0.0;
    }
    vec3 center = place.translation + place.rotation * group.sphere.xyz;
    vec4 w_row = vec4(view.view_projection[0][3], view.view_projection[1][3],
                      view.view_projection[2][3], view.view_projection[3][3]);
    float w = dot(w_row, vec4(center, 1.0));
    bool perspective = w_row.w == 0.0;
    float nearest = perspective ? w - group.sphere.w * place.scale : w;
    if (nearest <= 1e-6) {
        return 1.0 / 0.0;
    }
    return group.error * place.scale * view.sub_pixel.y / nearest;
}

// Whether the clusters of `group` may belong to the level-of-detail cut at `threshold` pixels:
// the coarser clusters made from the group would be too coarse. Threshold 0: the groups of
// original clusters; COARSEST: the groups never simplified further.
bool group_in_cut(Group group, Placement place, float threshold) {
    if (threshold <= 0.0) {
        return group.depth == 0u;
    }
    return projected_error(group, place) > threshold;
}

// Whether a cluster of a group in the cut belongs to it: its own error is small enough.
bool in_cut(Cluster cluster, Placement place, float threshold) {
    return threshold <= 0.0 || cluster.refined == CLUSTER_ORIGINAL
        || projected_error(groups[cluster.refined], place) <= threshold;
}

const float COARSEST = 3.0e38;

// Whether every triangle of the cluster faces away from the eye.
bool faces_away(Cluster cluster, Placement place) {
    if (cluster.cone_cutoff >= 1.0) {
        return false;
    }
    vec3 axis = normalize(place.rotation * cluster.cone_axis);
    vec4 w_row = vec4(view.view_projection[0][3], view.view_projection[1][3],
                      view.view_projection[2][3], view.view_projection[3][3]);
    if (w_row.w != 0.0) {
        // Orthographic: every ray runs along the view direction, the near plane's normal.
        return dot(normalize(view.planes[4].xyz), axis) >= cluster.cone_cutoff;
    }
    vec3 apex = place.translation + place.rotation * cluster.cone_apex;
    return dot(normalize(apex), axis) >= cluster.cone_cutoff;
}

// The counting walk's pyramid verdicts (a bit each, in the order it tested its clusters), which
// the writing walk after it, over the same cut, reads instead of testing again: the first 64.
uint walk_verdicts_low;
uint walk_verdicts_high;
const uint VERDICTS_KEPT = 64u;

// Whether cluster box (`center`, `half_axes`) passes the depth pyramid: the `tests`-th test of
// a walk, recorded by the counting walk and read back by the writing one (`write`).
bool walk_passes_pyramid(vec3 center, mat3 half_axes, uint tests, bool write) {
    uint bit = 1u << (tests & 31u);
    bool low = tests < 32u;
    if (write && tests < VERDICTS_KEPT) {
        return ((low ? walk_verdicts_low : walk_verdicts_high) & bit) != 0u;
    }
    bool visible = passes_pyramid_box(center, half_axes);
    if (!write && visible && tests < VERDICTS_KEPT) {
        if (low) {
            walk_verdicts_low |= bit;
        } else {
            walk_verdicts_high |= bit;
        }
    }
    return visible;
}

// The bit of cluster `k` of instance `id` in the cluster visibility tables.
uint cluster_bit(uint id, uint k) {
    uint h = id * 0x9e3779b1u ^ (k + 0x7f4a7c15u) * 0x85ebca77u;
    h ^= h >> 15;
    h *= 0x2c1b3c6du;
    h ^= h >> 12;
    return h & dispatch.cluster_bit_mask;
}

// The clusters the counting walk found drawn, a bit each by their place in the part, for a part
// of at most 64 clusters (`walk_drawn_recorded`): the writing walk then writes them without
// walking the cut and testing them again.
uint walk_drawn_low;
uint walk_drawn_high;
bool walk_drawn_recorded;
// Whether a counting walk of the part found a cluster that passes the depth pyramid.
bool walk_found_visible;

// The command a walk is making: clusters that follow each other in the index buffer are drawn
// by one command.
struct CommandRun {
    uint first;
    uint count;
    uint made;
};

// Adds `cluster` to `run`: to its command where it follows the command's last index, else to a
// new one, the one before written (where `write`, at command `slot` + its number).
void add_to_run(inout CommandRun run, Cluster cluster, bool write, uint slot, uint vertex_base,
                uint id) {
    if (run.count > 0u && run.first + run.count == cluster.first_index) {
        run.count += cluster.index_count;
        return;
    }
    if (run.count > 0u && write) {
        write_command(slot + run.made - 1u, run.first, run.count, vertex_base, id);
    }
    run.made += 1u;
    run.first = cluster.first_index;
    run.count = cluster.index_count;
}

// Writes the last command of `run`, where `write`; returns how many commands it made.
uint end_run(CommandRun run, bool write, uint slot, uint vertex_base, uint id) {
    if (run.count > 0u && write) {
        write_command(slot + run.made - 1u, run.first, run.count, vertex_base, id);
    }
    return run.made;
}

// Writes the commands of the clusters the counting walk recorded drawn, from `slot` on.
uint write_recorded_clusters(CullEntry entry, uint id, uint slot) {
    CommandRun run = CommandRun(0u, 0u, 0u);
    atomicAdd(counts[10], bitCount(walk_drawn_low) + bitCount(walk_drawn_high));
    for (uint word = 0u; word < 2u; ++word) {
        uint bits = word == 0u ? walk_drawn_low : walk_drawn_high;
        while (bits != 0u) {
            uint k = entry.first_cluster + word * 32u + uint(findLSB(bits));
            bits &= bits - 1u;
            add_to_run(run, clusters[k], true, slot, entry.vertex_base, id);
        }
    }
    return end_run(run, true, slot, entry.vertex_base, id);
}

// Walks the instance's clusters in the cut at `threshold` that pass the cluster tests, merging
// those that follow each other in the index buffer into one command: counts the commands, and
// writes them from `slot` on when `write`. With occlusion, phase 0 takes the clusters visible
// at the end of the last frame (of an instance that was: `was_visible`), phase 1 the others
// that pass the depth pyramid, and records every cluster that passes it.
uint walk_clusters(CullEntry entry, uint id, Placement place, bool back_faces_may_go,
                   float threshold, bool write, uint slot, bool phase0_drew_none) {
    bool was_visible = dispatch.mode != MODE_FRUSTUM && bit(id) && !phase0_drew_none;
    uint count = clusters[entry.first_cluster].part_clusters;
    CommandRun run = CommandRun(0u, 0u, 0u);
    uint pyramid_tests = 0u;
    if (!write) {
        walk_verdicts_low = 0u;
        walk_verdicts_high = 0u;
        walk_drawn_low = 0u;
        walk_drawn_high = 0u;
        walk_drawn_recorded = count <= 64u;
    }
    // A part's stand-ins, its last clusters (each alone in a group of PROXY_DEPTH, errors
    // growing toward the last), replace its whole cut: the coarsest whose error projects at or
    // under the threshold is drawn alone. Otherwise none is drawn (nor at full detail, nor in
    // place of the coarsest clusters when the budget ran out).
    uint first = entry.first_cluster;
    uint end = entry.first_cluster + count;
    bool may_stand_in = threshold > 0.0 && threshold < COARSEST;
    uint stand_ins = end;
    uint chosen = end;
    while (stand_ins > first + 1u) {
        Group group = groups[clusters[stand_ins - 1u].group];
        if (group.depth != PROXY_DEPTH) {
            break;
        }
        stand_ins -= 1u;
        if (may_stand_in && projected_error(group, place) <= threshold) {
            chosen = stand_ins;
            break;
        }
    }
    bool stand_in_alone = chosen != end;
    if (stand_in_alone) {
        first = chosen;
        end = chosen + 1u;
    } else {
        end = stand_ins;
    }
    // Group by group (a part's groups cover its clusters in order): a group the cut leaves
    // out costs one test, not one per cluster.
    uint group_index = clusters[first].group;
    uint group_end = 0u;
    for (uint k = first; k < end; ++k) {
        if (k >= group_end) {
            Group group = groups[group_index];
            group_index += 1u;
            group_end = group.first_cluster + max(group.cluster_count, 1u);
            if (!stand_in_alone && !group_in_cut(group, place, threshold)) {
                k = max(k, group_end - 1u);
                continue;
            }
        }
        Cluster cluster = clusters[k];
        if (!stand_in_alone && !in_cut(cluster, place, threshold)) {
            continue;
        }
        vec3 center = place.translation + place.rotation * cluster.sphere.xyz;
        float radius = cluster.sphere.w * place.scale;
        bool tested = in_frustum(center, radius) && !against_sections(center, radius).x
            && !(back_faces_may_go && faces_away(cluster, place));
        // The box the cluster is tested by: its own where the host gives it, placed by the
        // instance's matrix (far tighter than the sphere around flat or long clusters), else the
        // sphere's cube on the view's axes.
        vec3 box_center = center;
        mat3 box_axes = view_axes * radius;
        if (tested && boxes_bound) {
            ObjectBox box = cluster_boxes[k];
            box_center = place.translation + place.rotation * box.center.xyz;
            box_axes = placed_half_axes(box, place.rotation);
            tested = box_in_frustum(box_center, box_axes) && !box_cut_away(box_center, box_axes);
        }
        if (!tested) {
            continue;
        }
        uint visibility_bit = cluster_bit(id, k - entry.first_cluster);
        bool was = was_visible && dispatch.back_faces_hidden != 0u
            && (last_clusters[visibility_bit >> 5] >> (visibility_bit & 31u) & 1u) != 0u;
        if (dispatch.mode == MODE_LAST_VISIBLE && !was) {
            continue;
        }
        if (dispatch.mode == MODE_NEWLY_VISIBLE) {
            bool visible = walk_passes_pyramid(box_center, box_axes, pyramid_tests, write);
            pyramid_tests += 1u;
            walk_found_visible = walk_found_visible || visible;
            // Recorded by the counting walk, which every part passes through (the writing
            // one runs only when there is something left to draw).
            if (visible && !write && (dispatch.writes_visibility & RECORDS_CLUSTERS) != 0u) {
                atomicOr(now_clusters[visibility_bit >> 5], 1u << (visibility_bit & 31u));
            }
            if (!visible || was) {
                continue;
            }
        }
        if (write) {
            atomicAdd(counts[10], 1u);
        } else if (walk_drawn_recorded) {
            uint place_in_part = k - entry.first_cluster;
            if (place_in_part < 32u) {
                walk_drawn_low |= 1u << place_in_part;
            } else {
                walk_drawn_high |= 1u << (place_in_part - 32u);
            }
        }
        add_to_run(run, cluster, write, slot, entry.vertex_base, id);
    }
    return end_run(run, write, slot, entry.vertex_base, id);
}

// Appends the commands of the instance's clusters in the cut: at the host's threshold while
// the pass's budget lasts, else at the part's coarsest (a part is never left out for want of
// room). Phase 0 past the budget draws none of the part, and says so to phase 1, which then
// draws all of it that is visible (the two phases must agree on what phase 0 drew). Returns
// whether, in phase 1, a cluster of the part passed the depth pyramid.
bool append_clusters(CullEntry entry, uint id, Placement place, bool back_faces_may_go) {
    walk_found_visible = false;
    float threshold = dispatch.lod_error;
    uint skipped_word = id >> 5;
    uint skipped_bit = 1u << (id & 31u);
    bool phase0_drew_none = dispatch.mode == MODE_NEWLY_VISIBLE
        && (phase0_skipped[skipped_word] & skipped_bit) != 0u;
    uint wanted = walk_clusters(entry, id, place, back_faces_may_go, threshold, false, 0u,
                                phase0_drew_none);
    uint asked = atomicAdd(counts[ASKED + dispatch.pass_slot], wanted);
    if (asked + wanted > dispatch.cluster_budget) {
        if (dispatch.mode == MODE_LAST_VISIBLE) {
            atomicOr(phase0_skipped[skipped_word], skipped_bit);
            return false;
        }
        // Phase 0's clusters of this part are of the threshold's cut, the coarsest ones are
        // not: they are all drawn (over phase 0's, where the part had any there).
        threshold = COARSEST;
        phase0_drew_none = true;
        wanted = walk_clusters(entry, id, place, back_faces_may_go, threshold, false, 0u,
                               phase0_drew_none);
    }
    if (wanted > 0u) {
        uint slot = atomicAdd(counts[dispatch.pass_slot], wanted);
        if (walk_drawn_recorded) {
            write_recorded_clusters(entry, id, slot);
        } else {
            walk_clusters(entry, id, place, back_faces_may_go, threshold, true, slot,
                          phase0_drew_none);
        }
    }
    return walk_found_visible;
}
#endif

// Asks the host for the full detail of a part's geometry (or to keep it), by setting the
// geometry's bit (`bit`), where the part's coarse form has an error (`coarse_error`, object
// space: positive while the coarse form is drawn, negated while the full detail is) that
// projects over `threshold` pixels: its sphere (`center`, `radius`, relative to the eye)
// measured at its nearest depth.
void request_full_detail(uint bit, float coarse_error, vec3 center, float radius, float scale,
                         float threshold) {
    coarse_error = abs(coarse_error);
    if (coarse_error == 0.0 || (bit >> 5) >= dispatch.request_words) {
        return;
    }
    vec4 w_row = vec4(view.view_projection[0][3], view.view_projection[1][3],
                      view.view_projection[2][3], view.view_projection[3][3]);
    float w = dot(w_row, vec4(center, 1.0));
    float nearest = w_row.w == 0.0 ? w - radius : w;
    if (nearest <= 1e-6 || coarse_error * scale * view.sub_pixel.y > threshold * nearest) {
        atomicOr(requests[bit >> 5], 1u << (bit & 31u));
    }
}

void main() {
    uint id = gl_GlobalInvocationID.x;
    if (id >= dispatch.instance_count) {
        return;
    }
    CullEntry entry = entries[id];
    if ((entry.flags & INSTANCE_CANDIDATE) == 0u) {
        return;
    }
    view_axes = view_axes_of_projection();
#ifdef CLUSTERS
    boxes_bound = cluster_boxes.length() >= clusters.length();
#endif
    if (dispatch.pass_kind == PASS_PICK && (entry.flags & INSTANCE_PICKABLE) == 0u) {
        return;
    }
    Matrix m = matrices[entry.matrix];
    mat3 rotation = mat3(m.columns[0].xyz, m.columns[1].xyz, m.columns[2].xyz);
    vec3 low = vec3(m.columns[0].w, m.columns[1].w, m.columns[2].w);
    vec3 center = (m.columns[3].xyz - view.eye_high.xyz) + (low - view.eye_low.xyz)
        + rotation * entry.sphere.xyz;
    float scale = max(length(rotation[0]), max(length(rotation[1]), length(rotation[2])));
    float radius = entry.sphere.w * scale;
    // The box the part is tested by: its own where the host gives it, placed by the
    // instance's matrix (far tighter than the sphere around a panel, a plate or a shaft), else
    // the sphere's cube on the view's axes.
    bool part_box_bound = part_boxes.length() >= dispatch.instance_count;
    vec3 box_center = center;
    mat3 box_axes = view_axes * radius;
    if (part_box_bound) {
        ObjectBox box = part_boxes[id];
        box_center = center + rotation * (box.center.xyz - entry.sphere.xyz);
        box_axes = placed_half_axes(box, rotation);
    }

    bvec2 sections = against_sections(center, radius);
    bool visible = in_frustum(center, radius) && !sections.x && large_enough(center, radius);
    if (visible && part_box_bound) {
        visible = box_in_frustum(box_center, box_axes) && !box_cut_away(box_center, box_axes);
    }
    bool draw = visible;
#ifdef CLUSTERS
    // Phase 0 fills the depth that phase 1 is tested against: with clusters it draws only the
    // passes that write it (opaque surfaces), what was visible of them. Every other pass (lines,
    // translucent surfaces, caps) waits for phase 1, when the surfaces are whole: a part's lines
    // drawn before all its surfaces would show through them.
    if (dispatch.mode == MODE_LAST_VISIBLE && dispatch.back_faces_hidden == 0u) {
        return;
    }
#endif
    uint first = entry.first_index;
    uint count = entry.index_count;
    if (dispatch.pass_kind == PASS_EDGES) {
        first = entry.first_wire_index;
        count = entry.wire_index_count;
    }
    // Whether the pass takes the part: its filter decides what it draws, not what is visible
    // (the visibility bit below is recorded whatever the pass takes). Asked only of a part in
    // view: one out of view is neither drawn nor recorded visible.
    bool excluded = dispatch.exclude_mask != 0u
        && (entry.flags & dispatch.exclude_mask) == dispatch.exclude_value;
    bool taken = visible && count != 0u && (entry.flags & dispatch.filter_mask) == dispatch.filter_value
        && !excluded && (dispatch.filter_section_cut == 0u || sections.y)
        && (dispatch.face_route == FACES_ANY
            || back_faces_culled(entry.flags, rotation, center, radius, sections.y)
                == (dispatch.face_route == FACES_CULLED));
    bool records_part = dispatch.mode == MODE_NEWLY_VISIBLE
        && (dispatch.writes_visibility & RECORDS_PARTS) != 0u;
#ifdef CLUSTERS
    // A part visible at the end of the last frame whose clusters this pass walks in phase 1:
    // their tests decide what is drawn and whether the part is still visible (each cluster's
    // box lies in the part's), so the part's own test would only repeat them.
    bool clusters_decide = dispatch.mode == MODE_NEWLY_VISIBLE && taken && bit(id)
        && dispatch.pass_kind != PASS_EDGES;
#else
    bool clusters_decide = false;
#endif
    if (dispatch.mode == MODE_LAST_VISIBLE) {
        draw = visible && bit(id);
    } else if (dispatch.mode == MODE_NEWLY_VISIBLE) {
        // The pyramid test is the dear one: a dispatch that neither records the part's
        // visibility nor draws it leaves it out.
        if (!taken && !records_part) {
            return;
        }
        if (!clusters_decide) {
            visible = visible && passes_pyramid_box(box_center, box_axes);
        }
        draw = visible && !bit(id);
#ifdef CLUSTERS
        // Phase 0 drew only clusters, and only in the passes that fill the depth: every
        // visible part goes on to phase 1 (its clusters that phase 0 left out, its lines).
        draw = visible;
#endif
        if (records_part && visible && !clusters_decide) {
            atomicOr(now_visible[id >> 5], 1u << (id & 31u));
        }
    }
    if (draw && part_box_bound && dispatch.pass_kind != PASS_EDGES) {
        ObjectBox box = part_boxes[id];
        request_full_detail(floatBitsToUint(box.half_extent.w), box.center.w, center, radius,
                            scale, dispatch.lod_error);
    }
    if (!draw || !taken) {
        return;
    }
#ifdef CLUSTERS
    if (dispatch.pass_kind != PASS_EDGES) {
        vec3 c0 = rotation[0];
        vec3 c1 = rotation[1];
        vec3 c2 = rotation[2];
        float l0 = dot(c0, c0);
        float tolerance = 1e-4 * l0;
        bool keeps_angles = abs(dot(c1, c1) - l0) <= tolerance && abs(dot(c2, c2) - l0) <= tolerance
            && abs(dot(c0, c1)) <= tolerance && abs(dot(c0, c2)) <= tolerance
            && abs(dot(c1, c2)) <= tolerance;
        Placement place = Placement(rotation, center - rotation * entry.sphere.xyz, scale);
        // Back faces may go where the pass hides them and the part shows none: closed, wound
        // counter-clockwise outside, opaque, and cut by no section plane.
        bool back_faces_may_go = dispatch.back_faces_hidden != 0u && keeps_angles
            && (entry.flags & (INSTANCE_CLOSED | INSTANCE_INSIDE_OUT | INSTANCE_TRANSLUCENT))
                == INSTANCE_CLOSED
            && !sections.y;
        bool some_cluster_visible = append_clusters(entry, id, place, back_faces_may_go);
        if (records_part && clusters_decide && some_cluster_visible) {
            atomicOr(now_visible[id >> 5], 1u << (id & 31u));
        }
        return;
    }
    // An edge pass draws a far part's edges at the coarsest of their levels (records after
    // its clusters, finest first: CADR_INSTANCE_EDGE_LEVELS) whose error projects at or under
    // EDGE_ERROR_SHARE of the threshold, as its surfaces are drawn at their cut.
    uint cluster_count = uint(clusters.length());
    if ((entry.flags & INSTANCE_EDGE_LEVELS) != 0u && dispatch.lod_error > 0.0
        && dispatch.lod_error < COARSEST && entry.first_cluster < cluster_count) {
        Placement place = Placement(rotation, center - rotation * entry.sphere.xyz, scale);
        uint level_record = entry.first_cluster + clusters[entry.first_cluster].part_clusters;
        uint levels = level_record < cluster_count
            ? min(clusters[level_record].refined, cluster_count - level_record) : 0u;
        for (uint i = 0u; i < levels; ++i) {
            Cluster level = clusters[level_record + i];
            if (projected_error(groups[level.group], place) > EDGE_ERROR_SHARE * dispatch.lod_error) {
                break;
            }
            first = level.first_index;
            count = level.index_count;
        }
    }
#endif
    append(first, count, entry.vertex_base, id);
}
