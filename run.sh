#!/usr/bin/env bash
# semioctree quick start. Run as root on Debian 12:
#   ./run.sh          install what is missing, build, run the main job (writes ./survey_out)
#   ./run.sh test     install what is missing, build, run the whole test suite
# Both are idempotent: a second run skips what is done.
set -euo pipefail
cd "$(dirname "$0")"

PACKAGES=(build-essential cmake ninja-build pkg-config
  liboctomap-dev libdynamicedt3d-dev libeigen3-dev libpcl-dev libembree-dev
  libgtest-dev libbenchmark-dev nlohmann-json3-dev libcli11-dev libpng-dev libcairo2-dev octomap-tools
  libnanoflann-dev)
BUILD_DIR=${SEMIOCTREE_BUILD_DIR:-build}

install_dependencies() {
  local missing=()
  for p in "${PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if ((${#missing[@]})); then
    echo "== installing ${missing[*]}"
    if [ "$(id -u)" -ne 0 ]; then
      echo "run.sh: missing Debian packages (${missing[*]}); run as root to install them" >&2
      exit 1
    fi
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends "${missing[@]}"
  fi
}

build() {
  if [ ! -f "$BUILD_DIR/CMakeCache.txt" ]; then
    echo "== configuring ($BUILD_DIR, Release)"
    cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release "$@"
  fi
  echo "== building"
  cmake --build "$BUILD_DIR" -j "$(nproc)"
}

main_job() {
  # The example survey: the simulated robot surveys the built-in lab scene
  # (scan → preprocess → register → update → next best view → move) until the
  # stop percentage is below 0.1 %; then the first scan's map is compared with
  # the homogeneous grid (the paper's Table 1, Table 2, Fig 15).
  local cli="$BUILD_DIR/semioctree" scene=sim/scenes/lab.scene.json
  rm -rf survey_out
  "$cli" scene-info "$scene"
  "$cli" survey --scene "$scene" --out survey_out
  "$cli" info survey_out/scan_00/semioctree.ot
  "$cli" compare --scene "$scene" --target-points 400000 --out survey_out/compare
  "$cli" report survey_out # rewritten: its list of files now holds compare/ too
  echo "== done: open survey_out/report.html in a browser (the survey on one page);"
  echo "   survey_out/survey.json, survey_out/scan_NN/ (maps, slice.png, cloud.ply),"
  echo "   survey_out/compare (report.html, comparison.md, fig15_octants.svg)"
}

run_tests() {
  (cd "$BUILD_DIR" && ctest --output-on-failure -j "$(nproc)")
}

case "${1:-run}" in
  run) install_dependencies; build; main_job ;;
  test) install_dependencies; build; run_tests ;;
  *) echo "usage: $0 [run|test]" >&2; exit 2 ;;
esac
