// Runs the Khronos glTF Validator (npm package `gltf-validator`) on one .gltf file, loading its
// buffers and images from beside it, and prints the report as JSON on stdout.
// Usage: NODE_PATH=<folder holding node_modules/gltf-validator>/node_modules node gltf-validate.js FILE
'use strict';
const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

const file = process.argv[2];
if (!file) {
  console.error('usage: gltf-validate.js FILE.gltf');
  process.exit(2);
}
const bytes = new Uint8Array(fs.readFileSync(file));
validator
  .validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 0,
    externalResourceFunction: (uri) =>
      new Promise((resolve, reject) => {
        fs.readFile(path.resolve(path.dirname(file), decodeURIComponent(uri)), (err, data) => {
          if (err) {
            reject(err.toString());
          } else {
            resolve(new Uint8Array(data));
          }
        });
      }),
  })
  .then((report) => {
    console.log(JSON.stringify(report, null, 2));
  })
  .catch((error) => {
    console.error('validation failed: ' + error);
    process.exit(1);
  });
