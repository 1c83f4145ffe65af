// What the MicroPython run covers, found from the source tree alone (nothing is imported here).
//
// The pytest bridge (test_runtime_on_micropython.py) finds the same things with Python's ast;
// keep the two rules in step: runtime modules are every .py under openbricks/, test modules
// are tests/openbricks/**/test_*.py, and a module-level `NEEDS_NATIVE = True` marks a test
// file that needs the host-only native binding.

import fs from "node:fs";
import path from "node:path";

const RUNTIME_DIR = "openbricks";
const TESTS_DIR = "tests/openbricks";
// The simulator's model of the hub's hardware, which the fakes build on (imported as `shim`).
const HARDWARE_MODEL_DIR = "sim/shim";

const NEEDS_NATIVE = /^NEEDS_NATIVE\s*(?::[^=]*)?=\s*True\b/m;
const TEST_FUNCTION = /^def\s+(test_\w+)\s*\(/gm;

function walk(repoRoot, relDir) {
  const out = [];
  const stack = [relDir];
  while (stack.length) {
    const dir = stack.pop();
    for (const entry of fs.readdirSync(path.join(repoRoot, dir), { withFileTypes: true })) {
      if (entry.name === "__pycache__" || entry.name.startsWith(".")) continue;
      const rel = `${dir}/${entry.name}`;
      if (entry.isDirectory()) stack.push(rel);
      else if (entry.isFile()) out.push(rel);
    }
  }
  return out.sort();
}

function moduleName(relPath) {
  const parts = relPath.replace(/\.py$/, "").split("/");
  if (parts[parts.length - 1] === "__init__") parts.pop();
  return parts.join(".");
}

export function discover(repoRoot) {
  const runtimeFiles = walk(repoRoot, RUNTIME_DIR);
  const testFiles = walk(repoRoot, TESTS_DIR);
  const runtimeModules = runtimeFiles.filter((f) => f.endsWith(".py")).map(moduleName);

  const testModules = [];
  const needsNative = [];
  for (const rel of testFiles) {
    const base = path.posix.basename(rel);
    if (!(base.startsWith("test_") && base.endsWith(".py"))) continue;
    const source = fs.readFileSync(path.join(repoRoot, rel), "utf8");
    const file = rel.slice(TESTS_DIR.length + 1);
    if (NEEDS_NATIVE.test(source)) {
      needsNative.push(file);
      continue;
    }
    const names = [...source.matchAll(TEST_FUNCTION)].map((m) => m[1]);
    testModules.push({ file, module: moduleName(rel), namesInSourceOrder: [...new Set(names)] });
  }

  // Everything the interpreter may need to import: the runtime, the tests and their fakes
  // (data files included), the hardware model under them, and the package markers that make
  // `tests.openbricks.*` importable.
  const modelFiles = walk(repoRoot, HARDWARE_MODEL_DIR);
  const files = [...runtimeFiles, ...testFiles, ...modelFiles, "tests/__init__.py"].filter((rel) =>
    fs.existsSync(path.join(repoRoot, rel)),
  );
  return { runtimeModules, testModules, needsNative, files };
}
