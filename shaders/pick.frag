#version 460
// The pick pass: writes which instance covers each pixel (instance id + 1; 0 is nothing).
// Instances that cannot be picked come with id 0 and let the click through to what is behind.
layout(location = 4) flat in uint in_pick_id;

layout(location = 0) out uint out_id;

void main() {
    if (in_pick_id == 0u) {
        discard;
    }
    out_id = in_pick_id;
}
