#!/usr/bin/env bash
# Runs every benchmark program (BUILD_DIR/tests/bench_*) once and writes one JSON summary:
# the machine (nproc, CPU model), the date, the git revision, each program's arguments,
# wall seconds, headline ratios (1 thread and all threads) and its whole JSON document.
# Then prints a Markdown table of the headlines on stdout (the README's table is pasted
# from it). Progress and each program's stderr go to stderr.
#
#   tests/run_benchmarks.sh [--build DIR] [--out FILE] [--quick]
#
# The arguments keep the whole set under about 10 minutes on a 2-core machine (bench_floor
# runs 3 scans of its 60 × 45 m floor instead of 30, bench_global_registration 8 lab
# pairs, bench_nbv's subset 8 candidates); --quick runs each with the smallest arguments,
# to check that the set runs (its figures mean nothing).
set -euo pipefail

source_dir=$(cd "$(dirname "$0")/.." && pwd)
build_dir=$source_dir/build
out=benchmarks.json
quick=0
while (($#)); do
  case $1 in
    --build) build_dir=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --quick) quick=1; shift ;;
    -h | --help)
      sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//'
      exit 0 ;;
    *) echo "run_benchmarks.sh: unknown argument $1 (see --help)" >&2; exit 2 ;;
  esac
done

# name, then its arguments (full run | --quick).
declare -A full_args quick_args
full_args[bench_traversal]="--segments 1000000 --rounds 2"
quick_args[bench_traversal]="--segments 20000 --rounds 1"
full_args[bench_discretize]="--rounds 2"
quick_args[bench_discretize]="--rounds 1"
full_args[bench_occlusion]="--rounds 3"
quick_args[bench_occlusion]="--rounds 1"
full_args[bench_nbv]="--subset 8"
quick_args[bench_nbv]="--subset 2 --no-homogeneous"
full_args[bench_raycast]="--benchmark_format=json"
quick_args[bench_raycast]="--benchmark_format=json --benchmark_filter=BM_IntersectRows"
full_args[bench_global_registration]="--pairs 8"
quick_args[bench_global_registration]="--pairs 1"
full_args[bench_floor]="--scans 3"
quick_args[bench_floor]="--size 12x10 --scans 1"
full_args[bench_update]="--scans 5"
quick_args[bench_update]="--scans 1"
order=(bench_traversal bench_discretize bench_occlusion bench_nbv bench_raycast
  bench_global_registration bench_floor bench_update)

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
: >"$work/runs.tsv"
for name in "${order[@]}"; do
  exe=$build_dir/tests/$name
  if [[ ! -x $exe ]]; then
    echo "== $name: not built ($exe), skipped" >&2
    continue
  fi
  if ((quick)); then args=${quick_args[$name]}; else args=${full_args[$name]}; fi
  echo "== $name $args" >&2
  start=$(date +%s%N)
  # shellcheck disable=SC2086  # the arguments are words
  if ! "$exe" $args >"$work/$name.json"; then
    echo "run_benchmarks.sh: $name failed" >&2
    exit 1
  fi
  milliseconds=$((($(date +%s%N) - start) / 1000000))
  printf '%s\t%s\t%s\n' "$name" "$args" "$milliseconds" >>"$work/runs.tsv"
done

cpu_model=$(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -n 1)
revision=$(git -C "$source_dir" describe --always --dirty 2>/dev/null || echo unknown)
python3 - "$work" "$out" "$(nproc)" "$cpu_model" "$revision" "$quick" <<'EOF'
import datetime, json, sys

work, out, nproc, cpu_model, revision, quick = sys.argv[1:7]
summary = {
    "machine": {"nproc": int(nproc), "cpu_model": cpu_model},
    "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
    "git_revision": revision,
    "quick": quick == "1",
    "note": "each ratio is baseline seconds / semioctree seconds for the same work on the "
            "same number of threads (1, and all: the machine's hardware threads)",
    "headlines": [],  # every program's, with its name
    "benchmarks": {},
}
rows = []
for line in open(f"{work}/runs.tsv"):
    name, args, milliseconds = line.rstrip("\n").split("\t")
    with open(f"{work}/{name}.json") as f:
        doc = json.load(f)
    entry = {"arguments": args, "wall_seconds": int(milliseconds) / 1000, "output": doc}
    headlines = doc.get("headlines", []) if isinstance(doc, dict) else []
    if name == "bench_raycast":  # Google Benchmark: rays/s, no baseline
        entry["rays_per_second"] = {b["name"]: b["rays/s"] for b in doc.get("benchmarks", [])
                                    if "rays/s" in b}
    entry["headlines"] = [
        {k: h.get(k) for k in ("name", "compares", "threads", "ratio_1_thread",
                               "ratio_all_threads", "note")} for h in headlines]
    summary["headlines"] += [{"program": name, **h} for h in entry["headlines"]]
    for h in headlines:
        fmt = lambda r: "n/a" if r is None else f"{r:.2f}"
        rows.append((name, h["name"], h["compares"], h["threads"], fmt(h["ratio_1_thread"]),
                     fmt(h["ratio_all_threads"]), h.get("note", "")))
    summary["benchmarks"][name] = entry
with open(out, "w") as f:
    json.dump(summary, f, indent=2)
    f.write("\n")

print(f"Benchmarks on {cpu_model} ({nproc} threads), {summary['date']}, {revision}"
      + (" (--quick: the figures mean nothing)" if quick == "1" else "") + "\n")
print("| program | headline | compares | all threads = | ratio, 1 thread | ratio, all threads | note |")
print("|---|---|---|---|---|---|---|")
for r in rows:
    print("| " + " | ".join(str(c).replace("|", "/") for c in r) + " |")
extra = summary["benchmarks"]
if "bench_raycast" in extra:
    print("\nbench_raycast (no ratio), rays/s: " + ", ".join(
        f"{k} {v:.3g}" for k, v in extra["bench_raycast"]["rays_per_second"].items()))
if "bench_global_registration" in extra:
    s = extra["bench_global_registration"]["output"].get("lab", {}).get("summary", {})
    print(f"\nbench_global_registration (no ratio; {extra['bench_global_registration']['arguments']}): "
          f"{s.get('placed', 0)} of {s.get('pairs', 0)} lab pairs placed, "
          f"mean {s.get('mean_seconds', 0):.2f} s a pair")
if "bench_floor" in extra:
    s = extra["bench_floor"]["output"].get("survey", {})
    print(f"\nbench_floor (no ratio; {extra['bench_floor']['arguments']}): NBV largest "
          f"{s.get('nbv_seconds_max', 0):.2f} s, survey peak {s.get('peak_mib', 0):.0f} MiB, "
          f"{s.get('scans', 0)} scans")
print(f"\nwritten: {out}")
EOF
