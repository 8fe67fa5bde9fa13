// Runs the Kotlin/JS build of sdk/core's common tests on Node's built-in test runner.
//
//   node --test-reporter=spec run-tests.mjs target/js-gate/js/pocketbot-sdk-core-test.js
//
// kotlin-test on JS registers its test classes through global Jasmine/Mocha-style
// describe/it/xdescribe/xit; when they do not exist it silently runs nothing and Node exits 0.
// So they are put on globalThis (backed by node:test) before the linked test module is loaded;
// node:test then prints its summary (tests/pass/fail) and sets a non-zero exit code on failure.
import { describe, it } from 'node:test';
import { createRequire } from 'node:module';
import path from 'node:path';

const testModule = process.argv[2];
if (!testModule) {
  console.error('usage: node run-tests.mjs <linked test module .js>');
  process.exit(2);
}

let registered = 0;
let passed = 0;
let failed = 0;

// Count outcomes ourselves as well, so that "no test registered" can fail the build too.
const counted = (fn) => async (...args) => {
  try {
    const result = await fn(...args);
    passed++;
    return result;
  } catch (e) {
    failed++;
    throw e;
  }
};

globalThis.describe = (name, fn) => describe(name, fn);
globalThis.xdescribe = (name, fn) => describe.skip(name, fn);
globalThis.it = (name, fn) => { registered++; return it(name, counted(fn)); };
globalThis.xit = (name, fn) => { registered++; return it.skip(name, fn); };

createRequire(import.meta.url)(path.resolve(testModule));

process.on('exit', () => {
  if (registered === 0) {
    console.error(`No Kotlin/JS test registered by ${testModule}: the kotlin-test adapter ran nothing.`);
    process.exitCode = 1;
    return;
  }
  console.log(`kotlin-js: ${passed} passed, ${failed} failed`);
});
