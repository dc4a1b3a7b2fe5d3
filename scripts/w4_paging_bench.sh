#!/usr/bin/env bash
# W4 built in memory and paged, same binary, same machine, one after the other (issue 13's
# figures): per backend, `fragg_map build` with -o (in memory), then with a page store and a
# RAM budget, then `fragg_map compare` of the two maps. Each build runs under /usr/bin/time -v
# where it exists (peak RSS). Prints one line per build and the paged/in-memory ratio; the
# builds' --json summaries, time logs and the comparison stay in OUT.
# Usage: bash scripts/w4_paging_bench.sh --fm FRAGG_MAP --w4 W4_DIR --out DIR
#          [--backends "cpu cuda"] [--budget-mb 512] [--radius 30] [--store lmdb|db]
#          [--disk]   (also writes 2 GiB with dd conv=fdatasync into OUT: the disk's bandwidth)
#          [--cmp]    (the paged build also writes its map with -o, compared byte for byte with the
#                      in-memory one: its peak RSS then includes the whole map, read back to write it)
set -uo pipefail
fm="" w4="" out="" backends="cpu" budget=512 radius=30 store=lmdb disk=0 cmp=0
while [ $# -gt 0 ]; do
  case "$1" in
    --fm) fm="$2"; shift 2 ;;
    --w4) w4="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --backends) backends="$2"; shift 2 ;;
    --budget-mb) budget="$2"; shift 2 ;;
    --radius) radius="$2"; shift 2 ;;
    --store) store="$2"; shift 2 ;;
    --disk) disk=1; shift ;;
    --cmp) cmp=1; shift ;;
    *) echo "unknown argument $1" >&2; exit 2 ;;
  esac
done
[ -x "$fm" ] && [ -d "$w4" ] && [ -n "$out" ] ||
  { echo "usage: $0 --fm FRAGG_MAP --w4 W4_DIR --out DIR [...]" >&2; exit 2; }
mkdir -p "$out"
timer=()
[ -x /usr/bin/time ] && timer=(/usr/bin/time -v -o)
status=0

# run NAME ARGS...: one timed build; prints its wall seconds and peak RSS.
run() {
  local name="$1"; shift
  local t0 t1
  t0=$(date +%s.%N)
  if [ ${#timer[@]} -gt 0 ]; then
    "${timer[@]}" "$out/$name.time" "$fm" build "$w4" --resolution 0.05 --max-range 30 --json "$@" \
      >"$out/$name.json" 2>"$out/$name.err"
  else
    "$fm" build "$w4" --resolution 0.05 --max-range 30 --json "$@" >"$out/$name.json" 2>"$out/$name.err"
  fi
  local rc=$?
  t1=$(date +%s.%N)
  local rss="n/a"
  [ -f "$out/$name.time" ] &&
    rss="$(awk -F': ' '/Maximum resident/ { printf "%.0f MiB", $2 / 1024 }' "$out/$name.time")"
  [ $rc -eq 0 ] || { echo "$name: failed (rc $rc): $(tail -2 "$out/$name.err")"; status=1; }
  wall=$(awk -v a="$t0" -v b="$t1" 'BEGIN { print b - a }')
  # The build loop's time (the --json summary's "seconds"): the ratio is taken from it, as
  # the wall time includes writing the map file, which only the in-memory build does.
  loop=$(grep -o '"seconds":[0-9.]*' "$out/$name.json" | head -1 | cut -d: -f2)
  printf '%-12s build loop %8.2f s  wall %8.1f s  peak RSS %s\n' "$name" "${loop:-0}" "$wall" "$rss"
}

for backend in $backends; do
  rm -rf "$out/paged_$backend".* "$out/memory_$backend.fgm"
  run "memory_$backend" --backend "$backend" -o "$out/memory_$backend.fgm"
  mem_loop=$loop
  paged_out=()
  [ $cmp -eq 1 ] && paged_out=(-o "$out/paged_$backend.fgm")
  run "paged_$backend" --backend "$backend" --page-store "$out/paged_$backend.$store" \
    --page-budget-mb "$budget" --page-radius "$radius" "${paged_out[@]}"
  printf '%-12s paged throughput %.1f %% of in memory (build loops)\n' "$backend" \
    "$(awk -v m="${mem_loop:-0}" -v p="${loop:-0}" 'BEGIN { print (p > 0 ? 100 * m / p : 0) }')"
  "$fm" compare "$out/memory_$backend.fgm" "$out/paged_$backend.$store" >"$out/compare_$backend.log" 2>&1 ||
    status=1
  tail -3 "$out/compare_$backend.log"
  if [ $cmp -eq 1 ]; then
    if cmp -s "$out/memory_$backend.fgm" "$out/paged_$backend.fgm"; then
      echo "$backend: paged map file == in-memory map file (cmp)"
    else
      echo "$backend: paged map file DIFFERS from the in-memory one"; status=1
    fi
  fi
  rm -rf "$out/memory_$backend.fgm" "$out/paged_$backend.fgm" "$out/paged_$backend.$store"*
done
if [ $disk -eq 1 ]; then
  dd if=/dev/zero of="$out/dd.bin" bs=1M count=2048 conv=fdatasync 2>&1 | tail -1
  rm -f "$out/dd.bin"
fi
exit $status
