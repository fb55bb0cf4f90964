#!/usr/bin/env bash
# CTest farm_faults: a shot on the local Slurm cluster survives what a farm
# does to it. It kills the simulation halfway through writing a file, then
# (resumed: the simulation goes on from its saved state) kills one render
# task halfway through writing its image and another mid-run, cancels the
# render array while a third writes, requeues a finished task and resumes
# again. Every output must then equal an undisturbed run's bit for
# bit, a watcher polling the shot's folder all along must never have seen a
# file at a final path that is not the undisturbed run's (a partial file)
# nor one written twice (a good file rewritten), and a file from another
# frame or shot, or one without a shot identity, must be refused. A shot on
# a full disk (a small tmpfs: root, as cluster.sh is) must fail with only
# whole files and resume on a larger one.
#
#   farm/fault_test.sh <shot binary> <creature.obj> <work dir> [hairs]
#
# 4 frames, one per render task: the faults are aimed at tasks 1, 2 and 3.
set -euo pipefail

here=$(dirname "$(realpath "$0")")
shot=$(realpath "$1") obj=$(realpath "$2") work=$3 frames=4 hairs=${4:-20000}
export POLL_SECONDS=0.2

mkdir -p "$work"
work=$(realpath "$work")
# The test empties its folder before it runs (as root): only a folder it
# made itself, marked so, or an empty one.
if [ ! -e "$work/.farm_faults" ] && [ -n "$(ls -A "$work")" ]; then
  echo "farm_faults: $work is not empty and not this test's folder; give a new or empty one" >&2
  exit 2
fi
was_up=1
"$here/cluster.sh" status >/dev/null || was_up=0
# Whatever happened, nothing of the test goes on: its background shells,
# its jobs (a stalled task waits to be killed), the tmpfs, the cluster if
# the test brought it up.
cleanup() {
  local pids
  pids=$(jobs -p)
  if [ -n "$pids" ]; then kill $pids 2>/dev/null || true; fi
  if [ -n "$(cat "$work"/*/logs/jobs 2>/dev/null)" ]; then
    scancel $(cat "$work"/*/logs/jobs) 2>/dev/null || true
    for _ in $(seq 50); do
      [ -n "$(squeue -h -o %F -u "$(id -un)" 2>/dev/null | grep -xF -f <(cat "$work"/*/logs/jobs))" ] || break
      sleep 0.2
    done
  fi
  umount "$work/full" 2>/dev/null || true
  if [ "$was_up" = 0 ]; then "$here/cluster.sh" stop; fi
}
trap cleanup EXIT
"$here/cluster.sh"

umount "$work/full" 2>/dev/null || true
rm -rf "${work:?}"/*
touch "$work/.farm_faults"
mkdir -p "$work/ref" "$work/run"
run=$work/run
fail() {
  echo "farm_faults: FAILED: $*" >&2
  touch "$work/stop"
  tail -n 5 "$run"/logs/*.log >&2 || true
  exit 1
}
SECONDS=0

"$shot" local "$obj" "$work/ref" "$frames" "$hairs" >"$work/ref.log"
finals=()
for f in "$work"/ref/*; do finals+=("$(basename "$f")"); done
echo "farm_faults: undisturbed run, ${#finals[@]} files: done at $SECONDS s"

# The watcher: every file that appears at a final path must be the
# undisturbed run's bytes the first time it is seen, and never be replaced
# (another inode or mtime) afterwards.
watch() {
  declare -A seen
  local polls=0 name sig line
  while [ ! -e "$work/stop" ]; do
    while read -r line; do
      name=${line%% *} sig=${line#* }
      name=$(basename "$name")
      case $name in *.part-*) continue ;; esac
      if [ -z "${seen[$name]:-}" ]; then
        if [ ! -e "$work/ref/$name" ]; then
          echo "$name: not a file of the shot" >>"$work/violations"
        elif ! cmp -s "$run/$name" "$work/ref/$name"; then
          echo "$name: at its final path but not the undisturbed run's bytes ($sig)" >>"$work/violations"
        fi
        seen[$name]=$sig
      elif [ "${seen[$name]}" != "$sig" ]; then
        echo "$name: written again (${seen[$name]} then $sig)" >>"$work/violations"
        seen[$name]=$sig
      fi
    done < <(find "$run" -maxdepth 1 -type f ! -name '.*' -printf '%p %i %s %T@\n' 2>/dev/null)
    polls=$((polls + 1))
    sleep 0.05
  done
  echo "$polls" >"$work/polls"
}
watch &
watcher=$!

# Waits up to 60 s for a command to succeed.
wait_for() {
  local what=$1
  shift
  for _ in $(seq 600); do if "$@"; then return; fi; sleep 0.1; done
  fail "no $what after 60 s"
}
temp_of() { compgen -G "$run/$1.part-*" >/dev/null; }
# Whether a log of $run matching the pattern $2 holds the text $1.
logged() { grep -qsF "$1" "$run"/logs/$2; }
kill_task() { kill -KILL "$(pgrep -fx "$shot $*")"; }
# The first submission, then the resumes exactly as docs/FARM.md's recipes
# say; a shot.sh that hangs is stopped (and the test fails) after 2 minutes.
submit() { timeout 120 "$here/shot.sh" "$shot" "$obj" "$run" "$frames" "$hairs" 1 >>"$work/submits.log" 2>&1; }
resume() { timeout 120 "$here/shot.sh" resume "$run" >>"$work/submits.log" 2>&1; }

# 1. The simulation, killed halfway through writing frame 1's mesh.
SHOT_FAULT_STALL=frame_0001.mesh submit &
submitter=$!
wait_for "simulation stalled in frame_0001.mesh" temp_of frame_0001.mesh
[ ! -e "$run/frame_0001.mesh" ] || fail "frame_0001.mesh at its final path while being written"
kill_task sim "$obj" "$run" "$frames" "$hairs"
if wait "$submitter"; then fail "shot.sh succeeded with its simulation killed"; fi
echo "farm_faults: simulation killed mid-write; shot.sh failed: done at $SECONDS s"

# 2. Resumed: render task 1 killed halfway through writing its image, task
#    2 killed mid-run (its image made, not yet written), the array cancelled
#    while task 3 writes its image (scancel's SIGTERM must remove the
#    temporary file). The stalls make the order the same on any machine.
SHOT_FAULT_STALL=frame_0001.png,frame_0002.png:before,frame_0003.png resume &
submitter=$!
wait_for "render task 1 stalled in frame_0001.png" temp_of frame_0001.png
[ ! -e "$run/frame_0001.png" ] || fail "frame_0001.png at its final path while being written"
kill_task render "$run" 1 1
wait_for "render task 2 stalled before writing frame_0002.png" \
  logged "stalled before writing $run/frame_0002.png" 'render-*_2.log'
kill_task render "$run" 2 1
wait_for "render task 3 stalled in frame_0003.png" temp_of frame_0003.png
scancel "$(tail -n 1 "$run/logs/jobs")"
if wait "$submitter"; then fail "shot.sh succeeded with its render array cancelled"; fi
! temp_of frame_0003.png || fail "the cancelled task left its temporary file"
grep -q "going on from the state saved after frame 0" "$run"/logs/sim-*.log ||
  fail "the resumed simulation did not go on from frame 0's saved state"
# Its stdout, line-buffered, kept what it printed before the SIGKILL.
grep -q "render: 1 of frames 2 to 2 to render" "$run"/logs/render-*_2.log || fail "killed task 2's log lost its lines"

for f in 1 2 3; do
  png=$(printf 'frame_%04d.png' "$f")
  [ ! -e "$run/$png" ] || fail "$png exists though its task was killed or cancelled"
done
echo "farm_faults: render tasks killed mid-write and mid-run, array cancelled: done at $SECONDS s"

# 3. The finished task 0 requeued by hand, as a preempted task would be
#    (released from the hold a requeue puts it in): it must not write its
#    good frame again, and the resume waits for it, then submits only what
#    is missing.
array=$(tail -n 1 "$run/logs/jobs")
scontrol requeue "${array}_0"
resume &
submitter=$!
wait_for "the resume waiting for the requeued task" \
  grep -q "waiting for the shot's jobs still queued: $array" "$work/submits.log"
scontrol update JobId="${array}_0" StartTime=now
wait "$submitter" || fail "the resumed shot failed"
logged "render: frame 0: already good" "render-${array}_0.log" || fail "the requeued task 0 did not skip its frame"
last=$(grep 'shot.sh: submitted' "$work/submits.log" | tail -n 1)
[[ $last == *"sim done, shot pass done, render tasks 1,2,3 "* ]] ||
  fail "the resume submitted more than frames 1 to 3: $last"
echo "farm_faults: resumed after the requeued task (${last#shot.sh: }): done at $SECONDS s"

touch "$work/stop"
wait "$watcher"
if [ -s "$work/violations" ]; then fail "seen while the faults happened: $(cat "$work/violations")"; fi
for name in "${finals[@]}"; do cmp "$work/ref/$name" "$run/$name" || fail "$name differs"; done
leftover=$(find "$run" -maxdepth 1 -name '*.part-*')
[ -z "$leftover" ] || fail "temporary files left: $leftover"
echo "farm_faults: ${#finals[@]} files bitwise equal to the undisturbed run; $(cat "$work/polls") polls saw no partial or rewritten file"

# 4. A full disk: a 2-frame shot on a 5 MB tmpfs fails when the simulation
#    cannot write frame 0's mesh, leaving only whole files and no temporary
#    one; on a larger disk the resumed shot equals an undisturbed run.
full=$work/full
mkdir -p "$full" "$work/ref2"
mount -t tmpfs -o size=5m tmpfs "$full" || fail "cannot mount a tmpfs for the full disk (needs root with CAP_SYS_ADMIN)"
"$shot" local "$obj" "$work/ref2" 2 "$hairs" >"$work/ref2.log"
if timeout 120 "$here/shot.sh" "$shot" "$obj" "$full" 2 "$hairs" >>"$work/submits.log" 2>&1; then
  fail "a shot on a full disk succeeded"
fi
grep -q "No space left on device" "$full"/logs/sim-*.log || fail "the simulation did not run out of space"
for f in "$full"/*; do
  if [ -f "$f" ]; then cmp "$f" "$work/ref2/$(basename "$f")" || fail "$f: partial on a full disk"; fi
done
[ -z "$(find "$full" -name '*.part-*')" ] || fail "a temporary file left on the full disk"
mount -o remount,size=64m "$full"
timeout 120 "$here/shot.sh" resume "$full" >>"$work/submits.log" 2>&1 || fail "the shot did not resume"
for f in "$work"/ref2/*; do cmp "$f" "$full/$(basename "$f")" || fail "$f differs after the full disk"; done
echo "farm_faults: a full disk failed the simulation cleanly; resumed on a larger one: done at $SECONDS s"

# 5. Files in the wrong place are refused, and nothing is written.
mkdir -p "$work/wrong"
cp "$run/creature.pgroom" "$run/shot.ptriml" "$run/frame_0000.pguide" "$work/wrong/"
cp "$run/frame_0001.mesh" "$work/wrong/frame_0000.mesh"
if "$shot" render "$work/wrong" 0 1 2>"$work/wrong.log"; then fail "frame 1's mesh rendered as frame 0"; fi
grep -q "frame_0000.mesh: holds frame 1 of this shot, not frame 0" "$work/wrong.log" || fail "$(cat "$work/wrong.log")"
tail -c +73 "$run/frame_0000.mesh" >"$work/wrong/frame_0000.mesh"
if "$shot" render "$work/wrong" 0 1 2>"$work/wrong.log"; then fail "a mesh without a shot identity rendered"; fi
grep -q "without a shot identity" "$work/wrong.log" || fail "$(cat "$work/wrong.log")"
cp "$run/frame_0000.mesh" "$work/wrong/"
cp "$full/shot.ptriml" "$work/wrong/"
if "$shot" render "$work/wrong" 0 1 2>"$work/wrong.log"; then fail "a 2-frame shot's lengths rendered in a 4-frame shot"; fi
grep -q "shot.ptriml: belongs to another shot" "$work/wrong.log" || fail "$(cat "$work/wrong.log")"
[ ! -e "$work/wrong/frame_0000.png" ] || fail "a refused frame left an image"
umount "$full"
echo "farm_faults: another frame's file, another shot's and an unsealed one refused: done at $SECONDS s"
