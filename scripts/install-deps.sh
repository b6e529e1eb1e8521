#!/usr/bin/env bash
# Installs the system packages galerkin needs, only those that are missing:
#   Mesa lavapipe (Vulkan on the CPU; Mesa 25 from bookworm-backports on Debian 12),
#   the Vulkan loader, the Khronos validation layer, glslc, spirv-tools, Xvfb, and the X11
#   client libraries the viewer's window (winit) loads at run time.
# With --mpi, also what the `mpi` cargo feature needs: OpenMPI (libopenmpi-dev, openmpi-bin:
#   mpirun) and libclang-dev (the mpi crate generates its bindings with bindgen).
# With --shaderc, what the `runtime-shaderc` feature links: the system's shaderc, glslang and
#   SPIRV-Tools static archives (libshaderc-dev, glslang-dev, spirv-tools).
# Idempotent and quick when everything is present. No mirror host name is written here:
# on Debian 12 the bookworm-backports entry is derived from the machine's own apt sources.
set -euo pipefail

ICD=/usr/share/vulkan/icd.d/lvp_icd.json
need=()
with_mpi=0
with_shaderc=0
for arg in "$@"; do
    case "$arg" in
        --mpi) with_mpi=1 ;;
        --shaderc) with_shaderc=1 ;;
        -h|--help) sed -n '2,12p' "$0"; exit 0 ;;
        *) echo "install-deps: unknown option '$arg' (options: --mpi, --shaderc)" >&2; exit 2 ;;
    esac
done

have_pkg() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q 'install ok installed'; }

mesa_major() {
    dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null | sed -E 's/^([0-9]+:)?([0-9]+)\..*/\2/'
}

is_bookworm() { [ -r /etc/os-release ] && grep -q '^VERSION_CODENAME=bookworm' /etc/os-release; }

if ! command -v apt-get >/dev/null 2>&1; then
    [ "$with_mpi" = 0 ] || command -v mpirun >/dev/null || { echo "install-deps: 'mpirun' is missing and this is not a Debian-like system; install OpenMPI and libclang by hand" >&2; exit 1; }
    for c in glslc spirv-val Xvfb; do
        command -v "$c" >/dev/null || { echo "install-deps: '$c' is missing and this is not a Debian-like system; install it by hand (packages: glslc, spirv-tools, xvfb, mesa-vulkan-drivers, libvulkan1, vulkan-validationlayers)" >&2; exit 1; }
    done
    exit 0
fi

for p in libvulkan1 vulkan-validationlayers glslc spirv-tools xvfb \
         libx11-xcb1 libxcursor1 libxrandr2 libxi6 libxkbcommon-x11-0; do
    have_pkg "$p" || need+=("$p")
done
if [ "$with_mpi" = 1 ]; then
    for p in libopenmpi-dev openmpi-bin libclang-dev; do
        have_pkg "$p" || need+=("$p")
    done
fi
if [ "$with_shaderc" = 1 ]; then
    for p in libshaderc-dev glslang-dev spirv-tools; do
        have_pkg "$p" || need+=("$p")
    done
fi
mesa_ok=1
if ! have_pkg mesa-vulkan-drivers || [ ! -f "$ICD" ]; then mesa_ok=0; fi
if [ "$mesa_ok" = 1 ] && is_bookworm && [ "$(mesa_major)" -lt 25 ]; then mesa_ok=0; fi

if [ ${#need[@]} -eq 0 ] && [ "$mesa_ok" = 1 ]; then
    exit 0
fi

SUDO=""
if [ "$(id -u)" != 0 ]; then
    command -v sudo >/dev/null || { echo "install-deps: not root and no sudo; install as root: ${need[*]} mesa-vulkan-drivers" >&2; exit 1; }
    SUDO=sudo
fi

# bookworm-backports: copy URIs, components and keyring of the machine's own main Debian entry.
add_backports() {
    if grep -rqs 'bookworm-backports' /etc/apt/sources.list /etc/apt/sources.list.d/*.sources /etc/apt/sources.list.d/*.list 2>/dev/null; then
        return 0
    fi
    local uris="" signed="" f
    for f in /etc/apt/sources.list.d/*.sources; do
        [ -f "$f" ] || continue
        # deb822 stanzas: the first one whose Suites contain plain "bookworm"
        read -r uris signed < <(awk '
            BEGIN { RS=""; FS="\n" }
            {
                u=""; s=""; k=""; t="";
                for (i = 1; i <= NF; i++) {
                    if ($i ~ /^URIs:/)      { u=$i; sub(/^URIs:[ \t]*/, "", u) }
                    if ($i ~ /^Suites:/)    { s=" " $i " "; sub(/^ Suites:/, " ", s) }
                    if ($i ~ /^Signed-By:/) { k=$i; sub(/^Signed-By:[ \t]*/, "", k) }
                    if ($i ~ /^Types:/)     { t=$i }
                }
                if (t ~ /deb( |$)/ && s ~ /[ \t]bookworm[ \t]/) { print u, (k == "" ? "-" : k); exit }
            }' "$f") || true
        [ -n "$uris" ] && break
    done
    if [ -z "$uris" ] && [ -f /etc/apt/sources.list ]; then
        # one-line form: deb [options] URI bookworm components...
        local line
        line=$(grep -E '^[[:space:]]*deb[[:space:]]' /etc/apt/sources.list | grep -E '[[:space:]]bookworm[[:space:]]' | head -n1 || true)
        if [ -n "$line" ]; then
            signed=$(sed -nE 's/.*signed-by=([^] ]+).*/\1/p' <<<"$line")
            uris=$(sed -E 's/^[[:space:]]*deb[[:space:]]+(\[[^]]*\][[:space:]]+)?//' <<<"$line" | awk '{print $1}')
            [ -n "$signed" ] || signed="-"
        fi
    fi
    if [ -z "$uris" ]; then
        echo "install-deps: found no Debian 'bookworm' entry in apt's sources to derive bookworm-backports from" >&2
        exit 1
    fi
    {
        echo "Types: deb"
        echo "URIs: $uris"
        echo "Suites: bookworm-backports"
        echo "Components: main"
        [ "$signed" != "-" ] && echo "Signed-By: $signed"
    } | $SUDO tee /etc/apt/sources.list.d/galerkin-bookworm-backports.sources >/dev/null
    echo "install-deps: added bookworm-backports (derived from the machine's own Debian entry)"
}

export DEBIAN_FRONTEND=noninteractive
mesa_target=()
if [ "$mesa_ok" = 0 ] && is_bookworm; then
    add_backports
    mesa_target=(-t bookworm-backports)
fi
echo "install-deps: installing ${need[*]} $([ "$mesa_ok" = 0 ] && echo mesa-vulkan-drivers)"
$SUDO apt-get update -qq
if [ "$mesa_ok" = 0 ]; then
    $SUDO apt-get install -y -qq --no-install-recommends "${mesa_target[@]}" mesa-vulkan-drivers
fi
if [ ${#need[@]} -gt 0 ]; then
    $SUDO apt-get install -y -qq --no-install-recommends "${need[@]}"
fi
[ -f "$ICD" ] || { echo "install-deps: $ICD is still missing after installing mesa-vulkan-drivers" >&2; exit 1; }
echo "install-deps: done (mesa-vulkan-drivers $(dpkg-query -W -f='${Version}' mesa-vulkan-drivers))"
