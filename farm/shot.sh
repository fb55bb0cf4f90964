#!/usr/bin/env bash
# Submits a shot to Slurm and waits for it: the simulation pass (one job,
# sequential over frames), the shot pass once it succeeded, then a job array
# of render tasks, `chunk` frames each, once the shot pass succeeded. A job
# that fails cancels the jobs waiting on it. Every path must be on storage
# all nodes share; the same lines run on a one-node or a many-node cluster.
#
#   farm/shot.sh <shot binary> <creature.obj> <dir> <frames> <hairs> [frames per task]
#   farm/shot.sh resume <dir>      the same, with the arguments <dir>'s shot was submitted with
#
# Running it again (either way) resumes the shot: it first waits for the
# shot's jobs still queued (a requeued task, one still running), then asks
# `shot status` what is missing or not good and submits only that; every
# task also skips the files that are already good, so a good frame is never
# written again. Jobs are requeueable and their logs append (DIR/logs/).
#
# CPUS_PER_TASK (default 1) is each job's --cpus-per-task; PARTITION, when
# set, its --partition; POLL_SECONDS (default 1) how often squeue is asked.
set -euo pipefail

if [ "${1:-}" = resume ] && [ $# = 2 ]; then
  if [ ! -f "$2/logs/args" ]; then echo "shot.sh: $2 holds no shot submitted by shot.sh (no logs/args)" >&2; exit 2; fi
  mapfile -t saved <"$2/logs/args"
  set -- "${saved[@]}"
fi
if [ $# -lt 5 ]; then
  echo "usage: $0 <shot binary> <creature.obj> <dir> <frames> <hairs> [frames per task]" >&2
  echo "       $0 resume <dir>" >&2
  exit 2
fi
shot=$(realpath "$1") obj=$(realpath "$2") frames=$4 hairs=$5 chunk=${6:-1}
mkdir -p "$3/logs"
dir=$(realpath "$3")

# One submitter per shot: two would submit the same frames twice.
exec 9>"$dir/logs/shot.lock"
flock -n 9 || { echo "shot.sh: another shot.sh is submitting $dir; wait for it" >&2; exit 1; }
printf '%s\n' "$shot" "$obj" "$dir" "$frames" "$hairs" "$chunk" >"$dir/logs/args.new"
mv "$dir/logs/args.new" "$dir/logs/args"

# The shot's jobs, from this run and every earlier one, and those of them
# still in the queue (%F: an array task's array id; the shot's jobs are this
# user's, and asking for only those spares a busy slurmctld). An unreachable
# slurmctld counts as "still queued": only an answer ends the wait.
touch "$dir/logs/jobs"
queued() {
  local q
  if ! q=$(squeue -h -o %F -u "$(id -un)" 2>/dev/null); then echo unreachable; return; fi
  grep -xF -f "$dir/logs/jobs" <<<"$q" | sort -u | xargs || true
}
wait_queue() {
  local left
  while left=$(queued) && [ -n "$left" ]; do sleep "${POLL_SECONDS:-1}"; done
}

left=$(queued)
if [ -n "$left" ]; then
  echo "shot.sh: waiting for the shot's jobs still queued: $left"
  wait_queue
fi
# No job of this shot runs now: a temporary file is a killed writer's.
rm -f "$dir"/*.part-*

status=$("$shot" status "$obj" "$dir" "$frames" "$hairs")
sim_todo=$(grep -qx 'sim todo' <<<"$status" && echo 1 || echo 0)
reduce_todo=$(grep -qx 'reduce todo' <<<"$status" && echo 1 || echo 0)
read -r -a missing <<<"$(sed -n 's/^render//p' <<<"$status")"
# Task ids are first frames (0, chunk, 2 chunk, ...); a task runs its chunk,
# skipping the frames already good, and the last task may hold fewer.
tasks=$(for f in "${missing[@]}"; do echo $((f / chunk * chunk)); done | sort -nu | paste -sd, -)

opts=(--parsable --requeue --open-mode=append --kill-on-invalid-dep=yes --chdir="$dir"
  --cpus-per-task="${CPUS_PER_TASK:-1}")
if [ -n "${PARTITION:-}" ]; then opts+=(--partition="$PARTITION"); fi
jobs=() after=()
if [ "$sim_todo" = 1 ]; then
  sim=$(sbatch "${opts[@]}" --job-name=sim --output="$dir/logs/sim-%j.log" \
    --wrap="exec '$shot' sim '$obj' '$dir' $frames $hairs")
  jobs+=("$sim") after=(--dependency="afterok:$sim")
  echo "$sim" >>"$dir/logs/jobs"
fi
if [ "$sim_todo" = 1 ] || [ "$reduce_todo" = 1 ]; then
  shotpass=$(sbatch "${opts[@]}" --job-name=shot-pass --output="$dir/logs/shot-pass-%j.log" "${after[@]}" \
    --wrap="exec '$shot' reduce '$dir' $frames")
  jobs+=("$shotpass") after=(--dependency="afterok:$shotpass")
  echo "$shotpass" >>"$dir/logs/jobs"
fi
if [ -n "$tasks" ]; then
  render=$(sbatch "${opts[@]}" --job-name=render --output="$dir/logs/render-%A_%a.log" "${after[@]}" \
    --array="$tasks" \
    --wrap="n=\$(($frames - SLURM_ARRAY_TASK_ID)); exec '$shot' render '$dir' \$SLURM_ARRAY_TASK_ID \$((n < $chunk ? n : $chunk))")
  jobs+=("${render%%;*}")
  echo "${render%%;*}" >>"$dir/logs/jobs"
fi
if [ ${#jobs[@]} = 0 ]; then
  echo "shot.sh: every file of the $frames frames in $dir is already good; nothing to submit"
  exit 0
fi
echo "shot.sh: submitted ${jobs[*]}: sim $([ "$sim_todo" = 1 ] && echo yes || echo done)," \
  "shot pass $([ "$sim_todo$reduce_todo" != 00 ] && echo yes || echo done)," \
  "render tasks ${tasks:-none} ($chunk frames per task) of $frames frames"

# Polled rather than `sbatch --wait`, whose interval grows to 32 s; a
# requeued task stays in the queue, so this waits for it too.
wait_queue

failed=0
for job in "${jobs[@]}"; do
  states=$(scontrol -o show job "$job" 2>/dev/null | grep -o 'JobState=[A-Z_]*' | sort -u | xargs) || true
  # slurmctld forgets a job MinJobAge seconds after it ends: a job it no
  # longer knows is judged by the files below, not reported as failed
  if [ -n "$states" ] && [ "$states" != JobState=COMPLETED ]; then
    echo "shot.sh: job $job: $(scontrol -o show job "$job" 2>/dev/null |
      grep -o 'JobName=[^ ]*\|JobState=[A-Z_]*\|Reason=[^ ]*' | sort -u | xargs)" >&2
    failed=1
  fi
done
status=$("$shot" status "$obj" "$dir" "$frames" "$hairs")
if [ "$status" != "$(printf 'sim done\nreduce done\nrender')" ]; then
  echo "shot.sh: not done yet: $(tr '\n' ' ' <<<"$status")(render: frames without a good image)" >&2
  failed=1
fi
if [ "$failed" != 0 ]; then
  echo "shot.sh: FAILED; this run's logs:" >&2
  for job in "${jobs[@]}"; do
    for log in "$dir"/logs/*-"$job".log "$dir"/logs/*-"$job"_*.log; do
      if [ -f "$log" ]; then tail -n 20 "$log" | sed "s|^|$(basename "$log"): |" >&2; fi
    done
  done
  echo "shot.sh: once the cause is fixed, resume with: $0 resume $dir" >&2
  exit 1
fi
echo "shot.sh: $frames frames in $dir"
