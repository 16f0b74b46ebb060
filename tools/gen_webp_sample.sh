#!/bin/sh
# Regenerates tests/data/gltf/BoxTexturedWebp/BoxTexturedWebp.glb: Khronos's BoxTextured with
# its PNG texture re-encoded as WebP by glTF-Transform (EXT_texture_webp, no PNG fallback),
# a third-party writer for tests/gltf_samples.rs. Needs Node.js; GLTF_TRANSFORM may name an
# installed `gltf-transform` (the committed file was made by @gltf-transform/cli 4.5.1),
# else npx fetches that version from the npm registry.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
out="$root/tests/data/gltf/BoxTexturedWebp/BoxTexturedWebp.glb"
mkdir -p "$(dirname "$out")"
if [ -n "${GLTF_TRANSFORM:-}" ]; then
    "$GLTF_TRANSFORM" webp "$root/tests/data/gltf/BoxTextured/BoxTextured.glb" "$out"
else
    npx --yes @gltf-transform/cli@4.5.1 webp "$root/tests/data/gltf/BoxTextured/BoxTextured.glb" "$out"
fi
