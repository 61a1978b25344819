#!/usr/bin/env bash
# Installs what cadr needs on a fresh Debian 12 machine, skipping what is already there.
#   scripts/setup.sh          build and test dependencies
#   scripts/setup.sh --bench  also the tools the comparison benchmarks use (f3d, Xvfb, hyperfine)
set -euo pipefail

packages=(
  # Vulkan loader and headers, the CPU driver (lavapipe), validation layers, vulkaninfo.
  libvulkan1 libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers vulkan-tools
  # Shader compiler library linked at build time (shaderc plus its glslang and SPIRV-Tools).
  libshaderc-dev glslang-dev spirv-tools
  # The Khronos "2CylinderEngine" glTF sample used by the tests.
  assimp-testmodels
  # Build tools for crates with C parts.
  build-essential pkg-config
  # Windows for the GLFW sample programs, run under Xvfb; xwd grabs the viewer's window.
  xvfb libglfw3-dev x11-apps
  # The installed package is tested from a C++ host with CMake and with pkg-config.
  cmake
  # The font of `cadr bench --plot`'s labels.
  fonts-dejavu-core
  # Fetching and unpacking SwiftShader (below).
  curl ca-certificates brotli
)
if [[ "${1:-}" == "--bench" ]]; then
  packages+=(f3d hyperfine xauth)
fi

missing=()
for package in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$package")
  fi
done

if (( ${#missing[@]} > 0 )); then
  echo "setup: installing ${missing[*]}"
  sudo=""
  if [[ $(id -u) -ne 0 ]]; then sudo="sudo"; fi
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if ! command -v cargo >/dev/null 2>&1; then
  echo "setup: cargo is missing; install a Rust toolchain (rustup) first" >&2
  exit 1
fi

# SwiftShader, Google's CPU Vulkan driver, as a second Vulkan implementation for the
# portability test (cli/tests/swiftshader.rs): it keeps to the specification where lavapipe is
# lenient. Debian does not package it; the npm package @sparticuz/chromium carries a build
# (MIT; SwiftShader itself is Apache-2.0), fetched from the npm registry at a pinned version
# and checked against its digest. Only the driver and its manifest are kept, in
# target/swiftshader (CADR_SWIFTSHADER_DIR overrides).
repository="$(cd "$(dirname "$0")/.." && pwd)"
swiftshader_dir="${CADR_SWIFTSHADER_DIR:-$repository/target/swiftshader}"
if [[ ! -f "$swiftshader_dir/vk_swiftshader_icd.json" ]]; then
  echo "setup: fetching SwiftShader into $swiftshader_dir"
  package_url="https://registry.npmjs.org/@sparticuz/chromium/-/chromium-153.0.0.tgz"
  package_sha256="20e5656fcdcf4118ede85edfb9d6bb9cc1bbb7ffb8b75622fffbcf36a835c3c0"
  work="$(mktemp -d)"
  trap 'rm -rf "$work"' EXIT
  curl --fail --silent --show-error --location --retry 3 -o "$work/package.tgz" "$package_url"
  echo "$package_sha256  $work/package.tgz" | sha256sum --check --quiet
  tar -xzf "$work/package.tgz" -C "$work" package/bin/swiftshader.tar.br
  brotli --decompress --stdout "$work/package/bin/swiftshader.tar.br" > "$work/swiftshader.tar"
  mkdir -p "$swiftshader_dir"
  tar -xf "$work/swiftshader.tar" -C "$swiftshader_dir" libvk_swiftshader.so vk_swiftshader_icd.json
fi
