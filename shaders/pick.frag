#version 460
// The pick pass: writes which instance covers each pixel (instance id + 1; 0 is nothing).
layout(location = 4) flat in uint in_pick_id;

layout(location = 0) out uint out_id;

void main() {
    out_id = in_pick_id;
}
