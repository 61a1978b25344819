#!/usr/bin/env bash
# Every test: set up, check formatting, lints and docs, run all tests (validation layers on) on the
# default driver (Mesa 25's lavapipe from scripts/setup.sh, or whatever Vulkan device is present),
# then the compatibility subsets on the drivers without Vulkan 1.4's extras.
set -euo pipefail
cd "$(dirname "$0")/.."
# Where the time goes, for whoever shortens CI: the seconds since the start at each step.
step() { echo "test: at ${SECONDS} s: $*"; }
step "set-up"
scripts/setup.sh
export CARGO_TERM_COLOR=never
# A clean build of the checks and tests peaks at about 2.5 GB under target/ (measured
# 2026-11-29); with less room the linker dies of a bus error or "No space left on device", which
# says nothing about why. Say it first.
mkdir -p target
free_mb=$(df -Pm target | awk 'NR == 2 { print $4 }')
if [[ -n "$free_mb" && "$free_mb" -lt 3072 ]]; then
  echo "test: warning: only ${free_mb} MB free for target/; a clean build of the tests needs about 2 500 MB" >&2
fi
step "formatting, clippy and docs"
cargo fmt --all -- --check
cargo clippy --workspace --all-targets --locked -- -D warnings
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --locked
# Only the check matters here; the pages would take disk the test builds need on a clean machine.
rm -rf target/doc

step "the suite (its build first)"
if cargo nextest --version >/dev/null 2>&1; then
  cargo nextest run --workspace --locked --no-fail-fast
else
  cargo test --workspace --locked --no-fail-fast
fi

# The compatibility subsets: the fallback paths (no mesh shaders, no device-generated commands;
# textures as layers of one array on Mesa 22.3; no drawIndirectCount, multi-draw or geometry
# shaders on SwiftShader) draw the reference pictures. Debian 12's own driver, Mesa 22.3's
# lavapipe, is unpacked under target/ by setup.sh, as is SwiftShader; VK_ICD_FILENAMES points the
# Vulkan loader at one alone. (The tests that need a driver of their own point themselves at it.)
mesa22_manifest="${CADR_MESA22_DIR:-$PWD/target/mesa-22.3}/lvp_icd.json"
mesa22_subset=(rendering display_modes gpu_culling textures vulkan_layer transparency sections
  antialiasing frame_replay clusters frames_in_flight back_faces streaming)
# Streaming tests whose subject is the host's bookkeeping (replaced geometries, page reads that
# fail, eviction, relayout, hysteresis), not what the driver draws or how it sizes memory: the
# suite runs them on the default driver, and on Mesa 22.3 they were a minute of test time.
mesa22_skipped=(a_geometry_replaced_while_the_scene_streams_is_drawn_as_its_new_data
  a_page_file_that_cannot_be_read_keeps_the_coarse_form_until_a_retry_reads_it
  a_geometry_put_back_in_its_coarse_form_draws_it_as_it_first_did
  coarse_forms_laid_out_again_draw_as_they_did
  a_view_that_needs_more_than_the_budget_does_not_swap_geometries_back_and_forth)
# SwiftShader draws the reference pictures of these; it rasterizes and filters differently from
# lavapipe (by more than the references' tolerance on some textured, translucent and MSAA
# pictures), which cli/tests/swiftshader.rs judges with a tolerance of its own. It lacks
# drawIndirectCount: the gpu- cullers' commands are drawn there by their capacity
# (individual-mdi), which the GPU culling, cluster and streaming tests check against pictures
# drawn in the same run (the streaming tests of the host's bookkeeping are skipped, as on Mesa
# 22.3).
swiftshader_subset=(rendering vulkan_layer gpu_culling clusters cluster_budget streaming)
run_subset() { # MANIFEST SKIPPED-TEST-NAMES TEST-BINARY... (the names space-separated)
  local manifest=$1 skipped=$2
  shift 2
  step "the compatibility subset ($*) on $manifest"
  if cargo nextest --version >/dev/null 2>&1; then
    # --workspace, as the full run above: built for one package alone, cadr-tests would get other
    # features unified into its dependencies and every test binary would be built a second time
    # (about 1 GB of disk and minutes of linking on a clean CI machine).
    local filter exclude=""
    filter=$(printf 'binary(%s) | ' "$@")
    if [[ -n $skipped ]]; then
      exclude=$(printf 'test(=%s) | ' $skipped)
      exclude=" - (${exclude% | })"
    fi
    VK_ICD_FILENAMES="$manifest" cargo nextest run --workspace --locked --no-fail-fast \
      -E "package(cadr-tests) & (${filter% | })${exclude}"
  else
    VK_ICD_FILENAMES="$manifest" cargo test --workspace --locked --no-fail-fast \
      $(printf -- '--test %s ' "$@") -- $(printf -- '--skip %s ' $skipped)
  fi
}
run_subset "$mesa22_manifest" "${mesa22_skipped[*]}" "${mesa22_subset[@]}"
run_subset "${CADR_SWIFTSHADER_DIR:-$PWD/target/swiftshader}/vk_swiftshader_icd.json" \
  "${mesa22_skipped[*]}" "${swiftshader_subset[@]}"

# Injected Vulkan failures need cadr-core built with the fault-injection feature: every
# allocation, submission and device loss of a render is made to fail in turn. The same feature
# injects a panic into file reading, which the load's panic boundary must turn into an error
# (through the Rust API, the C API and the command line). The injected failures run on the
# default driver and again on Mesa 22.3's lavapipe: core/src/vk/fault.rs keeps the allocations
# each driver uses unchecked or leaks after out of them. Built for the whole workspace, as the
# runs above (built for one package alone, the dependencies would get other features and be
# built again: two minutes), with only the test targets that need the feature.
fault_injection=(--workspace --features cadr-tests/fault-injection,cadr-cli/fault-injection --locked)
step "clippy with the fault-injection feature"
cargo clippy "${fault_injection[@]}" --all-targets -- -D warnings
for driver in default "$mesa22_manifest"; do
  if [[ $driver == default ]]; then driver_variable=(); else driver_variable=(VK_ICD_FILENAMES="$driver"); fi
  step "injected failures on the $driver driver"
  if cargo nextest --version >/dev/null 2>&1; then
    env "${driver_variable[@]}" cargo nextest run "${fault_injection[@]}" --test fault_injection
  else
    # One process for the five tests: the armed failure is the process's, so one at a time.
    env "${driver_variable[@]}" cargo test "${fault_injection[@]}" --test fault_injection \
      -- --test-threads=1
  fi
done
step "a panic while reading, through the Rust API, the C API and the command line"
if cargo nextest --version >/dev/null 2>&1; then
  cargo nextest run "${fault_injection[@]}" --test reader_panic --test cli \
    -E 'binary(reader_panic) | test(panic_while_reading)'
else
  cargo test "${fault_injection[@]}" --test reader_panic
  cargo test "${fault_injection[@]}" --test cli panic_while_reading
fi
step "done"
