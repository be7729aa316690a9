#!/usr/bin/env node
// Runs the Khronos glTF-Validator (npm package `gltf-validator`) on each FILE (.glb or .gltf)
// and prints, per file, the number of errors, warnings, infos and hints and every message.
// Exits 1 when any file has an error or cannot be read, 2 on a usage error, 0 otherwise.
// External buffers of a .gltf are loaded from the file's own folder only.
//
// Usage: node validate.cjs FILE...

'use strict';

const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

const SEVERITY = ['error', 'warning', 'info', 'hint'];

/** Loads an external resource named by `uri`, refusing anything outside `folder`. */
function loader(folder) {
  return (uri) =>
    new Promise((resolve, reject) => {
      const target = path.resolve(folder, decodeURIComponent(uri));
      if (path.relative(folder, target).startsWith('..')) {
        reject(`refused ${uri}: outside ${folder}`);
        return;
      }
      fs.readFile(target, (error, data) => (error ? reject(error.toString()) : resolve(data)));
    });
}

/** Validates one file; returns its number of errors (1 when it cannot be validated). */
async function validate(file) {
  let bytes;
  try {
    bytes = fs.readFileSync(file);
  } catch (error) {
    console.log(`${file}: cannot read: ${error.message}`);
    return 1;
  }
  let report;
  try {
    report = await validator.validateBytes(new Uint8Array(bytes), {
      uri: path.basename(file),
      maxIssues: 0,
      writeTimestamp: false,
      externalResourceFunction: loader(path.dirname(path.resolve(file))),
    });
  } catch (error) {
    console.log(`${file}: the validator could not read it: ${error}`);
    return 1;
  }
  const issues = report.issues;
  console.log(
    `${file}: ${issues.numErrors} errors, ${issues.numWarnings} warnings, ` +
      `${issues.numInfos} infos, ${issues.numHints} hints ` +
      `(glTF-Validator ${report.validatorVersion})`,
  );
  for (const message of issues.messages) {
    const where = message.pointer ? ` at ${message.pointer}` : '';
    console.log(`  ${SEVERITY[message.severity] || message.severity} ${message.code}${where}: ${message.message}`);
  }
  return issues.numErrors;
}

async function main() {
  const files = process.argv.slice(2);
  if (files.length === 0) {
    console.error('usage: node validate.cjs FILE...');
    return 2;
  }
  let failed = 0;
  for (const file of files) {
    if ((await validate(file)) > 0) {
      failed += 1;
    }
  }
  if (failed > 0) {
    console.log(`${failed} of ${files.length} file(s) have errors`);
    return 1;
  }
  return 0;
}

main().then((code) => {
  process.exitCode = code;
});
