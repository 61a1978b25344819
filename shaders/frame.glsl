// Per-frame parameters (binding frequency "view"): set 0, binding 0.
// Mirrored by cadr_core::render::FrameUniforms; offsets are asserted in a test.
layout(set = 0, binding = 0, std140) uniform FrameUniforms {
    mat4 projection;       // view space -> clip space (Vulkan: y down, depth 0..1)
    mat4 view_rotation;    // world -> view space with the eye at the origin (no translation)
    vec4 eye_high;         // the eye's world position: f32 high part (xyz) ...
    vec4 eye_low;          // ... and the f32 remainder, split from f64 on the CPU
    vec4 light;            // x: ambient, y: diffuse, z: specular, w: unused
} frame;
