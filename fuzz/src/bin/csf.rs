//! AFL++ entry point of the `csf` fuzz target (see `cadr_fuzz::Target::Csf` and fuzz/README.md).

fn main() {
    afl::fuzz!(|data: &[u8]| cadr_fuzz::Target::Csf.run(data));
}
