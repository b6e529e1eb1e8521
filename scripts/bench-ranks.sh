#!/usr/bin/env bash
# Strong scaling of the precompute over MPI ranks on this machine (BENCHMARKS.md, "Training
# over ranks"): the radiosity training of the 496-face scene with the default model (exact
# near field, operator correction; RANKS_SCENE to choose another) and the cavity's fluid
# training (Table 1's basis sizes on four short cavity runs) at 1, 2 and 4 ranks, against one
# process without MPI. Every rank runs one rayon thread (RAYON_NUM_THREADS=1), so 2 ranks use
# the machine's two cores and 4 are oversubscribed; the process without MPI uses both cores
# through rayon. About 25 minutes on 2 cores.
#
#   scripts/bench-ranks.sh            # writes out/bench-ranks/*.log and prints the tables
#
# Needs a build with the `mpi` feature (`cargo build --release --features mpi`; this script
# builds it) and OpenMPI (`scripts/install-deps.sh --mpi`).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${OUT:-out/bench-ranks}
RANKS=${RANKS:-"1 2 4"}
mkdir -p "$OUT"
cargo build --release --features mpi --quiet
BIN=${CARGO_TARGET_DIR:-target}/release/galerkin
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export GALERKIN_LOG=galerkin=info

# `timed NAME CMD…`: runs CMD, its log in $OUT/NAME.log, wall seconds and the largest resident
# set of the process tree (GNU time's %M, kB) on the log's last line. A finished log is kept
# (FORCE=1 runs it again).
timed() {
    local name=$1
    shift
    if [ "${FORCE:-0}" = 1 ] || ! tail -n 1 "$OUT/$name.log" 2>/dev/null | grep -q '^wall'; then
        /usr/bin/time -f "wall %e s, peak %M kB" "$@" >"$OUT/$name.out" 2>"$OUT/$name.log"
    fi
    tail -n 1 "$OUT/$name.log"
}

mpi=(mpirun --oversubscribe --mca btl_vader_single_copy_mechanism none -x RAYON_NUM_THREADS=1 -x GALERKIN_LOG)

scene=${RANKS_SCENE:-scenes/radiosity/two_rooms_small.toml}
echo "radiosity train $scene (540 samples)"
printf '  %-22s ' "one process, 2 threads"
timed radiosity-alone "$BIN" radiosity train "$scene" --out "$OUT/radiosity-alone"
for n in $RANKS; do
    printf '  %-22s ' "$n ranks"
    timed "radiosity-$n" "${mpi[@]}" -n "$n" "$BIN" radiosity train "$scene" --out "$OUT/radiosity-$n"
done

# Four cavity training runs of 33 frames (132 snapshots: enough for Table 1's m_u = 128).
runs=()
for r in 0 1 2 3; do
    dir="$OUT/cavity-run-$r"
    runs+=("$dir")
    [ -f "$dir/snapshots.json" ] || "$BIN" fluid simulate scenes/fluid/cavity.toml --run "$r" --frames 33 --out "$dir" --force >/dev/null
done
sizes=(--m-f 64 --m-u 128 --m-g 5)
echo "fluid train: the cavity, 4 runs × 33 frames, m_f 64, m_u 128, m_g 5"
printf '  %-22s ' "one process, 2 threads"
timed fluid-alone "$BIN" fluid train "${runs[@]}" "${sizes[@]}" --out "$OUT/fluid-alone.safetensors"
for n in $RANKS; do
    printf '  %-22s ' "$n ranks"
    timed "fluid-$n" "${mpi[@]}" -n "$n" "$BIN" fluid train "${runs[@]}" "${sizes[@]}" --out "$OUT/fluid-$n.safetensors"
done
echo "stage logs (seconds, megabytes sent by rank 0): $OUT/*.log"
