#!/usr/bin/env bash
# Build `pd` at each COMMIT in one scratch worktree and take a behaviour snapshot of it with this
# tree's tools/behaviour_snapshot.py and scenes, so that snapshots differ only by the binary.
# Compare two of them with `python3 tools/behaviour_snapshot.py diff OUT/snap-A OUT/snap-B`.
#
#   bash tools/snapshot_commits.sh WORKTREE OUT COMMIT...
#
# WORKTREE is created (git worktree add --detach) if missing; a snapshot already in OUT is kept.
# Used as docs/maintainers.md describes (each change that brought the fibre work in, against its parent).
set -u
if [ $# -lt 3 ]; then
  sed -n 2,9p "$0"
  exit 64
fi
root=$(cd "$(dirname "$0")/.." && pwd)
wt=$1 out=$2
shift 2
mkdir -p "$out"
[ -d "$wt" ] || git -C "$root" worktree add --detach "$wt" "$1" >/dev/null
for c in "$@"; do
  [ -d "$out/snap-$c" ] && continue
  start=$(date +%s)
  git -C "$wt" checkout -q --detach "$c" || { echo "$c: checkout failed"; continue; }
  [ -f "$wt/build/build.ninja" ] || cmake --preset default -S "$wt" >/dev/null
  if ! ninja -C "$wt/build" bin/pd >"$out/build-$c.log" 2>&1; then
    echo "$c: build failed ($out/build-$c.log)"
    continue
  fi
  built=$(date +%s)
  python3 "$root/tools/behaviour_snapshot.py" take "$wt/build" "$out/snap-$c" >"$out/snap-$c.log" 2>&1
  echo "$c: built in $((built - start)) s, snapshot in $(($(date +%s) - built)) s"
done
