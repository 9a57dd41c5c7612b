// node validate.mjs NODE_MODULES FILE...: runs the Khronos glTF-Validator on
// each file and prints one JSON line per file with its issue counts and
// messages. Exits 1 if any file has an error or a warning.
import { readFile } from 'node:fs/promises';
import { createRequire } from 'node:module';
import path from 'node:path';

const [modules, ...files] = process.argv.slice(2);
const require = createRequire(path.join(path.resolve(modules), 'index.js'));
const validator = require('gltf-validator');

let failed = false;
for (const file of files) {
  const bytes = new Uint8Array(await readFile(file));
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 50,
    externalResourceFunction: (uri) => Promise.reject(new Error(`external resource ${uri} not expected`)),
  });
  const { numErrors, numWarnings, numInfos, numHints, messages } = report.issues;
  failed ||= numErrors > 0 || numWarnings > 0;
  console.log(JSON.stringify({ file, numErrors, numWarnings, numInfos, numHints,
    messages: messages.map((m) => `${m.severity} ${m.code} ${m.pointer ?? ''}: ${m.message}`) }));
}
process.exit(failed ? 1 : 0);
