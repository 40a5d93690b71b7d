#!/usr/bin/env bash
# Command (b): set up, build, and run the whole test suite:
#  1. the CPU unit tests (importers, pack reader with its mutation fuzz, math) built a second time with
#     AddressSanitizer + UndefinedBehaviorSanitizer + LeakSanitizer (build-asan/), any report fails;
#  2. every test through ctest: unit, GPU on lavapipe with validation layers (any message fails), CLI,
#     the installed CMake package.
# Exits non-zero on any failure; ctest's summary is the last thing printed.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh

echo "== sanitizer build of the CPU unit tests (build-asan/)"
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DVISBUF_SANITIZE=ON >/dev/null
cmake --build build-asan -j "$(nproc)" --target visbuf_unit_tests
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  build-asan/tests/visbuf_unit_tests --gtest_brief=1

echo "== full suite (build/)"
cd build
ctest --output-on-failure -j "$(nproc)" --timeout 1200
