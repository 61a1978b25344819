#!/usr/bin/env bash
# Whole-process time from start to PNG written: `cadr render` (default techniques) vs the f3d
# viewer, on the same glTF file at the same size, alternating runs in one session. cadr runs
# twice per round: with its disk cache warm, and cold (an empty CADR_CACHE_DIR each run, so
# every shader is compiled and every pipeline built afresh; the driver's own cache is left as
# it is for both programs). Prints the medians and the ratios (cadr / f3d: below 1 means cadr
# is faster).
#   scripts/bench-f3d.sh [MODEL.glb] [RUNS]
set -euo pipefail
cd "$(dirname "$0")/.."
model="${1:-/usr/share/assimp/models/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb}"
runs="${2:-15}"
size_cadr="1024x768"
size_f3d="1024,768"

scripts/setup.sh --bench
cargo build --release --locked -p cadr-cli
cadr=./target/release/cadr
out="$(mktemp -d)"

# f3d needs an X display: start Xvfb first, so that its start-up is not counted.
display=":$(( 90 + RANDOM % 9 ))"
Xvfb "$display" -screen 0 1280x1024x24 -nolisten tcp >/dev/null 2>&1 &
xvfb_pid=$!
trap 'kill $xvfb_pid 2>/dev/null || true; rm -rf "$out"' EXIT
for _ in $(seq 50); do [[ -S "/tmp/.X11-unix/X${display#:}" ]] && break; sleep 0.1; done

elapsed_ms() {
  local start end
  start=$(date +%s%N)
  "$@" >/dev/null 2>&1 || { echo "failed: $*" >&2; exit 1; }
  end=$(date +%s%N)
  echo $(( (end - start) / 1000000 ))
}

median() { sort -n | awk '{ v[NR] = $1 } END { if (NR % 2) print v[(NR + 1) / 2]; else print (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }

# One warm-up each (disk cache, shader caches), then alternate.
warm_cache="$out/cache"
CADR_CACHE_DIR="$warm_cache" elapsed_ms "$cadr" render "$model" -o "$out/cadr.png" --size "$size_cadr" >/dev/null
DISPLAY="$display" elapsed_ms f3d --output="$out/f3d.png" --resolution="$size_f3d" "$model" >/dev/null
: > "$out/cadr.ms"; : > "$out/cold.ms"; : > "$out/f3d.ms"
for run in $(seq "$runs"); do
  CADR_CACHE_DIR="$warm_cache" elapsed_ms "$cadr" render "$model" -o "$out/cadr.png" --size "$size_cadr" >> "$out/cadr.ms"
  CADR_CACHE_DIR="$out/cold-$run" elapsed_ms "$cadr" render "$model" -o "$out/cadr.png" --size "$size_cadr" >> "$out/cold.ms"
  DISPLAY="$display" elapsed_ms f3d --output="$out/f3d.png" --resolution="$size_f3d" "$model" >> "$out/f3d.ms"
done
cadr_median=$(median < "$out/cadr.ms")
cold_median=$(median < "$out/cold.ms")
f3d_median=$(median < "$out/f3d.ms")
echo "model:            $model ($size_cadr, $runs runs each, alternating)"
echo "cadr, warm cache: median ${cadr_median} ms  (runs: $(tr '\n' ' ' < "$out/cadr.ms"))"
echo "cadr, cold cache: median ${cold_median} ms  (runs: $(tr '\n' ' ' < "$out/cold.ms"))"
echo "f3d:              median ${f3d_median} ms  (runs: $(tr '\n' ' ' < "$out/f3d.ms"))"
awk -v c="$cadr_median" -v k="$cold_median" -v f="$f3d_median" 'BEGIN {
  printf "ratio warm:       cadr / f3d = %.2f\n", c / f
  printf "ratio cold:       cadr / f3d = %.2f\n", k / f
}'
