#!/usr/bin/env bash
# Lints brdftab for the targets beside x86-64 Linux (README.md, "Platforms"): clippy with
# -D warnings of every workspace member but the Python one, all targets (tests, benches), for
# aarch64 Linux and Windows (GNU), and with `--test` also runs the library's unit tests and the
# cheap integration tests on aarch64 under qemu-user. Not part of .ci/run (CI has no rustup
# network access): run by hand where the targets are installed:
#   rustup target add aarch64-unknown-linux-gnu x86_64-pc-windows-gnu
#   apt-get install gcc-aarch64-linux-gnu gcc-mingw-w64-x86-64 qemu-user
# Usage: tools/cross-check.sh [--test]   (CARGO_TARGET_DIR defaults to target/cross)
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-target/cross}"
export CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_LINKER=aarch64-linux-gnu-gcc
export CC_aarch64_unknown_linux_gnu=aarch64-linux-gnu-gcc
export CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_RUNNER="qemu-aarch64 -L /usr/aarch64-linux-gnu"
export CARGO_TARGET_X86_64_PC_WINDOWS_GNU_LINKER=x86_64-w64-mingw32-gcc
for t in aarch64-unknown-linux-gnu x86_64-pc-windows-gnu; do
  cargo clippy --workspace --exclude brdftab-python --all-targets --target "$t" -- -D warnings
done
if [ "${1:-}" = --test ]; then
  cargo test --release --target aarch64-unknown-linux-gnu -p brdftab --lib \
    --test table --test store --test codec_compat --test models_lecture --test sample_domain \
    --test rgl_reference --test merl --test library_api --test contract
fi
