#!/usr/bin/env bash
# The plugin SDK end to end (README, "Writing a plugin"), as a user meets it:
#   1. `cmake --install` this build into a temporary prefix, then move the prefix (RPATHs are
#      relative), and check its layout: the CLI, its built-in node module, headers, the package;
#   2. copy examples/plugin (a node plugin and a constraint-kind plugin) outside the source tree and
#      build it against the prefix with find_package(Kinegraph) and kinegraph_add_plugin();
#   3. run the installed kinegraph on the example graph with --plugin-dir, and check that both
#      plugins did their part (the node's figures, the solver meeting the plugin's constraints);
#   4. install the plugins into the prefix: the CLI then finds them by name alone.
# Everything happens in a temporary folder, removed at the end; nothing is written to the source
# tree (the build tree gets CMake's install_manifest.txt).
#
# usage: test_sdk.sh BUILD_DIR SOURCE_DIR LIBDIR GENERATOR CXX_COMPILER [COMPILER_LAUNCHER]
set -euo pipefail
build=$1 source=$2 libdir=$3 generator=$4 cxx=$5 launcher=${6:-}

work=$(mktemp -d "${TMPDIR:-/tmp}/kinegraph_sdk.XXXXXX")
trap 'rm -rf "$work"' EXIT
unset KINEGRAPH_PLUGIN_PATH
start=$SECONDS
step() { echo "== [$((SECONDS - start)) s] $*"; }
fail() { echo "FAILED: $*" >&2; exit 1; }
# Runs a command quietly, showing its output only when it fails.
quiet() {
  local log=$work/last.log
  "$@" > "$log" 2>&1 || { cat "$log" >&2; fail "$*"; }
}

step "install the build into a temporary prefix"
quiet cmake --install "$build" --prefix "$work/staging"
mv "$work/staging" "$work/prefix"  # relocated: nothing may refer to where it was installed
prefix=$work/prefix
for f in bin/kinegraph lib/kinegraph/kg_builtin_nodes.so "$libdir/libkg_graph.so" "$libdir/libkg_retarget.so" \
         "$libdir/libkg_motion_nodes.so" "$libdir/cmake/Kinegraph/KinegraphConfig.cmake" \
         "$libdir/cmake/Kinegraph/KinegraphConfigVersion.cmake" "$libdir/cmake/Kinegraph/KinegraphTargets.cmake" \
         "$libdir/cmake/Kinegraph/KinegraphPlugin.cmake" include/kg/graph/plugin_abi.hpp \
         include/kg/retarget/constraints.hpp include/kg/motion/nodes.hpp include/kg/base/error.hpp \
         share/kinegraph/examples/plugin/CMakeLists.txt; do
  [[ -e $prefix/$f ]] || fail "the installation lacks $f"
done
for plugin in kg_lowpass kg_ladder; do  # the in-tree plugins, when this build has them
  if [[ -e $build/lib/kinegraph/plugins/$plugin.so && ! -e $prefix/lib/kinegraph/plugins/$plugin.so ]]; then
    fail "the installation lacks lib/kinegraph/plugins/$plugin.so"
  fi
done
if command -v readelf > /dev/null; then
  while IFS= read -r -d '' elf; do
    if readelf -d "$elf" 2>/dev/null | grep -E 'R(UN)?PATH' | grep -qF -e "$build" -e "$work/staging"; then
      fail "$elf has an RPATH into the build tree or the staging prefix: $(readelf -d "$elf" | grep -E 'R(UN)?PATH')"
    fi
  done < <(find "$prefix/bin" "$prefix/lib" -type f \( -name '*.so' -o -name kinegraph \) -print0)
fi
quiet "$prefix/bin/kinegraph" nodes
grep -q "motion.synthesize" "$work/last.log" || fail "the installed kinegraph lists no built-in nodes"

step "build examples/plugin outside the source tree against the prefix"
mkdir "$work/src"  # its files only, not a build/ or out/ of someone trying it in place
find "$source/examples/plugin" -maxdepth 1 -type f -exec cp {} "$work/src/" \;
configure=(cmake -S "$work/src" -B "$work/build" -G "$generator" -DCMAKE_BUILD_TYPE=Release
           -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF)
[[ -z $launcher ]] || configure+=(-DCMAKE_CXX_COMPILER_LAUNCHER="$launcher")
export CCACHE_BASEDIR=$work  # the same relative paths on every run of this test: cache hits
quiet "${configure[@]}"
found=$(sed -n 's/^Kinegraph_DIR:PATH=//p' "$work/build/CMakeCache.txt")
[[ $found == "$prefix/$libdir/cmake/Kinegraph" ]] || fail "find_package(Kinegraph) found '$found', not the prefix"
quiet cmake --build "$work/build" -j 2
for plugin in example_lift example_plane; do
  [[ -f $work/build/plugins/$plugin.so ]] || fail "no build/plugins/$plugin.so"
done

step "run the example graph with the installed kinegraph and --plugin-dir"
cd "$work/src"  # the graph's constraint file is relative to the working folder
quiet "$prefix/bin/kinegraph" run stage.yaml --plugin-dir "$work/build/plugins" --set out="$work/out" \
      --report "$work/report.json"
for f in stage_walk.bvh stage_ducked.bvh stage_metrics.json; do
  [[ -s $work/out/$f ]] || fail "the run wrote no $f"
done
# A figure of the report, e.g. figure lift height.
figure() {
  tr -d ' \n' < "$work/report.json" | grep -o "\"id\":\"$1\"[^}]*}" | grep -o "\"$2\":[-0-9.eE+]*" | cut -d: -f2
}
[[ $(figure lift height) == 0.2 ]] || fail "example.lift reported height '$(figure lift height)', not 0.2"
worst=$(figure metrics worst_example.plane_cm)
[[ -n $worst ]] || fail "retarget.metrics reported no example.plane violation: $(cat "$work/report.json")"
before=$(figure before worst_example.plane_cm)
awk -v w="$worst" -v b="$before" 'BEGIN { exit !(w < 0.1 && b > 5) }' ||
  fail "example.plane: worst violation $before cm before the solve, $worst cm after (want > 5 and < 0.1)"
echo "example.plane: worst violation $before cm before the solve, $worst cm after"

step "install the plugins into the prefix: found by name, no --plugin-dir"
quiet cmake --install "$work/build" --prefix "$prefix"
[[ -f $prefix/lib/kinegraph/plugins/example_lift.so ]] || fail "no lib/kinegraph/plugins/example_lift.so"
quiet "$prefix/bin/kinegraph" validate stage.yaml --set out="$work/out"  # loads both by name
step "done"
