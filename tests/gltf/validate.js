#!/usr/bin/env node
// Runs the Khronos glTF Validator (the npm package pinned in package.json, installed by
// scripts/setup.sh with `npm ci`) on each file given. Prints one line of JSON per file:
//   {"file", "validator", "errors", "warnings", "infos", "hints", "messages": [...]}
// where messages holds every error and warning as "SEVERITY CODE at POINTER: message".
// Exit status: 0 when no file has an error, 1 when one has, 2 when a file cannot be read or
// the validator is missing (a missing install is a failure, never a skip).
'use strict';

const fs = require('fs');
const path = require('path');

let validator;
try {
  validator = require(path.join(__dirname, 'node_modules', 'gltf-validator'));
} catch (e) {
  console.error('validate.js: the glTF Validator is not installed in ' + path.join(__dirname, 'node_modules') +
                ': run scripts/setup.sh (it runs `npm ci` in tests/gltf)');
  process.exit(2);
}

const kSeverityNames = ['ERROR', 'WARNING', 'INFO', 'HINT'];

async function ValidateFile(file) {
  const bytes = fs.readFileSync(file);
  const report = await validator.validateBytes(new Uint8Array(bytes), {
    uri: path.basename(file),
    maxIssues: 0,  // all of them
    // A .glb of ours has no external resources; one that asks for any is an error below.
    externalResourceFunction: (uri) => Promise.reject('external resource ' + uri + ' not allowed'),
  });
  const issues = report.issues;
  const messages = issues.messages.filter((m) => m.severity <= 1)
                       .map((m) => kSeverityNames[m.severity] + ' ' + m.code + ' at ' + (m.pointer || '/') + ': ' +
                                   m.message);
  return {
    file: file,
    validator: report.validatorVersion,
    errors: issues.numErrors,
    warnings: issues.numWarnings,
    infos: issues.numInfos,
    hints: issues.numHints,
    messages: messages,
  };
}

async function Main() {
  const files = process.argv.slice(2);
  if (files.length === 0) {
    console.error('usage: node validate.js FILE.glb [FILE.glb ...]');
    return 2;
  }
  let status = 0;
  for (const file of files) {
    if (!fs.existsSync(file)) {
      console.log(JSON.stringify({file: file, errors: 0, messages: ['cannot read ' + file]}));
      status = 2;
      continue;
    }
    try {
      const result = await ValidateFile(file);
      console.log(JSON.stringify(result));
      if (result.errors > 0 && status === 0) status = 1;
    } catch (e) {
      // The validator rejects what it cannot even parse as glTF or GLB.
      console.log(JSON.stringify({file: file, errors: 1, messages: ['ERROR ' + String(e)]}));
      if (status === 0) status = 1;
    }
  }
  return status;
}

Main().then((status) => process.exit(status), (e) => {
  console.error('validate.js: ' + e);
  process.exit(2);
});
