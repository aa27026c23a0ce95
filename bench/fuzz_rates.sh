#!/usr/bin/env bash
# Fuzzing throughput of every harness of tests/fuzz (issue 13: at least 1,000 inputs/s each):
#   bash bench/fuzz_rates.sh [BUILD_DIR] [SECONDS]
# BUILD_DIR (default build-asan) is a KG_FUZZ build (KG_SANITIZE_TEST=1 bash scripts/dev.sh test
# makes one): each harness fuzzes for SECONDS (default 60) from its seeds and regressions into a
# scratch corpus as CTest's fuzz test does (tests/fuzz/fuzz.sh), and its executions, their rate
# and the corpus it reached are printed from libFuzzer's final statistics. In a build without
# KG_FUZZ the harnesses replay their seeds and regressions instead, and the replay rate is printed.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=$(realpath "${1:-build-asan}")
seconds=${2:-60}
seeds=$build/fuzz/seeds
[[ -d $seeds ]] || "$build/bin/fuzz_seeds" "$here" "$seeds" >/dev/null
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
printf '%-12s %12s %10s %12s %8s\n' harness executions seconds inputs/s corpus
for harness in bvh asf amc graph target constraints body contacts; do
  exe=$build/bin/fuzz_$harness
  corpora=("$seeds/$harness")
  [[ -d $here/tests/fuzz/regressions/$harness ]] && corpora+=("$here/tests/fuzz/regressions/$harness")
  help=$("$exe" -help=1 2>&1 || true)  # not piped into grep -q: under pipefail its SIGPIPE reads as "no"
  if [[ $help == *libFuzzer* ]]; then
    log=$(bash "$here/tests/fuzz/fuzz.sh" "$exe" "$seconds" "$scratch/$harness-" "$scratch/$harness" \
          "${corpora[@]}" 2>&1) || {
      echo "$log" | tail -40
      echo "fuzz_$harness: a finding (above)" >&2
      exit 1
    }
    runs=$(echo "$log" | sed -n 's/^stat::number_of_executed_units: *//p')
    took=$(echo "$log" | sed -n 's/^Done [0-9]* runs in \([0-9]*\) second.*/\1/p')
    rate=$(echo "$log" | sed -n 's/^stat::average_exec_per_sec: *//p')
    units=$(ls "$scratch/$harness" | wc -l)
    printf '%-12s %12s %10s %12s %8s\n' "$harness" "$runs" "$took" "$rate" "$units"
  else
    line=$("$exe" "${corpora[@]}" 2>/dev/null)
    runs=$(echo "$line" | sed -n 's/^replayed \([0-9]*\) inputs in \([0-9.]*\) s (\([0-9]*\) inputs\/s)/\1/p')
    took=$(echo "$line" | sed -n 's/^replayed \([0-9]*\) inputs in \([0-9.]*\) s (\([0-9]*\) inputs\/s)/\2/p')
    rate=$(echo "$line" | sed -n 's/^replayed \([0-9]*\) inputs in \([0-9.]*\) s (\([0-9]*\) inputs\/s)/\3/p')
    printf '%-12s %12s %10s %12s %8s\n' "$harness" "$runs" "$took" "$rate" "(replay)"
  fi
done
