#!/usr/bin/env bash
# Command (b): set up, build, and run the whole test suite (unit, GPU on lavapipe with validation
# layers, CLI). Prints ctest's summary; exits non-zero on any failure.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cd build
ctest --output-on-failure -j "$(nproc)" --timeout 1200
