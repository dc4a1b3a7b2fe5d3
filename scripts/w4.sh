#!/usr/bin/env bash
# W4 long drive (issue 13): generates the workload when missing (scripts/make_workloads.sh
# --only w4: 579 scans of W1's LiDAR along a closed 1,156 m loop through the campus laid out
# four times, ~1.5 GB) and builds its map at 5 cm with a 30 m max range
#   - in memory:  fragg_map build W4 -o mem.fgm --resolution 0.05 --max-range 30
#   - paged:      the same with --page-store FILE --page-budget-mb N, when the CLI has paging
# each under /usr/bin/time -v (else Python's rusage), then prints a table: wall time, scans/s
# (scans over the build loop's seconds, reading and insertion; the map file's write excluded),
# peak RSS, the map's host memory (Map::memory()) and, for the paged build, what its --json
# says about pages.
# Usage: bash scripts/w4.sh [--workloads DIR] [--out DIR] [--bin DIR] [--budget-mb N]
#                           [--backend cpu|cuda|auto] [--scans N] [--no-paged] [--keep-maps]
#                           [--page-args "FLAGS"]
#   --workloads DIR  workload cache (default: $FRAGG_WORKLOADS or ~/.cache/fragg_map/workloads)
#   --out DIR        maps, logs and JSON (default: WORKLOADS/w4_runs)
#   --bin DIR        folder with fragg_map and fragg_map_sim (default: <checkout>_ws/devel/lib/fragg_map,
#                    else build-core/bin)
#   --budget-mb N    paged build's --page-budget-mb (default 512)
#   --store lmdb|db  page store of the paged build: LMDB (default) or SQLite
#   --radius M       paged build's --page-radius (default 40: a 30 m scan's reach and more)
#   --scans N        only the first N scans (default: all)
#   --keep-maps      keep the map file and the page store (several GB each) after the run
#   --compare        `fragg_map compare` of the in-memory map with the page store (cell states)
#   --cmp            the paged build also writes its map with -o (read back whole: its peak RSS
#                    then includes the whole map), compared byte for byte with the in-memory one
#   --disk           also writes 2 GiB with dd conv=fdatasync into OUT: the disk's bandwidth
#   --page-args "A"  more flags for the paged build only (e.g. "--read-ahead-rays 0
#                    --page-low-water 0.5"; word-split)
# The last line gives the paged build's throughput against the in-memory one (build loops).
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)"
workloads="${FRAGG_WORKLOADS:-$HOME/.cache/fragg_map/workloads}"
out="" bin="" budget_mb=512 store_ext=lmdb radius_m=40 backend=auto scans=0 paged=1 keep=0
compare=0 cmp_files=0 disk=0 page_args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --workloads) workloads="${2:?}"; shift 2 ;;
    --out) out="${2:?}"; shift 2 ;;
    --bin) bin="${2:?}"; shift 2 ;;
    --budget-mb) budget_mb="${2:?}"; shift 2 ;;
    --store) store_ext="${2:?}"; shift 2 ;;
    --radius) radius_m="${2:?}"; shift 2 ;;
    --backend) backend="${2:?}"; shift 2 ;;
    --scans) scans="${2:?}"; shift 2 ;;
    --no-paged) paged=0; shift ;;
    --keep-maps) keep=1; shift ;;
    --compare) compare=1; shift ;;
    --cmp) cmp_files=1; shift ;;
    --disk) disk=1; shift ;;
    --page-args) read -r -a page_args <<<"${2?}"; shift 2 ;;
    -h|--help) sed -n '2,28p' "$0"; exit 0 ;;
    *) echo "w4: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
if [ -z "$bin" ]; then
  if [ -x "${FRAGG_WS:-${repo}_ws}/devel/lib/fragg_map/fragg_map" ]; then bin="${FRAGG_WS:-${repo}_ws}/devel/lib/fragg_map"
  else bin="$repo/build-core/bin"; fi
fi
fm="$bin/fragg_map"
[ -x "$fm" ] || { echo "w4: no fragg_map in $bin (build first)" >&2; exit 1; }
command -v python3 >/dev/null || { echo "w4: needs python3" >&2; exit 1; }
mkdir -p "$workloads"
workloads="$(cd "$workloads" && pwd -P)"
out="${out:-$workloads/w4_runs}"
mkdir -p "$out"
w4="$workloads/w4_long_drive"

if [ ! -f "$w4/poses.txt" ] || [ "$(find "$w4/velodyne" -name '*.bin' | wc -l)" -lt 579 ]; then
  echo "w4: generating W4 into $w4"
  sim_args=()
  [ -x "$bin/fragg_map_sim" ] && sim_args=(--sim "$bin/fragg_map_sim")
  bash "$repo/scripts/make_workloads.sh" --out "$workloads" --only w4 "${sim_args[@]}"
fi

# LOG COMMAND...: runs COMMAND under /usr/bin/time -v into LOG; where that is missing (the GPU
# machine may lack Debian's 'time'), Python writes the two lines read below (peak RSS of the
# child, wall time) in the same form.
timed() {
  local log="$1"; shift
  if [ -x /usr/bin/time ]; then
    /usr/bin/time -v -o "$log" "$@"
    return
  fi
  python3 -c '
import resource, subprocess, sys, time
log, cmd = sys.argv[1], sys.argv[2:]
t0 = time.monotonic()
rc = subprocess.call(cmd)
wall = time.monotonic() - t0
rss_kib = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss  # KiB on Linux
with open(log, "w") as f:
    f.write(f"\tMaximum resident set size (kbytes): {rss_kib}\n")
    f.write(f"\tElapsed (wall clock) time (h:mm:ss or m:ss): {int(wall // 60)}:{wall % 60:05.2f}\n")
sys.exit(rc)' "$log" "$@"
}

# name, build arguments...: runs the build under timed(), keeps its JSON and time log.
build() {
  local name="$1"; shift
  echo "w4: $name build ($*)" >&2
  # The previous build's map file (406 MB for W4) is on disk first: its writeback would
  # otherwise run during this build, sharing the disk with this build's page store commits.
  sync
  timed "$out/$name.time" "$fm" build "$w4" --resolution 0.05 --max-range 30 \
    --backend "$backend" --scans "$scans" --json "$@" > "$out/$name.json"
}

rm -f "$out/in_memory.fgm"
build in_memory -o "$out/in_memory.fgm"
runs=(in_memory)
checks=()
if [ "$paged" = 1 ]; then
  # The help read whole first: `grep -q` stops at its first match, fragg_map then dies of
  # SIGPIPE and pipefail made the test false (the paged build was skipped).
  build_help="$("$fm" build --help 2>&1 || true)"
  if grep -q -- '--page-store' <<<"$build_help"; then
    # The store is the map: no .fgm is written (that would page every block back in) unless
    # --cmp asks for it.
    rm -f "$out/w4_pages.$store_ext"* "$out/paged.fgm"
    paged_out=()
    [ "$cmp_files" = 1 ] && paged_out=(-o "$out/paged.fgm")
    build paged --page-store "$out/w4_pages.$store_ext" --page-budget-mb "$budget_mb" \
      --page-radius "$radius_m" "${page_args[@]}" "${paged_out[@]}"
    if [ "$compare" = 1 ]; then
      "$fm" compare "$out/in_memory.fgm" "$out/w4_pages.$store_ext" >"$out/compare.log" 2>&1
      checks+=("compare (cell states): $(grep '^known in either' "$out/compare.log")")
    fi
    if [ "$cmp_files" = 1 ]; then
      if cmp -s "$out/in_memory.fgm" "$out/paged.fgm"; then
        checks+=("cmp: the paged build's map file == the in-memory one")
      else
        checks+=("cmp: the paged build's map file DIFFERS from the in-memory one")
      fi
      rm -f "$out/paged.fgm"
    fi
    [ "$keep" = 1 ] || rm -f "$out/w4_pages.$store_ext"*
    runs+=(paged)
  else
    echo "w4: this fragg_map has no --page-store: in-memory build only" >&2
  fi
fi
[ "$keep" = 1 ] || rm -f "$out/in_memory.fgm"
if [ "$disk" = 1 ]; then
  checks+=("disk: $(dd if=/dev/zero of="$out/dd.bin" bs=1M count=2048 conv=fdatasync 2>&1 | tail -1)")
  rm -f "$out/dd.bin"
fi

echo
echo "W4 long drive, 5 cm, 30 m, backend $backend, $(nproc) cores, $fm"
python3 - "$out" "${runs[@]}" <<'PY'
import json, re, sys
out, runs = sys.argv[1], sys.argv[2:]
print("| build | scans | wall s | loop s | scans/s | peak RSS MiB | map host MiB | blocks | paging |")
print("|---|---|---|---|---|---|---|---|---|")
for name in runs:
    j = json.load(open(f"{out}/{name}.json"))
    t = open(f"{out}/{name}.time").read()
    rss_mib = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", t).group(1)) / 1024
    wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): ([\d:.]+)", t).group(1)
    wall_s = sum(float(x) * 60 ** i for i, x in enumerate(reversed(wall.split(":"))))
    paging = ", ".join(f"{k} {v}" for k, v in sorted(j.get("paging", {}).items())
                       if re.search(r"pages_|records_|resident|commits", k))
    print(f"| {name} | {j['scans']} | {wall_s:.1f} | {j['seconds']:.1f} | "
          f"{j['scans'] / j['seconds']:.2f} | {rss_mib:,.0f} | {j['host_bytes'] / 2**20:,.0f} | "
          f"{j['blocks']:,} | {paging or '-'} |")
for name in runs:
    r = json.load(open(f"{out}/{name}.json")).get("rss_mib")
    if r:  # the build loop's peak, before the last commit and the -o write (--cmp)
        print(f"{name}: peak RSS of the build loop {r['peak_build_loop']:,.0f} MiB, before the "
              f"first scan {r['before_first_scan']:,.0f} MiB (the process and the backend); at "
              f"the loop's end anonymous {r.get('anon_loop_end', 0):,.0f}, files "
              f"{r.get('file_loop_end', 0):,.0f}, shared {r.get('shmem_loop_end', 0):,.0f} MiB; "
              f"malloc's heap in use {r.get('heap_in_use_loop_end', 0):,.0f}, free in its arenas "
              f"{r.get('heap_free_loop_end', 0):,.0f}, mapped apart "
              f"{r.get('heap_mapped_loop_end', 0):,.0f} MiB")
if "paged" in runs:
    p = json.load(open(f"{out}/paged.json"))
    pg = p["paging"]
    if "stops_in_scan" in pg:
        # Where the paged build's time goes, summed over its scans.
        print(f"paged stages (s): ray pass {p['seconds_raycast']:.2f}, apply "
              f"{p['seconds_apply']:.2f}, residency {p['seconds_residency']:.2f}; read-ahead "
              f"walk {pg['seconds_reach']:.2f}, read-ahead {pg['seconds_read_ahead']:.2f} "
              f"({pg['scans_read_ahead']} scans, {pg['blocks_read_ahead']:,} blocks); "
              f"in-scan stops {pg['stops_in_scan']} ({pg['seconds_in_scan']:.2f} s, "
              f"{pg['blocks_read_in_scan']:,} blocks, sync {pg['seconds_sync_in_scan']:.2f}), "
              f"passes redone {p['passes_redone']} ({p['passes_redone'] / max(1, p['scans']):.2f} a "
              f"scan, {p['seconds_redone']:.2f} s with the stops); "
              f"store reads+decode {pg['seconds_page_in']:.2f}; device write-back (sync) "
              f"{pg['seconds_sync']:.2f}; page-out {pg['seconds_page_out']:.2f} (evict "
              f"{pg['seconds_evict']:.2f}, encode {pg['seconds_encode']:.2f}, choosing "
              f"{pg.get('seconds_choose', float('nan')):.2f}); rounds "
              f"{pg['rounds_between_scans']} between scans, {pg['rounds_in_scan']} in scans; "
              f"commits {pg['seconds_commit']:.2f} on the map's thread, writer "
              f"{pg['seconds_writer']:.2f}")
    mem = json.load(open(f"{out}/in_memory.json"))["seconds"]
    paged = json.load(open(f"{out}/paged.json"))["seconds"]
    print(f"paged throughput: {100 * mem / paged:.1f} % of in-memory (build loops {paged:.2f} "
          f"against {mem:.2f} s)")
    p = json.load(open(f"{out}/paged.json"))
    # Stored blocks: the map's (the in-memory build's count; the paged build's is its resident
    # blocks only, unless it wrote its map).
    pg, blocks = p["paging"], json.load(open(f"{out}/in_memory.json"))["blocks"]
    if blocks:
        print(f"written per stored block: {pg['pages_written'] / blocks:.2f} blocks, "
              f"{pg.get('records_written', pg['pages_written']) / blocks:.3f} records "
              f"({blocks:,} blocks; store {pg['store_bytes'] / 2**20:,.0f} MiB; "
              f"peak resident {pg['peak_resident_blocks']:,} of {pg['budget_blocks']:,} allowed)")
        if "blocks_encoded" in pg:
            print(f"compressed per stored block: {pg['blocks_encoded'] / blocks:.2f} blocks "
                  f"(the others kept their encodings); blocks held for a commit: "
                  f"{pg.get('blocks_held', 0):,}; budget count peak "
                  f"{pg['peak_counted_bytes'] / 2**20:,.1f} of {pg['budget_bytes'] / 2**20:,.1f} MiB "
                  f"(blocks and kept records); commits {pg['commits']}")
PY
for line in "${checks[@]}"; do echo "$line"; done
