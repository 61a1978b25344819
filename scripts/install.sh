#!/usr/bin/env bash
# Installs cadr for C and C++ hosts under a prefix:
#   include/cadr/cadr.h, include/cadr/cadr_plugin.h   the C API and the plugin ABI
#   lib/libcadr.so(.1, .1.x.y), lib/libcadr.a          shared and static libraries
#   lib/cadr/plugins/libcadr_plugin_*.so               the technique plugins (found by libcadr.so)
#   lib/cmake/cadr/cadrConfig*.cmake                   find_package(cadr): cadr::cadr, cadr::cadr_static
#   lib/pkgconfig/cadr.pc                              pkg-config --cflags --libs cadr
#   bin/cadr                                           the command-line tool
#   share/cadr/samples/                                the C samples, buildable with CMake
#
# Usage: scripts/install.sh [--prefix DIR] [--profile release|debug] [--no-build] [--from DIR]
#   --prefix   where to install (default /usr/local)
#   --profile  which cargo profile to build and install (default release)
#   --no-build install what target/<profile> already holds
#   --from     take the built libraries from DIR instead of target/<profile> (implies --no-build)
set -euo pipefail
cd "$(dirname "$0")/.."

prefix=/usr/local
profile=release
build=1
from=""
while (( $# > 0 )); do
  case "$1" in
    --prefix) prefix="$2"; shift 2 ;;
    --profile) profile="$2"; shift 2 ;;
    --no-build) build=0; shift ;;
    --from) from="$2"; build=0; shift 2 ;;
    -h|--help) sed -n '2,17p' "$0"; exit 0 ;;
    *) echo "install: unknown option $1 (see --help)" >&2; exit 2 ;;
  esac
done

packages=(-p cadr-capi -p cadr-cli -p cadr-plugin-vertex -p cadr-plugin-parameters
          -p cadr-plugin-submission -p cadr-plugin-culling -p cadr-plugin-transparency)
if (( build )); then
  if [[ "$profile" == release ]]; then
    cargo build --locked --release "${packages[@]}"
  else
    cargo build --locked --profile "$profile" "${packages[@]}"
  fi
fi
target_dir="${CARGO_TARGET_DIR:-target}"
out="$target_dir/$profile"
[[ "$profile" == dev ]] && out="$target_dir/debug"
[[ -n "$from" ]] && out="$from"
for needed in libcadr.so libcadr.a; do
  if [[ ! -f "$out/$needed" ]]; then
    echo "install: $out/$needed is missing; build first (drop --no-build)" >&2
    exit 1
  fi
done

version=$(sed -n 's/^version = "\(.*\)"/\1/p' Cargo.toml | head -1)
major=${version%%.*}
mkdir -p "$prefix"
prefix=$(cd "$prefix" && pwd)
lib="$prefix/lib"
mkdir -p "$prefix/include/cadr" "$lib/cadr/plugins" "$lib/cmake/cadr" "$lib/pkgconfig" \
         "$prefix/bin" "$prefix/share/cadr/samples/common"

install -m 644 include/cadr.h include/cadr_plugin.h "$prefix/include/cadr/"
install -m 755 "$out/libcadr.so" "$lib/libcadr.so.$version"
ln -sf "libcadr.so.$version" "$lib/libcadr.so.$major"
ln -sf "libcadr.so.$major" "$lib/libcadr.so"
install -m 644 "$out/libcadr.a" "$lib/libcadr.a"
for plugin in "$out"/libcadr_plugin_*.so; do
  install -m 755 "$plugin" "$lib/cadr/plugins/"
done
if [[ -f "$out/cadr" ]]; then
  install -m 755 "$out/cadr" "$prefix/bin/cadr"
fi

# What the static library needs from the system (rustc --print native-static-libs).
static_libs="-lstdc++ -ldl -lgcc_s -lutil -lrt -lpthread -lm -lc"
sed -e "s|@VERSION@|$version|g" -e "s|@MAJOR@|$major|g" -e "s|@STATIC_LIBS@|${static_libs//-l/}|g" \
  packaging/cadrConfig.cmake.in > "$lib/cmake/cadr/cadrConfig.cmake"
sed -e "s|@VERSION@|$version|g" -e "s|@MAJOR@|$major|g" packaging/cadrConfigVersion.cmake.in \
  > "$lib/cmake/cadr/cadrConfigVersion.cmake"
sed -e "s|@PREFIX@|$prefix|g" -e "s|@VERSION@|$version|g" -e "s|@STATIC_LIBS@|$static_libs|g" \
  packaging/cadr.pc.in > "$lib/pkgconfig/cadr.pc"

install -m 644 samples/*.c samples/*.cpp samples/CMakeLists.txt samples/README.md "$prefix/share/cadr/samples/"
install -m 644 samples/common/* "$prefix/share/cadr/samples/common/"
echo "installed cadr $version under $prefix"
