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
# allocation, submission and device loss of a render is made to fail in turn. The same feature
# injects a panic into file reading, which the load's panic boundary must turn into an error
# (through the Rust API, the C API and the command line).
cargo clippy -p cadr-tests -p cadr-cli --features fault-injection --all-targets --locked -- -D warnings
if cargo nextest --version >/dev/null 2>&1; then
  cargo nextest run -p cadr-tests --features fault-injection --locked --test fault_injection --test reader_panic
  cargo nextest run -p cadr-cli --features fault-injection --locked --test cli panic_while_reading
else
  cargo test -p cadr-tests --features fault-injection --locked --test fault_injection --test reader_panic
  cargo test -p cadr-cli --features fault-injection --locked --test cli panic_while_reading
fi
