#!/usr/bin/env bash
# Stages what bench/device.sh needs on a GPU machine that has no Rust toolchain, no
# network and maybe no Vulkan loader, into the ignored folder bench/device-kit/ (run it
# here, in the repository root or anywhere, before the device call that carries it):
#
#   meshtrace.xz          target/release/meshtrace, copied (others rebuild it) and xz'ed
#   libvulkan1_*.deb      the Khronos Vulkan loader (Debian's, `apt-get download`, no root)
#   mitsuba-cp312.tar.xz  Mitsuba 3 + Dr.Jit for CPython 3.12 (the device's Python),
#                         trimmed to the variants the comparison uses (all plugins), so the
#                         kit fits the 64 MiB the device call may carry (the wheels alone
#                         are 67 MB); skipped with MITSUBA=0 or when pip cannot fetch them
#   cornell_ref.npy       tests/references/cornell_ref.exr as float32 HxWx3 (read with
#                         mitsuba.Bitmap here), so the device needs no EXR reader for it
#   MANIFEST.txt          versions, sizes and sha256 of the above
#
# Usage: bash bench/device_stage.sh        (env: MITSUBA=0 to skip Mitsuba,
#        MITSUBA_VERSION=3.9.1, BINARY=path/to/meshtrace, KIT=bench/device-kit)
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
KIT=${KIT:-$ROOT/bench/device-kit}
BINARY=${BINARY:-$ROOT/target/release/meshtrace}
MITSUBA=${MITSUBA:-1}
MITSUBA_VERSION=${MITSUBA_VERSION:-3.9.1}
LIMIT=$((64 * 1024 * 1024))

say() { printf 'device_stage: %s\n' "$*"; }
die() { say "error: $*" >&2; exit 1; }

[ -x "$BINARY" ] || die "no binary at $BINARY (cargo build --release first; this script never builds)"
mkdir -p "$KIT"
TMP=$(mktemp -d /tmp/device_stage.XXXXXX)
trap 'rm -rf "$TMP"' EXIT

# --- 1. the binary: copy first (a rebuild may replace it meanwhile), check, compress
cp "$BINARY" "$TMP/meshtrace"
"$TMP/meshtrace" --version >/dev/null || die "$BINARY does not run"
VERSION=$("$TMP/meshtrace" --version)
if ldd "$TMP/meshtrace" | grep "not found"; then die "binary has unresolved libraries"; fi
xz -T0 -6 -c "$TMP/meshtrace" >"$KIT/meshtrace.xz.tmp" && mv "$KIT/meshtrace.xz.tmp" "$KIT/meshtrace.xz"
say "binary: $VERSION, $(stat -c %s "$TMP/meshtrace") bytes -> meshtrace.xz $(stat -c %s "$KIT/meshtrace.xz") bytes"

# --- 2. the Vulkan loader .deb (amd64), without root: the system's apt lists if they
# know the package, else private lists under $TMP (as the device README does)
rm -f "$KIT"/libvulkan1_*.deb
if ! (cd "$KIT" && apt-get -q download libvulkan1:amd64 >/dev/null 2>"$TMP/apt.err"); then
    say "apt-get download with the system lists failed ($(tail -1 "$TMP/apt.err")); using private lists"
    mkdir -p "$TMP/lists/partial" "$TMP/cache/archives/partial"
    o=(-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 "-oDir::State::Lists=$TMP/lists"
       "-oDir::Cache=$TMP/cache" -oDebug::NoLocking=1)
    apt-get "${o[@]}" -q update >/dev/null
    (cd "$KIT" && apt-get "${o[@]}" -q download libvulkan1) >/dev/null
fi
DEB=$(ls "$KIT"/libvulkan1_*.deb 2>/dev/null | head -1)
[ -n "$DEB" ] || die "no libvulkan1 .deb was downloaded"
dpkg-deb -c "$DEB" >"$TMP/deb.lst"; grep -q libvulkan.so.1 "$TMP/deb.lst" || die "$DEB holds no libvulkan.so.1"
say "loader: $(basename "$DEB"), $(stat -c %s "$DEB") bytes"

# --- 3. the reference image as .npy (the device may lack an EXR reader)
python3 - "$ROOT/tests/references/cornell_ref.exr" "$KIT/cornell_ref.npy" <<'EOF' || say "warning: could not convert the reference (device.sh then needs mitsuba or cv2 to read the EXR)"
import sys
import numpy as np
import mitsuba as mi
mi.set_variant("scalar_rgb")
a = np.array(mi.Bitmap(sys.argv[1]).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False),
             dtype=np.float32)[:, :, :3]
np.save(sys.argv[2], a)
print("device_stage: reference %s -> %s %s" % (sys.argv[1], a.shape, sys.argv[2]))
EOF

# --- 4. Mitsuba 3 + Dr.Jit for the device's CPython 3.12, trimmed
# The wheels (mitsuba 62.6 MB + drjit 5.0 MB for 3.9.1) exceed the 64 MiB a device call
# may carry. Kept: the scalar_rgb (Bitmap, EXR I/O) and cuda_ad_rgb variants, the shared
# libraries they link, Python sources and every plugin (each holds all variants; scenes
# load implicit ones, e.g. `merge`); dropped: the other 14 variants, headers, stubs, and
# the spectral upsampling table and sun-sky data (unused by RGB variants).
rm -f "$KIT/mitsuba-cp312.tar.xz"
if [ "$MITSUBA" != 0 ]; then
    if python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 \
            --implementation cp --platform manylinux_2_28_x86_64 --platform manylinux_2_27_x86_64 \
            --platform manylinux_2_17_x86_64 --platform manylinux2014_x86_64 -d "$TMP/whl" \
            "mitsuba==$MITSUBA_VERSION" drjit 2>"$TMP/pip.err"; then
        # drjit's version must be the one mitsuba asks for
        want=$(unzip -p "$TMP"/whl/mitsuba-*.whl '*/METADATA' | sed -n 's/^Requires-Dist: drjit *(*==*\([0-9.]*\).*/\1/p' | head -1)
        if [ -n "$want" ] && ! ls "$TMP"/whl/drjit-"$want"-*.whl >/dev/null 2>&1; then
            rm -f "$TMP"/whl/drjit-*.whl
            python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 \
                --implementation cp --platform manylinux_2_28_x86_64 --platform manylinux_2_27_x86_64 \
                --platform manylinux_2_17_x86_64 --platform manylinux2014_x86_64 -d "$TMP/whl" "drjit==$want"
        fi
        say "wheels: $(cd "$TMP/whl" && for f in *.whl; do printf '%s (%s bytes) ' "$f" "$(stat -c %s "$f")"; done)"
        S="$TMP/site"
        mkdir -p "$S"
        for w in "$TMP"/whl/*.whl; do unzip -q -o "$w" -d "$S"; done
        M="$S/mitsuba"
        for f in "$M"/*_ad_*.cpython-*.so "$M"/scalar_*.cpython-*.so; do
            case $(basename "$f") in cuda_ad_rgb.*|scalar_rgb.*) ;; *) rm -f "$f" ;; esac
        done
        rm -rf "$M/include" "$M/cmake" "$M/pkgconfig" "$M/mitsuba_stubs" "$M/python/test" \
               "$M/data/srgb.coeff" "$M/data/sunsky" "$M/libIlmImfUtil-mitsuba.so" \
               "$S/drjit/include" "$S/drjit/cmake"
        find "$S" \( -name '*.pyi' -o -name '__pycache__' \) -prune -exec rm -rf {} +
        tar -C "$S" -cf - . | xz -T0 -9e >"$KIT/mitsuba-cp312.tar.xz"
        say "mitsuba: trimmed to $(du -sb "$S" | cut -f1) bytes -> mitsuba-cp312.tar.xz $(stat -c %s "$KIT/mitsuba-cp312.tar.xz") bytes"
    else
        say "warning: pip could not fetch mitsuba==$MITSUBA_VERSION/drjit ($(tail -1 "$TMP/pip.err")); the Mitsuba comparison will be skipped"
    fi
else
    say "MITSUBA=0: no Mitsuba in the kit; the comparison will be skipped"
fi

# --- 5. manifest and sizes
{
    echo "staged $(date -u +%Y-%m-%dT%H:%M:%SZ) on $(uname -m) from $(cd "$ROOT" && git rev-parse --short HEAD 2>/dev/null)$(cd "$ROOT" && git diff --quiet HEAD -- src shaders 2>/dev/null || echo '+dirty')"
    echo "binary $VERSION"
    (cd "$KIT" && sha256sum -- * | grep -v MANIFEST)
} >"$KIT/MANIFEST.txt"
KIT_BYTES=$(du -sb "$KIT" | cut -f1)
TREE_BYTES=$(cd "$ROOT" && git ls-files -co --exclude-standard -z | xargs -0 du -cb 2>/dev/null | tail -1 | cut -f1)
say "kit: $KIT ($KIT_BYTES bytes, $((KIT_BYTES / 1048576)) MiB); tree without it: $TREE_BYTES bytes; together $(((KIT_BYTES + TREE_BYTES) / 1048576)) MiB of the 64 MiB a device call carries"
[ $((KIT_BYTES + TREE_BYTES)) -lt $LIMIT ] || die "kit + tree exceed 64 MiB: stage with MITSUBA=0"
ls -l "$KIT"
