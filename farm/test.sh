#!/usr/bin/env bash
# CTest farm_slurm: a reduced shot rendered through the local Slurm cluster
# at two chunkings must give the same PNG bits as the same shot run in one
# process on one core (so also at another thread count than the farm's).
# Brings the cluster up (failing with the daemons' logs when it cannot) and
# stops it again if it was not up before.
#
#   farm/test.sh <shot binary> <creature.obj> <work dir> [frames] [hairs]
set -euo pipefail

here=$(dirname "$(realpath "$0")")
shot=$1 obj=$2 work=$3 frames=${4:-4} hairs=${5:-30000}

if ! "$here/cluster.sh" status; then trap '"$here/cluster.sh" stop' EXIT; fi
"$here/cluster.sh"

rm -rf "$work"
mkdir -p "$work"
SECONDS=0
for chunk in 1 2; do
  "$here/shot.sh" "$shot" "$obj" "$work/chunk$chunk" "$frames" "$hairs" "$chunk"
  echo "farm_slurm: $chunk frame(s) per task: done at $SECONDS s"
done
mkdir -p "$work/local"
taskset -c 0 "$shot" local "$obj" "$work/local" "$frames" "$hairs"
echo "farm_slurm: one process on one core: done at $SECONDS s"

for chunk in 1 2; do cmp "$work/local/shot.ptriml" "$work/chunk$chunk/shot.ptriml"; done
for ((f = 0; f < frames; f++)); do
  png=$(printf 'frame_%04d.png' "$f")
  for chunk in 1 2; do cmp "$work/local/$png" "$work/chunk$chunk/$png"; done
done
echo "farm_slurm: the trim lengths and $frames frames bitwise equal: one process, Slurm at 1 and 2 frames per task"
