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
