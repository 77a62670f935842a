// What the live view costs the supervisor: one `swarm run` of N point agents on a ring of degree 4
// (bench/ring.txtpb, never converged, so it flies its whole duration) per cell: without --view,
// with --view and one client (a real page in headless Chromium), and with ten clients (that page
// and nine Foxglove protocol clients subscribed to the page's channel, as nine more pages would
// be, without drawing). The supervisor's CPU is read from /proc over the middle of the run (from
// 30% to 90% of its duration); the page reports the latency from a sample's publication by its
// agent to the page (one host, one clock).
// Usage: node bench/view_cost.mjs [N]      (default 32)
// Environment: DURATION=40 (simulated = wall seconds), BUILD_DIR=build, DOMAIN=13
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { createRequire } from 'node:module';
import { fileURLToPath } from 'node:url';

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');
const require = createRequire(path.join(root, 'node/node_modules/x.js'));
const puppeteer = require('puppeteer-core');
const WebSocket = require('ws');
const n = Number(process.argv[2] || 32);
const duration = Number(process.env.DURATION || 40);
const build = path.resolve(root, process.env.BUILD_DIR || 'build');
const domain = process.env.DOMAIN || '13';
const out = path.join(build, 'bench-runs');
fs.mkdirSync(out, { recursive: true });
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const ticks = 100;  // USER_HZ: /proc's clock ticks per second on Linux

function ringScenario() {
  let edges = '';
  for (let i = 1; i <= n; ++i) for (let k = 1; k <= 2; ++k) edges += ` edges { a: ${i} b: ${((i + k - 1) % n) + 1} }`;
  const text = fs.readFileSync(path.join(root, 'bench/ring.txtpb'), 'utf8')
    .replace('count: 8', `count: ${n}`).replace('duration_s: 30', `duration_s: ${duration}`);
  const file = path.join(out, `view-cost-ring-${n}.txtpb`);
  fs.writeFileSync(file, `${text}\ntopology { policy: FIXED${edges} }\n`);
  return file;
}

function cpuSeconds(pid) {
  const f = fs.readFileSync(`/proc/${pid}/stat`, 'utf8').split(') ')[1].split(' ');
  return (Number(f[11]) + Number(f[12])) / ticks;  // utime + stime
}

async function cell(name, clients) {
  const dir = path.join(out, `view-cost-${n}-${name}`);
  fs.rmSync(dir, { recursive: true, force: true });
  const args = ['run', ringScenario(), '--out', dir, '--domain', domain, '--quiet'];
  if (clients >= 0) args.push('--view', '0');
  const run = spawn(path.join(build, 'bin/swarm'), args, { stdio: 'ignore' });
  const done = new Promise((r) => run.on('exit', r));
  // The supervisor's pid, once processes.csv names it.
  let pid = null;
  while (!pid) {
    await sleep(100);
    try {
      const line = fs.readFileSync(path.join(dir, 'processes.csv'), 'utf8').split('\n')
        .find((l) => l.includes('supervisor'));
      if (line) pid = Number(line.split(',').pop());  // role,id,pid
    } catch { /* not yet */ }
  }
  let browser = null, page = null;
  const sockets = [];
  if (clients >= 1) {
    while (!fs.existsSync(path.join(dir, 'view.url'))) await sleep(100);
    const url = fs.readFileSync(path.join(dir, 'view.url'), 'utf8').trim();
    browser = await puppeteer.launch({ executablePath: '/usr/bin/chromium', headless: true,
      args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader'] });
    page = await browser.newPage();
    await page.setViewport({ width: 1400, height: 820 });
    await page.goto(url);
    for (let k = 1; k < clients; ++k) {
      const ws = new WebSocket(url.replace('http', 'ws'), ['foxglove.websocket.v1']);
      ws.on('message', (d, binary) => {
        if (binary) return;
        const m = JSON.parse(d);
        if (m.op !== 'advertise') return;
        const ch = m.channels.find((c) => c.topic === '/swarm/view');
        ws.send(JSON.stringify({ op: 'subscribe', subscriptions: [{ id: 1, channelId: ch.id }] }));
      });
      sockets.push(ws);
    }
  }
  // The first running sample starts the run's clock: measure from 30% to 90% of its duration.
  const t0 = Date.now();
  while (!fs.existsSync(path.join(dir, 'telemetry.csv'))) await sleep(100);
  await sleep(duration * 300);
  const c0 = cpuSeconds(pid), w0 = Date.now();
  await sleep(duration * 600);
  const c1 = cpuSeconds(pid), w1 = Date.now();
  let lat = null, frames = null;
  if (page) {
    const s = await page.evaluate(() => ({ lat: window.qswarm.latencyMs.slice(), frames: window.qswarm.frames }));
    lat = s.lat.sort((a, b) => a - b);
    frames = s.frames;
  }
  for (const ws of sockets) ws.terminate();
  if (browser) await browser.close();
  const code = await done;
  const cpu = (100 * (c1 - c0)) / ((w1 - w0) / 1000);
  const q = (p) => (lat && lat.length ? lat[Math.floor(p * (lat.length - 1))].toFixed(0) : '-');
  const summary = JSON.parse(fs.readFileSync(path.join(dir, 'summary.json'), 'utf8'));
  console.log(`| ${n} | ${name} | ${cpu.toFixed(1)} | ${q(0.5)} / ${q(0.9)} | ${frames ?? '-'} | ` +
    `${summary.end_reason} (exit ${code}) | ${((Date.now() - t0) / 1000).toFixed(0)} |`);
}

console.log('| agents | view | supervisor CPU [% of a core] | latency p50 / p90 [ms] | page frames | end | wall [s] |');
console.log('| --- | --- | --- | --- | --- | --- | --- |');
await cell('none', -1);
await cell('1 client', 1);
await cell('10 clients', 10);
