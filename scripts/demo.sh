#!/usr/bin/env bash
# The main job: set up, build, render the built-in demo scene to demo.png and benchmark it.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cargo build --release --locked -p cadr-cli
./target/release/cadr render gen:demo -o demo.png --size 1024x768 --frames 30 "$@"
