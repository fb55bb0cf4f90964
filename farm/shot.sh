#!/usr/bin/env bash
# Submits a shot to Slurm and waits for it: the simulation pass (one job,
# sequential over frames), the shot pass once it succeeded, then a job array
# of render tasks, `chunk` frames each, once the shot pass succeeded. A job
# that fails cancels the jobs waiting on it. Every path must be on storage
# all nodes share; the same lines run on a one-node or a many-node cluster.
#
#   farm/shot.sh <shot binary> <creature.obj> <dir> <frames> <hairs> [frames per task]
#
# CPUS_PER_TASK (default 1) is each job's --cpus-per-task; PARTITION, when
# set, its --partition; POLL_SECONDS (default 1) how often squeue is asked.
set -euo pipefail

if [ $# -lt 5 ]; then
  echo "usage: $0 <shot binary> <creature.obj> <dir> <frames> <hairs> [frames per task]" >&2
  exit 2
fi
shot=$(realpath "$1") obj=$(realpath "$2") frames=$4 hairs=$5 chunk=${6:-1}
mkdir -p "$3/logs"
dir=$(realpath "$3")
rm -f "$dir"/frame_*.png "$dir"/logs/*.log  # only this run's frames count
opts=(--parsable --kill-on-invalid-dep=yes --chdir="$dir" --cpus-per-task="${CPUS_PER_TASK:-1}")
if [ -n "${PARTITION:-}" ]; then opts+=(--partition="$PARTITION"); fi

sim=$(sbatch "${opts[@]}" --job-name=sim --output="$dir/logs/sim-%j.log" \
  --wrap="exec '$shot' sim '$obj' '$dir' $frames $hairs")
shotpass=$(sbatch "${opts[@]}" --job-name=shot-pass --output="$dir/logs/shot-pass-%j.log" \
  --dependency="afterok:$sim" --wrap="exec '$shot' reduce '$dir' $frames")
# Task ids are first frames (0, chunk, 2 chunk, ...); the last task may hold fewer.
render=$(sbatch "${opts[@]}" --job-name=render --output="$dir/logs/render-%A_%a.log" \
  --dependency="afterok:$shotpass" --array="0-$((frames - 1)):$chunk" \
  --wrap="n=\$(($frames - SLURM_ARRAY_TASK_ID)); exec '$shot' render '$dir' \$SLURM_ARRAY_TASK_ID \$((n < $chunk ? n : $chunk))")
jobs=("$sim" "$shotpass" "${render%%;*}")
echo "shot.sh: sim $sim, shot pass $shotpass, render array $render: $frames frames, $chunk per task"

# Polled rather than `sbatch --wait`, whose interval grows to 32 s. Without
# slurmdbd, the job states come from slurmctld (kept MinJobAge seconds).
while [ -n "$(squeue -h -o %i -j "$(IFS=,; echo "${jobs[*]}")")" ]; do sleep "${POLL_SECONDS:-1}"; done

failed=0
for job in "${jobs[@]}"; do
  states=$(scontrol -o show job "$job" | grep -o 'JobState=[A-Z_]*' | sort -u | xargs) || true
  if [ "$states" != JobState=COMPLETED ]; then
    echo "shot.sh: job $job: $(scontrol -o show job "$job" | grep -o 'JobName=[^ ]*\|JobState=[A-Z_]*\|Reason=[^ ]*' | xargs)" >&2
    failed=1
  fi
done
for ((f = 0; f < frames; f++)); do
  png=$(printf '%s/frame_%04d.png' "$dir" "$f")
  if [ ! -s "$png" ]; then echo "shot.sh: $png is missing" >&2; failed=1; fi
done
if [ "$failed" != 0 ]; then
  echo "shot.sh: FAILED; the jobs' logs:" >&2
  tail -n 20 "$dir"/logs/*.log >&2
  exit 1
fi
echo "shot.sh: $frames frames in $dir"
