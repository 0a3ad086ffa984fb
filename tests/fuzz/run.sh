#!/usr/bin/env bash
# Builds the libFuzzer targets of the file readers and runs each (docs/fuzzing.md).
#   tests/fuzz/run.sh [SECONDS] [TARGET...]   each target for SECONDS (default 60)
#   FUZZ_RUNS=N tests/fuzz/run.sh 0 [TARGET...]   each target for N executions instead
# Builds in build-fuzz (SEMIOCTREE_FUZZ_BUILD_DIR) with clang. Each target fuzzes a
# copy of its seed corpus (tests/fuzz/corpus/<target>) in a scratch directory, so the
# repository is never written. A finding (crash, sanitizer report, leak, timeout,
# out-of-memory) is kept in <build dir>/findings/<target>/ and makes the script exit 1.
set -euo pipefail
cd "$(dirname "$0")/../.."

SECONDS_EACH=${1:-60}
shift || true
ALL_TARGETS=(fuzz_scene fuzz_pcd fuzz_ply fuzz_xyz fuzz_ptx fuzz_octree_ot fuzz_octomap_bt)
TARGETS=("$@")
((${#TARGETS[@]})) || TARGETS=("${ALL_TARGETS[@]}")
BUILD_DIR=${SEMIOCTREE_FUZZ_BUILD_DIR:-build-fuzz}

if ! command -v clang++ >/dev/null || ! command -v clang >/dev/null; then
  echo "run.sh: clang is needed for libFuzzer (Debian: apt-get install clang libclang-rt-dev)" >&2
  exit 1
fi
if [ ! -f "$BUILD_DIR/CMakeCache.txt" ]; then
  # -O1 with line tables: quick to build, fast to run, stack traces with lines. Only
  # the libraries the targets link are built: no tests, benchmarks or command line.
  CC=clang CXX=clang++ cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release \
    "-DCMAKE_C_FLAGS_RELEASE=-O1 -gline-tables-only" \
    "-DCMAKE_CXX_FLAGS_RELEASE=-O1 -gline-tables-only" \
    -DSEMIOCTREE_FUZZ=ON -DSEMIOCTREE_BUILD_TESTS=OFF
fi
cmake --build "$BUILD_DIR" -j "${SEMIOCTREE_FUZZ_BUILD_JOBS:-$(nproc)}" --target "${TARGETS[@]}"

dictionary_of() {
  case "$1" in
    fuzz_scene) echo tests/fuzz/scene.dict ;;
    fuzz_pcd) echo tests/fuzz/pcd.dict ;;
    fuzz_ply) echo tests/fuzz/ply.dict ;;
    fuzz_octree_ot | fuzz_octomap_bt) echo tests/fuzz/ot.dict ;;
  esac
}

SCRATCH=$(mktemp -d)
# The targets' own scratch files (point files written for PCL), on a RAM disk if any.
SHM_BASE=/dev/shm
[ -d "$SHM_BASE" ] && [ -w "$SHM_BASE" ] || SHM_BASE=$SCRATCH
export SEMIOCTREE_FUZZ_SCRATCH
SEMIOCTREE_FUZZ_SCRATCH=$(mktemp -d "$SHM_BASE/semioctree-fuzz-run.XXXXXX")
trap 'rm -rf "$SCRATCH" "$SEMIOCTREE_FUZZ_SCRATCH"' EXIT
# Leaks are findings too; UBSan reports abort (the build has -fno-sanitize-recover).
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1}
budget="$SECONDS_EACH s"
[ -z "${FUZZ_RUNS:-}" ] || budget="$FUZZ_RUNS runs"
# One target: fuzzes, then writes its report to $SCRATCH/<target>.report and its status
# to $SCRATCH/<target>.status (0: no finding).
fuzz_target() {
  local t=$1 corpus="$SCRATCH/$1" findings="$BUILD_DIR/findings/$1" dict log start status
  mkdir -p "$corpus" "$findings"
  cp tests/fuzz/corpus/"$t"/* "$corpus"/
  local args=(-timeout=25 -rss_limit_mb=2048 -max_len=8192 -print_final_stats=1
    -artifact_prefix="$findings/")
  if [ -n "${FUZZ_RUNS:-}" ]; then args+=(-runs="$FUZZ_RUNS"); else args+=(-max_total_time="$SECONDS_EACH"); fi
  dict=$(dictionary_of "$t")
  [ -n "$dict" ] && args+=(-dict="$dict")
  log="$SCRATCH/$t.log"
  start=$(date +%s)
  status=0
  "$BUILD_DIR/tests/fuzz/$t" "${args[@]}" "$corpus" >"$log" 2>&1 || status=$?
  {
    echo "== $t ($budget)"
    if ((status == 0)); then
      grep -E "^stat::(number_of_executed_units|average_exec_per_sec|peak_rss_mb)" "$log" || true
      echo "wall time: $(($(date +%s) - start)) s"
    else
      tail -n 60 "$log"
      echo "== $t: FINDING, input kept in $findings/"
    fi
  } >"$SCRATCH/$t.report"
  echo "$status" >"$SCRATCH/$t.status"
}
# As many targets at once as cores (SEMIOCTREE_FUZZ_JOBS): each fuzzes on one.
jobs_at_once=${SEMIOCTREE_FUZZ_JOBS:-$(nproc)}
running=0
for t in "${TARGETS[@]}"; do
  if ((running >= jobs_at_once)); then
    wait -n || true
    running=$((running - 1))
  fi
  fuzz_target "$t" &
  running=$((running + 1))
done
wait
failed=()
for t in "${TARGETS[@]}"; do
  cat "$SCRATCH/$t.report"
  [ "$(cat "$SCRATCH/$t.status" 2>/dev/null)" = 0 ] || failed+=("$t")
done
if ((${#failed[@]})); then
  echo "fuzzing found problems in: ${failed[*]}" >&2
  exit 1
fi
echo "== no finding"
