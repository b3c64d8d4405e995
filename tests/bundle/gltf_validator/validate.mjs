// Validates glTF files with the Khronos validator and prints one JSON line per file:
// {"file", "errors", "warnings", "messages": [first errors]}. Exits 1 when any file has an error.
import { readFile } from "node:fs/promises";
import { createRequire } from "node:module";
import path from "node:path";

const require = createRequire(import.meta.url);
const validator = require("gltf-validator");

let failed = false;
for (const file of process.argv.slice(2)) {
  const data = new Uint8Array(await readFile(file));
  const folder = path.dirname(file);
  const report = await validator.validateBytes(data, {
    uri: path.basename(file),
    // Bundles reference no external resources; anything asked for is read from the file's folder.
    externalResourceFunction: (uri) => readFile(path.join(folder, decodeURIComponent(uri))).then((b) => new Uint8Array(b)),
  });
  const errors = report.issues.numErrors;
  failed = failed || errors > 0;
  const messages = report.issues.messages.filter((m) => m.severity === 0).slice(0, 5).map((m) => `${m.code} ${m.pointer ?? ""}: ${m.message}`);
  console.log(JSON.stringify({ file, errors, warnings: report.issues.numWarnings, messages }));
}
process.exit(failed ? 1 : 0);
