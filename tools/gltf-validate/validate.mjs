#!/usr/bin/env node
// Validates glTF 2.0 / GLB files with the Khronos glTF-Validator (npm package
// `gltf-validator`, version pinned in package.json / package-lock.json).
//
// Usage:  node tools/gltf-validate/validate.mjs [--strict] FILE...
//
// For each file prints one summary line (errors, warnings, infos, hints) and the
// first few messages. Exit status: 0 when no report has errors (with --strict:
// no errors and no warnings), 1 otherwise, 2 on bad usage or when the validator
// cannot be loaded (run `npm ci` in tools/gltf-validate first).

import { readFile } from "node:fs/promises";
import path from "node:path";

const SHOWN_MESSAGES = 8;
const SEVERITY = ["error", "warning", "info", "hint"];

function usage() {
  console.error("usage: node validate.mjs [--strict] FILE...");
  process.exit(2);
}

async function loadValidator() {
  try {
    return await import("gltf-validator");
  } catch (e) {
    console.error(
      `gltf-validate: cannot load the gltf-validator package (${e.message}); ` +
        "run `npm ci --no-audit --no-fund` in tools/gltf-validate",
    );
    process.exit(2);
  }
}

function describe(m) {
  const where = m.pointer ?? (m.offset !== undefined ? `byte ${m.offset}` : "");
  const sev = SEVERITY[m.severity] ?? `severity ${m.severity}`;
  return `  ${sev} ${m.code}${where ? ` at ${where}` : ""}: ${m.message}`;
}

/** Validates one file; returns true when it passes. */
async function validateFile(validator, file, strict) {
  let bytes;
  try {
    bytes = new Uint8Array(await readFile(file));
  } catch (e) {
    console.log(`${file}: FAIL cannot read: ${e.message}`);
    return false;
  }
  let report;
  try {
    report = await validator.validateBytes(bytes, {
      uri: path.basename(file),
      maxIssues: 0,
      writeTimestamp: false,
    });
  } catch (e) {
    console.log(`${file}: FAIL validator rejected the input: ${e}`);
    return false;
  }
  const is = report.issues;
  const ok = is.numErrors === 0 && (!strict || is.numWarnings === 0);
  console.log(
    `${file}: ${ok ? "ok" : "FAIL"} numErrors=${is.numErrors} numWarnings=${is.numWarnings} ` +
      `numInfos=${is.numInfos} numHints=${is.numHints} (validator ${report.validatorVersion})`,
  );
  const shown = is.messages.slice().sort((a, b) => a.severity - b.severity).slice(0, SHOWN_MESSAGES);
  for (const m of shown) console.log(describe(m));
  if (is.messages.length > shown.length) {
    console.log(`  ... and ${is.messages.length - shown.length} more`);
  }
  return ok;
}

async function main() {
  const args = process.argv.slice(2);
  const strict = args.includes("--strict");
  const files = args.filter((a) => a !== "--strict");
  if (files.length === 0 || files.some((f) => f.startsWith("--"))) usage();
  const validator = await loadValidator();
  let failed = 0;
  for (const f of files) {
    if (!(await validateFile(validator, f, strict))) failed += 1;
  }
  console.log(`${files.length - failed} passed, ${failed} failed`);
  process.exit(failed === 0 ? 0 : 1);
}

await main();
