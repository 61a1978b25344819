//! AFL++ entry point of the `gltf` fuzz target (see `cadr_fuzz::Target::Gltf` and fuzz/README.md).

fn main() {
    afl::fuzz!(|data: &[u8]| cadr_fuzz::Target::Gltf.run(data));
}
