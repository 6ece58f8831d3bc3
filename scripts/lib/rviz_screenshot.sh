#!/usr/bin/env bash
# Usage: scripts/lib/rviz_screenshot.sh OUT.png [SECONDS]
#
# Starts rviz with rviz/exploration.rviz (or $RVIZ_CONFIG) on a virtual X screen
# (xvfb-run, 1280x800x24), waits SECONDS (default 15), saves a screenshot of the whole
# screen to OUT.png (ImageMagick `import -window root`; taken again every 2 s, up to 10
# times, while the screen is blank), stops rviz and prints the rviz ERROR lines it saw.
# rviz's full output is kept in OUT.rviz.log.
#
# Needs a ROS master already running (ROS_MASTER_URI); it never starts one.
# Exit status: 0 when the screenshot was written, 1 otherwise.
set -euo pipefail

# ROS tools need Debian's python3 and rviz, not a pyenv/venv one found first.
export PATH="/usr/bin:/bin:/usr/sbin:/sbin:$PATH"

SCRIPT_DIR="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
GO_FEAP_ROOT="$(cd "$SCRIPT_DIR/../.." && pwd)"
CONFIG="${RVIZ_CONFIG:-$GO_FEAP_ROOT/rviz/exploration.rviz}"
SCREEN="${RVIZ_SCREEN:-1280x800x24}"

log() { printf '[rviz_screenshot] %s\n' "$*" >&2; }
die() { log "error: $*"; exit 1; }

if [ $# -lt 1 ] || [ $# -gt 2 ]; then die "usage: $(basename "$0") OUT.png [SECONDS]"; fi
OUT="$1"
SECONDS_WAIT="${2:-15}"
[[ "$SECONDS_WAIT" =~ ^[0-9]+([.][0-9]+)?$ ]] || die "SECONDS must be a number, got '$SECONDS_WAIT'"
[ -f "$CONFIG" ] || die "rviz config not found: $CONFIG (set RVIZ_CONFIG to use another file)"
CONFIG="$(cd "$(dirname "$CONFIG")" && pwd)/$(basename "$CONFIG")"

mkdir -p "$(dirname "$OUT")"
OUT="$(cd "$(dirname "$OUT")" && pwd)/$(basename "$OUT")"
RVIZ_LOG="${OUT%.*}.rviz.log"

command -v rviz >/dev/null || die "rviz not found (apt-get install rviz)"
command -v xvfb-run >/dev/null || die "xvfb-run not found (apt-get install xvfb)"
if ! command -v import >/dev/null; then
  sudo=()
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || die "ImageMagick's import is missing; need root (or sudo) to apt-get install imagemagick"
    sudo=(sudo)
  fi
  log "ImageMagick's import is missing: installing imagemagick with apt-get"
  export DEBIAN_FRONTEND=noninteractive
  "${sudo[@]}" apt-get install -y -q --no-install-recommends imagemagick >/dev/null 2>&1 || {
    "${sudo[@]}" apt-get update -q >/dev/null 2>&1 &&
      "${sudo[@]}" apt-get install -y -q --no-install-recommends imagemagick >/dev/null 2>&1
  } || die "apt-get install imagemagick failed"
  command -v import >/dev/null || die "imagemagick installed but import is still missing"
fi

# The master must already be up: rviz would otherwise wait for it forever.
timeout 15 rostopic list >/dev/null 2>&1 ||
  die "no ROS master answers at ${ROS_MASTER_URI:-http://localhost:11311} (start roscore first)"

# Runs inside xvfb-run: rviz in the background, wait, screenshot, stop rviz.
# Exit 3: rviz died before the screenshot; 4: import failed.
# shellcheck disable=SC2016
INNER='
set -u
cfg="$1"; out="$2"; secs="$3"
rviz -d "$cfg" &
rpid=$!
stop_rviz() {
  local sig _
  for sig in INT TERM KILL; do  # INT first: rviz then unregisters from the master
    kill -0 "$rpid" 2>/dev/null || break
    kill -"$sig" "$rpid" 2>/dev/null || true
    for _ in 1 2 3 4 5 6 7 8 9 10; do kill -0 "$rpid" 2>/dev/null || break; sleep 0.5; done
  done
  wait "$rpid" 2>/dev/null || true
}
trap stop_rviz EXIT
trap "exit 130" INT TERM
sleep "$secs" &
wait $!  # unlike a foreground sleep, wait lets the TERM trap run at once
if ! kill -0 "$rpid" 2>/dev/null; then
  wait "$rpid"; rc=$?
  echo "[rviz_screenshot] rviz exited (status $rc) before the screenshot" >&2
  exit 3
fi
# A screen still blank (rviz slow to draw on a loaded machine) is taken again, every 2 s, up to 10 times.
for try in 1 2 3 4 5 6 7 8 9 10; do
  import -window root "$out" || exit 4
  sd="$(convert "$out" -format "%[fx:standard_deviation]" info: 2>/dev/null || echo 1)"
  awk -v sd="$sd" "BEGIN { exit !(sd > 0.01) }" && break
  echo "[rviz_screenshot] the screen is still blank (try $try): waiting 2 s more" >&2
  sleep 2
done
exit 0
'

XPID=""
cleanup() {
  local rc=$?
  trap - EXIT INT TERM
  if [ -n "$XPID" ] && kill -0 "$XPID" 2>/dev/null; then
    # First the inner shell: it stops rviz (which unregisters from the master), then
    # xvfb-run stops Xvfb and removes its lock and auth files.
    local inner _
    inner="$(pgrep -P "$XPID" -x bash || true)"
    if [ -n "$inner" ]; then kill -TERM "$inner" 2>/dev/null || true; fi
    for _ in $(seq 40); do kill -0 "$XPID" 2>/dev/null || break; sleep 0.5; done
    # Then anything left in xvfb-run's process group (setsid made it the leader).
    if kill -0 "$XPID" 2>/dev/null; then
      kill -TERM -- "-$XPID" 2>/dev/null || true
      for _ in $(seq 10); do kill -0 "$XPID" 2>/dev/null || break; sleep 0.5; done
      kill -KILL -- "-$XPID" 2>/dev/null || true
    fi
  fi
  exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

rm -f "$OUT"
log "rviz -d $CONFIG on a $SCREEN virtual screen, screenshot after ${SECONDS_WAIT}s (master ${ROS_MASTER_URI:-default})"
setsid xvfb-run -a -s "-screen 0 $SCREEN" bash -c "$INNER" rviz_screenshot_inner \
  "$CONFIG" "$OUT" "$SECONDS_WAIT" >"$RVIZ_LOG" 2>&1 &
XPID=$!
status=0
wait "$XPID" || status=$?
XPID=""

# rospack's "no such package media_export" (rviz looking for plugin media) is harmless noise.
errors="$(sed 's/\x1b\[[0-9;]*m//g' "$RVIZ_LOG" | grep -E '\[ ?ERROR\]|^ERROR|[Ee]rror:' |
  grep -v -E 'no such package media_export' || true)"
if [ -n "$errors" ]; then
  log "rviz ERROR lines ($(printf '%s\n' "$errors" | wc -l)):"
  printf '%s\n' "$errors"
else
  log "rviz printed no ERROR lines"
fi
log "rviz output: $RVIZ_LOG"

case "$status" in
  0) ;;
  3) tail -20 "$RVIZ_LOG" >&2; die "rviz exited before the screenshot (see $RVIZ_LOG)" ;;
  4) die "import -window root failed (see $RVIZ_LOG)" ;;
  *) tail -20 "$RVIZ_LOG" >&2; die "xvfb-run failed with status $status (see $RVIZ_LOG)" ;;
esac
[ -s "$OUT" ] || die "no screenshot written to $OUT"
log "screenshot: $OUT"
