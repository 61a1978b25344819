// Per-frame parameters (binding frequency "view"): set 0, binding 0.
// Mirrored by cadr_core::render::FrameUniforms; offsets are asserted in a test.
layout(set = 0, binding = 0, std140) uniform FrameUniforms {
    mat4 projection;       // view space -> clip space (Vulkan: y down, depth 0..1)
    mat4 view_from_origin; // scene-origin-relative world space -> view space (made in f64 on the CPU)
    vec4 light;            // x: ambient, y: diffuse, z: specular, w: unused
} frame;
