#!/usr/bin/env bash
# Spherical Faces developer entry point.
#   bash www/dev.sh serve   install what is missing, build the release wasm, serve on 127.0.0.1:8080
#   bash www/dev.sh test    install what is missing, run the lint gate, native, wasm-pack and browser end-to-end tests
#   bash www/dev.sh lint    cargo fmt --check, and clippy -D warnings natively and for the app's wasm
#   bash www/dev.sh timings the app's timings in headless Chromium (tests/e2e/timings.mjs)
#   bash www/dev.sh bench   native benches (cargo bench, divan) and the same workloads in release wasm in
#                           headless Chromium, then a native-vs-wasm table (target/bench/)
#   bash www/dev.sh fuzz [target|all] [seconds]
#                           libFuzzer on stable Rust (fuzz/README.md): build the fuzz targets, run each for
#                           `seconds` (default all, 60 s each), one line per target; exits 1 on a finding.
#                           `test` runs it for 10 s per target after the native tests (SF_SKIP_FUZZ=1 skips it)
# Both are idempotent: installs are skipped when present, target/ is reused.
# The install recipe is ../shared/toolchain.md: nothing is downloaded outside crates.io, npm and Debian.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
WASM_TARGET=wasm32-unknown-unknown
DIST="$ROOT/target/dist"
PORT="${PORT:-8080}"

log() { printf '\033[1m[dev]\033[0m %s\n' "$*" >&2; }
have() { command -v "$1" >/dev/null 2>&1; }

as_root() { if [ "$(id -u)" = 0 ]; then "$@"; else sudo "$@"; fi; }

APT_UPDATED=0
apt_install() {
  local missing=()
  for p in "$@"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
  [ ${#missing[@]} -eq 0 ] && return 0
  have apt-get || { log "missing system packages (${missing[*]}) and no apt-get: install them by hand"; exit 1; }
  if [ $APT_UPDATED = 0 ]; then as_root apt-get update -qq; APT_UPDATED=1; fi
  log "apt-get install ${missing[*]}"
  as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
}

# --- Rust toolchain able to build wasm32 -----------------------------------------------------
setup_rust() {
  if have rustup && rustup target list --installed 2>/dev/null | grep -qx "$WASM_TARGET"; then
    log "using rustup's installed $WASM_TARGET target"
    return 0
  fi
  # Debian route (toolchain.md steps 1-2): rustc-web with std sources, wasm32 std built once.
  apt_install rustc-web cargo-web rust-web-src rust-web-llvm lld-22
  export PATH="/usr/bin:$PATH"
  local sysroot
  sysroot="$(/usr/bin/rustc --print sysroot)"
  local libdir="$sysroot/lib/rustlib/$WASM_TARGET/lib"
  if ! ls "$libdir"/libstd-*.rlib >/dev/null 2>&1; then
    log "building std for $WASM_TARGET into $libdir (once per machine)"
    local scratch
    scratch="$(mktemp -d)"
    mkdir -p "$scratch/src"
    cat >"$scratch/Cargo.toml" <<'TOML'
[package]
name = "sf_wasm_std_scratch"
version = "0.0.0"
edition = "2021"
[lib]
crate-type = ["cdylib"]
[profile.release]
lto = true
TOML
    echo '#[no_mangle] pub extern "C" fn sf_scratch() -> i32 { 1 }' >"$scratch/src/lib.rs"
    (cd "$scratch" && RUSTC_BOOTSTRAP=1 /usr/bin/cargo build -q --release --target "$WASM_TARGET" \
      -Zbuild-std=std,test,panic_abort)
    as_root mkdir -p "$libdir"
    as_root cp "$scratch/target/$WASM_TARGET/release/deps/"lib*.rlib "$libdir/"
    as_root rm -f "$libdir"/libsf_wasm_std_scratch*.rlib
    rm -rf "$scratch"
  fi
}

lock_version() { # version of a package in Cargo.lock
  awk -v n="$1" '$0=="name = \"" n "\""{getline; gsub(/version = |"/,""); print; exit}' Cargo.lock
}

setup_wasm_tools() {
  local wbv
  wbv="$(lock_version wasm-bindgen)"
  if ! (have wasm-bindgen && wasm-bindgen --version | grep -q " $wbv\$"); then
    log "cargo install wasm-bindgen-cli $wbv (a few minutes, once)"
    cargo install -q wasm-bindgen-cli --version "$wbv" --force
  fi
  if ! have wasm-pack; then
    log "cargo install wasm-pack (a few minutes, once)"
    cargo install -q wasm-pack --version 0.13.1
  fi
}

setup_browser() {
  apt_install chromium chromium-driver
  if [ ! -d tests/e2e/node_modules/playwright-core ] || [ tests/e2e/package-lock.json -nt tests/e2e/node_modules/.stamp ]; then
    have npm || apt_install nodejs npm
    node -e 'const [a,b]=process.versions.node.split(".").map(Number); process.exit(a>20||(a==20&&b>=10)?0:1)' ||
      { log "Node.js >= 20.10 is needed for the browser tests (found $(node --version))"; exit 1; }
    log "npm ci (tests/e2e)"
    (cd tests/e2e && npm ci --no-audit --no-fund --silent && touch node_modules/.stamp)
  fi
}

# rhino3dm.js (npm, MIT: OpenNURBS in wasm) reads and writes Rhino .3dm files: in the app's worker,
# loaded on the first .3dm read or written, and in the CLI through Node (www/rhino3dm/cli.mjs reads,
# write-cli.mjs writes panels.3dm).
setup_rhino3dm() {
  if [ ! -d www/rhino3dm/node_modules/rhino3dm ] || [ www/rhino3dm/package-lock.json -nt www/rhino3dm/node_modules/.stamp ]; then
    have npm || apt_install nodejs npm
    log "npm ci (www/rhino3dm)"
    (cd www/rhino3dm && npm ci --no-audit --no-fund --silent && touch node_modules/.stamp)
  fi
}

# --- build ------------------------------------------------------------------------------------
build_web() {
  local profile="${1:-release}"
  log "building wasm ($profile)"
  local flag=--release; [ "$profile" = dev ] && flag=--dev
  wasm-pack --quiet build --mode no-install $flag --target web --out-dir target/pkg --out-name spherical_faces --no-typescript --no-pack . >&2
  rm -rf "$DIST"; mkdir -p "$DIST/pkg"
  cp index.html "$DIST/"
  cp www/*.js www/*.css "$DIST/" 2>/dev/null || true
  cp www/favicon.svg "$DIST/"
  cp target/pkg/spherical_faces.js target/pkg/spherical_faces_bg.wasm "$DIST/pkg/"
  setup_rhino3dm
  mkdir -p "$DIST/rhino3dm"
  cp www/rhino3dm/convert.mjs www/rhino3dm/write.mjs www/rhino3dm/node_modules/rhino3dm/rhino3dm.module.js \
    www/rhino3dm/node_modules/rhino3dm/rhino3dm.wasm "$DIST/rhino3dm/"
  log "wasm: $(stat -c %s "$DIST/pkg/spherical_faces_bg.wasm") bytes"
  # .cargo/config.toml builds with +simd128: the module must hold SIMD instructions (faer's
  # kernels through pulp, LLVM's vectorized loops).
  have wasm-objdump || apt_install wabt
  local simd
  simd="$(wasm-objdump -d "$DIST/pkg/spherical_faces_bg.wasm" | grep -cE '(v128|f64x2|f32x4|i32x4)\.' || true)"
  log "wasm: $simd SIMD instructions"
  [ "$simd" -gt 0 ] || { echo "the wasm holds no SIMD instructions: is +simd128 in .cargo/config.toml?" >&2; exit 1; }
}

cmd_setup() { setup_rust; setup_wasm_tools; }

# rustfmt and clippy of the toolchain that builds (Debian's on the Debian route, rustup's else).
setup_lints() {
  if [ "$(command -v cargo)" = /usr/bin/cargo ]; then apt_install rust-web-clippy rustfmt-web; fi
}

# The lint gate: the house format (rustfmt.toml) and clippy without warnings, the allows that
# remain justified in Cargo.toml's [lints.clippy]; the app's code is wasm-only, so clippy runs
# for wasm too.
cmd_lint() {
  setup_rust
  setup_lints
  log "format: cargo fmt --check"
  cargo fmt --check
  log "lints: cargo clippy -D warnings (native, all targets; wasm32, the library and its tests)"
  cargo clippy -q --all-targets -- -D warnings
  cargo clippy -q --target "$WASM_TARGET" --lib --tests -- -D warnings
}

cmd_serve() {
  cmd_setup
  build_web release
  exec python3 www/serve.py --root "$DIST" --port "$PORT"
}

cmd_test() {
  cmd_lint
  cmd_setup
  setup_browser
  setup_rhino3dm
  log "rhino3dm reader and writer tests (node)"
  (cd www/rhino3dm && node --test convert.test.mjs write.test.mjs)
  log "native tests"
  cargo test --all-targets
  log "doc tests (--all-targets leaves them out)"
  cargo test --doc
  if [ "${SF_SKIP_FUZZ:-0}" != 1 ]; then
    log "fuzz smoke: every target for 10 s (SF_SKIP_FUZZ=1 skips it)"
    cmd_fuzz all 10
  fi
  log "wasm-pack tests in headless Chromium"
  # The runner's default budget is 20 s for the whole page; the tests take about 40 s. They run in
  # a dedicated worker, so that no run holds the page (chromedriver drops a page that does not
  # answer for 30 s), and each long run in a task of its own (≤ 11 s here).
  WASM_BINDGEN_TEST_TIMEOUT="${WASM_BINDGEN_TEST_TIMEOUT:-900}" \
    wasm-pack test --headless --chrome --chromedriver /usr/bin/chromedriver . --test web
  build_web release
  log "browser end-to-end tests (WebGPU and WebGL2 on SwiftShader)"
  (cd tests/e2e && SF_DIST="$DIST" node --test --test-concurrency=1 *.test.mjs)
}

# Native (cargo bench, divan) and wasm (release, headless Chromium) runs of the workloads in
# src/bench_workloads.rs; both print `bench <name>: <ms> ms/iter (n=..)` lines, compared here.
cmd_bench() {
  cmd_setup
  apt_install chromium chromium-driver
  local out="${CARGO_TARGET_DIR:-$ROOT/target}/bench"
  mkdir -p "$out"
  log "native benches: cargo bench --bench pipeline"
  cargo bench --bench pipeline 2>&1 | tee "$out/native.txt"
  log "wasm benches (release) in headless Chromium: tests/wasm_bench.rs"
  # cargo with wasm-bindgen's runner, as wasm-pack test does, but building this one test target only.
  WASM_BINDGEN_TEST_TIMEOUT="${WASM_BINDGEN_TEST_TIMEOUT:-1800}" CHROMEDRIVER=/usr/bin/chromedriver \
    CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_RUNNER=wasm-bindgen-test-runner \
    cargo test --release --target wasm32-unknown-unknown --test wasm_bench -- --nocapture \
    2>&1 | tee "$out/wasm.txt"
  local pat='bench [A-Za-z0-9_]+: [0-9.]+ ms/iter'
  {
    printf '%-28s %14s %14s %8s\n' benchmark "native ms/iter" "wasm ms/iter" wasm/nat
    grep -oE "$pat" "$out/native.txt" | while read -r _ name ms _; do
      name="${name%:}"
      local w
      w="$(grep -oE "bench $name: [0-9.]+ ms/iter" "$out/wasm.txt" | awk '{print $3}' | tail -1 || true)"
      awk -v n="$name" -v a="$ms" -v b="${w:-nan}" \
        'BEGIN { r = (b == "nan" || a == 0) ? "-" : sprintf("%.2f", b / a); printf "%-28s %14.3f %14s %8s\n", n, a, b, r }'
    done
    echo "load: $(uptime | sed 's/.*load average/load average/')  ($(nproc) cores)"
  } | tee "$out/table.txt"
  log "results in $out (native.txt, wasm.txt, table.txt)"
}

# Browser timings of the release build (tests/e2e/timings.mjs): ST adapted to about 600 faces and
# SQ on a sample, from the run's request to the result, and a 1M-triangle OBJ import with its
# curvature. Measurements, not tests.
cmd_timings() {
  cmd_setup
  setup_browser
  build_web release
  (cd tests/e2e && SF_DIST="$DIST" node timings.mjs) 2>&1 | tee "${CARGO_TARGET_DIR:-$ROOT/target}/timings.txt"
  echo "load: $(uptime | sed 's/.*load average/load average/')  ($(nproc) cores)"
}

# --- fuzzing (fuzz/README.md) -----------------------------------------------------------------
# libFuzzer on stable rustc: fuzz/rustc-wrapper.sh adds SanitizerCoverage to the crates under
# test; libfuzzer-sys builds libFuzzer's C++ (a C++ compiler is needed). New inputs go to a
# working corpus in target/fuzz/work/<t>; the committed seeds in fuzz/corpus/<t> are read only.
# Reproducers land in fuzz/artifacts/<t>/ (tests/fuzz_replay.rs replays them).
FUZZ_TARGETS=(obj gltf bspline design_link protocol)

fuzz_max_len() {
  case "$1" in
    design_link) echo 4096 ;;
    *) echo 65536 ;;
  esac
}

cmd_fuzz() {
  local which="${1:-all}" secs="${2:-60}"
  local targets=()
  if [ "$which" = all ]; then
    targets=("${FUZZ_TARGETS[@]}")
  elif [[ " ${FUZZ_TARGETS[*]} " == *" $which "* ]]; then
    targets=("$which")
  else
    log "unknown fuzz target '$which' (targets: ${FUZZ_TARGETS[*]}, or all)"
    exit 2
  fi
  [[ "$secs" =~ ^[0-9]+$ ]] || { log "fuzz: seconds must be a whole number, got '$secs'"; exit 2; }
  have c++ || have g++ || have clang++ || apt_install g++
  local tdir="$ROOT/target/fuzz"
  log "building the fuzz targets (release, SanitizerCoverage through fuzz/rustc-wrapper.sh)"
  CARGO_TARGET_DIR="$tdir" RUSTC_WRAPPER="$ROOT/fuzz/rustc-wrapper.sh" \
    cargo build --release --manifest-path fuzz/Cargo.toml --bins
  local total=0 lines=() t
  for t in "${targets[@]}"; do
    local work="$tdir/work/$t" out="$tdir/logs/$t.log" arts="fuzz/artifacts/$t"
    mkdir -p "$work" "$tdir/logs" "$arts"
    local before rc=0
    before="$(ls -A "$arts")"
    log "fuzz $t for ${secs} s (log: $out)"
    nice -n 19 "$tdir/release/$t" -max_total_time="$secs" -rss_limit_mb=2048 -max_len="$(fuzz_max_len "$t")" \
      -timeout=10 -print_final_stats=1 -artifact_prefix="$arts/" "$work" "fuzz/corpus/$t" >"$out" 2>&1 || rc=$?
    local execs corpus findings
    execs="$(grep -oE 'stat::number_of_executed_units: *[0-9]+' "$out" | grep -oE '[0-9]+$' | tail -1 || true)"
    corpus="$(grep -oE 'corp: [0-9]+' "$out" | grep -oE '[0-9]+$' | tail -1 || true)"
    findings="$(comm -13 <(printf '%s\n' "$before" | sort) <(ls -A "$arts" | sort) | grep -c . || true)"
    # A crash on an input whose artifact is already there writes no new file; it still counts.
    if [ "$rc" != 0 ] && [ "$findings" = 0 ]; then findings=1; fi
    if [ "$findings" != 0 ]; then
      grep -E -A1 '^(==[0-9]+== ERROR: libFuzzer|thread .* panicked at)' "$out" | head -4 >&2 || true
      grep -E 'Test unit written to' "$out" | head -1 >&2 || true
    fi
    total=$((total + findings))
    lines+=("$(printf 'fuzz %s: %s execs, corpus %s files, %s findings' "$t" "${execs:-0}" "${corpus:-0}" "$findings")")
  done
  printf '%s\n' "${lines[@]}"
  if [ "$total" != 0 ]; then
    log "fuzz: $total findings; reproducers in fuzz/artifacts/ (replay: cargo test --test fuzz_replay)"
    return 1
  fi
}

case "${1:-}" in
  setup) cmd_setup ;;
  build) cmd_setup; build_web "${2:-release}" ;;
  serve) cmd_serve ;;
  test) cmd_test ;;
  lint) cmd_lint ;;
  bench) cmd_bench ;;
  timings) cmd_timings ;;
  fuzz) cmd_fuzz "${2:-all}" "${3:-60}" ;;
  *) echo "usage: bash www/dev.sh serve|test|lint|bench|timings|fuzz [target|all] [seconds]   (also: setup, build [release|dev])" >&2; exit 2 ;;
esac
