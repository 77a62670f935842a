// Reads an MCAP file with Foxglove's own reader (npm @mcap/core: an implementation independent of
// the project's writer) and checks it against the run's records.pb.
//
//   node validate.mjs --modules NODE_MODULES FILE [--records RECORDS_PB] [--truncated]
//
// A complete file: the indexed reader opens it through its summary (footer, summary CRC), reads
// every message in log-time order with chunk CRCs checked; the streamed reader reads it from end to
// end; the data section's CRC matches; both readers and the Statistics record count the same
// messages per channel; scene messages are JSON SceneUpdates; with --records, the counts per
// channel are those of records.pb (samples, snapshots, events; one scene per snapshot) and the last
// event is the run's "end", and the samples, snapshots and events are records.pb's, byte for byte.
// With --truncated: the indexed reader must refuse the file, the streamed reader must not reach
// its end, and what it recovers must be records.pb's records, in order, as far as both go.
// Prints one JSON line of what it found; exits 0 when every check passed, else 1 naming them.
import { createRequire } from "node:module";
import { open, readFile } from "node:fs/promises";
import path from "node:path";

const args = process.argv.slice(2);
const flag = (name) => {
  const i = args.indexOf(name);
  if (i < 0) return undefined;
  const v = args[i + 1];
  args.splice(i, 2);
  return v;
};
const modules = flag("--modules");
const recordsPath = flag("--records");
const truncated = args.includes("--truncated");
const file = args.filter((a) => a !== "--truncated")[0];
if (!modules || !file) {
  console.error("usage: node validate.mjs --modules NODE_MODULES FILE [--records RECORDS_PB] [--truncated]");
  process.exit(2);
}
const require = createRequire(path.join(path.resolve(modules), "_"));
const { McapIndexedReader, McapStreamReader } = require("@mcap/core");
const { crc32 } = require("@foxglove/crc");

const failures = [];
const check = (ok, what) => {
  if (!ok) failures.push(what);
};
const found = { file };

// records.pb: varint length, then a Record whose one field (1 sample, 2 graph, 3 event) says what
// it is. Read here from the bytes, not through the project's code.
function readVarint(buf, at) {
  let v = 0;
  let shift = 0;
  for (;;) {
    if (at >= buf.length) return undefined;
    const b = buf[at++];
    v += (b & 0x7f) * 2 ** shift;
    if (!(b & 0x80)) return [v, at];
    shift += 7;
  }
}
function decodeFields(buf) {
  // Top-level fields of a protobuf message: number -> last value (varint or bytes).
  const out = new Map();
  let at = 0;
  while (at < buf.length) {
    const tag = readVarint(buf, at);
    if (!tag) break;
    at = tag[1];
    const [field, wire] = [Math.floor(tag[0] / 8), tag[0] % 8];
    if (wire === 0) {
      const v = readVarint(buf, at);
      out.set(field, v[0]);
      at = v[1];
    } else if (wire === 2) {
      const len = readVarint(buf, at);
      out.set(field, buf.subarray(len[1], len[1] + len[0]));
      at = len[1] + len[0];
    } else if (wire === 1) {
      at += 8;
    } else if (wire === 5) {
      at += 4;
    } else {
      break;
    }
  }
  return out;
}
async function recordCounts(p) {
  const buf = await readFile(p);
  const counts = { "/swarm/agents": 0, "/swarm/graph": 0, "/swarm/events": 0, "/swarm/scene": 0 };
  let at = 0;
  let lastEvent;
  const bodies = [];  // each record's one field and its bytes, in order
  while (at < buf.length) {
    const len = readVarint(buf, at);
    if (!len || len[1] + len[0] > buf.length) break;  // a record cut short: not counted
    const body = buf.subarray(len[1], len[1] + len[0]);
    const field = body.length ? body[0] >> 3 : 0;
    bodies.push({ field, data: decodeFields(body).get(field) });
    if (field === 1) counts["/swarm/agents"]++;
    if (field === 2) {
      counts["/swarm/graph"]++;
      counts["/swarm/scene"]++;
    }
    if (field === 3) {
      counts["/swarm/events"]++;
      lastEvent = decodeFields(decodeFields(body).get(3));
    }
    at = len[1] + len[0];
  }
  return {
    counts,
    bodies,
    lastKind: lastEvent ? Buffer.from(lastEvent.get(2) ?? []).toString() : undefined,
  };
}

// The file's samples, snapshots and events, in the order the streamed reader met them, are
// records.pb's records, byte for byte, for as many as both hold (all of them for a whole file).
function comparePrefix(bodies) {
  const n = Math.min(bodies.length, streamedRecords.length);
  for (let i = 0; i < n; i++) {
    const a = streamedRecords[i];
    const b = bodies[i];
    if (a.field !== b.field || !Buffer.from(a.data).equals(Buffer.from(b.data ?? []))) {
      check(false, `message ${i} (channel ${a.field}) is not records.pb's record ${i} (field ${b.field})`);
      return n;
    }
  }
  return n;
}

const bytes = await readFile(file);
found.bytes = bytes.length;

// The streamed reader, from the first byte to the last.
const stream = new McapStreamReader({ validateCrcs: true });
const streamed = new Map();
const streamedRecords = [];  // samples, snapshots and events in file order
let dataEndCrc;
let dataEndAt;
let streamError;
try {
  stream.append(bytes);
  for (let r; (r = stream.nextRecord()); ) {
    if (r.type === "Message") {
      streamed.set(r.channelId, (streamed.get(r.channelId) ?? 0) + 1);
      if (r.channelId <= 3) streamedRecords.push({ field: r.channelId, data: r.data });
    }
    if (r.type === "DataEnd") {
      dataEndCrc = r.dataSectionCrc;
      dataEndAt = bytes.length - stream.bytesRemaining();
    }
  }
} catch (e) {
  streamError = String(e.message ?? e);
}
found.streamDone = stream.done();
found.streamError = streamError;

if (truncated) {
  let refused;
  try {
    const fh = await open(file, "r");
    try {
      await McapIndexedReader.Initialize({ readable: readableOf(fh) });
    } finally {
      await fh.close();
    }
  } catch (e) {
    refused = String(e.message ?? e);
  }
  found.indexedRefused = refused;
  check(refused !== undefined, "the indexed reader opened a truncated file");
  check(!stream.done(), "the streamed reader reached the end of a truncated file");
  found.recovered = Object.fromEntries([...streamed].map(([k, v]) => [k, v]));
  if (recordsPath) {
    // What a streaming reader recovers is a prefix of the run's records (records.pb itself may be
    // cut shorter or longer: both stopped when the writer was killed).
    const { counts, bodies } = await recordCounts(recordsPath);
    found.records = counts;
    found.matchedRecords = comparePrefix(bodies);
    // records.pb reaches the disk before each chunk does, so it holds all the file recovered:
    // `swarm export` can rebuild the file from it.
    check(found.matchedRecords === streamedRecords.length, "the file holds records records.pb lost");
  }
} else {
  check(streamError === undefined, `streamed reader: ${streamError}`);
  check(stream.done(), "the streamed reader did not reach the end of the file");
  // The DataEnd record's CRC: every byte before it, computed here.
  if (dataEndCrc !== undefined && dataEndAt !== undefined) {
    const dataEndRecordBytes = 1 + 8 + 4;
    const expected = crc32(bytes.subarray(0, dataEndAt - dataEndRecordBytes));
    found.dataSectionCrc = dataEndCrc;
    check(dataEndCrc !== 0 && dataEndCrc === expected, `data section CRC ${dataEndCrc}, computed ${expected}`);
  } else {
    check(false, "no DataEnd record");
  }

  const fh = await open(file, "r");
  const perTopic = {};
  try {
    const reader = await McapIndexedReader.Initialize({ readable: readableOf(fh) });
    check(reader.chunkIndexes.length > 0 || (reader.statistics?.messageCount ?? 0n) === 0n, "no chunk index");
    const topicOf = new Map([...reader.channelsById].map(([id, c]) => [id, c.topic]));
    found.channels = [...reader.channelsById.values()].map((c) => ({
      topic: c.topic,
      encoding: c.messageEncoding,
      schema: reader.schemasById.get(c.schemaId)?.name,
      schemaEncoding: reader.schemasById.get(c.schemaId)?.encoding,
    }));
    let last = -1n;
    let outOfOrder = 0;
    let badScenes = 0;
    let lastEvent;
    for await (const m of reader.readMessages({ validateCrcs: true })) {
      const t = topicOf.get(m.channelId);
      perTopic[t] = (perTopic[t] ?? 0) + 1;
      if (m.logTime < last) outOfOrder++;
      last = m.logTime;
      if (t === "/swarm/scene") {
        try {
          const scene = JSON.parse(Buffer.from(m.data).toString());
          if (!Array.isArray(scene.entities) || !Array.isArray(scene.deletions)) badScenes++;
        } catch {
          badScenes++;
        }
      }
      if (t === "/swarm/events") lastEvent = decodeFields(m.data);
    }
    found.indexed = perTopic;
    check(outOfOrder === 0, `${outOfOrder} messages out of log-time order from the indexed reader`);
    check(badScenes === 0, `${badScenes} scene messages are not JSON SceneUpdates`);
    const stats = reader.statistics;
    check(stats !== undefined, "no Statistics record");
    for (const [id, c] of reader.channelsById) {
      const n = perTopic[c.topic] ?? 0;
      check(BigInt(n) === (stats?.channelMessageCounts.get(id) ?? -1n), `${c.topic}: statistics say ${stats?.channelMessageCounts.get(id)}, read ${n}`);
      check(n === (streamed.get(id) ?? 0), `${c.topic}: indexed reader ${n}, streamed reader ${streamed.get(id) ?? 0}`);
    }
    if (recordsPath) {
      const { counts, bodies, lastKind } = await recordCounts(recordsPath);
      found.records = counts;
      found.matchedRecords = comparePrefix(bodies);
      check(found.matchedRecords === bodies.length, "records.pb holds records the file does not");
      for (const [t, n] of Object.entries(counts))
        check((perTopic[t] ?? 0) === n, `${t}: ${perTopic[t] ?? 0} messages, records.pb says ${n}`);
      const kind = lastEvent ? Buffer.from(lastEvent.get(2) ?? []).toString() : undefined;
      check(kind === lastKind, `last event "${kind}", records.pb's "${lastKind}"`);
    }
  } catch (e) {
    check(false, `indexed reader: ${e.message ?? e}`);
  } finally {
    await fh.close();
  }
}

function readableOf(fh) {
  return {
    size: async () => BigInt((await fh.stat()).size),
    read: async (offset, size) => {
      const buf = Buffer.alloc(Number(size));
      const { bytesRead } = await fh.read(buf, 0, Number(size), Number(offset));
      if (bytesRead !== Number(size)) throw new Error(`short read at ${offset}`);
      return new Uint8Array(buf.buffer, buf.byteOffset, bytesRead);
    },
  };
}

found.failures = failures;
console.log(JSON.stringify(found, (_, v) => (typeof v === "bigint" ? Number(v) : v)));
process.exit(failures.length ? 1 : 0);
