#!/usr/bin/env bash
# Installs what cadr needs on a fresh Debian 12 machine, skipping what is already there.
#   scripts/setup.sh          build and test dependencies
#   scripts/setup.sh --bench  also the tools the comparison benchmarks use (f3d, Xvfb, hyperfine)
set -euo pipefail

packages=(
  # Vulkan loader and headers, validation layers, vulkaninfo. The CPU driver (lavapipe) comes
  # from the backports suite, below.
  libvulkan1 libvulkan-dev vulkan-validationlayers vulkan-tools
  # Shader compiler library linked at build time (shaderc plus its glslang and SPIRV-Tools).
  libshaderc-dev glslang-dev spirv-tools
  # The Khronos "2CylinderEngine" glTF sample used by the tests.
  assimp-testmodels
  # Build tools for crates with C parts.
  build-essential pkg-config
  # Windows for the GLFW sample programs, run under Xvfb; xwd grabs the viewer's window. The
  # OpenGL samples (gl_view, quad_view) link libGL.
  xvfb libglfw3-dev libgl-dev x11-apps
  # The C API's ABI is compared with its committed baseline (abidw, abidiff).
  abigail-tools
  # The Qt 6 sample (samples/qt_viewer.cpp) and the xcb headers of its X11 surface.
  qt6-base-dev libxcb1-dev
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

sudo=""
if [[ $(id -u) -ne 0 ]]; then sudo="sudo"; fi

missing=()
for package in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$package")
  fi
done

if (( ${#missing[@]} > 0 )); then
  echo "setup: installing ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# Mesa 25's lavapipe (Vulkan 1.4: mesh shaders, descriptor indexing, device-generated commands)
# is the default driver of the tests. Debian 12 ships Mesa 22.3; Debian's own backports suite
# has Mesa 25. The suite is added on the mirror this machine already uses for bookworm (read
# from its apt configuration, so no host name is written here); backports are pinned below the
# release by default, so nothing else is upgraded from it.
mesa_wanted="25."
if [[ "$(dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null)" != "$mesa_wanted"* ||
      "$(dpkg-query -W -f='${Version}' libgl1-mesa-dri 2>/dev/null)" != "$mesa_wanted"* ]]; then
  backports_list=/etc/apt/sources.list.d/cadr-bookworm-backports.sources
  if ! apt-get indextargets --no-release-info --format '$(RELEASE)' 'Created-By: Packages' \
      | grep -qx bookworm-backports; then
    mirror="$(apt-get indextargets --no-release-info --format '$(REPO_URI) $(RELEASE)' \
      'Created-By: Packages' | awk '$2 == "bookworm" { print $1; exit }')"
    if [[ -z "$mirror" ]]; then
      echo "setup: no apt source serves Debian 12 (bookworm); cannot add bookworm-backports" >&2
      exit 1
    fi
    echo "setup: adding bookworm-backports from $mirror"
    printf 'Types: deb\nURIs: %s\nSuites: bookworm-backports\nComponents: main\nSigned-By: %s\n' \
      "$mirror" /usr/share/keyrings/debian-archive-keyring.gpg | $sudo tee "$backports_list" >/dev/null
  fi
  # Its OpenGL driver too (llvmpipe): the OpenGL sample imports lavapipe's exported memory,
  # which the two drivers share only when they are of one Mesa.
  echo "setup: installing Mesa 25's Vulkan and OpenGL drivers from bookworm-backports"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends \
    -t bookworm-backports mesa-vulkan-drivers libgl1-mesa-dri libglx-mesa0 >/dev/null
fi

repository="$(cd "$(dirname "$0")/.." && pwd)"

# Debian 12's own driver, Mesa 22.3's lavapipe (Vulkan 1.3: no mesh shaders, no descriptor
# indexing, no device-generated commands), stays a tested target for the fallback paths. Its
# package is fetched from the bookworm suite and unpacked, not installed, into target/mesa-22.3
# (CADR_MESA22_DIR overrides), with a manifest that names the unpacked library.
mesa22_dir="${CADR_MESA22_DIR:-$repository/target/mesa-22.3}"
if [[ ! -f "$mesa22_dir/lvp_icd.json" ]]; then
  echo "setup: unpacking Mesa 22.3's lavapipe into $mesa22_dir"
  work22="$(mktemp -d)"
  # As root, apt would download as its own user, who cannot write into a private directory.
  download_mesa22() {
    (cd "$work22" && apt-get download -qq -o APT::Sandbox::User="$(id -un)" mesa-vulkan-drivers/bookworm)
  }
  if ! download_mesa22; then
    $sudo apt-get update -qq
    download_mesa22
  fi
  dpkg -x "$work22"/mesa-vulkan-drivers_22.3*.deb "$work22/root"
  mkdir -p "$mesa22_dir"
  cp "$(find "$work22/root" -name libvulkan_lvp.so -print -quit)" "$mesa22_dir/"
  # The package's own manifest, pointed at the unpacked library.
  sed -E "s|\"library_path\": *\"[^\"]*\"|\"library_path\": \"$mesa22_dir/libvulkan_lvp.so\"|" \
    "$(find "$work22/root" -name 'lvp_icd.*.json' -print -quit)" > "$mesa22_dir/lvp_icd.json"
  rm -rf "$work22"
fi

if ! command -v cargo >/dev/null 2>&1; then
  echo "setup: cargo is missing; install a Rust toolchain (rustup) first" >&2
  exit 1
fi

# The toolchain rust-toolchain.toml pins. Where rustup lacks it but its stable toolchain is that
# very release (a machine that cannot download toolchains), stable is made to answer to the
# pinned name as well (rustup refuses to `link` a custom toolchain under a release's name, so
# the link is made in rustup's toolchains folder, as rustup names installed releases);
# otherwise rustup installs it.
pinned_toolchain="$(sed -n 's/^channel = "\(.*\)"$/\1/p' "$repository/rust-toolchain.toml")"
if command -v rustup >/dev/null 2>&1 && ! rustup toolchain list | grep -q "^$pinned_toolchain-"; then
  if [[ "$(rustc +stable --version 2>/dev/null | cut -d' ' -f2)" == "$pinned_toolchain" ]]; then
    host="$(rustc +stable -vV | sed -n 's/^host: //p')"
    toolchains="$(rustup show home)/toolchains"
    echo "setup: the stable toolchain answers to Rust $pinned_toolchain (rust-toolchain.toml) too"
    ln -s "$toolchains/stable-$host" "$toolchains/$pinned_toolchain-$host"
  else
    echo "setup: installing Rust $pinned_toolchain (rust-toolchain.toml)"
    rustup toolchain install "$pinned_toolchain" --profile minimal --component rustfmt,clippy
  fi
fi

# SwiftShader, Google's CPU Vulkan driver, as a second Vulkan implementation for the
# portability test (cli/tests/swiftshader.rs): it keeps to the specification where lavapipe is
# lenient. Debian does not package it; the npm package @sparticuz/chromium carries a build
# (MIT; SwiftShader itself is Apache-2.0), fetched from the npm registry at a pinned version
# and checked against its digest. Only the driver and its manifest are kept, in
# target/swiftshader (CADR_SWIFTSHADER_DIR overrides).
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
