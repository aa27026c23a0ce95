#!/usr/bin/env bash
# One entry point for set-up on a fresh Debian 12 machine (run as root, or with sudo available):
#   bash scripts/dev.sh demo    install what is missing, build, run graphs/demo.yaml (writes out/)
#   bash scripts/dev.sh test    install what is missing, build, run every test with CTest; with
#                               KG_SANITIZE_TEST=1 then the sanitizer build (clang 14, Address-
#                               Sanitizer, UndefinedBehaviorSanitizer, libFuzzer) in build-asan:
#                               every test again, the fuzz corpora replayed, each harness fuzzed
#   bash scripts/dev.sh build   install what is missing and build only
#   bash scripts/dev.sh install [PREFIX]   install what is missing, build, and install Kinegraph into
#                               PREFIX (default /usr/local): PREFIX/bin/kinegraph, its libraries,
#                               headers and CMake package (README, "Installing" and "Writing a plugin")
# Environment: BUILD_DIR (default build), JOBS (default nproc), KG_SKIP_BLENDER=1 skips installing
# Blender (its tests then skip with a message), SANITIZE_BUILD_DIR (default build-asan),
# KG_SANITIZE_TEST=1 adds the sanitizer build to `test`, KG_FUZZ_SECONDS (default 20) how long
# `test` fuzzes each harness.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$here"
build_dir=${BUILD_DIR:-build}
sanitize_dir=${SANITIZE_BUILD_DIR:-build-asan}
jobs=${JOBS:-$(nproc)}

build_packages=(g++ cmake ninja-build pkg-config libeigen3-dev libceres-dev libglpk-dev libyaml-cpp-dev
                libboost-dev libboost-filesystem-dev catch2 libssl-dev nlohmann-json3-dev libcli11-dev
                libre2-dev liburdfdom-dev libtinyxml2-dev)
test_packages=(liborocos-kdl-dev  # KDL: reference inverse dynamics for test_retime and bench_retime
               slurmctld slurmd slurm-client munge  # test_cli's single-node Slurm cluster
               clang-format  # the "format" test: every source as clang-format 14 writes it
               graphviz      # the "readme" test: the README's `kinegraph dot ... | dot -Tpng`
               jq)           # the "corpus" test (bench/corpus.sh reads the reports)
[[ ${KG_SKIP_BLENDER:-0} == 1 ]] || test_packages+=(blender)
sanitize_packages=(clang-14 libclang-rt-14-dev  # the compiler, its sanitizer and libFuzzer runtimes
                   llvm-14)                     # llvm-symbolizer: findings with file:line stacks

install_missing() {
  local missing=()
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  ((${#missing[@]})) || return 0
  echo "Installing missing Debian packages: ${missing[*]}"
  local sudo=()
  [[ $(id -u) == 0 ]] || sudo=(sudo)
  "${sudo[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

build() {
  cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release "$@"
  cmake --build "$build_dir" -j "$jobs"
}

# The sanitizer build: every finding fatal, with a stack of file:line (llvm-symbolizer). The
# benchmarks are not built (their figures mean nothing under sanitizers), and `format`,
# `test_sdk`, `readme` and `corpus` (source layout, installation, the README's text and the
# sweep's verdicts over the CLI the other tests run, the same in both builds) run in the first only.
sanitize_test() {
  CC=clang-14 CXX=clang++-14 cmake -S . -B "$sanitize_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release \
    -DKG_SANITIZE=ON -DKG_FUZZ=ON -DKG_BUILD_BENCH=OFF -DKG_FUZZ_SECONDS="${KG_FUZZ_SECONDS:-20}"
  cmake --build "$sanitize_dir" -j "$jobs"
  export ASAN_SYMBOLIZER_PATH=/usr/bin/llvm-symbolizer-14
  (cd "$sanitize_dir" && ctest --output-on-failure -j "$jobs" --timeout 900 -E '^(format|test_sdk|readme|corpus)$')
}

# install PREFIX: builds with PREFIX as the install prefix (so that GNUInstallDirs picks its
# library folder) and installs there, with sudo when PREFIX is not writable.
install_into() {
  local prefix
  prefix=$(realpath -m "$1")
  build -DCMAKE_INSTALL_PREFIX="$prefix"
  local sudo=()
  local existing=$prefix
  while [[ ! -e $existing ]]; do existing=$(dirname "$existing"); done
  [[ -w $existing && ( ! -e $prefix || -w $prefix ) ]] || sudo=(sudo)
  "${sudo[@]}" cmake --install "$build_dir"
  echo "Installed Kinegraph in $prefix ($build_dir/install_manifest.txt lists every file)."
  if [[ $(command -v kinegraph || true) == "$prefix/bin/kinegraph" ]]; then
    echo "kinegraph is on your PATH: $prefix/bin/kinegraph"
  else
    echo "Add $prefix/bin to your PATH to run kinegraph:  export PATH=\"$prefix/bin:\$PATH\""
  fi
}

case "${1:-}" in
  demo)
    install_missing "${build_packages[@]}"
    build
    "$build_dir/bin/kinegraph" run graphs/demo.yaml --report out/demo_report.json "${@:2}"
    echo "Demo outputs are in out/ (per-node timings and figures: out/demo_report.json)."
    ;;
  test)
    sanitize=(); [[ ${KG_SANITIZE_TEST:-0} != 1 ]] || sanitize=("${sanitize_packages[@]}")
    install_missing "${build_packages[@]}" "${test_packages[@]}" "${sanitize[@]}"
    build
    (cd "$build_dir" && ctest --output-on-failure -j "$jobs" --timeout 600)
    [[ ${KG_SANITIZE_TEST:-0} != 1 ]] || sanitize_test
    ;;
  build)
    install_missing "${build_packages[@]}"
    build
    ;;
  install)
    install_missing "${build_packages[@]}"
    install_into "${2:-/usr/local}"
    ;;
  *)
    echo "usage: bash scripts/dev.sh demo|test|build|install [PREFIX]" >&2
    exit 2
    ;;
esac
