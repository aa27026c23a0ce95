#!/usr/bin/env bash
# The README's command blocks run as written (issue 14, item 9): every ```sh block of README.md,
# in order, from a project root as a new user has it (graphs/, build/ and ../shared/data beside
# it), each with bash -e -o pipefail; a block fails the test with its line and its output. A
# block the test cannot run (it installs, builds, starts daemons or runs the benchmarks) follows
# a line `<!-- readme-test: skip (why) -->`, and its reason is printed. Commands outside those
# call the built CLI, build/bin/kinegraph: a `kinegraph` as if installed fails the test.
#
#   bash tests/readme/run_readme.sh SOURCE_DIR BINARY_DIR   # exit 0, 1 (a block failed), 77 (no data)
set -euo pipefail
source_dir=$(realpath "$1")
binary_dir=$(realpath "$2")
readme=$source_dir/README.md
shared=$(realpath -m "$source_dir/../shared")
if [[ ! -d $shared/data ]]; then
  echo "skipped: the README's examples read ../shared/data, not found at $shared/data"
  exit 77
fi

base=$(mktemp -d)
trap 'rm -rf "$base"' EXIT
root=$base/kinegraph
mkdir -p "$root"
ln -s "$shared" "$base/shared"
for entry in graphs tests examples scripts README.md; do ln -s "$source_dir/$entry" "$root/$entry"; done
ln -s "$binary_dir" "$root/build"
mkdir -p "$root/out"

failed=0 ran=0
block="" start=0 in_block=0 skip_reason="" previous=""
line_number=0
run_block() {
  local text=$1 at=$2
  if grep -nE '(^|[;&|(]|&&)[[:space:]]*kinegraph[[:space:]]' <<<"$text" >/dev/null; then
    echo "README.md:$at: a command calls kinegraph as if installed (write build/bin/kinegraph):"
    grep -nE '(^|[;&|(]|&&)[[:space:]]*kinegraph[[:space:]]' <<<"$text"
    failed=$((failed + 1))
    return
  fi
  local log=$base/block_$at.log started=$SECONDS
  if (cd "$root" && bash -e -o pipefail -c "$text") >"$log" 2>&1; then
    echo "README.md:$at: ok ($((SECONDS - started)) s)"
  else
    echo "README.md:$at: the block failed (exit $?); its commands:"
    sed 's/^/    /' <<<"$text"
    echo "  its output (last 40 lines):"
    tail -n 40 "$log" | sed 's/^/    /'
    failed=$((failed + 1))
  fi
  ran=$((ran + 1))
}
while IFS= read -r line || [[ -n $line ]]; do
  line_number=$((line_number + 1))
  if ((in_block)); then
    if [[ $line == '```'* ]]; then
      in_block=0
      if [[ -n $skip_reason ]]; then
        echo "README.md:$start: not run: $skip_reason"
      else
        run_block "$block" "$start"
      fi
      skip_reason=""
    else
      block+="$line"$'\n'
    fi
    continue
  fi
  if [[ $line == '```sh' ]]; then
    in_block=1 block="" start=$line_number
    if [[ $previous =~ ^\<\!--\ readme-test:\ skip\ \((.*)\)\ --\>$ ]]; then skip_reason=${BASH_REMATCH[1]}; fi
  fi
  [[ -z ${line// /} ]] || previous=$line
done <"$readme"

echo "$ran blocks run, $failed failed"
((ran > 0)) || { echo "no block of README.md ran"; exit 1; }
((failed == 0))
