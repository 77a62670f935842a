// `swarm view RUN_DIR`: a recorded run served to the same page protocol as if live, paused,
// scrubbed and sped up from a client; and its bad input refused with exit 2 naming the flag.
import { spawn, spawnSync } from 'node:child_process';
import fs from 'node:fs';
import net from 'node:net';
import path from 'node:path';
import { binDir, check, domain, finish, freshDir, npm, until, SCENARIO, SUMMARY, TELEMETRY,
  RECORDS, VIEW_URL } from './harness.mjs';

const { FoxgloveClient } = npm('@foxglove/ws-protocol');
const WebSocket = npm('ws');
const swarm = path.join(binDir, 'swarm');

// A short recorded run (no view: any run directory can be replayed).
const dir = freshDir('view-replay');
const flown = spawnSync(swarm, ['run', '--agents', '8', '--seed', '3', '--quiet', '--duration', '30', '--time-scale', '2',
  '--out', dir, '--domain', domain], { encoding: 'utf8', timeout: 120000 });
check(flown.status === 0, `an 8-agent run to replay (exit ${flown.status})`);

// ---- bad input: exit 2, the flag named, nothing served ----
function refused(args, words, what) {
  const r = spawnSync(swarm, args, { encoding: 'utf8', timeout: 20000 });
  check(r.status === 2 && words.every((w) => r.stderr.includes(w)),
    `${what}: exit ${r.status}, "${r.stderr.trim().split('\n').pop()}"`);
}
refused(['view', path.join(dir, 'nope')], ['RUN_DIR', 'no such run directory'], 'a missing directory');
const empty = freshDir('view-replay-empty');
fs.mkdirSync(empty);
fs.copyFileSync(path.join(dir, SCENARIO), path.join(empty, SCENARIO));
refused(['view', empty], ['RUN_DIR', RECORDS], `a run directory without ${RECORDS}`);
fs.writeFileSync(path.join(empty, RECORDS), '');
refused(['view', empty], ['no records'], `an empty ${RECORDS}`);
for (const k of ['0', '-1', 'nan', 'inf', '1e9'])
  refused(['view', dir, '--speed', k], ['--speed'], `--speed ${k}`);
refused(['view', dir, '--speed', '1000.0001'], ['--speed 1000.0001'], 'a speed just past 1000, said as given');
refused(['run', '--agents', '2', '--domain', domain, '--view-listen', '127.0.0.1'],
  ['--view-listen', '--view'], '--view-listen without --view');
refused(['run', '--agents', '2', '--domain', domain, '--view', '0', '--view-listen', '239.1.2.3'],
  ['--view', 'multicast'], 'a multicast --view-listen');
refused(['view', dir, '--listen', 'nowhere'], ['--listen', 'not an IP address'], 'a listen address that is none');
const blocker = net.createServer();
await new Promise((r) => blocker.listen(0, '127.0.0.1', r));
const busy = blocker.address().port;
refused(['view', dir, '--port', String(busy)], ['--port', 'in use'], 'a port in use');
const out = freshDir('view-replay-busy-run');
refused(['run', '--agents', '2', '--out', out, '--domain', domain, '--view', String(busy)],
  ['--view', 'in use'], 'swarm run --view on a port in use');
check(!fs.existsSync(out), 'nothing was flown for it (no run directory)');
blocker.close();

// ---- Ctrl-C during a run with a view and a client that never reads ----
{
  const dirC = freshDir('view-interrupted');
  const run = spawn(swarm, ['run', '--agents', '8', '--seed', '4', '--quiet', '--duration', '120',
    '--time-scale', '0.5', '--out', dirC, '--domain', domain, '--view', '0'], { stdio: 'ignore' });
  const exited = new Promise((r) => run.on('exit', (c, sig) => r(sig ? 128 : c)));
  const urlFile = path.join(dirC, VIEW_URL);
  await until(() => fs.existsSync(urlFile) && fs.readFileSync(urlFile, 'utf8').trim(), 60000, VIEW_URL);
  const url = fs.readFileSync(urlFile, 'utf8').trim();
  const stuck = new WebSocket(url.replace('http', 'ws'), ['foxglove.websocket.v1']);
  await until(() => stuck.readyState === 1, 5000, 'a client');
  stuck.send(JSON.stringify({ op: 'subscribe', subscriptions: [1, 2, 3, 4, 5].map((c) => ({ id: c, channelId: c })) }));
  await until(() => fs.existsSync(path.join(dirC, TELEMETRY)) &&
    fs.readFileSync(path.join(dirC, TELEMETRY), 'utf8').split('\n').length > 50, 60000, 'the swarm flying');
  stuck._socket.pause();
  run.kill('SIGINT');
  const code = await exited;
  const summary = JSON.parse(fs.readFileSync(path.join(dirC, SUMMARY), 'utf8'));
  check(code === 1 && summary.end_reason === 'interrupted',
    `Ctrl-C with a view open: exit ${code}, end_reason ${summary.end_reason}`);
  const pids = fs.readFileSync(path.join(dirC, 'processes.csv'), 'utf8').trim().split('\n').slice(1)
    .map((l) => Number(l.split(',').pop()));
  const alive = pids.filter((p) => { try { process.kill(p, 0); return true; } catch { return false; } });
  check(pids.length === 9 && alive.length === 0, `no process left of ${pids.length} (${alive.join(',')})`);
  const log = fs.readFileSync(path.join(dirC, 'supervisor.log'), 'utf8');
  check(/live view: \{"connections"/.test(log), 'the view counts are in supervisor.log');
  stuck.terminate();
}

// ---- the replay ----
const view = spawn(swarm, ['view', dir, '--port', '0', '--speed', '2'], { stdio: ['ignore', 'pipe', 'pipe'] });
let said = '';
view.stdout.on('data', (d) => { said += d; });
view.stderr.on('data', (d) => { said += d; });
const viewExit = new Promise((r) => view.on('exit', (c, s) => r(s ? 128 : c)));
process.on('exit', () => view.kill('SIGKILL'));
try {
  const url = (await until(() => (said.match(/open (http:\/\/[0-9.:]+\/)/) || [])[1], 10000, 'the replay to listen'));
  const client = new FoxgloveClient({ ws: new WebSocket(url.replace('http', 'ws'), [FoxgloveClient.SUPPORTED_SUBPROTOCOL]) });
  const msgs = [];
  let channels = null;
  client.on('advertise', (c) => { channels = c; });
  client.on('error', (e) => console.log('client error:', e.message));
  await until(() => channels, 10000, 'advertise');
  const viewCh = channels.find((c) => c.topic === '/swarm/view');
  const sub = client.subscribe(viewCh.id);
  const decoder = new TextDecoder();
  client.on('message', (m) => {
    if (m.subscriptionId === sub) msgs.push(JSON.parse(decoder.decode(m.data)));
  });
  const snap = await until(() => msgs.find((m) => m.type === 'snapshot'), 10000, 'a snapshot');
  check(snap.replay && snap.replay.duration > 0, `a replay: ${JSON.stringify(snap.replay)}`);
  check(snap.run.agents.length === 8, `the run's 8 agents (${snap.run.agents.length})`);
  const duration = snap.replay.duration;
  await until(() => msgs.some((m) => m.type === 'frame' && m.t > 0.5), 10000, 'frames as it plays');
  // Playback control is a text op of its own (the page sends it; Foxglove never does).
  const raw = new WebSocket(url.replace('http', 'ws'), ['foxglove.websocket.v1']);
  await until(() => raw.readyState === 1, 5000, 'a control connection');
  raw.on('message', (d) => { const m = JSON.parse(d); if (m.op === 'status') said += `status: ${m.message}\n`; });
  const send = (o) => raw.send(JSON.stringify({ op: 'qswarmPlayback', ...o }));
  const sent = msgs.length;
  send({ action: 'pause' });
  const paused = await until(() => msgs.slice(sent).find((m) => m.replay && !m.replay.playing), 5000, 'paused');
  const tPaused = paused.replay.t;
  check(tPaused < duration - 0.5, `paused before the end: at ${tPaused} of ${duration} s`);
  // Paused, the server still sends a heartbeat frame each wall second: two of them after the
  // pause span at least a second, and the replay's time must not move in them.
  const from = msgs.indexOf(paused) + 1;
  const beats = await until(() => { const f = msgs.slice(from).filter((m) => m.type === 'frame');
    return f.length >= 2 && f; }, 5000, 'two heartbeats while paused');
  check(beats.every((m) => m.replay && !m.replay.playing && m.replay.t === tPaused),
    `paused: time stays at ${tPaused.toFixed(2)} s (${beats.map((m) => m.replay && m.replay.t)})`);
  msgs.length = 0;
  send({ action: 'seek', t: 0.5 });  // back: a fresh snapshot up to t = 0.5
  const back = await until(() => msgs.find((m) => m.type === 'snapshot'), 5000, 'a snapshot after seeking back');
  check(Math.abs(back.replay.t - 0.5) < 1e-6 && back.metrics.every((r) => r[0] <= 0.5 + 1e-9),
    `seek back to 0.5 s: ${back.metrics.length} metrics, none later`);
  send({ action: 'speed', speed: 10 });
  send({ action: 'play' });
  const end = await until(() => msgs.find((m) => m.summary), 30000, 'the end of the replay');
  check(end.summary.converged === true, `the replay ends as the run did: converged (${end.summary.end_reason})`);
  const final = await until(() => msgs.slice().reverse().find((m) => m.replay && !m.replay.playing), 5000, 'paused at the end');
  check(Math.abs(final.replay.t - duration) < 1e-6, `paused at the end, ${final.replay.t} of ${duration} s`);
  send({ action: 'speed', speed: -3 });
  const refused = await until(() => /status: .*speed/.test(said), 5000, 'a refused speed')
    .then(() => true, () => false);
  check(refused, `a bad speed from a client is refused with a status (${said.trim()})`);
  raw.close();
  client.close();
} catch (e) {
  check(false, e.message);
  console.log(said);
}
view.kill('SIGINT');
const code = await viewExit;
check(code === 0, `swarm view stops on Ctrl-C with exit 0 (${code})`);
finish();
