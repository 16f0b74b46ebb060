// Runs Khronos' glTF-Validator (npm `gltf-validator`) on each file named, and fails where it
// reports an error. Usage: node tools/gltf_corpus/validate.mjs FILE...
// The package is the one MESHTRACE_GLTF_VALIDATOR names (its folder), else the one
// node_modules in the working directory holds.
import { readFile } from "node:fs/promises";
import { createRequire } from "node:module";
import path from "node:path";

const require = createRequire(path.join(process.cwd(), "package.json"));
const validator = require(process.env.MESHTRACE_GLTF_VALIDATOR ?? "gltf-validator");

let failed = 0;
for (const file of process.argv.slice(2)) {
  const report = await validator.validateBytes(new Uint8Array(await readFile(file)), {
    uri: path.basename(file),
    externalResourceFunction: async (uri) =>
      new Uint8Array(await readFile(path.join(path.dirname(file), decodeURIComponent(uri)))),
  });
  const { numErrors, numWarnings } = report.issues;
  console.log(`${file}: ${numErrors} errors, ${numWarnings} warnings (glTF-Validator ${report.validatorVersion})`);
  for (const m of report.issues.messages.filter((m) => m.severity === 0)) {
    console.log(`  ${m.code} at ${m.pointer}: ${m.message}`);
  }
  failed += numErrors > 0;
}
process.exit(failed ? 1 : 0);
