//! Links the parts of Debian's shaderc that its `libshaderc_combined.a` leaves out.
//!
//! Debian builds shaderc against the system glslang and SPIRV-Tools, so its "combined"
//! archive holds only shaderc itself; glslang and SPIRV-Tools come as their own static
//! archives (packages glslang-dev and spirv-tools). shaderc-sys links the shaderc archive
//! (feature `prefer-static-linking`); this adds the rest. Other systems (a Vulkan SDK, a truly
//! combined archive) need none of it, so only archives that exist are linked.

use std::path::Path;

const LIB_DIR_ENV: &str = "SHADERC_LIB_DIR";
const COMPANION_ARCHIVES: &[&str] = &[
    "glslang",
    "MachineIndependent",
    "GenericCodeGen",
    "OSDependent",
    "OGLCompiler",
    "HLSL",
    "SPIRV",
    "glslang-default-resource-limits",
    "SPIRV-Tools-opt",
    "SPIRV-Tools",
];

fn main() {
    println!("cargo:rerun-if-env-changed={LIB_DIR_ENV}");
    let Ok(dir) = std::env::var(LIB_DIR_ENV) else {
        return;
    };
    let dir = Path::new(&dir);
    let combined_has_glslang = !dir.join("libglslang.a").exists();
    if combined_has_glslang {
        return;
    }
    println!("cargo:rustc-link-search=native={}", dir.display());
    for name in COMPANION_ARCHIVES {
        if dir.join(format!("lib{name}.a")).exists() {
            println!("cargo:rustc-link-lib=static={name}");
        }
    }
    println!("cargo:rustc-link-lib=dylib=stdc++");
}
