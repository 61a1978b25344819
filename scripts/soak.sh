#!/usr/bin/env bash
# A soak run: a C host (tests/c/soak.c) loads, edits, renders, picks and swaps technique
# plugins in a loop through the C API, and reports its resident memory and the device memory
# cadr holds over time.
#
#   scripts/soak.sh [MINUTES] [soak options...]      MINUTES default 30; gen:graphicscard stays,
#                                                    gen:demo is loaded and unloaded each time
#
# The first minute is the warm-up (pipelines compiled, caches and pools filled); after it, the
# run fails when either memory grows by more than 1 % over the warm-up's peak. Every sample is
# written to target/soak/memory.csv; options after MINUTES go to the program (for example
# `--load FILE.glb`, `--scene gen:racecar`, `--validation`, `--max-growth-percent 0.5`).
#
# It runs on SwiftShader (fetched by setup.sh into target/swiftshader) unless VK_ICD_FILENAMES
# names another driver: Debian 12's lavapipe (Mesa 22.3) itself keeps about 0.3 MB on its queue
# thread for every pick, which would hide cadr's own figures (Mesa 25's lavapipe does not).
set -euo pipefail
cd "$(dirname "$0")/.."

minutes="${1:-30}"
shift || true
if ! [[ "$minutes" =~ ^[0-9]+([.][0-9]+)?$ ]]; then
  echo "usage: scripts/soak.sh [MINUTES] [soak options...]" >&2
  exit 2
fi

scripts/setup.sh
cargo build --release --locked -p cadr-capi -p cadr-plugin-vertex -p cadr-plugin-parameters \
  -p cadr-plugin-submission -p cadr-plugin-culling -p cadr-plugin-transparency

out=target/soak
mkdir -p "$out"
# Linked against this build's libcadr.so; the technique plugins lie beside it.
# The library's SONAME (libcadr.so.MAJOR) is linked from target/soak/lib to this build's file.
mkdir -p "$out/lib"
ln -sf "$PWD/target/release/libcadr.so" "$out/lib/libcadr.so"
ln -sf "$PWD/target/release/libcadr.so" "$out/lib/libcadr.so.$(sed -n 's/^version = "\([0-9]*\)\..*/\1/p' Cargo.toml | head -1)"
cc -std=c99 -O2 -Wall -Wextra -Wpedantic -Werror -Iinclude -Isamples tests/c/soak.c \
  samples/common/sample.c -o "$out/soak" \
  -L"$out/lib" -Wl,-rpath,"$PWD/$out/lib" -lcadr -lm

swiftshader="${CADR_SWIFTSHADER_DIR:-$PWD/target/swiftshader}/vk_swiftshader_icd.json"
export VK_ICD_FILENAMES="${VK_ICD_FILENAMES:-$swiftshader}"
# The technique plugins lie beside libcadr.so.
export CADR_PLUGIN_PATH="$PWD/target/release"

seconds=$(awk -v m="$minutes" 'BEGIN { printf "%d", m * 60 }')
warmup=$(( seconds < 600 ? seconds / 10 : 60 ))
echo "soak: $minutes minutes (warm-up $warmup s), samples in $out/memory.csv"
"$out/soak" --seconds "$seconds" --warmup-seconds "$warmup" --csv "$out/memory.csv" "$@"
