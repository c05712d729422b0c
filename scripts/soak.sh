#!/usr/bin/env bash
# Soak test: resident memory must stay flat (within 5% after the first minute) while
#  1. the viewer, under Xvfb, animates the noise deformation and orbits the light for
#     VIEW_SECONDS (default 600), re-solving every frame, and
#  2. `lucent render` writes a FRAMES-frame (default 1000) noise animation.
# RSS is sampled every 5 s from /proc; the samples go to target/soak/*.tsv.
# Usage: scripts/soak.sh [VIEW_SECONDS] [FRAMES]      (needs xvfb-run: apt-get install xvfb)
set -euo pipefail
cd "$(dirname "$0")/.."
VIEW_SECONDS=${1:-600}
FRAMES=${2:-1000}
OUT=target/soak
mkdir -p "$OUT"
cargo build --release -p lucent >/dev/null
BIN=$PWD/target/release/lucent

# Samples VmRSS (KiB) of process $1 every 5 s into $2 as "seconds<TAB>KiB" until it exits.
sample() {
  local pid=$1 file=$2 start=$SECONDS
  : >"$file"
  while kill -0 "$pid" 2>/dev/null; do
    local rss
    rss=$(awk '/^VmRSS/ {print $2}' "/proc/$pid/status" 2>/dev/null || true)
    [ -n "$rss" ] && printf '%s\t%s\n' $((SECONDS - start)) "$rss" >>"$file"
    sleep 5
  done
}

# Prints the verdict for a sample file: RSS at the first minute, the largest after it, growth.
verdict() {
  awk -v name="$1" -F'\t' '
    $1 >= 60 && base == "" { base = $2 }
    $1 >= 60 { if ($2 > max) max = $2; last = $2; n++ }
    END {
      if (base == "") { printf "%s: ran under a minute, no verdict\n", name; exit 1 }
      growth = 100 * (max - base) / base
      printf "%s: RSS %.1f MiB at 60 s, max %.1f MiB after, last %.1f MiB, growth %+.1f%% over %d samples: %s\n",
        name, base / 1024, max / 1024, last / 1024, growth, n, (growth <= 5 ? "flat" : "GROWING")
      exit (growth <= 5 ? 0 : 1)
    }' "$2"
}

status=0
echo "== viewer: ${VIEW_SECONDS} s of animated noise and an orbiting light under Xvfb"
xvfb-run -a -s "-screen 0 1280x800x24" "$BIN" view --frames 10 --script "animate:${VIEW_SECONDS}" --screenshot "$OUT/view.png" \
  >"$OUT/view.log" 2>&1 &
sleep 3
VIEW_PID=$(pgrep -n -f "lucent view --frames 10 --script animate" || true)
[ -n "$VIEW_PID" ] && sample "$VIEW_PID" "$OUT/view.tsv"
wait || true
verdict viewer "$OUT/view.tsv" || status=1

echo "== render: ${FRAMES} frames of a noise animation"
rm -rf "$OUT/frames"
"$BIN" render --frames "$FRAMES" --deform noise:0.2,0.3 --width 320 --height 240 --out "$OUT/frames" \
  >"$OUT/render.log" 2>&1 &
sample $! "$OUT/render.tsv"
wait $! || status=1
verdict "render ${FRAMES} frames" "$OUT/render.tsv" || status=1
exit $status
