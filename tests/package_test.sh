#!/usr/bin/env bash
# The installed CMake package as another project uses it: `cmake --install` into a fresh
# prefix, then configure, build and run tests/package_consumer against it (that project sets
# no C++ standard). Usage: package_test.sh BUILD_DIR [SANITIZERS]
# A sanitizer build (SANITIZERS = NBV_SANITIZE, e.g. address,undefined) installs instrumented
# libraries; the consumer is then built with the same -fsanitize, as its user would have to.
set -euo pipefail
BUILD="$(cd "$1" && pwd)"
SOURCE="$(cd "$(dirname "$0")" && pwd)/package_consumer"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
cmake --install "$BUILD" --prefix "$WORK/prefix" >"$WORK/install.log" || { cat "$WORK/install.log"; exit 1; }
[ -f "$WORK/prefix/include/nbv/errors.hpp" ] || { echo "FAIL: nbv/errors.hpp is not installed"; exit 1; }
sanitize=()
if [ -n "${2:-}" ]; then
  sanitize=(-DCMAKE_CXX_FLAGS="-fsanitize=$2" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=$2")
fi
cmake -S "$SOURCE" -B "$WORK/consumer" -DCMAKE_PREFIX_PATH="$WORK/prefix" -DCMAKE_BUILD_TYPE=Release "${sanitize[@]}" \
  >"$WORK/configure.log" 2>&1 ||
  { cat "$WORK/configure.log"; exit 1; }
# Finding nbv prints nothing of its dependencies' own (Debian's FindOpenVDB.cmake printed
# "COMPONENT = openvdb" in every consumer's configure).
if grep -n "COMPONENT = " "$WORK/configure.log"; then
  echo "FAIL: find_package(nbv) prints a dependency's notices"; exit 1
fi
cmake --build "$WORK/consumer" >"$WORK/build.log" 2>&1 || { cat "$WORK/build.log"; echo "FAIL: the consumer does not build"; exit 1; }
"$WORK/consumer/consumer"
# The Python package, where the README says cmake --install puts it, imports from there.
site=$(ls -d "$WORK"/prefix/lib/python3*/dist-packages 2>/dev/null || true)
if [ -n "$site" ]; then
  (cd "$WORK" && PYTHONPATH="$site" /usr/bin/python3 -c \
    "import nbv; assert nbv.__file__.startswith('$site'), nbv.__file__; print('installed package:', nbv.__file__)") ||
    { echo "FAIL: the installed Python package does not import"; exit 1; }
fi
echo "package: the installed nbv builds and runs a consumer that sets no C++ standard"
