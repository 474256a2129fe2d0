#!/bin/sh
# Installs what is missing (Debian 12, as root), builds vesph and its tests, and runs the whole
# test suite through ctest. .ci/run runs exactly this.
set -eu
cd "$(dirname "$0")/.."
sh tools/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build
ctest --test-dir build --output-on-failure -j 2
