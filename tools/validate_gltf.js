// Validates .glb files with the Khronos glTF Validator (npm package gltf-validator).
// Usage: NODE_PATH=DIR/node_modules node tools/validate_gltf.js FILE.glb...
// Prints every issue; exits 1 if any file has an error.
const fs = require('fs');
const validator = require('gltf-validator');
(async () => {
  let failed = 0;
  for (const file of process.argv.slice(2)) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)));
    const i = report.issues;
    console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos, ${i.numHints} hints`);
    for (const m of i.messages) console.log(`  ${m.severity} ${m.code} ${m.pointer || ''} ${m.message}`);
    if (i.numErrors > 0) failed++;
  }
  process.exit(failed ? 1 : 0);
})();
