#!/usr/bin/env bash
# The GPU benchmark for a lent machine (one NVIDIA H100 or H200): every table of
# docs/BENCHMARKS.md's GPU section, as bench JSON and PNG plots, at 1920x1080, in under 9
# minutes. That machine reaches no package registry, so nothing is built there: run it from a
# copy of the repository that carries a release build (target/release: cadr and the plugin
# libraries, made here with `cargo build --release --workspace`) and, where the machine has no
# Vulkan loader, the loader packages in .gl/ (the device tool's README says how to fetch
# them); NVIDIA's Vulkan driver is found where that machine keeps it.
#   scripts/bench-gpu.sh --pack [DIR]       here, after `cargo build --release --workspace`
#   scripts/bench-gpu.sh [--dry-run] [OUT-DIR]
# --pack copies what the machine needs into DIR (default target/bench-gpu-build): cadr and the
# plugin libraries, stripped (about 15 MB), and the plot labels' font; name DIR (and .gl) in the
# device tool's `carry`, and the script finds it there. --dry-run measures the same rows at a small size and scene on whatever Vulkan driver is
# present (lavapipe here): the test that the script starts and writes its files. Files go to
# OUT-DIR (default target/bench-gpu); the device's name and driver are in devices.txt.
# The whole run keeps inside CADR_BENCH_GPU_SECONDS (default 450): a table that would start with
# under 20 s left is skipped and counted as failed, and a table's limit is cut to what is left,
# so the caller's archive step always runs inside the device tool's time limit.
# CADR_BENCH_GPU_TABLES=NAME,NAME runs only the tables named (a rerun of those that failed).
set -euo pipefail
cd "$(dirname "$0")/.."

packed=target/bench-gpu-build
if [[ "${1:-}" == "--pack" ]]; then
  pack="${2:-$packed}"
  mkdir -p "$pack"
  for file in target/release/cadr target/release/libcadr_plugin_*.so; do
    [[ -f "$file" ]] || { echo "bench-gpu: $file is missing: cargo build --release --workspace" >&2; exit 1; }
    strip -o "$pack/$(basename "$file")" "$file"
  done
  font=/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf
  if [[ -f "$font" ]]; then cp "$font" "$pack/"; fi
  echo "bench-gpu: packed $(du -sh "$pack" | cut -f1) into $pack: carry it (and .gl) to the machine"
  exit 0
fi

dry_run=0
if [[ "${1:-}" == "--dry-run" ]]; then
  dry_run=1
  shift
fi
out="${1:-target/bench-gpu}"
mkdir -p "$out"

if [[ -z "${CADR_BIN:-}" && -x "$packed/cadr" ]]; then
  CADR_BIN="$packed/cadr"
fi
cadr="${CADR_BIN:-target/release/cadr}"
if [[ ! -x "$cadr" ]]; then
  echo "bench-gpu: $cadr is missing: build it first (cargo build --release --workspace)" >&2
  exit 1
fi
export CADR_PLUGIN_PATH="${CADR_PLUGIN_PATH:-$(dirname "$cadr")}"
# The plot labels' font, where the machine has no DejaVu Sans of its own.
if [[ -z "${CADR_PLOT_FONT:-}" && ! -f /usr/share/fonts/truetype/dejavu/DejaVuSans.ttf \
      && -f "$(dirname "$cadr")/DejaVuSans.ttf" ]]; then
  export CADR_PLOT_FONT="$(dirname "$cadr")/DejaVuSans.ttf"
fi

# The Vulkan loader: carried as packages where the machine has none. (ldconfig lives in /sbin,
# which an unprivileged PATH may lack.)
ldconfig=$(command -v ldconfig || echo /sbin/ldconfig)
# (grep reads all of ldconfig's list: -q would close the pipe early, a SIGPIPE under pipefail.)
if ! "$ldconfig" -p 2>/dev/null | grep 'libvulkan\.so\.1' >/dev/null; then
  if compgen -G ".gl/*.deb" >/dev/null; then
    for package in .gl/*.deb; do dpkg -x "$package" /; done
    "$ldconfig"
  else
    echo "bench-gpu: no Vulkan loader (libvulkan1) and no .gl/*.deb to unpack" >&2
    exit 1
  fi
fi
nvidia_icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
if [[ -z "${VK_DRIVER_FILES:-}${VK_ICD_FILENAMES:-}" && -f "$nvidia_icd" ]]; then
  export VK_DRIVER_FILES="$nvidia_icd"
fi

if (( dry_run )); then
  size=320x240 frames=2 few_frames=1 big="gen:grid:parts=2000" heavy="gen:grid:parts=200,tris=400"
  scaling_small="gen:grid:parts=20,tris=400" scaling_large="gen:grid:parts=2000,tris=400"
  card="gen:demo" racecar="gen:demo" cabinet="gen:cabinet:cabinets=2"
  fine="gen:fine:units=1,detail=1" details=1,2 units=1
  per_run=120
else
  size=1920x1080 frames=20 few_frames=3 big="gen:grid:parts=10000000" heavy="gen:grid:parts=100000,tris=400"
  scaling_small="gen:grid:parts=1000,tris=400" scaling_large="gen:grid:parts=100000,tris=400"
  card="gen:graphicscard" racecar="gen:racecar" cabinet="gen:cabinet"
  fine="gen:fine:units=16,detail=4" details=1,2,4,8 units=16
  per_run=150
fi

{
  date -u +"%Y-%m-%dT%H:%M:%SZ"
  "$cadr" devices
  if command -v nvidia-smi >/dev/null 2>&1; then
    nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader
  fi
} | tee "$out/devices.txt"

failures=0
deadline=$((SECONDS + ${CADR_BENCH_GPU_SECONDS:-450}))
# One table: NAME, measured frames per row, then cadr bench's arguments. Each table has its time
# limit, so that one slow table cannot eat the others' time.
bench() {
  local name=$1 table_frames=$2
  shift 2
  if [[ -n "${CADR_BENCH_GPU_TABLES:-}" && ",$CADR_BENCH_GPU_TABLES," != *",$name,"* ]]; then
    return
  fi
  local left=$((deadline - SECONDS))
  if (( left < 20 )); then
    echo "bench-gpu: $name skipped: the run's ${CADR_BENCH_GPU_SECONDS:-450} s are spent" >&2
    failures=$((failures + 1))
    return
  fi
  local limit=$(( left < per_run ? left : per_run ))
  echo "bench-gpu: $name (at most $limit s)"
  if ! timeout "$limit" "$cadr" bench "$@" --size "${table_size:-$size}" --frames "$table_frames" \
    --json "$out/$name.json" --plot "$out/$name.png" >"$out/$name.txt" 2>&1; then
    echo "bench-gpu: $name failed or ran past ${limit} s (see $out/$name.txt)" >&2
    failures=$((failures + 1))
  fi
  tail -n +1 "$out/$name.txt" | sed 's/^/  /'
}

scene_wide=(--vertex arena --params ssbo-index)
# Every submission technique, still camera.
bench graphicscard-static "$frames" "$card" --camera static
# The cullers while the camera orbits (the frustum cuts the scene).
bench graphicscard-orbit "$frames" "$card" --camera orbit "${scene_wide[@]}" \
  --submit individual-indirect-count --cull none,frustum,gpu-frustum,gpu-occlusion
# Occlusion: machines in closed housings, whose panels' boxes find far more of them hidden than
# their spheres would; whole parts against clusters.
bench cabinet-orbit "$frames" "$cabinet" --camera orbit "${scene_wide[@]}" \
  --submit individual-indirect-count --cull none,gpu-frustum,gpu-occlusion,gpu-clusters
# Every display mode.
bench graphicscard-display-all "$frames" "$card" --display all "${scene_wide[@]}" --submit groups-mdi-replay
# 400 triangles a part, 32 million in all (41 a pixel): rasterization, not the CPU, bounds the
# frame, unless clusters and LOD cut it.
bench triangle-heavy "$frames" "$heavy" "${scene_wide[@]}" --submit individual-indirect-count,dgc \
  --cull none,gpu-frustum,gpu-clusters
# Ten million parts.
bench grid-10m "$few_frames" "$big" "${scene_wide[@]}" --submit individual-indirect-count,dgc \
  --cull gpu-frustum --camera orbit
# Device-generated commands against the recorded multi-draw-indirect replay, and (with a GPU
# culler, whose two back-face passes dgc draws as one stream switching pipelines per sequence)
# against the two indirect-count draws of the same passes; with the push parameter path too
# (the culler writes each draw's parameter block, a push-constant token pushes it: the only
# valid push row here is dgc / gpu-frustum, the others are left out).
bench dgc-graphicscard "$frames" "$card" --vertex arena --params ssbo-index,push \
  --submit dgc,groups-mdi-replay,individual-indirect-count --cull none,gpu-frustum --camera orbit
bench dgc-racecar "$frames" "$racecar" "${scene_wide[@]}" --submit dgc,groups-mdi-replay \
  --cull none,gpu-frustum --camera orbit
# Clusters and level of detail: per-part occlusion against clusters at full detail and at 1 px,
# orbiting; then the GPU time over gen:fine's tessellations (scene triangles).
bench clusters-fine "$frames" "$fine" "${scene_wide[@]}" --submit individual-indirect-count \
  --cull gpu-occlusion,gpu-clusters --lod-error 0,1 --camera orbit --no-replay
bench clusters-sweep "$few_frames" --sweep-detail "$details" --sweep-units "$units" --no-replay
# The GPU cullers' commands drawn by mesh workgroups (VK_EXT_mesh_shader) against the same
# commands as indexed indirect draws, both with the paths a mesh shader runs (pulling,
# ssbo-index): per part, per cluster at full detail, per cluster at 1 px.
bench mesh-fine "$frames" "$fine" --vertex pulling --params ssbo-index \
  --submit individual-indirect-count,mesh-tasks --cull gpu-occlusion,gpu-clusters --lod-error 0,1 \
  --camera orbit --no-replay

# Issue 41's scaling goal, as it is worded: at 1024x768 and the default level of detail, the
# 100 000-part grid of 400-triangle parts against the 1 000-part one (at most 3x the GPU time,
# at most 4 triangles rasterized per covered pixel); and the same in the edges display mode,
# whose lines follow the pixels through their levels (plugin ABI 1.25).
scaling=(--vertex arena --params ssbo-index --submit individual-indirect-count --cull gpu-clusters
  --lod-error 1 --no-replay --display solid,edges)
table_size=1024x768 bench scaling-small "$frames" "$scaling_small" "${scaling[@]}"
table_size=1024x768 bench scaling-large "$frames" "$scaling_large" "${scaling[@]}"
if command -v python3 >/dev/null 2>&1 && [[ -f "$out/scaling-small.json" && -f "$out/scaling-large.json" ]]; then
  python3 - "$out/scaling-small.json" "$out/scaling-large.json" <<'PY' | tee "$out/scaling.txt"
import json, sys
tables = [json.load(open(path))["rows"] for path in sys.argv[1:3]]
def clusters_row(rows, shade):
    return [r for r in rows if "gpu-clusters" in r["technique"] and r["shade"] == shade][-1]
small, large = (clusters_row(rows, "solid") for rows in tables)
print("scaling goal: GPU time %.2fx the small grid's (%.0f against %.0f us; goal at most 3x); "
      "%.2f triangles per covered pixel (goal at most 4)"
      % (large["gpu_us"] / small["gpu_us"], large["gpu_us"], small["gpu_us"],
         large["triangles_per_covered_pixel"]))
small, large = (clusters_row(rows, "edges") for rows in tables)
print("in the edges mode: GPU time %.2fx the small grid's (%.0f against %.0f us)"
      % (large["gpu_us"] / small["gpu_us"], large["gpu_us"], small["gpu_us"]))
PY
fi

echo "bench-gpu: wrote $out ($failures of 13 tables failed)"
exit $(( failures > 0 ))
