# Shared by scripts/run and scripts/test: install what is missing, then build.
# Sourced, not run. Works as root on a fresh Debian 12 (bookworm) machine.

GO_FEAP_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
GO_FEAP_BUILD="${GO_FEAP_BUILD:-$GO_FEAP_ROOT/build}"
# Without trailing slashes: the logs go beside the folder, as $GO_FEAP_BUILD.build.log ("build/" put them
# inside one not yet made).
while [ "${#GO_FEAP_BUILD}" -gt 1 ] && [ "${GO_FEAP_BUILD%/}" != "$GO_FEAP_BUILD" ]; do GO_FEAP_BUILD="${GO_FEAP_BUILD%/}"; done
# ROS tools need Debian's python3 (with catkin_pkg), not a pyenv/venv one found first.
export PATH="/usr/bin:/bin:/usr/sbin:/sbin:$PATH"

GO_FEAP_APT_PACKAGES=(
  build-essential cmake
  ros-core-dev catkin libnodeletlib-dev libnodeletlib-tools pluginlib-dev
  librostest-dev python3-rostest python3-roslaunch librosbag-dev python3-rosbag
  libtf2-ros-dev libtf2-eigen-dev libcv-bridge-dev libimage-transport-dev
  libmessage-filters-dev libpcl-conversions-dev
  ros-geometry-msgs ros-nav-msgs ros-sensor-msgs ros-visualization-msgs ros-std-msgs ros-std-srvs
  libpcl-dev libopencv-dev libnlopt-cxx-dev liboctomap-dev libeigen3-dev libgtest-dev
  libyaml-cpp-dev nlohmann-json3-dev
  rviz librviz-dev xvfb imagemagick python3-matplotlib
  gdb  # the chain tests' thread stacks when one times out
)

log() { printf '[go_feap] %s\n' "$*" >&2; }

# usage_of SCRIPT: prints the comment block at the top of SCRIPT (after its #! line), without the "# ".
usage_of() { awk 'NR == 1 { next } /^#/ { sub(/^# ?/, ""); print; next } { exit }' "$1"; }

# needs_value ARGS_LEFT OPTION: an option given last, without its value, is refused by name (the
# script's own usage() is printed after).
needs_value() { [ "$1" -ge 2 ] || { log "$2 needs a value"; usage; exit 2; }; }

# check_seed S: a whole number that fits the ROS parameter it travels as (a 32-bit XML-RPC integer).
check_seed() {
  case "$1" in ''|*[!0-9]*) ;; *) [ "${#1}" -le 10 ] && [ "$1" -le 2147483647 ] && return 0 ;; esac
  log "--seed must be a whole number in [0, 2147483647], not '$1'"; exit 2
}

# Installs the Debian packages that are missing; a second run installs nothing.
install_dependencies() {
  local missing=() p
  for p in "${GO_FEAP_APT_PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if [ ${#missing[@]} -eq 0 ]; then
    log "dependencies: all ${#GO_FEAP_APT_PACKAGES[@]} packages present"
    return 0
  fi
  local sudo=()
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { log "need root (or sudo) to install: ${missing[*]}"; return 1; }
    sudo=(sudo)
  fi
  log "installing ${#missing[@]} missing packages with apt (a few minutes on a fresh machine): ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  # Waiting up to 10 minutes for the dpkg lock: right after boot apt-daily or unattended-upgrades hold it.
  local lock=(-o DPkg::Lock::Timeout=600)
  "${sudo[@]}" apt-get "${lock[@]}" update -q >/dev/null || { log "apt-get update failed"; return 1; }
  "${sudo[@]}" apt-get "${lock[@]}" install -y -q --no-install-recommends "${missing[@]}" >/dev/null ||
    { log "apt-get install failed for: ${missing[*]}"; return 1; }
  log "dependencies installed"
}

# Configures and builds the package standalone (devel space in build/devel).
build_package() {
  local shared="${GO_FEAP_SHARED_DIR:-$GO_FEAP_ROOT/../shared}"
  log "building in $GO_FEAP_BUILD"
  # The logs go beside the build folder, whose parent may not be made yet (cmake makes the folder itself).
  mkdir -p -- "$(dirname -- "$GO_FEAP_BUILD")" || { log "cannot make the parent of $GO_FEAP_BUILD"; return 1; }
  cmake -S "$GO_FEAP_ROOT" -B "$GO_FEAP_BUILD" -DCMAKE_BUILD_TYPE=Release \
    -DPYTHON_EXECUTABLE=/usr/bin/python3 -DGO_FEAP_SHARED_DIR="$shared" \
    >"$GO_FEAP_BUILD.configure.log" 2>&1 ||
    { tail -40 "$GO_FEAP_BUILD.configure.log" >&2; log "configure failed (log: $GO_FEAP_BUILD.configure.log)"; return 1; }
  cmake --build "$GO_FEAP_BUILD" -j"${GO_FEAP_JOBS:-2}" >"$GO_FEAP_BUILD.build.log" 2>&1 ||
    { grep -E "error|Error" "$GO_FEAP_BUILD.build.log" | head -40 >&2; log "build failed (log: $GO_FEAP_BUILD.build.log)"; return 1; }
  source_setup
  log "build ok"
}

# Sources the build's catkin setup (ROS_PACKAGE_PATH and the rest), which reads unset variables: without
# `set -u` while it runs.
source_setup() {
  local nounset=0
  [[ $- == *u* ]] && nounset=1
  set +u
  # shellcheck disable=SC1091
  source "$GO_FEAP_BUILD/devel/setup.bash"
  [ "$nounset" = 1 ] && set -u
}

# prepare_build NO_BUILD: install and build (NO_BUILD false), or, with --no-build (true), use the build
# already in $GO_FEAP_BUILD as it is, refused when there is none. The test suite runs the scripts so from
# inside `ctest`, where configuring or building the same build folder again would rewrite the files the
# running tests use; a user can run on a build while editing sources not meant to be built yet.
prepare_build() {
  if [ "$1" != true ]; then
    install_dependencies
    build_package
    return
  fi
  [ -f "$GO_FEAP_BUILD/devel/setup.bash" ] && [ -x "$GO_FEAP_BUILD/devel/lib/go_feap/go_feap_bench" ] ||
    { log "--no-build: there is no build in $GO_FEAP_BUILD (run once without --no-build)"; return 2; }
  source_setup
  log "--no-build: using the build in $GO_FEAP_BUILD as it is"
}

# new_folder BASE: makes a new folder BASE, or BASE-2, BASE-3, ... when it is there already (two runs
# started in the same second), and prints its path. mkdir is atomic: two callers never get the same one.
new_folder() {
  local path=$1 n=1
  mkdir -p -- "$(dirname -- "$1")" || return 1
  until mkdir -- "$path" 2>/dev/null; do
    n=$((n + 1))
    [ "$n" -le 1000 ] || { log "cannot make a folder $1 (nor $1-N)"; return 1; }
    path="$1-$n"
  done
  printf '%s\n' "$path"
}

# read_pid FILE: the pid a part of a background pipeline wrote to FILE, waited for up to 5 s (a signal may
# come before it is written); nothing when it never came.
read_pid() {
  local i
  for i in $(seq 50); do [ -s "$1" ] && break; sleep 0.1; done
  cat -- "$1" 2>/dev/null
}

# Kills (KILL) every process whose environment holds GO_FEAP_SESSION_TOKEN=$1.
kill_token_holders() {
  local pids
  pids=$(grep -lzx "GO_FEAP_SESSION_TOKEN=$1" /proc/[0-9]*/environ 2>/dev/null | cut -d/ -f3 || true)
  # shellcheck disable=SC2086
  if [ -n "$pids" ]; then kill -KILL $pids 2>/dev/null || true; fi
}

# Runs a command (a roslaunch under `timeout`) in a session of its own and, once it has exited, kills
# whatever is left of it: a roslaunch killed in the middle of its shutdown leaves its master and nodelet
# manager running, and they hold its output pipe open, so a reader of that pipe (tee, the progress
# filter) would wait for ever. roslaunch starts the master and every node in a session of their own
# (setsid), so they are found by a token in their environment, which they inherit. An INT, TERM or HUP
# to the caller is passed on to the command's session, as a terminal's Ctrl-C reaches roslaunch and its
# nodes. Returns the command's exit status.
run_in_own_session() {
  local sid_file child status sid token
  sid_file=$(mktemp)
  token="$$-${RANDOM}-$(date +%s%N)"
  # In the background (so that `wait` below can be interrupted by the trap), which leaves SIGINT ignored
  # in the command: env restores it, or neither Ctrl-C nor timeout's INT would stop roslaunch.
  setsid -w env --default-signal=INT GO_FEAP_SESSION_TOKEN="$token" sh -c 'echo $$ > "$0"; exec "$@"' \
    "$sid_file" "$@" &
  child=$!
  # shellcheck disable=SC2064
  trap "pkill -INT -s \"\$(cat '$sid_file' 2>/dev/null)\" 2>/dev/null" INT TERM HUP
  # `wait` returns early when a trapped signal arrives: wait again until the command has exited, then
  # once more for its exit status.
  while kill -0 "$child" 2>/dev/null; do wait "$child" || true; done
  if wait "$child"; then status=0; else status=$?; fi
  trap - INT TERM HUP
  sid=$(cat "$sid_file" 2>/dev/null || true)
  if [ -n "$sid" ] && [ "$sid" -gt 1 ]; then pkill -KILL -s "$sid" 2>/dev/null || true; fi
  kill_token_holders "$token"
  rm -f "$sid_file"
  return "$status"
}
