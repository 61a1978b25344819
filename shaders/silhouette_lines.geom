#version 460
// Silhouette lines of curved surfaces, as the hidden-line mode's dashed hidden lines show them
// (hidden_edges.frag after this shader, drawn only behind the surfaces). A curved CAD surface
// is tessellated with shared normals that vary across its triangles, so its silhouette (the
// outline that no feature edge marks: a hole's or a shaft's sides) is where the surface turns
// from facing the eye to facing away, the zero of n·v interpolated across each triangle: the
// segment between the two points on the triangle's edges where that sign changes. A triangle
// with one normal (a flat face, a faceted mesh's facet) emits nothing: a faceted mesh's outline
// runs along its facets' edges, where only the screen-space silhouettes of the visible picture
// find it.
#include "frame.glsl"

layout(triangles) in;
layout(line_strip, max_vertices = 2) out;

// As technique.vert declares it.
in gl_PerVertex {
    vec4 gl_Position;
    float gl_ClipDistance[6];
} gl_in[];

out gl_PerVertex {
    vec4 gl_Position;
    float gl_ClipDistance[6];
};

// What technique.vert writes, and of that what the line's fragment shader reads.
layout(location = 0) in vec3 in_view_position[];
layout(location = 1) in vec3 in_view_normal[];
layout(location = 2) flat in vec4 in_base_color[];
layout(location = 3) flat in vec2 in_surface[];
layout(location = 11) flat in uint in_highlighted[];

layout(location = 0) out vec3 out_view_position;
layout(location = 1) out vec3 out_view_normal;
layout(location = 2) flat out vec4 out_base_color;
layout(location = 3) flat out vec2 out_surface;
layout(location = 11) flat out uint out_highlighted;

// Whether vertex `i` faces away from the eye, and by how much (the cosine between its normal
// and the direction the eye sees it in: from the eye for a perspective projection, along -Z
// for an orthographic one, whose bottom row is (0, 0, 0, 1)).
float facing(int i) {
    float orthographic = frame.projection[3][3];
    vec3 toward = mix(normalize(in_view_position[i]), vec3(0.0, 0.0, -1.0), orthographic);
    vec3 normal = in_view_normal[i];
    float length_squared = dot(normal, normal);
    return length_squared > 0.0 ? dot(normal, toward) * inversesqrt(length_squared) : 0.0;
}

// Emits the point of edge a-b where the interpolated facing is zero.
void emit_crossing(int a, int b, float facing_a, float facing_b) {
    float t = facing_a / (facing_a - facing_b);
    gl_Position = mix(gl_in[a].gl_Position, gl_in[b].gl_Position, t);
    for (int i = 0; i < 6; ++i) {
        gl_ClipDistance[i] = mix(gl_in[a].gl_ClipDistance[i], gl_in[b].gl_ClipDistance[i], t);
    }
    out_view_position = mix(in_view_position[a], in_view_position[b], t);
    out_view_normal = mix(in_view_normal[a], in_view_normal[b], t);
    out_base_color = in_base_color[0];
    out_surface = in_surface[0];
    out_highlighted = in_highlighted[0];
    EmitVertex();
}

void main() {
    // A part the vertex shader clipped away whole (one its pass does not draw) has every clip
    // distance negative: its segment is clipped too.
    // A triangle with one normal is flat: no silhouette crosses it (the parts without any
    // other, not CADR_INSTANCE_CURVED, are left out of the pass).
    if (in_view_normal[0] == in_view_normal[1] && in_view_normal[1] == in_view_normal[2]) {
        return;
    }
    float g[3] = float[3](facing(0), facing(1), facing(2));
    // The sign changes on no edge or on two.
    for (int a = 0; a < 3; ++a) {
        int b = (a + 1) % 3;
        if ((g[a] < 0.0) != (g[b] < 0.0)) {
            emit_crossing(a, b, g[a], g[b]);
        }
    }
    EndPrimitive();
}
