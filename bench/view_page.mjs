// How the live page keeps up with a large swarm: `swarm view RUN_DIR` replays a recorded run and a
// real page in headless Chromium (SwiftShader: software WebGL, no GPU) draws it; over ten seconds
// the page's own counters say how many frames it received and how many times it drew the scene,
// how many agents and links it drew, and how long its script was busy (the DevTools protocol's
// Performance metrics).
// Usage: node bench/view_page.mjs RUN_DIR [SPEED]     (BUILD_DIR=build)
import { spawn } from 'node:child_process';
import path from 'node:path';
import { createRequire } from 'node:module';
import { fileURLToPath } from 'node:url';

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');
const require = createRequire(path.join(root, 'node/node_modules/x.js'));
const puppeteer = require('puppeteer-core');
const [runDir, speed = '1'] = process.argv.slice(2);
const build = path.resolve(root, process.env.BUILD_DIR || 'build');
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

const view = spawn(path.join(build, 'bin/swarm'), ['view', runDir, '--port', '0', '--speed', speed],
  { stdio: ['ignore', 'pipe', 'inherit'] });
let said = '';
view.stdout.on('data', (d) => { said += d; });
let url = null;
while (!(url = (said.match(/open (http:\/\/[0-9.:]+\/)/) || [])[1])) await sleep(100);
const browser = await puppeteer.launch({ executablePath: '/usr/bin/chromium', headless: true,
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader'] });
const page = await browser.newPage();
await page.setViewport({ width: 1400, height: 820 });
await page.goto(url);
await sleep(3000);  // the page loads and gets its snapshot
const cdp = await page.createCDPSession();
await cdp.send('Performance.enable');
const metric = async () => Object.fromEntries((await cdp.send('Performance.getMetrics')).metrics
  .map((m) => [m.name, m.value]));
const s0 = await page.evaluate(() => ({ ...window.qswarm, latencyMs: 0 }));
const m0 = await metric();
const t0 = Date.now();
await sleep(10000);
const s1 = await page.evaluate(() => ({ ...window.qswarm, latencyMs: 0 }));
const m1 = await metric();
const dt = (Date.now() - t0) / 1000;
const busy = (m1.ScriptDuration - m0.ScriptDuration) + (m1.LayoutDuration - m0.LayoutDuration) +
  (m1.RecalcStyleDuration - m0.RecalcStyleDuration);
console.log(`agents drawn ${s1.agentsDrawn}, links drawn ${s1.linksDrawn}; ` +
  `frames ${((s1.frames - s0.frames) / dt).toFixed(1)}/s, scene drawn ${((s1.renders - s0.renders) / dt).toFixed(1)}/s, ` +
  `page busy (script, layout, style) ${((100 * busy) / dt).toFixed(0)}% of the time, ` +
  `JS heap ${(m1.JSHeapUsedSize / 1e6).toFixed(0)} MB`);
await browser.close();
view.kill('SIGINT');
