// Writes corpus/spec_gloss.glb from Blender's corpus/materials.glb with glTF-Transform: its
// two bare spheres ("red", "blue") given KHR_materials_pbrSpecularGlossiness equivalents of
// their metallic-roughness materials (which stay, as the fallback such files keep): the
// base colour as diffuseFactor, glossinessFactor 1 − roughness, and F0 0.04 (glTF's IOR
// 1.5) carried by a 1 × 1 specularGlossinessTexture (RGB the sRGB byte 56, alpha 255) over
// a white specularFactor. tests/gltf_corpus.rs renders it against materials.glb.
//
//   NODE_PATH=/path/to/node_modules node tools/gltf_corpus/spec_gloss.cjs CORPUS_DIR
"use strict";
const { NodeIO } = require("@gltf-transform/core");
const {
  ALL_EXTENSIONS,
  KHRMaterialsPBRSpecularGlossiness,
} = require("@gltf-transform/extensions");
const path = require("node:path");
const zlib = require("node:zlib");

/// A PNG of one RGBA8 texel.
function png([r, g, b, a]) {
  const crcTable = Array.from({ length: 256 }, (_, n) => {
    let c = n;
    for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
    return c >>> 0;
  });
  const crc = (bytes) => {
    let c = 0xffffffff;
    for (const x of bytes) c = crcTable[(c ^ x) & 255] ^ (c >>> 8);
    return (c ^ 0xffffffff) >>> 0;
  };
  const chunk = (type, data) => {
    const out = Buffer.alloc(12 + data.length);
    out.writeUInt32BE(data.length, 0);
    out.write(type, 4, "ascii");
    data.copy(out, 8);
    out.writeUInt32BE(crc(out.subarray(4, 8 + data.length)), 8 + data.length);
    return out;
  };
  const header = Buffer.alloc(13);
  header.writeUInt32BE(1, 0);
  header.writeUInt32BE(1, 4);
  header.set([8, 6, 0, 0, 0], 8);
  const pixels = zlib.deflateSync(Buffer.from([0, r, g, b, a]));
  return Buffer.concat([
    Buffer.from([137, 80, 78, 71, 13, 10, 26, 10]),
    chunk("IHDR", header),
    chunk("IDAT", pixels),
    chunk("IEND", Buffer.alloc(0)),
  ]);
}

async function main() {
  const dir = process.argv[2];
  if (!dir) throw new Error("usage: spec_gloss.cjs CORPUS_DIR");
  const io = new NodeIO().registerExtensions(ALL_EXTENSIONS);
  const doc = await io.read(path.join(dir, "materials.glb"));
  const ext = doc.createExtension(KHRMaterialsPBRSpecularGlossiness);
  const texture = doc
    .createTexture("specular 0.04, glossy")
    .setImage(png([56, 56, 56, 255]))
    .setMimeType("image/png");
  for (const material of doc.getRoot().listMaterials()) {
    if (!["red", "blue"].includes(material.getName())) continue;
    const sg = ext
      .createPBRSpecularGlossiness()
      .setDiffuseFactor(material.getBaseColorFactor())
      .setSpecularFactor([1, 1, 1])
      .setGlossinessFactor(1 - material.getRoughnessFactor())
      .setSpecularGlossinessTexture(texture);
    material.setExtension("KHR_materials_pbrSpecularGlossiness", sg);
  }
  await io.write(path.join(dir, "spec_gloss.glb"), doc);
}

main().catch((e) => {
  console.error(e);
  process.exit(1);
});
