#!/usr/bin/env bash
# Fuzzes one harness of a KG_FUZZ build, as CTest's fuzz_<harness>:fuzz and bench/fuzz_rates.sh do:
#   bash tests/fuzz/fuzz.sh EXE SECONDS ARTIFACT_PREFIX CORPUS SEEDS [REGRESSIONS]
# libFuzzer grows CORPUS from SEEDS and REGRESSIONS for SECONDS and writes a finding as
# ARTIFACT_PREFIX{crash,timeout,oom}-<sha1> (exit non-zero). The longest input it makes is the
# longest seed (at least libFuzzer's 4,096 bytes): the regressions, some 30-60 KB of nesting made
# to break a reader, are starting points to mutate (cut to that length) but do not set the length
# of every input, or a YAML harness spends its time parsing 60 KB texts (the graph harness made
# 562 inputs/s so). CTest's fuzz_<harness>:replay runs every regression whole.
# -timeout: an input taking 10 s is a finding (every reader is linear); -rss_limit_mb: 2 GB too.
set -euo pipefail
[[ $# -ge 5 && $# -le 6 ]] || { echo "usage: fuzz.sh EXE SECONDS ARTIFACT_PREFIX CORPUS SEEDS [REGRESSIONS]" >&2; exit 2; }
exe=$1 seconds=$2 prefix=$3 corpus=$4 seeds=$5
[[ -d $seeds ]] || { echo "fuzz.sh: no seed folder $seeds (the fuzz_seeds test writes it)" >&2; exit 2; }
longest=$(find "$seeds" -type f -printf '%s\n' | sort -n | tail -1)
max_len=$(( ${longest:-0} > 4096 ? longest : 4096 ))
mkdir -p "$corpus"
# A smaller quarantine (freed memory held back to catch a use after free, default 256 MB) and
# shorter allocation stacks: allocator bookkeeping was a third of the YAML harnesses' time (the
# graph harness 750 -> 900 inputs/s). A use after free within the last 16 MB of frees is still
# caught; CTest's replay keeps the defaults. ASAN_OPTIONS set by the caller wins.
export ASAN_OPTIONS=${ASAN_OPTIONS:-quarantine_size_mb=16:malloc_context_size=5}
exec "$exe" -max_total_time="$seconds" -max_len="$max_len" -timeout=10 -rss_limit_mb=2048 \
  -print_final_stats=1 -artifact_prefix="$prefix" "$corpus" "$seeds" ${6:+"$6"}
