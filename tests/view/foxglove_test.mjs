// Foxglove's WebSocket protocol during a real run (`swarm run --view`): npm's @foxglove/ws-protocol
// client subscribes to the agent samples and decodes them with the schema the server advertised
// (a protobuf FileDescriptorSet, read by protobufjs). Beside it, hostile clients: one that never
// reads, malformed, binary and oversized frames, a flood of subscribe requests, a WebSocket
// without the sub-protocol, and more connections than the server takes. The run still converges
// and the good client keeps getting samples; the server counts what it refused.
import fs from 'node:fs';
import net from 'node:net';
import path from 'node:path';
import { check, finish, freshDir, npm, startRun, until, getJson } from './harness.mjs';

const { FoxgloveClient } = npm('@foxglove/ws-protocol');
const WebSocket = npm('ws');
const protobuf = npm('protobufjs');
const descriptor = npm('protobufjs/ext/descriptor');

// Eight point agents on the complete graph with a slow gain: about 25 s of agreement, long enough
// for the hostile clients to do their worst while it flies.
const scenario = path.join(freshDir('view-foxglove-scenario') + '.txtpb');
fs.writeFileSync(scenario, `name: "view_foxglove"
random_agents { count: 8 box_m: 20 }
mode: PARTICLE
law: EDGE_FLOW
gain: 0.05
weight { policy: UNWEIGHTED }
topology { policy: PROXIMITY threshold_m: 100 }
convergence { tolerance_m: 0.001 hold_s: 1 }
duration_s: 120
seed: 11
`);
const run = await startRun('view-foxglove', [scenario, '--quiet']);
const wsUrl = run.url.replace('http://', 'ws://');
try {
  // ---- a Foxglove client ----
  const client = new FoxgloveClient({ ws: new WebSocket(wsUrl, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]) });
  let serverInfo = null, channels = null;
  const samples = [];
  client.on('serverInfo', (m) => { serverInfo = m; });
  client.on('advertise', (c) => { channels = c; });
  client.on('error', (e) => console.log('client error:', e.message));
  await until(() => serverInfo && channels, 10000, 'serverInfo and advertise');
  check(serverInfo.capabilities.length === 0, 'serverInfo: no capability (a read-only server)');
  const ch = channels.find((c) => c.topic === '/swarm/agents');
  check(ch && ch.encoding === 'protobuf' && ch.schemaEncoding === 'protobuf' &&
    ch.schemaName === 'qswarm.records.AgentSample', `agent samples advertised: ${JSON.stringify(ch && { ...ch, schema: '...' })}`);
  const set = descriptor.FileDescriptorSet.decode(Buffer.from(ch.schema, 'base64'));
  const root = protobuf.Root.fromDescriptor(set);
  const Sample = root.lookupType(ch.schemaName);
  const sub = client.subscribe(ch.id);
  client.on('message', (m) => {
    if (m.subscriptionId !== sub) return;
    const bytes = new Uint8Array(m.data.buffer, m.data.byteOffset, m.data.byteLength);
    samples.push({ t: m.timestamp, s: Sample.toObject(Sample.decode(bytes), { defaults: true, longs: Number }) });
  });
  const ids = () => new Set(samples.map((x) => x.s.id));
  await until(() => ids().size === 8 && samples.some((x) => x.s.stamp_s > 0), 60000,
    'samples of all 8 agents, running');
  const s = samples.filter((x) => x.s.stamp_s > 0).pop();
  check(ids().size === 8, `decoded samples of agents ${[...ids()].sort((a, b) => a - b).join(',')}`);
  check(s.s.position.length === 3 && s.s.position.every(Number.isFinite), `a sample's position ${s.s.position}`);
  check(samples.every((x) => x.t === BigInt(Math.round(x.s.stamp_s * 1e9))),
    `log times are the samples' stamps in ns (${s.t} ns for ${s.s.stamp_s} s)`);

  // The 3D scene: foxglove.SceneUpdate as JSON, the whole swarm in each message.
  const sceneCh = channels.find((c) => c.topic === '/swarm/scene');
  check(sceneCh && sceneCh.encoding === 'json' && sceneCh.schemaName === 'foxglove.SceneUpdate',
    'the scene channel is advertised');
  const sceneSub = client.subscribe(sceneCh.id);
  let scene = null;
  const onScene = (m) => {
    if (m.subscriptionId === sceneSub) scene = JSON.parse(new TextDecoder().decode(m.data));
  };
  client.on('message', onScene);
  await until(() => scene, 10000, 'a scene update');
  const agentsInScene = scene.entities.filter((e) => e.id.startsWith('agent/')).length;
  check(agentsInScene === 8 && scene.entities.some((e) => e.id === 'links'),
    `the scene draws 8 agents and the links (${scene.entities.length} entities)`);
  client.unsubscribe(sceneSub);

  // foxglove.sdk.v1 (newer Foxglove) is accepted too.
  const sdk = new WebSocket(wsUrl, ['foxglove.sdk.v1']);
  await until(() => sdk.readyState === 1, 5000, 'an sdk.v1 connection');
  check(sdk.protocol === 'foxglove.sdk.v1', `sub-protocol foxglove.sdk.v1 accepted (${sdk.protocol})`);
  sdk.close();

  // ---- hostile clients ----
  // One that subscribes to everything, then never reads.
  const stuck = new WebSocket(wsUrl, ['foxglove.websocket.v1']);
  let stuckGot = 0;
  stuck.on('message', (data, binary) => { if (binary) ++stuckGot; });
  await until(() => stuck.readyState === 1, 5000, 'the stuck client');
  stuck.send(JSON.stringify({ op: 'subscribe', subscriptions: [1, 2, 3, 4].map((c) => ({ id: c, channelId: c })) }));
  await until(() => stuckGot > 0, 10000, 'the stuck client subscribed (its first message)');
  stuck._socket.pause();  // its receive buffer fills; the server's queue for it fills next
  // Malformed, binary and oversized frames.
  const bad = new WebSocket(wsUrl, ['foxglove.websocket.v1']);
  await until(() => bad.readyState === 1, 5000, 'the malformed client');
  bad.send('not json');
  bad.send('{"op":"subscribe","subscriptions":[{"id":-1,"channelId":2}]}');
  bad.send(Buffer.from([1, 2, 3, 4]));
  bad.send(JSON.stringify({ op: 'advertise', channels: [{ id: 1, topic: '/cmd', encoding: 'json', schemaName: 'x' }] }));
  bad.send('x'.repeat(100000));  // above the 64 KiB a client frame may have: the session ends
  await until(() => bad.readyState === 3, 5000, 'the oversized frame to end its session');
  // A flood of subscribe requests.
  const flood = new WebSocket(wsUrl, ['foxglove.websocket.v1']);
  await until(() => flood.readyState === 1, 5000, 'the flooding client');
  for (let k = 0; k < 3000 && flood.readyState === 1; ++k)
    flood.send(JSON.stringify({ op: 'subscribe', subscriptions: [{ id: k, channelId: 1 + (k % 4) }] }));
  await until(() => flood.readyState === 3, 10000, 'the flood to be cut off');
  // A WebSocket without the sub-protocol.
  const plain = new WebSocket(wsUrl);
  const plainErr = await new Promise((r) => { plain.on('error', (e) => r(e.message)); plain.on('open', () => r('opened')); });
  check(/400/.test(plainErr), `a WebSocket without the sub-protocol is refused (${plainErr})`);
  // More connections than the server takes (64) that never send a request: past the limit each new
  // one takes the place of the oldest such one, and the subscribed clients stay.
  const sockets = [];
  for (let k = 0; k < 80; ++k) sockets.push(net.connect(Number(new URL(run.url).port), '127.0.0.1'));
  await until(async () => (await getJson(`${run.url}stats`)).evicted > 0, 20000,
    'held connections to make room for new ones');
  for (const so of sockets) so.destroy();

  // The good client still gets samples, newer ones.
  const before = samples.length;
  await until(() => samples.length > before + 16, 20000, 'new samples after the hostile clients');
  check(samples.length > before + 16, `the Foxglove client kept receiving (${samples.length - before} more samples)`);
  const stats = await until(async () => {
    const st = await getJson(`${run.url}stats`);
    return st.frames_dropped > 0 ? st : null;
  }, 60000, 'frames dropped for the stuck client').catch(async () => getJson(`${run.url}stats`));
  console.log('server counts:', JSON.stringify(stats));
  check(stats.frames_dropped > 0, `frames dropped for the client that never reads: ${stats.frames_dropped}`);
  // Exactly what the malformed client sent: two malformed frames, one oversized; refused ops are
  // its two (binary, advertise) and however many of the flood's came before it was cut off.
  check(stats.malformed === 2, `malformed frames counted: ${stats.malformed}`);
  check(stats.oversized === 1, `oversized frames counted: ${stats.oversized}`);
  check(stats.refused_ops >= 2, `refused ops (binary, advertise, the flood's) counted: ${stats.refused_ops}`);
  check(stats.flooded > 0 && stats.closed_for_abuse >= 1, `the flood refused (${stats.flooded}) and cut off`);
  check(stats.refused_upgrades >= 1, `upgrades without the sub-protocol refused: ${stats.refused_upgrades}`);
  check(stats.evicted > 0 && stats.refused_connections === 0,
    `held connections made room, none refused (${stats.evicted} closed, ${stats.refused_connections} refused)`);
  stuck.terminate();
  client.close();
} catch (e) {
  check(false, e.message);
  console.log(run.output());
}
const exit = await run.done;
check(exit === 0, `the run converged with its view under attack (swarm run exited ${exit})`);
finish();
