// What the view's multi-process tests share: a real `swarm run --view` (or `swarm view`) as a
// child process, waiting on conditions (the run directory's view.url, a predicate), skipping
// with the reason (exit 77, ctest's SKIP_RETURN_CODE) only where the test cannot run at all, and
// never under CI (CI set): there a test that cannot run fails, naming what is missing.
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { createRequire } from 'node:module';

// The run directory's files these tests read, spelled as RunDir names them
// (common/record/run_dir.hpp; tests/record/run_dir_test.cpp checks this block against it).
// One run directory.
export const SCENARIO = 'scenario.txtpb';
export const SUMMARY = 'summary.json';
export const TELEMETRY = 'telemetry.csv';
export const RECORDS = 'records.pb';
export const VIEW_URL = 'view.url';

export const binDir = process.env.QSWARM_BIN_DIR;
export const nodeModules = process.env.QSWARM_NODE_MODULES;
export const runsDir = process.env.QSWARM_TEST_RUNS_DIR;
export const domain = process.env.QSWARM_TEST_DOMAIN;

export function skip(reason) {
  if (process.env.CI) {
    console.log(`FAIL (CI): cannot run: ${reason}`);
    process.exit(1);
  }
  console.log(`SKIPPED: ${reason}`);
  process.exit(77);
}

// npm packages from node/node_modules (tools/setup.sh installs them there).
export function npm(name) {
  if (!nodeModules || !fs.existsSync(path.join(nodeModules, name)))
    skip(`npm package ${name} is not in ${nodeModules}: run tools/setup.sh (npm ci --prefix node)`);
  return createRequire(path.join(nodeModules, 'x.js'))(name);
}

export const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

export async function until(pred, timeoutMs, what) {
  const end = Date.now() + timeoutMs;
  while (Date.now() < end) {
    const v = await pred();
    if (v) return v;
    await sleep(50);
  }
  throw new Error(`timed out after ${timeoutMs} ms waiting for ${what}`);
}

let failures = 0, checks = 0;
export function check(cond, what) {
  checks++;
  if (cond) {
    console.log(`ok: ${what}`);
  } else {
    failures++;
    console.log(`FAILED: ${what}`);
  }
}
export function finish() {
  console.log(`${checks - failures} passed, ${failures} failed`);
  process.exit(failures ? 1 : 0);
}

export function freshDir(name) {
  const d = path.join(runsDir, `${name}-${process.pid}`);
  fs.rmSync(d, { recursive: true, force: true });
  fs.mkdirSync(runsDir, { recursive: true });
  return d;
}

// A swarm run with its view on a free port. Resolves once the view listens: {proc, dir, url,
// done (a promise of the exit code), output()}.
export async function startRun(name, args) {
  const dir = freshDir(name);
  const proc = spawn(path.join(binDir, 'swarm'),
    ['run', ...args, '--out', dir, '--domain', domain, '--view', '0'],
    { stdio: ['ignore', 'pipe', 'pipe'] });
  let out = '';
  proc.stdout.on('data', (d) => { out += d; });
  proc.stderr.on('data', (d) => { out += d; });
  const done = new Promise((resolve) => proc.on('exit', (code, sig) => resolve(sig ? 128 : code)));
  let exited = false;
  done.then(() => { exited = true; });
  const urlFile = path.join(dir, VIEW_URL);
  await until(() => exited || fs.existsSync(urlFile), 60000, `the view to listen (${VIEW_URL})`);
  if (exited) throw new Error(`swarm run ended before its view listened:\n${out}`);
  const url = (await until(() => fs.readFileSync(urlFile, 'utf8').trim(), 5000, VIEW_URL)).trim();
  process.on('exit', () => { if (!exited) proc.kill('SIGKILL'); });
  return { proc, dir, url, done, output: () => out };
}

export async function getJson(url) {
  const res = await fetch(url);
  return res.json();
}
