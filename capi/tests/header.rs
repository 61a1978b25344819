//! The committed include/cadr.h is exactly what cbindgen generates from the sources, and it
//! compiles as strict C99 and C++. `CADR_UPDATE_HEADER=1` rewrites it.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::path::{Path, PathBuf};
use std::process::Command;

fn crate_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn header_path() -> PathBuf {
    crate_dir().join("../include/cadr.h")
}

fn generate() -> String {
    let config =
        cbindgen::Config::from_file(crate_dir().join("cbindgen.toml")).expect("read cbindgen.toml");
    let bindings = cbindgen::Builder::new()
        .with_crate(crate_dir())
        .with_config(config)
        .generate()
        .expect("cbindgen generates the header");
    let mut out = Vec::new();
    bindings.write(&mut out);
    String::from_utf8(out).expect("utf-8 header")
}

#[test]
fn committed_header_is_current() {
    let generated = generate();
    let committed = std::fs::read_to_string(header_path()).unwrap_or_default();
    if generated != committed {
        if std::env::var("CADR_UPDATE_HEADER").is_ok_and(|v| v == "1") {
            std::fs::write(header_path(), &generated).unwrap();
            return;
        }
        panic!("include/cadr.h is out of date: run CADR_UPDATE_HEADER=1 cargo test -p cadr-capi --test header, and commit it");
    }
}

fn compile(compiler: &str, standard: &str, language: &str, dir: &Path) {
    let source = dir.join(format!("header_check.{language}"));
    std::fs::write(
        &source,
        "#include \"cadr.h\"\nint main(void) { return cadr_version_string() == 0; }\n",
    )
    .unwrap();
    let output = Command::new(compiler)
        .args([
            standard,
            "-Wall",
            "-Wextra",
            "-Wpedantic",
            "-Werror",
            "-fsyntax-only",
            "-I",
        ])
        .arg(crate_dir().join("../include"))
        .arg(&source)
        .output()
        .unwrap_or_else(|e| panic!("{compiler} is needed (build-essential): {e}"));
    assert!(
        output.status.success(),
        "{compiler} {standard}:\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
}

#[test]
fn header_compiles_as_strict_c99_and_cpp() {
    let dir = std::env::temp_dir().join(format!("cadr-header-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    compile("cc", "-std=c99", "c", &dir);
    compile("c++", "-std=c++17", "cpp", &dir);
    // Kept where the test fails, for a look.
    let _ = std::fs::remove_dir_all(&dir);
}
