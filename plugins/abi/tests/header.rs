//! The committed include/cadr_plugin.h is exactly what cbindgen generates from the ABI crate,
//! and it compiles as strict C99 and C++. `CADR_UPDATE_HEADER=1` rewrites it.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::path::PathBuf;
use std::process::Command;

fn crate_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn header_path() -> PathBuf {
    crate_dir().join("../../include/cadr_plugin.h")
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
        panic!("include/cadr_plugin.h is out of date: run CADR_UPDATE_HEADER=1 cargo test -p cadr-plugin-abi --test header, and commit it");
    }
}

/// The C plugin in tests/c-plugin compiles against the header as strict C99 and as C++.
#[test]
fn header_compiles_as_strict_c99_and_cpp() {
    let plugin = crate_dir().join("../../tests/c-plugin/cull_everything_visible.c");
    for (compiler, standard, language) in [("cc", "-std=c99", "c"), ("c++", "-std=c++17", "c++")] {
        let output = Command::new(compiler)
            .args([
                "-x",
                language,
                standard,
                "-Wall",
                "-Wextra",
                "-Wpedantic",
                "-Werror",
                "-fsyntax-only",
                "-I",
            ])
            .arg(crate_dir().join("../../include"))
            .arg(&plugin)
            .output()
            .unwrap_or_else(|e| panic!("{compiler} is needed (build-essential): {e}"));
        assert!(
            output.status.success(),
            "{compiler} {standard}:\n{}",
            String::from_utf8_lossy(&output.stderr)
        );
    }
}
