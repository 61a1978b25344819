#!/usr/bin/env bash
# A coverage-guided fuzzing campaign of one of cadr's readers with AFL++ (cargo-afl, stable Rust).
#
#   scripts/fuzz.sh TARGET [EXECUTIONS]     TARGET: gltf | csf | scene_load (default 1000000)
#
# Installs afl++ and cargo-afl on first use, builds the instrumented targets into target/afl,
# fuzzes from fuzz/corpus/TARGET/ until about EXECUTIONS inputs have run, then prints the
# executions, the paths found and the findings. Crashes and hangs are kept in
# target/afl/out/TARGET/default/{crashes,hangs}/; replay one with
#   target/afl/release/fuzz-TARGET < FILE
# and, once fixed, copy it into fuzz/findings/TARGET/ (the test run replays it from then on).
# The inputs that found new paths are in target/afl/out/TARGET/default/queue/.
set -euo pipefail
cd "$(dirname "$0")/.."

target="${1:-}"
executions="${2:-1000000}"
case "$target" in
  gltf | csf | scene_load) ;;
  *) echo "usage: scripts/fuzz.sh gltf|csf|scene_load [EXECUTIONS]" >&2; exit 2 ;;
esac

if ! command -v cargo-afl >/dev/null 2>&1; then
  # cargo-afl builds its own AFL++ (and the runtime matching this rustc) when it is installed;
  # Debian's afl++ brings the compilers and tools that build needs.
  sudo=""
  if [[ $(id -u) -ne 0 ]]; then sudo="sudo"; fi
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends afl++ >/dev/null
  cargo install --locked cargo-afl
fi

export CARGO_TARGET_DIR=target/afl
cargo afl build --release --locked -p cadr-fuzz --features afl

out="target/afl/out/$target"
rm -rf "$out"
mkdir -p "$out"
# The limits a campaign holds every input to: 1 s per input and 2 GiB of address space, so an
# input that makes cadr hang or allocate without bound is a finding. A .csf.gz may decompress to
# 64 MiB here (the product's default is 8 GiB, more than the memory limit), and a scene may
# expand to what 1 GiB holds (the product's default is the machine's memory).
export CADR_MAX_DECOMPRESSED_BYTES=$((64 << 20)) CADR_MEMORY_BUDGET=1G
export AFL_NO_UI=1 AFL_SKIP_CPUFREQ=1 AFL_I_DONT_CARE_ABOUT_MISSING_CRASHES=1
# glTF's keys and constants help the mutator reach what a byte flip rarely writes.
dictionary=()
if [[ "$target" != csf ]]; then dictionary=(-x fuzz/gltf.dict); fi
cargo afl fuzz -i "fuzz/corpus/$target" -o "$out" -E "$executions" -t 1000 -m 2048 "${dictionary[@]}" \
  "target/afl/release/fuzz-${target//_/-}" >"$out/afl.log" 2>&1 || {
  tail -30 "$out/afl.log" >&2
  exit 1
}

stats="$out/default/fuzzer_stats"
value() { awk -F' *: *' -v key="$1" '$1 == key { print $2 }' "$stats"; }
crashes=$(find "$out/default/crashes" -type f -name 'id:*' | wc -l)
hangs=$(find "$out/default/hangs" -type f -name 'id:*' | wc -l)
echo "fuzz $target: $(value execs_done) executions in $(value run_time) s ($(value execs_per_sec)/s)," \
  "$(value corpus_count) paths ($(value corpus_found) new), edges $(value edges_found)/$(value total_edges)," \
  "$crashes crashes, $hangs hangs"

(( crashes == 0 && hangs == 0 ))
