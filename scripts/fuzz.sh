#!/bin/bash
# make fuzz: runs every loader's fuzz target (fuzz/fuzz_targets: VTU and .pvd, .gst, MFEM,
# Gmsh, OBJ sequences and OBJ scenes, scene TOML, reduced models, snapshot directories, the
# command line's value parsers) under libFuzzer and AddressSanitizer, FUZZ_SECONDS each
# (default 600) or until FUZZ_RUNS executions (when set; whichever comes first), FUZZ_JOBS at a
# time (default 2; a pool: the next target starts as soon as any one ends, so list the slow
# targets first). Needs the nightly toolchain and cargo-fuzz
# (`cargo install cargo-fuzz`). Not part of `make test`.
#
# Corpora start from valid files: the VTK and MFEM fixtures under tests/data, and files the
# engine writes itself (a spacetime mesh, a fluid run, its reduced model); they grow under
# fuzz/corpus. A crash, timeout or out-of-memory leaves its input under fuzz/artifacts/TARGET
# and the target's log under fuzz/logs names it; each finding becomes a regression test in
# the ordinary suite (tests/fuzz_findings.rs).
set -eu
cd "$(dirname "$0")/.."
SECONDS_EACH=${FUZZ_SECONDS:-600}
RUNS=${FUZZ_RUNS:-}
JOBS=${FUZZ_JOBS:-2}
ALL="vtu reduced_model scene_toml snapshots obj mfem gst gmsh cli_values"  # slowest first
TARGETS=${FUZZ_TARGETS:-$ALL}
SEP='
--8<--
'
command -v cargo-fuzz >/dev/null || { echo "fuzz: cargo-fuzz is not installed (cargo install cargo-fuzz)" >&2; exit 1; }
rustup run nightly rustc --version >/dev/null 2>&1 || { echo "fuzz: no nightly toolchain (rustup toolchain list)" >&2; exit 1; }

# The engine writes some of the seeds: GALERKIN_BIN names a built binary to use, else it is
# built here.
if [ -n "${GALERKIN_BIN:-}" ]; then
    G=$GALERKIN_BIN
else
    TARGET_DIR=${CARGO_TARGET_DIR:-target}
    cargo build --release --bin galerkin
    G="$TARGET_DIR/release/galerkin"
fi
C=fuzz/corpus
mkdir -p fuzz/logs
for t in $ALL; do mkdir -p "$C/$t"; done
seeds=$(mktemp -d)
trap 'rm -rf "$seeds"' EXIT

# VTU (+ a .pvd after the separator).
cp tests/data/vtk/*.vtu "$C/vtu/"
"$G" spectral gen --generate grid --order 2 --out "$C/vtu/spectral_grid.vtu" >/dev/null
"$G" spacetime gen --generate pulses --elements 300 --out "$C/vtu/spacetime_pulses.vtu" >/dev/null
{ cat tests/data/vtk/quad_series_0.vtu; printf '%s' "$SEP"; cat tests/data/vtk/quad_series.pvd; } > "$C/vtu/with_pvd"
# .gst
"$G" spacetime gen --generate pulses --elements 300 --out "$C/gst/pulses.gst" >/dev/null
"$G" spacetime gen --generate crack --elements 300 --out "$C/gst/crack.gst" >/dev/null
# MFEM: mesh, separator, GridFunction.
for m in tests/data/mfem/*.mesh; do
    { cat "$m"; printf '%s' "$SEP"; cat "${m%.mesh}.gf"; } > "$C/mfem/$(basename "${m%.mesh}")"
done
# Gmsh 4.1: two triangles, and one tetrahedron.
printf '$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4 1 4\n2 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n$EndNodes\n$Elements\n1 2 1 2\n2 1 2 2\n1 1 2 3\n2 1 3 4\n$EndElements\n' > "$C/gmsh/triangles.msh"
printf '$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n$EndElements\n' > "$C/gmsh/tetrahedron.msh"
# OBJ: a closed box in two frames, then a radiosity scene naming them (a.obj, b.obj).
box() {
    printf 'o floor\nv 0 0 0\nv %s 0 0\nv %s 1 0\nv 0 1 0\nf 1 3 2\nf 1 4 3\n' "$1" "$1" "$1"
    printf 'o walls\nv 0 0 1\nv %s 0 1\nv %s 1 1\nv 0 1 1\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\n' "$1" "$1"
    printf 'o window\nf 4 1 5\nf 4 5 8\n'
}
{ box 1; printf '%s' "$SEP"; box 2; printf '%s' "$SEP"; printf 'base = "a.obj"\n[[targets]]\nname = "width"\nfile = "b.obj"\nrange = [0.0, 1.0]\ndefault = 0.0\n[materials]\ndefault = [0.7, 0.7, 0.7]\n[openings]\nwindows = ["window"]\nskylights = []\n'; } > "$C/obj/box"
# Scene TOML: every kind of scene at its coarsest (fuzz/seeds; a valid scene builds its mesh on
# every run, so seeds of scenes/ size would make nearly every execution a mesh build).
cp scenes/demo.toml fuzz/seeds/*.toml "$C/scene_toml/"
# A fluid run and its reduced model: snapshots (header, mesh, frames) and model (+ visibility),
# on the 45-cell tunnel; a radiosity model of the 134-face rooms (model, then visibility).
"$G" fluid simulate fuzz/seeds/tunnel_tiny.toml --frames 2 --out "$seeds/sim" >/dev/null
"$G" fluid train "$seeds/sim" --m-f 2 --m-u 2 --out "$seeds/model.safetensors" >/dev/null
{ cat "$seeds/sim/snapshots.json"; printf '%s' "$SEP"; cat "$seeds/sim/mesh.json"; printf '%s' "$SEP"; cat "$seeds/sim/p.f64"; } > "$C/snapshots/tunnel_tiny"
cp "$seeds/model.safetensors" "$C/reduced_model/fluid"
"$G" radiosity train fuzz/seeds/rooms_tiny.toml --samples 12 --cap 2 --out "$seeds/rooms" >/dev/null
{ cat "$seeds/rooms/model.safetensors"; printf '%s' "$SEP"; cat "$seeds/rooms/visibility.safetensors"; } > "$C/reduced_model/radiosity"
# The command line's values (and --expr expressions).
for v in 1920x1080 0.5,2 -1e-3,1e300 100000 out.png 1@3,3@20 "0:0.5,1:0.2" crack inclusions \
         "length(grad(u))" "u * pressure - field(\"a b\") / 2" "clamp(sqrt(abs(u)), 0, 1e-3) + t" \
         "dot(grad(speed), v) + eps_xx * U"; do
    printf '%s' "$v" > "$C/cli_values/$(printf '%s' "$v" | tr -c 'a-zA-Z0-9' '_')"
done

cd fuzz
cargo +nightly fuzz build -O --debug-assertions
run() {
    # -rss_limit_mb: an input that makes a loader allocate 2 GiB is a finding (the limits module
    # caps what a file can ask for); -timeout: 20 s for one input is a finding (fluid scenes
    # build their meshes within the harness's budget of 20,000 cells: about a second under
    # AddressSanitizer).
    cargo +nightly fuzz run -O --debug-assertions "$1" "corpus/$1" -- \
        -max_total_time="$SECONDS_EACH" ${RUNS:+-runs=$RUNS} -rss_limit_mb=2048 -timeout=20 -max_len=262144 \
        -print_final_stats=1 > "logs/$1.log" 2>&1 || echo "fuzz: $1 stopped with a finding: see fuzz/logs/$1.log" >&2
    runs=$(grep -o 'Done [0-9]* runs in [0-9]* second' "logs/$1.log" | tail -1)
    echo "fuzz: $1: ${runs:-no summary (see fuzz/logs/$1.log)}"
}
running=0
for t in $TARGETS; do
    if [ "$running" -ge "$JOBS" ]; then
        wait -n || true
        running=$((running - 1))
    fi
    run "$t" &
    running=$((running + 1))
done
wait
# crash-*, timeout-*, oom-*, leak-* are findings; slow-unit-* are valid inputs that took over
# 10 s under AddressSanitizer (e.g. a scene asking for a large mesh within the limits): a
# report, not a failure.
ls artifacts/*/* 2>/dev/null | grep -v '/slow-unit-' && echo "fuzz: findings above (fuzz/artifacts)" || echo "fuzz: no findings"
ls artifacts/*/slow-unit-* 2>/dev/null | sed 's/^/fuzz: slow (not a finding): /' || true
