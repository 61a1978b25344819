//! AFL++ entry point of the `scene_load` fuzz target (see `cadr_fuzz::Target::SceneLoad` and fuzz/README.md).

fn main() {
    afl::fuzz!(|data: &[u8]| cadr_fuzz::Target::SceneLoad.run(data));
}
