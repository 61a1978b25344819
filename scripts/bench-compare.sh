#!/usr/bin/env bash
# CPU per frame of this working tree against an older revision, both release builds, run one
# after the other, alternating: `cadr bench gen:graphicscard` still, orbiting and animating,
# every default row. Prints, per motion and run, the median over the rows (the baseline
# aside) of CPU µs per frame, of it cadr's own work (CPU µs minus the driver's submission
# call) and the scene update, and the baseline's CPU µs. What changed is within noise when
# the new runs fall among the old ones.
#
#   scripts/bench-compare.sh OLD_REVISION [ROUNDS]      (default 2 rounds; after setup.sh)
#
# Environment: CADR_COMPARE_ARGS replaces the bench arguments shared by every run (default
# `gen:graphicscard --frames 10 --size 640x480`).
set -euo pipefail
cd "$(dirname "$0")/.."

old_revision="${1:?usage: scripts/bench-compare.sh OLD_REVISION [ROUNDS]}"
rounds="${2:-2}"
root="$(pwd)"
work="$root/target/compare"
read -r -a shared <<<"${CADR_COMPARE_ARGS:-gen:graphicscard --frames 10 --size 640x480}"
mkdir -p "$work"

# Copies the release binary and its plugins (found beside it) into $1.
keep_build() {
  rm -rf "$1" && mkdir -p "$1"
  cp target/release/cadr target/release/libcadr_plugin_*.so "$1/"
}

echo "bench-compare: building this working tree" >&2
cargo build --release --workspace --quiet
keep_build "$work/new"

echo "bench-compare: building $old_revision" >&2
rm -rf "$work/old-src"
git worktree prune
git worktree add --detach --force "$work/old-src" "$old_revision" >/dev/null
# The same target folder: the dependencies are built once for both.
(cd "$work/old-src" && CARGO_TARGET_DIR="$root/target" cargo build --release --workspace --quiet)
keep_build "$work/old"
git worktree remove --force "$work/old-src"
# target/release holds this tree's build again (relinked from what is already built).
cargo build --release --workspace --quiet

results="$work/results"
rm -rf "$results" && mkdir -p "$results"
for motion in static orbit animate; do
  case "$motion" in
    static) motion_args=() ;;
    orbit) motion_args=(--camera orbit) ;;
    animate) motion_args=(--animate 50) ;;
  esac
  for round in $(seq 1 "$rounds"); do
    for build in old new; do
      echo "bench-compare: $motion, $build, round $round" >&2
      "$work/$build/cadr" bench "${shared[@]}" "${motion_args[@]}" \
        --json "$results/$motion-$build-$round.json" >/dev/null
    done
  done
done

python3 - "$results" "$rounds" <<'EOF'
import json, statistics, sys
results, rounds = sys.argv[1], int(sys.argv[2])
print("| motion | build, round | median over rows: CPU µs | of it cadr (CPU − submit) µs | scene update µs | baseline CPU µs |")
print("|---|---|---:|---:|---:|---:|")
for motion in ("static", "orbit", "animate"):
    for build in ("old", "new"):
        for round in range(1, rounds + 1):
            rows = json.load(open(f"{results}/{motion}-{build}-{round}.json"))["rows"]
            baseline = [r for r in rows if r["technique"].startswith("baseline")]
            others = [r for r in rows if not r["technique"].startswith("baseline")]
            cpu = statistics.median(r["cpu_us"] for r in others)
            own = statistics.median(r["cpu_us"] - r["cpu_submit_us"] for r in others)
            update = statistics.median(r["scene_update_us"] for r in others)
            base = baseline[0]["cpu_us"] if baseline else float("nan")
            print(f"| {motion} | {build} {round} | {cpu:.1f} | {own:.2f} | {update:.1f} | {base:.0f} |")
EOF
