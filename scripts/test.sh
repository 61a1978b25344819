#!/usr/bin/env bash
# Every test: set up, check formatting, lints and docs, run all tests (validation layers on) on lavapipe
# or whatever Vulkan device is present.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
export CARGO_TERM_COLOR=never
cargo fmt --all -- --check
cargo clippy --workspace --all-targets --locked -- -D warnings
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --locked

if cargo nextest --version >/dev/null 2>&1; then
  cargo nextest run --workspace --locked --no-fail-fast
else
  cargo test --workspace --locked --no-fail-fast
fi

# Injected Vulkan failures need cadr-core built with the fault-injection feature: every
# allocation, submission and device loss of a render is made to fail in turn.
cargo clippy -p cadr-tests --features fault-injection --all-targets --locked -- -D warnings
if cargo nextest --version >/dev/null 2>&1; then
  cargo nextest run -p cadr-tests --features fault-injection --locked --test fault_injection
else
  cargo test -p cadr-tests --features fault-injection --locked --test fault_injection
fi
