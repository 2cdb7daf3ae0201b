#!/bin/sh
# run_fuzz.sh TARGET CORPUS WORK SECONDS: runs a libFuzzer target for SECONDS on
# a fresh copy of CORPUS in WORK (new inputs and findings stay in WORK, not in
# the source tree), then prints its final statistics and findings. Exit status:
# the fuzzer's (non-zero when it found a crash, hang, leak or escaped exception).
set -u
target=$1 corpus=$2 work=$3 seconds=$4
rm -rf "$work"
mkdir -p "$work/corpus" "$work/findings"
cp "$corpus"/* "$work/corpus/"
cd "$work" || exit 1
"$target" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=4096 -max_len=65536 -print_final_stats=1 \
  -artifact_prefix="$work/findings/" "$work/corpus" > "$work/fuzz.log" 2>&1
status=$?
tail -40 "$work/fuzz.log"
echo "findings: $(ls "$work/findings" | wc -l) in $work/findings"
exit $status
