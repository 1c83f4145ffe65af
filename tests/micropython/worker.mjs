// One MicroPython interpreter in a worker thread, running the jobs run_tests.mjs hands it.
//
// A Python loop inside WebAssembly cannot be interrupted from its own thread, so the
// interpreter lives here and the main thread owns the clock: before each step the worker
// posts "begin", after it "end"; if "end" is late the main thread terminates this worker
// and starts a fresh one for the remaining jobs. Output a test prints is forwarded as it
// happens, so a test that hangs still shows what it printed.

import fs from "node:fs";
import path from "node:path";
import { parentPort, workerData } from "node:worker_threads";

const { repoRoot, packageDir, heapBytes, files } = workerData;
const FS_ROOT = "/repo";
const HARNESS_DIR = "/harness";

// Output is forwarded a line at a time (or every OUTPUT_CHUNK bytes of a line that never ends):
// per byte would cost a message each, and holding it to the end of a step would lose what a test
// printed before it hung.
const OUTPUT_CHUNK = 4096;
const pending = { stdout: [], stderr: [] };
const decoders = { stdout: new TextDecoder(), stderr: new TextDecoder() };

function flushOutput(stream) {
  if (pending[stream].length === 0) return;
  const text = decoders[stream].decode(new Uint8Array(pending[stream]), { stream: true });
  pending[stream] = [];
  parentPort.postMessage({ type: "output", stream, text });
}

const forward = (stream) => (bytes) => {
  for (const byte of bytes) {
    pending[stream].push(byte);
    if (byte === 10 || pending[stream].length >= OUTPUT_CHUNK) flushOutput(stream);
  }
};

const { loadMicroPython } = await import(path.join(packageDir, "micropython.mjs"));
const mp = await loadMicroPython({
  heapsize: heapBytes,
  linebuffer: false,
  stdout: forward("stdout"),
  stderr: forward("stderr"),
});

function mkdirs(fsPath) {
  let current = "";
  for (const part of fsPath.split("/").filter(Boolean)) {
    current += "/" + part;
    if (!mp.FS.analyzePath(current).exists) mp.FS.mkdir(current);
  }
}

function copyIn(relPath, destRoot, sourceRoot) {
  const dest = `${destRoot}/${relPath}`;
  mkdirs(path.posix.dirname(dest));
  mp.FS.writeFile(dest, fs.readFileSync(path.join(sourceRoot, relPath)));
}

for (const rel of files) copyIn(rel, FS_ROOT, repoRoot);
copyIn("harness.py", HARNESS_DIR, path.dirname(new URL(import.meta.url).pathname));

// Paths relative to the repository root make tracebacks name files as the repository does.
mp.FS.chdir(FS_ROOT);
mp.runPython(`
import sys
sys.path[:] = ["", "tests/openbricks", "${HARNESS_DIR}"] + [p for p in sys.path if p not in ("", "/lib")]
import harness as _harness
`);
const harness = mp.pyimport("harness");

function call(fnName, ...args) {
  // Every harness function returns a JSON string; a JS exception here means the harness itself broke.
  const result = JSON.parse(harness[fnName](...args));
  flushOutput("stdout");
  flushOutput("stderr");
  return result;
}

parentPort.postMessage({ type: "ready", interpreter: call("interpreter") });

parentPort.on("message", (job) => {
  if (job.kind === "import") {
    parentPort.postMessage({ type: "begin", step: { kind: "import", module: job.module } });
    const started = performance.now();
    const result = call("check_import", job.module);
    parentPort.postMessage({ type: "end", result: { ...result, ms: performance.now() - started } });
  } else if (job.kind === "tests") {
    parentPort.postMessage({ type: "begin", step: { kind: "load", module: job.module } });
    let started = performance.now();
    const loaded = call("load_tests", job.module, JSON.stringify(job.namesInSourceOrder));
    parentPort.postMessage({ type: "end", result: { ...loaded, ms: performance.now() - started } });
    if (loaded.ok) {
      const skip = new Set(job.done || []);
      const only = job.only ? new Set(job.only) : null;
      for (const name of loaded.tests) {
        if (skip.has(name) || (only && !only.has(name))) continue;
        parentPort.postMessage({ type: "begin", step: { kind: "test", module: job.module, name } });
        started = performance.now();
        const result = call("run_test", name);
        parentPort.postMessage({ type: "end", result: { ...result, ms: performance.now() - started } });
      }
    }
    call("unload_tests");
  }
  parentPort.postMessage({ type: "idle" });
});
