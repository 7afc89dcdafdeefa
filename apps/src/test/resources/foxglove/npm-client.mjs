// The feed read by clients we did not write (FoxgloveNpmClientSpec): the ws-protocol's own FoxgloveClient from the npm
// registry, and a bare WebSocket offering both subprotocol names as the Foxglove SDK's viewers do.
// Usage: node npm-client.mjs ws://127.0.0.1:PORT/foxglove
// Prints one JSON line per finding: {"client":...}, {"datagram":...}, {"sdk":...}; exits 0 when all are in, 1 on an
// error or after 30 s.
import { createRequire } from "node:module";

const require = createRequire(import.meta.url);
const WebSocket = require("ws");
const protobuf = require("protobufjs");
require("protobufjs/ext/descriptor");
const wsProtocol = require("@foxglove/ws-protocol");
const FoxgloveClient = wsProtocol.FoxgloveClient ?? wsProtocol.default?.FoxgloveClient ?? wsProtocol.default;

const url = process.argv[2];
const found = {};
const done = () => {
  if (found.client && found.datagram && found.sdk) process.exit(0);
};
setTimeout(() => {
  console.log(JSON.stringify({ timeout: Object.keys(found) }));
  process.exit(1);
}, 30000).unref();

// 1. FoxgloveClient subscribes to /robot/1/status and /gateway/datagrams and decodes a message of each with the schema
// the server advertised.
const client = new FoxgloveClient({ ws: new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]) });
const channels = new Map();
const subscriptions = new Map();
client.on("error", (e) => {
  console.log(JSON.stringify({ error: String(e) }));
  process.exit(1);
});
client.on("advertise", (advertised) => {
  for (const c of advertised) {
    channels.set(c.id, c);
    if (c.topic === "/robot/1/status" || c.topic === "/gateway/datagrams") subscriptions.set(client.subscribe(c.id), c);
  }
});
client.on("message", ({ subscriptionId, timestamp, data }) => {
  const channel = subscriptions.get(subscriptionId);
  if (!channel) return;
  const root = protobuf.Root.fromDescriptor(Buffer.from(channel.schema, "base64"));
  const type = root.lookupType(channel.schemaName);
  const bytes = new Uint8Array(data.buffer, data.byteOffset, data.byteLength);
  const decoded = type.toObject(type.decode(bytes), { defaults: false, longs: String, enums: String, bytes: String });
  if (channel.topic === "/gateway/datagrams") {
    // A datagram robot 1 sent, as the recording holds it.
    if (found.datagram || decoded.port !== "ROBOT_PORT" || decoded.direction !== "RECEIVED" || decoded.robotID !== 1)
      return;
    found.datagram = true;
    console.log(JSON.stringify({ datagram: { schemaName: channel.schemaName, recorded: decoded } }));
    if (found.client) client.close();
    done();
    return;
  }
  if (found.client) return;
  found.client = true;
  console.log(JSON.stringify({
    client: {
      protocol: FoxgloveClient.SUPPORTED_SUBPROTOCOL,
      topic: channel.topic,
      encoding: channel.encoding,
      schemaEncoding: channel.schemaEncoding,
      schemaName: channel.schemaName,
      timestamp: String(timestamp),
      status: decoded,
    },
  }));
  if (found.datagram) client.close();
  done();
});

// 2. A viewer of the SDK's generation offers foxglove.sdk.v1 first: the name the server answers, and its first message.
const sdk = new WebSocket(url, ["foxglove.sdk.v1", "foxglove.websocket.v1"]);
sdk.on("message", (data, isBinary) => {
  if (found.sdk) return;
  found.sdk = true;
  console.log(JSON.stringify({ sdk: { protocol: sdk.protocol, binary: isBinary, first: JSON.parse(data.toString()) } }));
  sdk.close();
  done();
});
sdk.on("error", (e) => {
  console.log(JSON.stringify({ error: String(e) }));
  process.exit(1);
});
