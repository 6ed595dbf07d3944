#!/bin/sh
# Extracts the 21 CGAL sample meshes used as synthetic training objects from
# Debian's libcgal-demo package (data.tar.gz under /usr/share/doc/libcgal-dev)
# into OUTDIR, flat. Only these names are extracted: the package's other
# meshes stay out of training, tuning and tests on purpose. The meshes are
# under CGAL's GPL/LGPL terms, so they are never committed to this repository.
# Usage: data/synth/get_cgal_meshes.sh OUTDIR
set -eu

if [ $# -ne 1 ]; then
    echo "usage: $0 OUTDIR" >&2
    exit 2
fi
out=$1
archive=/usr/share/doc/libcgal-dev/data.tar.gz
names="bunny00 cow elephant mushroom blobby head fandisk pig knot1 camel bull homer dino cactus pinion spool rotor anchor handle helmet bear"

if [ ! -f "$archive" ]; then
    # --no-install-recommends: the package otherwise pulls in Qt.
    if [ "$(id -u)" -eq 0 ]; then sudo=""; elif command -v sudo >/dev/null; then sudo=sudo; else
        echo "$0: $archive is missing and installing libcgal-demo needs root or sudo" >&2
        exit 1
    fi
    $sudo apt-get install -y --no-install-recommends libcgal-demo >&2 || {
        $sudo apt-get update >&2 && $sudo apt-get install -y --no-install-recommends libcgal-demo >&2
    }
fi
[ -f "$archive" ] || { echo "$0: $archive not found after installing libcgal-demo" >&2; exit 1; }

# In libcgal-demo 5.5 all of them are data/meshes/NAME.off (pig also comes
# as .stl). Any extension is accepted, .off preferred, in case a later
# package moves a mesh to another format; nothing else is extracted.
patterns=""
for n in $names; do patterns="$patterns data/meshes/$n.*"; done
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# A pattern matching nothing makes tar fail; the loop below names what is missing.
# shellcheck disable=SC2086
tar -xzf "$archive" -C "$tmp" --wildcards $patterns 2>/dev/null || true
missing=""
for n in $names; do
    pick=""
    for f in "$tmp/data/meshes/$n.off" "$tmp/data/meshes/$n".*; do
        if [ -f "$f" ]; then pick=$f; break; fi
    done
    if [ -n "$pick" ]; then cp "$pick" "$out/"; else missing="$missing $n"; fi
done
if [ -n "$missing" ]; then
    echo "$0: not in $archive:$missing" >&2
    exit 1
fi
echo "$(echo "$names" | wc -w) CGAL meshes in $out"
