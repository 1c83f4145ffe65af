#!/usr/bin/env node
// Runs the hub runtime's tests under the real MicroPython interpreter (WebAssembly port).
//
//   node tests/micropython/run_tests.mjs [--json FILE] [--filter TEXT] [--step-timeout-ms N] [--total-timeout-ms N]
//
// Imports every module under openbricks/ on its own, then runs every test function of
// tests/openbricks/**/test_*.py (files with NEEDS_NATIVE = True are listed, not run), each
// after fakes.reset(). Prints the results as JSON (stdout, or FILE) and a summary on stderr;
// exits 0 when everything passed, 1 when something failed, 2 when the run itself broke.
// See README.md in this folder.

import fs from "node:fs";
import path from "node:path";
import { fileURLToPath } from "node:url";
import { Worker } from "node:worker_threads";

import { discover } from "./discover.mjs";

const HERE = path.dirname(fileURLToPath(import.meta.url));
const PACKAGE_DIR = path.join(HERE, "node_modules", "@micropython", "micropython-webassembly-pyscript");

function parseArgs(argv) {
  const options = {
    repoRoot: path.resolve(HERE, "..", ".."),
    json: null,
    stepTimeoutMs: 30_000,
    totalTimeoutMs: 600_000,
    heapBytes: 4 * 1024 * 1024,
    filter: null,
  };
  const numeric = { "--step-timeout-ms": "stepTimeoutMs", "--total-timeout-ms": "totalTimeoutMs" };
  for (let i = 0; i < argv.length; i++) {
    const arg = argv[i];
    const value = argv[i + 1];
    if (arg === "--json") options.json = value;
    else if (arg === "--filter") options.filter = value;
    else if (arg === "--repo") options.repoRoot = path.resolve(value);
    else if (arg in numeric) {
      options[numeric[arg]] = Number(value);
      if (!(options[numeric[arg]] > 0)) throw new Error(`${arg} needs a positive number of milliseconds`);
    } else throw new Error(`unknown option ${arg} (options: --json FILE, --filter TEXT, --repo DIR, --step-timeout-ms N, --total-timeout-ms N)`);
    i++;
  }
  return options;
}

// What a step printed is kept for its report, but a runaway printer must not bloat the JSON or
// this process: past OUTPUT_HEAD + OUTPUT_TAIL characters only the start and the end are kept,
// where the clues usually are.
const OUTPUT_HEAD = 4_096;
const OUTPUT_TAIL = 12_288;

class StepOutput {
  constructor() {
    this.head = "";
    this.tail = "";
    this.total = 0;
  }

  add(text) {
    this.total += text.length;
    const room = OUTPUT_HEAD - this.head.length;
    if (room > 0) {
      this.head += text.slice(0, room);
      text = text.slice(room);
    }
    this.tail = (this.tail + text).slice(-OUTPUT_TAIL);
  }

  text() {
    const left = this.total - this.head.length - this.tail.length;
    return left > 0 ? `${this.head}\n[... ${left} characters of output left out ...]\n${this.tail}` : this.head + this.tail;
  }
}

// The queue of jobs, consumed by one worker at a time; a worker that times out or dies is
// replaced and the queue continues where it stopped.
class Run {
  constructor(options, plan) {
    this.options = options;
    this.plan = plan;
    this.jobs = [
      ...plan.runtimeModules.map((module) => ({ kind: "import", module })),
      ...plan.testModules.map((t) => ({ kind: "tests", ...t, done: [] })),
    ];
    this.imports = [];
    this.tests = [];
    this.modules = [];
    this.interpreter = null;
    this.workerStarts = 0;
    this.startedAt = performance.now();
  }

  remainingTotalMs() {
    return this.options.totalTimeoutMs - (performance.now() - this.startedAt);
  }

  // Records the step that was running when a worker had to be stopped, and marks the job so
  // the replacement worker does not run that step again.
  abandon(step, output, error) {
    const job = this.jobs[0];
    if (step.kind === "import") {
      this.imports.push({ module: step.module, outcome: "failed", error, output });
      this.jobs.shift();
    } else if (step.kind === "load") {
      this.modules.push({ file: job.file, module: step.module, ok: false, error, output });
      for (const name of job.namesInSourceOrder) {
        this.tests.push({ file: job.file, name, outcome: "failed", error: `importing the test module: ${error}`, output });
      }
      this.jobs.shift();
    } else {
      this.tests.push({ file: job.file, name: step.name, outcome: "failed", error, output });
      job.done.push(step.name);
    }
  }

  record(step, result, output) {
    const job = this.jobs[0];
    const ms = Math.round(result.ms * 10) / 10;
    if (step.kind === "import") {
      this.imports.push({
        module: step.module, outcome: result.ok ? "passed" : "failed", error: result.error ?? null, output, ms,
      });
    } else if (step.kind === "load") {
      // A module whose test timed out is loaded again by the next worker: record it once.
      if (!job.loadRecorded) {
        this.modules.push({ file: job.file, module: step.module, ok: result.ok, error: result.error ?? null, output, ms });
      }
      job.loadRecorded = true;
      if (!result.ok) {
        for (const name of job.namesInSourceOrder) {
          this.tests.push({
            file: job.file, name, outcome: "failed", error: `importing the test module failed:\n${result.error}`, output, ms: 0,
          });
        }
      }
    } else {
      this.tests.push({ file: job.file, name: step.name, outcome: result.outcome, error: result.error ?? null, output, ms });
      job.done.push(step.name);
    }
  }

  // Runs the queue on one worker until the queue is empty, a step overruns or the worker dies.
  runWorker() {
    return new Promise((resolve) => {
      this.workerStarts++;
      const worker = new Worker(path.join(HERE, "worker.mjs"), {
        workerData: {
          repoRoot: this.options.repoRoot,
          packageDir: PACKAGE_DIR,
          heapBytes: this.options.heapBytes,
          files: this.plan.files,
        },
        stdout: true,
        stderr: true,
      });
      let step = null;
      let output = new StepOutput();
      let timer = null;
      let finished = false;

      // Anything the interpreter writes outside the captured stdout/stderr callbacks
      // (Emscripten's own warnings) belongs to the step that was running.
      worker.stdout.on("data", (chunk) => output.add(String(chunk)));
      worker.stderr.on("data", (chunk) => output.add(String(chunk)));

      const finish = (failure) => {
        if (finished) return;
        finished = true;
        clearTimeout(timer);
        let outcome = { done: true };
        if (failure && step === null) outcome = { stalled: failure };
        else if (failure) this.abandon(step, output.text(), failure);
        worker.terminate().then(() => resolve(outcome));
      };
      const arm = (what) => {
        clearTimeout(timer);
        const limit = Math.min(this.options.stepTimeoutMs, Math.max(0, this.remainingTotalMs()));
        timer = setTimeout(() => {
          const total = this.remainingTotalMs() <= 0;
          finish(
            total
              ? `stopped: the whole MicroPython run exceeded ${this.options.totalTimeoutMs} ms (--total-timeout-ms)`
              : `timed out: ${what} took longer than ${this.options.stepTimeoutMs} ms (--step-timeout-ms); ` +
                "an endless loop, or a wait for something the fakes never produce?",
          );
        }, limit);
      };
      const next = () => {
        if (this.jobs.length === 0 || this.remainingTotalMs() <= 0) return finish(null);
        worker.postMessage(this.jobs[0]);
      };

      arm("starting the interpreter");
      worker.on("message", (msg) => {
        if (finished) return;
        if (msg.type === "ready") {
          this.interpreter = msg.interpreter;
          clearTimeout(timer);
          next();
        } else if (msg.type === "output") {
          output.add(msg.text);
        } else if (msg.type === "begin") {
          step = msg.step;
          output = new StepOutput();
          arm(step.kind === "test" ? `test ${step.name}` : `importing ${step.module}`);
        } else if (msg.type === "end") {
          clearTimeout(timer);
          this.record(step, msg.result, output.text());
          step = null;
          output = new StepOutput();
        } else if (msg.type === "idle") {
          this.jobs.shift();
          next();
        }
      });
      worker.on("error", (err) => {
        const where = step === null ? "the interpreter stopped" : "the interpreter crashed";
        const detail = err && err.stack ? err.stack : String(err);
        if (step === null && this.interpreter === null) {
          // Loading the interpreter itself failed: retrying will not help.
          finished = true;
          clearTimeout(timer);
          resolve({ fatal: `could not start MicroPython: ${detail}` });
          return;
        }
        finish(`${where}: ${detail}`);
      });
      worker.on("exit", (code) => {
        if (!finished) finish(`the interpreter's worker exited with code ${code}`);
      });
    });
  }

  async execute() {
    let stalls = 0;
    while (this.jobs.length > 0 && this.remainingTotalMs() > 0) {
      const outcome = await this.runWorker();
      if (outcome.fatal) return outcome.fatal;
      // A worker that fails outside any step (starting up, between modules) made no progress;
      // once may be bad luck, twice in a row would loop forever.
      stalls = outcome.stalled ? stalls + 1 : 0;
      if (stalls >= 2) return `the interpreter failed twice outside any test: ${outcome.stalled}`;
    }
    const stopped = "not run: the whole MicroPython run exceeded --total-timeout-ms";
    for (const job of this.jobs) {
      if (job.kind === "import") this.imports.push({ module: job.module, outcome: "failed", error: stopped });
      else {
        for (const name of job.namesInSourceOrder.filter((n) => !job.done.includes(n))) {
          this.tests.push({ file: job.file, name, outcome: "failed", error: stopped });
        }
      }
    }
    this.jobs = [];
    return null;
  }

  report(fatal) {
    const count = (items, outcome) => items.filter((i) => i.outcome === outcome).length;
    return {
      interpreter: this.interpreter,
      fatal,
      duration_s: Math.round(performance.now() - this.startedAt) / 1000,
      interpreter_starts: this.workerStarts,
      counts: {
        imports_passed: count(this.imports, "passed"),
        imports_failed: count(this.imports, "failed"),
        tests_passed: count(this.tests, "passed"),
        tests_failed: count(this.tests, "failed"),
        test_files: this.plan.testModules.length,
        test_files_needing_native: this.plan.needsNative.length,
      },
      needs_native: this.plan.needsNative,
      imports: this.imports,
      test_modules: this.modules,
      tests: this.tests,
    };
  }
}

// --filter TEXT keeps the runtime modules and test functions whose id contains TEXT; ids read
// `openbricks.drivers.st3215` and `drivers/test_l298n.py::test_invert_swaps_the_direction`.
function select(plan, filter) {
  if (!filter) return plan;
  const testModules = [];
  for (const t of plan.testModules) {
    const names = t.namesInSourceOrder.filter((n) => `${t.file}::${n}`.includes(filter));
    if (names.length) testModules.push({ ...t, namesInSourceOrder: names, only: names });
  }
  return { ...plan, runtimeModules: plan.runtimeModules.filter((m) => m.includes(filter)), testModules };
}

function summarize(report) {
  const c = report.counts;
  const lines = [];
  const who = report.interpreter ? `MicroPython ${report.interpreter.version}` : "MicroPython";
  lines.push(
    `${who}: ${c.tests_passed} passed, ${c.tests_failed} failed in ${c.test_files} test files; ` +
      `${c.imports_passed}/${c.imports_passed + c.imports_failed} runtime modules import; ` +
      `${c.test_files_needing_native} files skipped (NEEDS_NATIVE); ${report.duration_s} s`,
  );
  for (const i of report.imports.filter((x) => x.outcome !== "passed")) {
    lines.push(`FAILED import ${i.module}\n${indent(i.error)}`);
  }
  for (const t of report.tests.filter((x) => x.outcome !== "passed")) {
    lines.push(`FAILED ${t.file}::${t.name}\n${indent(t.error)}`);
  }
  if (report.fatal) lines.push(`RUN BROKEN: ${report.fatal}`);
  return lines.join("\n") + "\n";
}

function indent(text) {
  return String(text ?? "").trimEnd().split("\n").map((l) => `    ${l}`).join("\n");
}

async function main() {
  let options;
  try {
    options = parseArgs(process.argv.slice(2));
  } catch (err) {
    process.stderr.write(`${err.message}\n`);
    return 2;
  }
  if (!fs.existsSync(path.join(PACKAGE_DIR, "micropython.mjs"))) {
    process.stderr.write(
      `MicroPython WebAssembly package not installed in ${PACKAGE_DIR}: run \`make setup\` ` +
        "(or `npm ci` in tests/micropython).\n",
    );
    return 2;
  }
  const plan = select(discover(options.repoRoot), options.filter);
  const run = new Run(options, plan);
  const fatal = await run.execute();
  const report = run.report(fatal);
  const text = JSON.stringify(report, null, 1) + "\n";
  if (options.json) fs.writeFileSync(options.json, text);
  else process.stdout.write(text);
  process.stderr.write(summarize(report));
  if (fatal) return 2;
  return report.counts.tests_failed + report.counts.imports_failed === 0 ? 0 : 1;
}

process.exitCode = await main();
