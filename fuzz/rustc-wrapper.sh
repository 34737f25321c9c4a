#!/usr/bin/env bash
# RUSTC_WRAPPER for the fuzz build: adds SanitizerCoverage instrumentation (what libFuzzer's
# feedback reads) to the crates under test only: the library `spherical_faces` and the fuzz
# target binaries. std, libfuzzer-sys and every other dependency are compiled as usual.
#
# Everything used is stable rustc: `-C passes=sancov-module` runs LLVM's SanitizerCoverage pass,
# `-C llvm-args=...` configures it (what nightly's `-Zsanitizer`-free cargo-fuzz uses too), and
# `--cfg fuzzing` is a plain cfg. See fuzz/README.md.
#
# Cargo calls it as `rustc-wrapper.sh /path/to/rustc <args...>`.
set -euo pipefail

rustc="$1"
shift

# The crates to instrument: the library and the fuzz targets (fuzz/Cargo.toml's [[bin]]s).
INSTRUMENT=" spherical_faces obj gltf bspline design_link protocol "

crate_name=""
prev=""
for arg in "$@"; do
  if [ "$prev" = "--crate-name" ]; then
    crate_name="$arg"
    break
  fi
  prev="$arg"
done

if [ -n "$crate_name" ] && [[ "$INSTRUMENT" == *" $crate_name "* ]]; then
  exec "$rustc" "$@" \
    -Cpasses=sancov-module \
    -Cllvm-args=-sanitizer-coverage-level=4 \
    -Cllvm-args=-sanitizer-coverage-inline-8bit-counters \
    -Cllvm-args=-sanitizer-coverage-pc-table \
    -Cllvm-args=-sanitizer-coverage-trace-compares \
    --cfg fuzzing \
    -Cdebug-assertions \
    -Coverflow-checks
fi
exec "$rustc" "$@"
