//! The installed package, used the way C and C++ hosts use it: `scripts/install.sh` puts the
//! headers, libraries, plugins, CMake package and pkg-config file under a prefix; a C++ program
//! outside the workspace finds it with `find_package(cadr)` and links it shared and static; the
//! installed samples build with CMake; a C program builds with `pkg-config` flags alone.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::path::Path;
use std::process::Command;

use cadr_tests::c_programs::{describe, library_dir, repository, scratch_dir};

fn run(command: &mut Command) -> String {
    let output = command.output().unwrap();
    assert!(
        output.status.success(),
        "{command:?}\n{}",
        describe(&output)
    );
    String::from_utf8_lossy(&output.stdout).into_owned()
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        std::fs::copy(entry.path(), to.join(entry.file_name())).unwrap();
    }
}

fn png_size(path: &Path) -> (u32, u32) {
    image::image_dimensions(path).unwrap()
}

#[test]
fn cpp_host_builds_against_the_installed_package_with_cmake() {
    let dir = scratch_dir("package");
    let prefix = dir.join("prefix");
    run(Command::new(repository().join("scripts/install.sh"))
        .args(["--prefix", prefix.to_str().unwrap(), "--from"])
        .arg(library_dir()));
    for installed in [
        "include/cadr/cadr.h",
        "include/cadr/cadr_plugin.h",
        "lib/libcadr.so",
        "lib/libcadr.so.1",
        "lib/libcadr.a",
        "lib/cadr/plugins/libcadr_plugin_submission.so",
        "lib/cmake/cadr/cadrConfig.cmake",
        "lib/cmake/cadr/cadrConfigVersion.cmake",
        "lib/pkgconfig/cadr.pc",
        "share/cadr/samples/CMakeLists.txt",
    ] {
        assert!(
            prefix.join(installed).exists(),
            "{installed} was not installed"
        );
    }

    // The C++ host, copied out of the workspace: nothing but the prefix to go on.
    let host = dir.join("host");
    copy_dir(&repository().join("tests/cpp-consumer"), &host);
    let build = host.join("build");
    run(Command::new("cmake")
        .arg("-S")
        .arg(&host)
        .arg("-B")
        .arg(&build)
        .arg(format!("-DCMAKE_PREFIX_PATH={}", prefix.display())));
    run(Command::new("cmake").arg("--build").arg(&build));
    for program in ["consumer", "consumer_static"] {
        let png = dir.join(format!("{program}.png"));
        let stdout = run(Command::new(build.join(program))
            .arg(&png)
            .env_remove("CADR_PLUGIN_PATH")
            .current_dir(&dir));
        assert!(
            stdout.contains("368 of 368 triangles drawn"),
            "{program}: {stdout}"
        );
        assert_eq!(png_size(&png), (320, 240));
    }

    // An old or foreign major version is refused by the version file.
    let probe = dir.join("probe");
    std::fs::create_dir_all(&probe).unwrap();
    std::fs::write(
        probe.join("CMakeLists.txt"),
        "cmake_minimum_required(VERSION 3.16)\nproject(probe NONE)\nfind_package(cadr 7.0 REQUIRED)\n",
    )
    .unwrap();
    let refused = Command::new("cmake")
        .arg("-S")
        .arg(&probe)
        .arg("-B")
        .arg(probe.join("build"))
        .arg(format!("-DCMAKE_PREFIX_PATH={}", prefix.display()))
        .output()
        .unwrap();
    assert!(
        !refused.status.success(),
        "find_package(cadr 7.0) accepted this version"
    );

    // The installed samples build with CMake and run from the prefix.
    let samples = dir.join("samples-build");
    run(Command::new("cmake")
        .arg("-S")
        .arg(prefix.join("share/cadr/samples"))
        .arg("-B")
        .arg(&samples)
        .arg(format!("-DCMAKE_PREFIX_PATH={}", prefix.display())));
    run(Command::new("cmake").arg("--build").arg(&samples));
    let png = dir.join("headless.png");
    run(Command::new(samples.join("headless"))
        .args([png.to_str().unwrap(), "160", "120"])
        .env_remove("CADR_PLUGIN_PATH"));
    assert_eq!(png_size(&png), (160, 120));

    // pkg-config alone is enough for a C build.
    let flags = run(Command::new("pkg-config")
        .args(["--cflags", "--libs", "cadr"])
        .env("PKG_CONFIG_PATH", prefix.join("lib/pkgconfig")));
    let program = dir.join("headless-pkg-config");
    let mut cc = Command::new("cc");
    cc.args([
        "-std=c99",
        "-Wall",
        "-Wextra",
        "-Wpedantic",
        "-Werror",
        "-I",
    ])
    .arg(prefix.join("share/cadr/samples"))
    .arg(prefix.join("share/cadr/samples/headless.c"))
    .arg(prefix.join("share/cadr/samples/common/sample.c"))
    .args(flags.split_whitespace())
    .arg(format!("-Wl,-rpath,{}", prefix.join("lib").display()))
    .args(["-lm", "-o"])
    .arg(&program);
    run(&mut cc);
    let png = dir.join("pkg-config.png");
    run(Command::new(&program)
        .args([png.to_str().unwrap(), "64", "48"])
        .env_remove("CADR_PLUGIN_PATH"));
    assert_eq!(png_size(&png), (64, 48));
}
