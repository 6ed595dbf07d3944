#!/usr/bin/env bash
# vtloc synth killed midway (SIGKILL: no chance to clean up), then run again:
# - right after the kill, every object folder in place is complete (the one
#   being built is still objects/<name>.tmp), and there is no dataset.json;
# - the resumed build equals an uninterrupted one, file for file, byte for byte.
#   kill_resume.sh VTLOC WORK_DIR
set -euo pipefail
vtloc="$1"
work="$2"
rm -rf "$work"
mkdir -p "$work"
printf 'shape:sphere\nshape:box\nshape:cone\nshape:torus\n' > "$work/list.txt"
args=(synth --objects "$work/list.txt" --contacts 6 --extra 100 --n-points 64 --seed 5 --threads 1 --view)

"$vtloc" "${args[@]}" --out "$work/whole" > /dev/null

"$vtloc" "${args[@]}" --out "$work/killed" > /dev/null &
pid=$!
for _ in $(seq 1 3000); do  # until the first object is in place (at most ~60 s)
  if compgen -G "$work/killed/objects/*/object.json" > /dev/null; then break; fi
  sleep 0.02
done
kill -9 "$pid" 2> /dev/null || true
wait "$pid" 2> /dev/null || true

if [ -e "$work/killed/dataset.json" ]; then
  echo "the build finished before it could be killed: nothing was tested" >&2
  exit 1
fi
for d in "$work"/killed/objects/*/; do
  case "$d" in *.tmp/) continue ;; esac
  if [ ! -f "$d/object.json" ] || [ ! -f "$d/touches.csv" ] || [ ! -f "$d/points.csv" ]; then
    echo "torn object folder in place after the kill: $d" >&2
    exit 1
  fi
done
echo "killed with $(ls -d "$work"/killed/objects/*/ | grep -vc '\.tmp/$' || true) object(s) in place"

"$vtloc" "${args[@]}" --out "$work/killed" > /dev/null
if ! diff -r "$work/whole" "$work/killed"; then
  echo "the resumed dataset differs from the uninterrupted one" >&2
  exit 1
fi
echo "resumed dataset equals the uninterrupted build"

# A kill between the view's two files (view.xyz written, view.json still a .tmp):
# rare in the race above, so made here. The rerun writes the view again.
rm "$work/killed/objects/sphere/view.json"
echo '{"torn' > "$work/killed/objects/sphere/view.json.tmp"
"$vtloc" "${args[@]}" --out "$work/killed" > /dev/null
if ! diff -r "$work/whole" "$work/killed"; then
  echo "a view torn between its two files was not rewritten on resume" >&2
  exit 1
fi
echo "a torn view is rewritten on resume"
