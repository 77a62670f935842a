// The compose swarm's live view, seen from the host (compose_test.sh runs this while the swarm
// flies with docker/view.yml): the page and its npm libraries over the published loopback port,
// then npm's Foxglove client subscribes through the relay and decodes samples of all N agents.
//
// Usage: node view_check.mjs URL N   (QSWARM_NODE_MODULES: node/node_modules)
import { check, finish, npm, until } from '../view/harness.mjs';

const [url, nArg] = process.argv.slice(2);
const n = Number(nArg);
const { FoxgloveClient } = npm('@foxglove/ws-protocol');
const WebSocket = npm('ws');
const protobuf = npm('protobufjs');
const descriptor = npm('protobufjs/ext/descriptor');

async function get(path) {
  try {
    const res = await fetch(new URL(path, url));
    return { status: res.status, body: await res.text() };
  } catch (e) {
    return null;  // the relay is up before the supervisor listens: try again
  }
}
const page = await until(async () => { const r = await get('/'); return r && r.status === 200 && r; },
  60000, `the page at ${url}`);
check(page.body.includes('/view.js'), 'the page is served through the relay');
for (const lib of ['/view.js', '/lib/three.module.min.js', '/lib/uPlot.esm.js']) {
  const r = await get(lib);
  check(r && r.status === 200 && r.body.length > 1000, `${lib} served from the image (${r && r.status})`);
}

const client = new FoxgloveClient({
  ws: new WebSocket(url.replace('http://', 'ws://'), [FoxgloveClient.SUPPORTED_SUBPROTOCOL]) });
let channels = null;
const ids = new Set();
client.on('advertise', (c) => { channels = c; });
client.on('error', (e) => console.log('client error:', e.message));
await until(() => channels, 20000, 'advertised channels');
const ch = channels.find((c) => c.topic === '/swarm/agents');
check(ch && ch.schemaName === 'qswarm.records.AgentSample', 'agent samples advertised');
const root = protobuf.Root.fromDescriptor(
  descriptor.FileDescriptorSet.decode(Buffer.from(ch.schema, 'base64')));
const Sample = root.lookupType(ch.schemaName);
const sub = client.subscribe(ch.id);
client.on('message', (m) => {
  if (m.subscriptionId !== sub) return;
  const s = Sample.decode(new Uint8Array(m.data.buffer, m.data.byteOffset, m.data.byteLength));
  if (s.position.length === 3 && s.position.every(Number.isFinite)) ids.add(s.id);
});
await until(() => ids.size === n, 60000, `samples of all ${n} agents`).catch((e) => console.log(e.message));
check(ids.size === n, `decoded samples of agents ${[...ids].sort((a, b) => a - b).join(',')} (want ${n})`);
client.close();
finish();
