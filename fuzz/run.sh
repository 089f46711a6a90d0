#!/usr/bin/env bash
# Runs every fuzzer for a bounded number of inputs:
#   fuzz/run.sh BUILD_DIR [RUNS]      (make fuzz: RUNS=10000 each)
# For hours, by hand, pass libFuzzer's own limits after RUNS, e.g.
#   fuzz/run.sh build/fuzz -1 -max_total_time=3600
# (RUNS -1 means no limit on inputs), or run one fuzzer directly:
#   build/fuzz/fuzz_ply -max_total_time=3600 -timeout=10 -rss_limit_mb=2048 \
#     build/fuzz/corpus/ply build/fuzz/seeds/ply
# Each fuzzer starts from its seeds (fuzz/seeds/<fuzzer>, plus the test
# scenes' and ../shared/scenes' small files of its format, gathered into
# BUILD_DIR/seeds/<fuzzer>; the scene importers read those folders whole)
# and its corpus. New inputs libFuzzer finds go
# to BUILD_DIR/corpus/<fuzzer>; a crash, a timeout (10 s) or an input
# using more than 2 GiB (texture: 4 GiB) leaves its input in BUILD_DIR and
# fails the run.
# Two fuzzers run at a time (one per core).
set -euo pipefail
build=$1
runs=${2:-10000}
extra=("${@:3}")
root=$(cd "$(dirname "$0")/.." && pwd)
scene_folders=("$root/tests/scenes")
[ -d "$root/../shared/scenes" ] && scene_folders+=("$root/../shared/scenes")

# Copies files of the scene folders named *.EXT and under 16 KiB into
# folder DEST, each with PREFIX (a byte the harness reads first) in front.
gather() {
  local dest=$1 prefix=$2
  shift 2
  for ext in "$@"; do
    find "${scene_folders[@]}" -type f -name "*.$ext" -size -16k -print0
  done | while IFS= read -r -d '' file; do
    { printf "$prefix"; cat "$file"; } > "$dest/$(echo "$file" | md5sum | cut -c1-16)-$(basename "$file")"
  done
}

# The seed folder of each fuzzer.
seeds() {
  local fuzzer=$1 dest="$build/seeds/$1"
  rm -rf "$dest"
  mkdir -p "$dest"
  case $fuzzer in
    mitsuba | pbrt) ;;  # the scene folders themselves, see run()
    ply | obj | tokens) cp "$root/fuzz/seeds/$fuzzer/"* "$dest"; [ "$fuzzer" = tokens ] || gather "$dest" "" "$fuzzer" ;;
    serialized)
      for index in '\x00' '\x01'; do
        for file in "$root/fuzz/seeds/serialized/"*; do
          { printf "$index"; cat "$file"; } > "$dest/$(basename "$file")-$index"
        done
        gather "$dest" "$index" serialized
      done ;;
    texture)
      # The first byte picks the extension: exr, png, hdr, pfm.
      local index=0
      for ext in exr png hdr pfm; do
        for file in "$root/fuzz/seeds/texture/"*."$ext"; do
          { printf "\\x0$index"; cat "$file"; } > "$dest/$(basename "$file")"
        done
        gather "$dest" "\\x0$index" "$ext"
        index=$((index + 1))
      done ;;
    job_files) "$build/fuzz_job_files" --write-seeds="$dest" > /dev/null 2>&1 ;;
    irradiance_cache) cp "$root/fuzz/seeds/irradiance_cache/"* "$dest" ;;
  esac
  return 0
}

# Runs one fuzzer; prints one line of figures, or the log's end on failure.
run() {
  local fuzzer=$1 corpus="$build/corpus/$1" log="$build/fuzz_$1.log" start=$SECONDS
  local seed_folders=("$build/seeds/$1")
  # The scene importers read the scene folders' text as it is.
  case $fuzzer in mitsuba | pbrt) seed_folders+=("$root/tests/scenes/import" "${scene_folders[@]:1}") ;; esac
  # A bounded run uses a fixed seed, so a CI run is repeatable; runs of
  # hours (RUNS -1) draw a fresh one.
  local flags=(-runs="$runs" -rss_limit_mb=2048) asan=() seed=()
  [ "$runs" -ge 0 ] && seed=(-seed=1)
  if [ "$fuzzer" = texture ]; then
    # OpenImageIO runs at some 30 inputs a second (1/20 of the inputs in
    # the same time), and damaged PNG and EXR headers of a few hundred
    # bytes make libpng or OpenEXR take up to 1.6 GB. libpng leaves
    # OpenImageIO's reader by longjmp on a damaged PNG, past the
    # destructors of its strings: leaks in the libraries, not ours.
    flags=(-runs=$((runs < 0 ? runs : (runs + 19) / 20)) -rss_limit_mb=4096 -detect_leaks=0)
    asan=(ASAN_OPTIONS=detect_leaks=0)
  fi
  mkdir -p "$corpus"
  seeds "$fuzzer"
  if env "${asan[@]}" "$build/fuzz_$fuzzer" -max_len=16384 -timeout=10 -print_final_stats=1 \
      -artifact_prefix="$build/crash-$fuzzer-" "${flags[@]}" "${seed[@]}" "${extra[@]}" "$corpus" "${seed_folders[@]}" 2> "$log"; then
    echo "fuzz_$fuzzer: $(grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "$log" | tr '\n' ' ')($((SECONDS - start)) s)"
  else
    echo "fuzz_$fuzzer FAILED ($((SECONDS - start)) s):"
    tail -40 "$log"
    return 1
  fi
}

# Longest first (at 10 000 inputs: pbrt and mitsuba about 15 s each,
# texture 8 s, ply 7 s, the others less), each started as soon as one of
# the two slots is free.
fuzzers=(pbrt mitsuba texture ply job_files tokens irradiance_cache obj serialized)
failed=0
running=()
for fuzzer in "${fuzzers[@]}"; do
  if [ ${#running[@]} -ge 2 ]; then
    wait -n || failed=1
    still=()
    for pid in "${running[@]}"; do kill -0 "$pid" 2> /dev/null && still+=("$pid"); done
    running=("${still[@]}")
  fi
  run "$fuzzer" > "$build/run_$fuzzer.out" &
  running+=($!)
done
for pid in "${running[@]}"; do wait "$pid" || failed=1; done
for fuzzer in "${fuzzers[@]}"; do cat "$build/run_$fuzzer.out"; done
exit $failed
