#!/usr/bin/env bash
# The main job: set up, build, render the built-in demo scene to demo.png (30 frames measured),
# then benchmark the technique plugins on it against the built-in baseline.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cargo build --release --locked --workspace
./target/release/cadr render gen:demo -o demo.png --size 1024x768 --frames 30 "$@"
./target/release/cadr bench gen:demo --frames 30 --json demo-bench.json
