// The quadswarm live view: a Foxglove WebSocket client (sub-protocol foxglove.websocket.v1) that
// subscribes to the server's /swarm/view channel, whose JSON messages are a snapshot of the run
// and then, up to 20 times a second, what changed. It draws the swarm with three.js and the graph's
// metrics with uPlot, both served by the view server from npm's packages (no CDN).
import * as THREE from '/lib/three.module.min.js';
import uPlot from '/lib/uPlot.esm.js';

const $ = (id) => document.getElementById(id);
const FAULT_START = { cut: 'cut_end', partition: 'heal', loss: 'loss_end' };
const FAULT_END = new Set(Object.values(FAULT_START));
const PRESENCE = new Set(['join', 'rejoin', 'depart', 'kill', 'restart', 'late_join']);

// What the browser test and a curious user can read (window.qswarm).
const stats = {
  connected: false, frames: 0, snapshots: 0, agentsDrawn: 0, linksDrawn: 0, metricPoints: 0,
  events: 0, latencyMs: [], lastLatencyMs: null, renders: 0, ended: null, subprotocol: null,
  t: null,  // the swarm time of the newest frame or snapshot [s]
};
window.qswarm = stats;

// ---- the run's state, as the frames tell it ----
let run = null;          // run info: name, agents (start, offset), initial average, formation
const agents = new Map(); // id -> {p:[x,y,z], q:[w,x,y,z], c:[x,y,z], present, t}
let graph = null;        // newest graph snapshot
const metrics = [[], [], [], [], []];  // t, lambda2, disagreement, drift, min separation
const faultWindows = []; // {kind, from, to (null while open)}
const marks = [];        // {t, kind, agent}
let replay = null;
let dirty = true, chartsDirty = true;

// ---- 3D ----
const container = $('scene');
const renderer = new THREE.WebGLRenderer({ antialias: false });
renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
container.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x11151c);
const camera = new THREE.PerspectiveCamera(45, 1, 0.1, 5000);
camera.up.set(0, 0, 1);  // the scenarios' z is up
scene.add(new THREE.HemisphereLight(0xffffff, 0x334455, 2.2));
const sun = new THREE.DirectionalLight(0xffffff, 1.2);
sun.position.set(30, -20, 60);
scene.add(sun);
let grid = null;

const MAX = 512;  // the most agents a run may have
const bodyColor = new THREE.Color(0x4fc3f7), goneColor = new THREE.Color(0x555555);
function instanced(geometry, color) {
  const m = new THREE.InstancedMesh(geometry, new THREE.MeshStandardMaterial({ color }), MAX);
  m.count = 0;
  m.instanceMatrix.setUsage(THREE.DynamicDrawUsage);
  scene.add(m);
  return m;
}
// A quadcopter: two crossed arms (the paper's d = 0.25 m, drawn larger), a hub, and a nose on the
// body's x axis (its heading).
const armX = instanced(new THREE.BoxGeometry(1.0, 0.08, 0.05), 0xffffff);
const armY = instanced(new THREE.BoxGeometry(0.08, 1.0, 0.05), 0xffffff);
const hub = instanced(new THREE.SphereGeometry(0.16, 8, 6), 0xffffff);
const noseGeom = new THREE.ConeGeometry(0.1, 0.45, 10).rotateZ(-Math.PI / 2).translate(0.6, 0, 0);
const nose = instanced(noseGeom, 0xff7043);
const slotMesh = instanced(new THREE.SphereGeometry(0.22, 6, 4), 0x9ccc65);
slotMesh.material.wireframe = true;
const stateMesh = instanced(new THREE.OctahedronGeometry(0.12), 0xce93d8);  // consensus states

const linkGeom = new THREE.BufferGeometry();
linkGeom.setAttribute('position', new THREE.BufferAttribute(new Float32Array(MAX * 40 * 6), 3));
linkGeom.setAttribute('color', new THREE.BufferAttribute(new Float32Array(MAX * 40 * 6), 3));
const links = new THREE.LineSegments(linkGeom, new THREE.LineBasicMaterial({ vertexColors: true }));
scene.add(links);

const avgMarker = new THREE.Mesh(new THREE.OctahedronGeometry(0.5),
  new THREE.MeshStandardMaterial({ color: 0xffd54f, wireframe: true }));
const meanMarker = new THREE.Mesh(new THREE.SphereGeometry(0.3, 16, 10),
  new THREE.MeshStandardMaterial({ color: 0xffffff, transparent: true, opacity: 0.7 }));
scene.add(avgMarker, meanMarker);

let scale = 1;  // how much larger than life the quadcopters are drawn
const tmpM = new THREE.Matrix4(), tmpQ = new THREE.Quaternion(), tmpP = new THREE.Vector3();
const tmpS = new THREE.Vector3();

function weightColor(f) {  // 0 weak (blue) .. 1 strong (red)
  const c = new THREE.Color();
  if (f < 0.5) c.lerpColors(new THREE.Color(0x3b6fd8), new THREE.Color(0xe0b030), f * 2);
  else c.lerpColors(new THREE.Color(0xe0b030), new THREE.Color(0xe53935), (f - 0.5) * 2);
  return c;
}

function frameScene() {
  // The camera looks at the initial average from far enough to see every start.
  const pts = run.agents.map((a) => a.start);
  const c = run.initial_average;
  let r = 5;
  for (const p of pts) r = Math.max(r, Math.hypot(p[0] - c[0], p[1] - c[1], p[2] - c[2]));
  scale = Math.max(1, r / 12);
  camera.position.set(c[0] + r * 1.6, c[1] - r * 1.9, c[2] + r * 1.3);
  camera.lookAt(c[0], c[1], c[2]);
  camera.far = r * 20;
  camera.updateProjectionMatrix();
  if (grid) scene.remove(grid);
  const size = Math.ceil(r * 3 / 5) * 5;
  grid = new THREE.GridHelper(size, Math.min(60, size), 0x2c3544, 0x202733);
  grid.rotateX(Math.PI / 2);
  const minZ = Math.min(0, ...pts.map((p) => p[2]));
  grid.position.set(c[0], c[1], minZ);
  scene.add(grid);
  avgMarker.position.set(c[0], c[1], c[2]);
  avgMarker.scale.setScalar(scale);
}

function updateScene() {
  const list = [...agents.entries()].sort((a, b) => a[0] - b[0]);
  let i = 0;
  const mean = [0, 0, 0];
  let n = 0;
  for (const [, a] of list) {
    if (i >= MAX) break;
    tmpP.set(a.p[0], a.p[1], a.p[2]);
    tmpQ.set(a.q[1], a.q[2], a.q[3], a.q[0]);  // the record's order is w, x, y, z
    tmpS.setScalar(scale);
    tmpM.compose(tmpP, tmpQ, tmpS);
    for (const m of [armX, armY, hub, nose]) m.setMatrixAt(i, tmpM);
    const col = a.present ? bodyColor : goneColor;
    hub.setColorAt(i, col);
    armX.setColorAt(i, col);
    armY.setColorAt(i, col);
    tmpM.compose(new THREE.Vector3(a.c[0], a.c[1], a.c[2]), new THREE.Quaternion(), tmpS);
    stateMesh.setMatrixAt(i, tmpM);
    if (a.present) {
      mean[0] += a.c[0]; mean[1] += a.c[1]; mean[2] += a.c[2];
      ++n;
    }
    ++i;
  }
  for (const m of [armX, armY, hub, nose, stateMesh]) {
    m.count = i;
    m.instanceMatrix.needsUpdate = true;
    if (m.instanceColor) m.instanceColor.needsUpdate = true;
  }
  stats.agentsDrawn = i;
  if (n) {
    for (let k = 0; k < 3; ++k) mean[k] /= n;
    meanMarker.position.set(mean[0], mean[1], mean[2]);
    meanMarker.scale.setScalar(scale);
    meanMarker.visible = true;
  } else {
    meanMarker.visible = false;
  }
  // Formation slots: the consensus mean plus each agent's offset.
  let s = 0;
  if (run && run.formation && n) {
    for (const a of run.agents) {
      const o = a.offset;
      tmpM.compose(new THREE.Vector3(mean[0] + o[0], mean[1] + o[1], mean[2] + o[2]),
        new THREE.Quaternion(), tmpS);
      slotMesh.setMatrixAt(s++, tmpM);
      if (s >= MAX) break;
    }
  }
  slotMesh.count = s;
  slotMesh.instanceMatrix.needsUpdate = true;
  // Links, coloured by weight relative to the strongest.
  const pos = linkGeom.attributes.position.array, colr = linkGeom.attributes.color.array;
  let e = 0;
  if (graph) {
    let wmax = 0;
    for (const [, , w] of graph.edges) wmax = Math.max(wmax, w);
    for (const [a, b, w] of graph.edges) {
      const pa = agents.get(a), pb = agents.get(b);
      if (!pa || !pb || (e + 1) * 6 > pos.length) continue;
      pos.set([...pa.p, ...pb.p], e * 6);
      const c = weightColor(wmax > 0 ? w / wmax : 1);
      colr.set([c.r, c.g, c.b, c.r, c.g, c.b], e * 6);
      ++e;
    }
    $('legend').innerHTML =
      '<span class="swatch" style="background:#4fc3f7"></span>quadcopter (nose: heading)' +
      '<span class="swatch" style="background:#ce93d8"></span>consensus state' +
      '<span class="swatch" style="background:#ffd54f"></span>initial average' +
      '<span class="swatch" style="background:#fff"></span>agreement (mean)' +
      (run && run.formation ? '<span class="swatch" style="background:#9ccc65"></span>slot' : '') +
      `<br>links: ${graph.edges.length}, weight <span class="gradient"></span> ` +
      `0 to ${wmax.toPrecision(3)}`;
  }
  linkGeom.setDrawRange(0, e * 2);
  linkGeom.attributes.position.needsUpdate = true;
  linkGeom.attributes.color.needsUpdate = true;
  linkGeom.computeBoundingSphere();
  stats.linksDrawn = e;
}

function resize() {
  const w = container.clientWidth, h = container.clientHeight;
  renderer.setSize(w, h);
  camera.aspect = w / Math.max(1, h);
  camera.updateProjectionMatrix();
}
window.addEventListener('resize', () => { resize(); dirty = true; });

// Drag to orbit about the initial average, wheel to zoom.
let drag = null;
renderer.domElement.addEventListener('pointerdown', (e) => { drag = { x: e.clientX, y: e.clientY }; });
window.addEventListener('pointerup', () => { drag = null; });
window.addEventListener('pointermove', (e) => {
  if (!drag || !run) return;
  const c = new THREE.Vector3(...run.initial_average);
  const off = camera.position.clone().sub(c);
  off.applyAxisAngle(new THREE.Vector3(0, 0, 1), -(e.clientX - drag.x) * 0.005);
  const side = new THREE.Vector3().crossVectors(off, camera.up).normalize();
  off.applyAxisAngle(side, -(e.clientY - drag.y) * 0.005);
  camera.position.copy(c.clone().add(off));
  camera.lookAt(c);
  drag = { x: e.clientX, y: e.clientY };
  dirty = true;
});
renderer.domElement.addEventListener('wheel', (e) => {
  if (!run) return;
  const c = new THREE.Vector3(...run.initial_average);
  const off = camera.position.clone().sub(c).multiplyScalar(e.deltaY > 0 ? 1.1 : 0.9);
  camera.position.copy(c.clone().add(off));
  dirty = true;
  e.preventDefault();
}, { passive: false });

// ---- charts ----
function bandsPlugin() {
  // Fault windows shaded, presence changes as thin lines.
  return {
    hooks: {
      draw: (u) => {
        const ctx = u.ctx, top = u.bbox.top, h = u.bbox.height;
        ctx.save();
        ctx.fillStyle = 'rgba(255,152,0,0.16)';
        const xmax = u.scales.x.max;
        for (const w of faultWindows) {
          const x0 = u.valToPos(w.from, 'x', true);
          const x1 = u.valToPos(w.to === null ? xmax : w.to, 'x', true);
          ctx.fillRect(x0, top, Math.max(1, x1 - x0), h);
        }
        ctx.strokeStyle = 'rgba(129,212,250,0.6)';
        for (const m of marks) {
          const x = u.valToPos(m.t, 'x', true);
          ctx.beginPath(); ctx.moveTo(x, top); ctx.lineTo(x, top + h); ctx.stroke();
        }
        ctx.restore();
      },
    },
  };
}
const charts = [];
function makeChart(id, title, label, color, log) {
  const el = $(id);
  const u = new uPlot({
    title, width: 420, height: 150, plugins: [bandsPlugin()],
    scales: { x: { time: false }, y: log ? { distr: 3, log: 10 } : {} },
    axes: [{ stroke: '#aab', grid: { stroke: '#2a3140' } },
      { stroke: '#aab', grid: { stroke: '#2a3140' }, size: 56,
        values: log ? (u, vals) => vals.map((v) => (v == null ? '' : v.toExponential(0)))
          : (u, vals) => vals.map((v) => (v == null ? '' : +v.toPrecision(3))) }],
    series: [{ label: 't (s)' }, { label, stroke: color, width: 1.5 }],
    legend: { show: false },
  }, [[], []], el);
  charts.push({ u, index: charts.length + 1, log });
}
makeChart('chart-lambda2', 'lambda_2 (algebraic connectivity)', 'lambda_2', '#4fc3f7', false);
makeChart('chart-disagreement', 'disagreement (m)', 'disagreement', '#ef5350', true);
makeChart('chart-drift', 'drift from the initial average (m)', 'drift', '#ffd54f', true);
makeChart('chart-separation', 'smallest separation (m)', 'min separation', '#9ccc65', false);

function updateCharts() {
  for (const c of charts) {
    let ys = metrics[c.index];
    // A log axis shows no zero: the smallest positive number stands in for exact agreement.
    if (c.log) ys = ys.map((v) => (v === null || v > 0 ? v : 1e-12));
    c.u.setData([metrics[0], ys]);
  }
  stats.metricPoints = metrics[0].length;
}

// ---- frames ----
function setAgent(row) {
  const [id, p, q, c, present, t] = row;
  agents.set(id, { p, q, c, present, t });
}

function addEvent(e) {
  stats.events++;
  if (FAULT_START[e.kind]) faultWindows.push({ kind: e.kind, end: FAULT_START[e.kind], from: e.t, to: null, agent: e.agent });
  if (FAULT_END.has(e.kind)) {
    const w = faultWindows.find((f) => f.to === null && f.end === e.kind);
    if (w) w.to = e.t;
  }
  if (PRESENCE.has(e.kind)) {
    marks.push({ t: e.t, kind: e.kind, agent: e.agent });
    const a = agents.get(e.agent);
    if (a && e.kind === 'depart') a.present = false;
    if (a && (e.kind === 'join' || e.kind === 'rejoin')) a.present = true;
  }
  const li = document.createElement('li');
  li.className = FAULT_START[e.kind] || FAULT_END.has(e.kind) ? 'fault'
    : PRESENCE.has(e.kind) ? 'presence'
      : e.kind === 'converged' ? 'good' : e.kind === 'end' ? 'end' : '';
  li.textContent = `${e.t.toFixed(2)} s  ${e.kind}${e.agent ? ' agent ' + e.agent : ''}` +
    (e.detail ? `: ${e.detail}` : '');
  const list = $('events');
  list.appendChild(li);
  while (list.children.length > 500) list.removeChild(list.firstChild);
  list.scrollTop = list.scrollHeight;
}

function showEnd(s) {
  const el = $('end');
  if (!s) { el.className = 'hidden'; stats.ended = null; return; }
  stats.ended = { converged: s.converged, reason: s.end_reason };
  const q = (v) => (Array.isArray(v) ? v.map((x) => x.toFixed(3)).join(', ') : '');
  if (s.converged) {
    el.className = 'ok';
    el.textContent = `Converged at t = ${Number(s.convergence_time_s).toFixed(2)} s: ` +
      `agreed on (${q(s.final_consensus_mean)}), ${Number(s.average_drift_m).toExponential(2)} m ` +
      `from the initial average; smallest separation ${Number(s.min_separation_m).toFixed(2)} m.`;
  } else {
    el.className = 'bad';
    el.textContent = `Not converged: ${s.end_reason}` +
      (s.missing_agents && s.missing_agents.length ? ` (missing agents ${s.missing_agents.join(', ')})` : '') +
      `. Final disagreement ${Number(s.final_disagreement_m).toExponential(2)} m.`;
  }
}

function setReplay(r) {
  replay = r;
  $('replay').classList.toggle('hidden', !r);
  if (!r) return;
  $('conn').textContent = 'replay';
  $('conn').className = 'pill replay';
  const scrub = $('scrub');
  scrub.max = r.duration;
  if (!scrubbing) scrub.value = r.t;
  $('play').innerHTML = r.playing ? '&#9646;&#9646;' : '&#9654;';
  const speed = $('speed');
  if (![...speed.options].some((o) => Number(o.value) === r.speed)) speed.add(new Option(`${r.speed}x`, r.speed));
  speed.value = String(r.speed);
  $('replay-t').textContent = `${r.t.toFixed(1)} / ${r.duration.toFixed(1)} s`;
  $('replay-note').textContent = r.note || '';
}

function onSnapshot(m) {
  stats.snapshots++;
  const first = !run;
  run = m.run;
  agents.clear();
  for (const row of m.agents) setAgent(row);
  graph = m.graph;
  for (const a of metrics) a.length = 0;
  for (const row of m.metrics) row.forEach((v, k) => metrics[k].push(v));
  faultWindows.length = 0;
  marks.length = 0;
  $('events').innerHTML = '';
  for (const e of m.events) addEvent(e);
  showEnd(m.summary);
  setReplay(m.replay);
  $('title').textContent = `quadswarm: ${run.name} (${run.mode}, ${run.law}, ` +
    `${run.agents.length} agents${run.formation ? ', formation' : ''})`;
  if (first) { resize(); frameScene(); }
  dirty = true;
  onTime(m.t);
  dirty = chartsDirty = true;
}

let framesThisSecond = 0, fps = 0;
setInterval(() => { fps = framesThisSecond; framesThisSecond = 0; }, 1000);

function onFrame(m) {
  stats.frames++;
  framesThisSecond++;
  for (const row of m.agents) setAgent(row);
  if (m.graph) graph = m.graph;
  if (m.metrics) for (const row of m.metrics) row.forEach((v, k) => metrics[k].push(v));
  for (const e of m.events) addEvent(e);
  if (m.summary) showEnd(m.summary);
  if (m.replay) setReplay(m.replay);
  if (m.pub_ms > 0 && m.agents.length && !replay) {
    // From the newest sample's publication by its agent to this page (one host, one clock).
    const lat = Date.now() - m.pub_ms;
    stats.lastLatencyMs = lat;
    stats.latencyMs.push(lat);
    if (stats.latencyMs.length > 2000) stats.latencyMs.shift();
  }
  onTime(m.t);
  dirty = true;
  if (m.metrics || m.events.length) chartsDirty = true;
}

function onTime(t) {
  stats.t = t;
  $('clock').textContent = `t = ${t.toFixed(2)} s`;
  const present = [...agents.values()].filter((a) => a.present).length;
  const expected = run ? run.agents.length : 0;
  $('counts').textContent = `agents ${present}/${expected}` +
    (graph ? `  edges ${graph.edges.length}  lambda_2 ${Number(graph.lambda2).toPrecision(4)}` +
      `  disagreement ${Number(graph.disagreement).toExponential(2)} m` : '');
}

function median(xs) {
  if (!xs.length) return null;
  const s = [...xs].sort((a, b) => a - b);
  return s[Math.floor(s.length / 2)];
}

let lastCharts = 0;
function animate(now) {
  requestAnimationFrame(animate);
  if (!run) return;
  if (chartsDirty && now - lastCharts > 500) {  // charts at 2 Hz: their redraw is the page's cost
    updateCharts();
    chartsDirty = false;
    lastCharts = now;
  }
  if (dirty) {  // the scene is drawn when something moved, not every animation frame
    updateScene();
    dirty = false;
    renderer.render(scene, camera);
    stats.renders++;
  }
  const med = median(stats.latencyMs.slice(-100));
  $('perf').textContent = `${fps} frames/s` + (med !== null ? `, latency ${med.toFixed(0)} ms` : '');
}
requestAnimationFrame(animate);

// ---- the connection: Foxglove's WebSocket protocol ----
let ws = null, viewChannel = null;
const decoder = new TextDecoder();
function connect() {
  const url = `ws://${location.host}/`;
  ws = new WebSocket(url, ['foxglove.websocket.v1']);
  ws.binaryType = 'arraybuffer';
  ws.onopen = () => {
    stats.connected = true;
    stats.subprotocol = ws.protocol;
    if (!replay) { $('conn').textContent = 'live'; $('conn').className = 'pill live'; }
  };
  ws.onclose = () => {
    stats.connected = false;
    viewChannel = null;
    if (!replay) {
      $('conn').textContent = stats.ended ? 'run over' : 'disconnected';
      $('conn').className = stats.ended ? 'pill' : 'pill lost';
    }
    setTimeout(connect, 2000);  // the run may be over; a replay server may come back
  };
  ws.onmessage = (ev) => {
    if (typeof ev.data === 'string') {
      const msg = JSON.parse(ev.data);
      if (msg.op === 'advertise') {
        const ch = msg.channels.find((c) => c.topic === '/swarm/view');
        if (ch && viewChannel === null) {
          viewChannel = ch.id;
          ws.send(JSON.stringify({ op: 'subscribe', subscriptions: [{ id: 1, channelId: ch.id }] }));
        }
      } else if (msg.op === 'status' && msg.level >= 2) {
        console.warn('server:', msg.message);
      }
      return;
    }
    const dv = new DataView(ev.data);
    if (dv.getUint8(0) !== 1) return;  // only message data
    const m = JSON.parse(decoder.decode(new Uint8Array(ev.data, 13)));
    if (m.type === 'snapshot') onSnapshot(m);
    else if (m.type === 'frame' && run) onFrame(m);
  };
}
connect();

// ---- replay controls (a replay only; a live run ignores nothing because it gets none) ----
let scrubbing = false;
function control(action, extra) {
  if (ws && ws.readyState === 1) ws.send(JSON.stringify({ op: 'qswarmPlayback', action, ...extra }));
}
$('play').addEventListener('click', () => control(replay && replay.playing ? 'pause' : 'play'));
$('scrub').addEventListener('input', () => { scrubbing = true; });
$('scrub').addEventListener('change', (e) => {
  scrubbing = false;
  control('seek', { t: Number(e.target.value) });
});
$('speed').addEventListener('change', (e) => control('speed', { speed: Number(e.target.value) }));
