// Validates glTF / GLB files with the Khronos glTF validator.
// Usage: node validate.js FILE... ; prints one summary line per file (and every error and
// warning message); exit 0 when no file has an error, 1 when one has, 2 on usage or i/o errors.
'use strict';
const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

async function main(files) {
  if (files.length === 0) {
    console.error('usage: validate.js FILE.glb|FILE.gltf ...');
    return 2;
  }
  let failed = 0;
  for (const file of files) {
    let data;
    try {
      data = new Uint8Array(fs.readFileSync(file));
    } catch (e) {
      console.error(`${file}: cannot read: ${e.message}`);
      return 2;
    }
    const dir = path.dirname(file);
    const report = await validator.validateBytes(data, {
      uri: path.basename(file),
      maxIssues: 100,
      externalResourceFunction: (uri) =>
        new Promise((resolve, reject) => {
          fs.readFile(path.join(dir, decodeURIComponent(uri)), (err, d) => (err ? reject(err.toString()) : resolve(new Uint8Array(d))));
        }),
    });
    const i = report.issues;
    console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos, ${i.numHints} hints`);
    for (const m of i.messages) {
      if (m.severity <= 1) console.log(`  ${m.severity === 0 ? 'error' : 'warning'} ${m.code} at ${m.pointer || '/'}: ${m.message}`);
    }
    if (i.numErrors > 0) failed += 1;
  }
  return failed > 0 ? 1 : 0;
}

main(process.argv.slice(2)).then((code) => process.exit(code), (e) => {
  console.error(`validate.js: ${e && e.stack ? e.stack : e}`);
  process.exit(2);
});
