#!/usr/bin/env bash
# Runs every fuzz target for a while (cargo-fuzz, nightly) and reports how
# many inputs each ran; any crash fails (libFuzzer exits non-zero and leaves
# the input under fuzz/artifacts/).   usage: fuzz/run.sh [seconds per target]
set -euo pipefail
cd "$(dirname "$0")"
seconds="${1:-60}"
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz --locked --version 0.13.2
for target in decode_groom decode_cache decode_trim restore_sim; do
  log="$(mktemp)"
  if ! cargo +nightly fuzz run "$target" -- -max_total_time="$seconds" >"$log" 2>&1; then
    tail -60 "$log"
    echo "fuzz: $target FAILED (input saved under fuzz/artifacts/$target)"
    exit 1
  fi
  echo "fuzz: $target: $(grep -E '^Done [0-9]+ runs' "$log" | tail -1), no crash"
  rm -f "$log"
done
