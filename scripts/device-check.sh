#!/usr/bin/env bash
# The device check for a machine with a real GPU and nothing else: no Rust toolchain, no
# network, a small folder carried in. Two halves:
#
#   scripts/device-check.sh --pack DIR [--reference]
#       here: DIR gets the stripped release binary, the scenes, the Vulkan loader and the
#       Khronos validation layer as amd64 .deb files (apt-get download, so apt must reach its
#       sources) and this script; refused past 60 MiB. --reference also runs the same checks
#       here first (on this machine's device, lavapipe) so that the report sets the two side
#       by side (a few minutes). GALERKIN_BIN names a built binary to pack instead of
#       building one.
#
#   DIR/device-check.sh --run DIR [--short]
#       there: unpacks the .debs into DIR/root, finds the NVIDIA ICD when VK_DRIVER_FILES is
#       unset, and runs from DIR with the validation layer on: `galerkin demo` (every
#       capability checked against its CPU f64 reference; fails on any validation message)
#       and `galerkin bench all --quick`; writes DIR/out/device-check.md (device, driver, the
#       benchmark tables, and the reference's beside them when packed with --reference).
#       --short runs the demo alone (about a minute on lavapipe; what CI runs). Under 8
#       minutes on lavapipe's two cores; a discrete GPU takes less.
#
# Nothing here depends on lavapipe's limits: the binary reads the device's own (binding
# sizes, subgroup size, shared memory, memory types by property).
set -euo pipefail

usage() { sed -n '2,25p' "$0" | sed 's/^# \{0,1\}//'; }
die() { echo "device-check: $*" >&2; exit 2; }

MAX_PACK_BYTES=$((60 * 1024 * 1024))
PACKAGES="libvulkan1 vulkan-validationlayers"

pack() {
    local dir=$1 reference=$2
    local repo
    repo=$(cd "$(dirname "$0")/.." && pwd)
    mkdir -p "$dir"
    dir=$(cd "$dir" && pwd)
    [ -z "$(ls -A "$dir")" ] || die "$dir is not empty: pack into a new folder"
    command -v apt-get >/dev/null || die "--pack needs apt-get (Debian or Ubuntu) to download the Vulkan packages"
    local bin=${GALERKIN_BIN:-}
    if [ -z "$bin" ]; then
        (cd "$repo" && cargo build --release --bin galerkin --quiet)
        bin=${CARGO_TARGET_DIR:-$repo/target}/release/galerkin
    fi
    strip -o "$dir/galerkin" "$bin"
    cp -r "$repo/scenes" "$dir/scenes"
    cp "$repo/scripts/device-check.sh" "$dir/device-check.sh"
    mkdir -p "$dir/debs"
    # apt-get download writes into the working directory; amd64 whatever this machine is.
    (cd "$dir/debs" && for p in $PACKAGES; do apt-get download -q "$p:amd64" >/dev/null; done)
    local bytes
    bytes=$(du -sb "$dir" | cut -f1)
    [ "$bytes" -le "$MAX_PACK_BYTES" ] || die "$dir holds $bytes bytes, over the 60 MiB that may be carried in"
    if [ "$reference" = 1 ]; then
        echo "device-check: the reference run here (this machine's device)"
        run "$dir" 0 reference
    fi
    echo "device-check: packed $dir ($((bytes / 1024)) KiB): $(ls "$dir/debs" | tr '\n' ' ')"
}

# `run DIR SHORT NAME`: the checks from DIR, their output in DIR/out/NAME/.
run() {
    local dir=$1 short=$2 name=$3
    dir=$(cd "$dir" && pwd)
    [ -x "$dir/galerkin" ] || die "$dir/galerkin is missing: make the folder with --pack"
    local root=$dir/root
    if [ ! -d "$root" ]; then
        mkdir -p "$root"
        for deb in "$dir"/debs/*.deb; do
            [ -e "$deb" ] || die "no .deb files in $dir/debs"
            dpkg-deb -x "$deb" "$root"
        done
    fi
    local libs
    libs=$(find "$root" -name 'libvulkan.so.1' -printf '%h\n' | head -n 1)
    [ -n "$libs" ] || die "the loader (libvulkan.so.1) is not in $dir/debs"
    local layers
    layers=$(find "$root" -name 'VkLayer_khronos_validation.json' -printf '%h\n' | head -n 1)
    [ -n "$layers" ] || die "the validation layer is not in $dir/debs"
    export LD_LIBRARY_PATH="$libs${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
    export VK_LAYER_PATH="$layers"
    export GALERKIN_VULKAN_LIBRARY="$libs/libvulkan.so.1"
    if [ -z "${VK_DRIVER_FILES:-}" ] && [ -z "${VK_ICD_FILENAMES:-}" ]; then
        local icd
        for icd in /usr/share/vulkan/icd.d/nvidia_icd.json /etc/vulkan/icd.d/nvidia_icd.json \
                   /usr/share/vulkan/icd.d/nvidia_icd.x86_64.json; do
            if [ -f "$icd" ]; then
                export VK_DRIVER_FILES="$icd"
                break
            fi
        done
    fi
    export GALERKIN_VALIDATION=1
    local out=$dir/out/$name
    mkdir -p "$out"
    cd "$dir"
    local start=$SECONDS
    ./galerkin --version > "$out/version.txt"
    ./galerkin info > "$out/info.txt" 2> "$out/info.log" || die "no usable Vulkan device: $out/info.log"
    ./galerkin bench gpu --quick > "$out/bench-gpu-quick.md" 2> "$out/bench-gpu-quick.log" \
        || die "bench gpu --quick failed: $out/bench-gpu-quick.log"
    ./galerkin demo --out "$out/demo" > "$out/demo.txt" 2> "$out/demo.log" \
        || die "the demo failed (a capability differed from its reference, or validation spoke): $out/demo.log"
    if [ "$short" = 0 ]; then
        ./galerkin bench all --quick --out "$out/benchmarks.md" > "$out/bench-all.txt" 2> "$out/bench-all.log" \
            || die "bench all --quick failed: $out/bench-all.log"
    fi
    local seconds=$((SECONDS - start))
    report "$dir" "$name" "$seconds" > "$out/device-check.md"
    echo "device-check: $name passed in $seconds s: $out/device-check.md"
}

# The report: device and driver, what passed, the tables (and the reference's, if packed).
report() {
    local dir=$1 name=$2 seconds=$3
    local out=$dir/out/$name
    echo "# Device check: $(head -n 1 "$out/version.txt")"
    echo
    echo '```'
    sed -n '1,3p' "$out/info.txt"
    echo '```'
    echo "Validation layer on; the demo checked every capability against its CPU f64 reference (\`$out/demo.txt\`); $seconds s in all."
    echo
    echo "## The device's ceilings (\`galerkin bench gpu --quick\`)"
    echo
    cat "$out/bench-gpu-quick.md"
    if [ -f "$out/benchmarks.md" ]; then
        echo
        echo "## Every benchmark (\`galerkin bench all --quick\`)"
        echo
        cat "$out/benchmarks.md"
    fi
    if [ "$name" != reference ] && [ -f "$dir/out/reference/device-check.md" ]; then
        echo
        echo "## The same checks where the folder was packed"
        echo
        sed 's/^#/##/' "$dir/out/reference/device-check.md"
    fi
}

mode=${1:-}
case "$mode" in
    --pack)
        [ $# -ge 2 ] || die "--pack needs a folder"
        reference=0
        [ "${3:-}" = --reference ] && reference=1
        pack "$2" "$reference"
        ;;
    --run)
        [ $# -ge 2 ] || die "--run needs the packed folder"
        short=0
        [ "${3:-}" = --short ] && short=1
        run "$2" "$short" device
        ;;
    -h|--help) usage ;;
    *) usage >&2; exit 2 ;;
esac
