//! Building and running the C and C++ programs of the tests and samples against the
//! `libcadr.so` of this build, with the strict flags hosts are promised to compile with.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The flags every C program is built with.
pub const STRICT_C: [&str; 5] = ["-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Werror"];

/// The repository's root.
pub fn repository() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The directory holding this build's `libcadr.so`, `libcadr.a` and technique plugins:
/// `target/<profile>/deps`, where cargo puts them as dependencies of the tests (they are copied
/// up to `target/<profile>` only by some builds).
pub fn library_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("the test's own path");
    let deps = exe
        .parent()
        .map(Path::to_path_buf)
        .expect("the test runs from target/<profile>/deps");
    if deps.join("libcadr.so").exists() {
        return deps;
    }
    deps.parent().map(Path::to_path_buf).unwrap_or(deps)
}

/// A test's scratch directory: removed when the test passes, kept when it fails (the test is
/// panicking) as the failure's evidence. The C and C++ builds in it take up to about 200 MB
/// (the installed package, the Qt sample), which every run of the suite would otherwise leave
/// behind.
pub struct ScratchDir {
    path: PathBuf,
}

impl std::ops::Deref for ScratchDir {
    type Target = Path;

    fn deref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<Path> for ScratchDir {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<std::ffi::OsStr> for ScratchDir {
    fn as_ref(&self) -> &std::ffi::OsStr {
        self.path.as_os_str()
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.path);
        }
    }
}

/// A fresh, empty directory for one test's files (see [`ScratchDir`]).
pub fn scratch_dir(name: &str) -> ScratchDir {
    let path = std::env::temp_dir().join(format!("cadr-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&path);
    std::fs::create_dir_all(&path).expect("create a scratch directory");
    ScratchDir { path }
}

/// Compiles C `sources` into the executable `output`, linked with `libcadr.so` of this build
/// (its directory recorded as the run path) plus `extra` flags; panics with the compiler's
/// messages on failure.
pub fn build_c_program(sources: &[PathBuf], output: &Path, extra: &[&str]) {
    let lib_dir = linkable_library_dir(output.parent().unwrap_or(Path::new(".")));
    let mut command = Command::new("cc");
    command
        .args(STRICT_C)
        .arg("-g")
        .arg("-I")
        .arg(repository().join("include"))
        .args(sources)
        .args(extra)
        .arg("-o")
        .arg(output)
        .arg("-L")
        .arg(&lib_dir)
        .arg(format!("-Wl,-rpath,{}", lib_dir.display()))
        .args(["-lcadr", "-lm"]);
    let result = command.output().expect("run cc (build-essential)");
    assert!(
        result.status.success(),
        "cc failed for {}:\n{}",
        output.display(),
        String::from_utf8_lossy(&result.stderr)
    );
}

/// A directory holding `libcadr.so` and its SONAME link `libcadr.so.MAJOR`, both pointing at
/// this build's library (the build directory itself has no SONAME link). Plugins are still
/// found beside the real file.
fn linkable_library_dir(scratch: &Path) -> PathBuf {
    let dir = scratch.join("lib");
    std::fs::create_dir_all(&dir).expect("create the library link directory");
    let library = library_dir().join("libcadr.so");
    let soname = format!("libcadr.so.{}", env!("CARGO_PKG_VERSION_MAJOR"));
    for name in ["libcadr.so", soname.as_str()] {
        let link = dir.join(name);
        let _ = std::fs::remove_file(&link);
        std::os::unix::fs::symlink(&library, &link).expect("link libcadr.so");
    }
    dir
}

/// The combined output of a finished program, for messages.
pub fn describe(output: &Output) -> String {
    format!(
        "status {:?}\n--- stdout\n{}\n--- stderr\n{}",
        output.status,
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    )
}
