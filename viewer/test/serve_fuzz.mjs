#!/usr/bin/env node
// A bounded fuzz loop over serve.mjs's path handling: random request targets (bytes, %-escapes of anything, dot
// segments, encoded slashes, NUL, links) through resolveTarget, then raw random request lines to a live server.
// Asserts: resolveTarget never throws and answers 200 only with a real path inside its folder's real path, never
// the secret file beside the folder; the live server answers every request or closes it and is still up at the end.
// usage: node viewer/test/serve_fuzz.mjs WORK_DIR [ITERATIONS] [SEED]
import fs from 'node:fs';
import net from 'node:net';
import path from 'node:path';
import { resolveTarget, servedRoots, serve } from '../serve.mjs';

const [work, iterationsText = '20000', seedText = '1'] = process.argv.slice(2);
if (!work) { console.error('usage: serve_fuzz.mjs WORK_DIR [ITERATIONS] [SEED]'); process.exit(2); }
fs.rmSync(work, { recursive: true, force: true });
fs.mkdirSync(path.join(work, 'out/sub'), { recursive: true });
fs.writeFileSync(path.join(work, 'out/hello.json'), '{"hello": 1}\n');
fs.writeFileSync(path.join(work, 'out/sub/a.npy'), 'npy');
fs.writeFileSync(path.join(work, 'secret.txt'), 'secret\n');
fs.symlinkSync(path.join(work, 'secret.txt'), path.join(work, 'out/link.txt'));
fs.symlinkSync(work, path.join(work, 'out/up'));
fs.symlinkSync('/etc', path.join(work, 'out/etc'));

// mulberry32: the same seed, the same inputs.
let state = Number(seedText) >>> 0;
const random = () => {
  state = (state + 0x6d2b79f5) >>> 0;
  let t = state;
  t = Math.imul(t ^ (t >>> 15), t | 1);
  t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
  return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
};
const pick = (items) => items[Math.floor(random() * items.length)];
const hex = (byte) => '%' + byte.toString(16).padStart(2, pick([true, false]) ? '0' : '').toUpperCase();
const pieces = ['/', '..', '.', '%2e', '%2E%2E', '%2f', '%2F', '%5c', '\\', '%00', '%', '%%', '%e0%a4', '%c0%ae',
  '%ff', 'data', 'three', 'hello.json', 'sub', 'a.npy', 'link.txt', 'up', 'etc', 'passwd', 'secret.txt', 'out',
  'index.html', '?', '#', ';', '//', '~', ' ', '%20', '\u00e9', '\ud83d\ude00', 'three.module.js'];
function target() {
  let text = pick(['/data/', '/three/', '/', '/data', '']);
  const parts = 1 + Math.floor(random() * 8);
  for (let i = 0; i < parts; ++i) {
    const r = random();
    if (r < 0.6) text += pick(pieces);
    else if (r < 0.8) text += hex(Math.floor(random() * 256));
    else text += String.fromCharCode(Math.floor(random() * 256));
  }
  return text;
}

const roots = servedRoots(path.join(work, 'out'));
const realRoots = roots.filter((r) => r.real).map((r) => r.real);
const secret = fs.realpathSync(path.join(work, 'secret.txt'));
const counts = {};
let failures = 0;
const fail = (what) => { if (failures++ < 20) console.log(`FAILED: ${what}`); };
const iterations = Number(iterationsText);
for (let i = 0; i < iterations; ++i) {
  const t = target();
  let result;
  try {
    result = resolveTarget(roots, t);
  } catch (error) {
    fail(`resolveTarget(${JSON.stringify(t)}) threw ${error.message}`);
    continue;
  }
  counts[result.status] = (counts[result.status] || 0) + 1;
  if (![200, 400, 403, 404].includes(result.status)) fail(`${JSON.stringify(t)}: status ${result.status}`);
  if (result.status === 200) {
    const inside = realRoots.some((root) => result.file === root || result.file.startsWith(root + path.sep));
    if (!inside || result.file === secret || result.file.startsWith('/etc/'))
      fail(`${JSON.stringify(t)} served ${result.file}, outside the served folders`);
  }
}
console.log(`resolveTarget: ${iterations} targets, statuses ${JSON.stringify(counts)}`);

// Raw request lines to a live server: whatever the bytes, it answers or closes, and keeps serving.
const server = await serve(path.join(work, 'out'));
const { port } = server.address();
const raw = (line) => new Promise((resolve) => {
  const socket = net.connect(port, '127.0.0.1');
  let answer = '';
  socket.setTimeout(500, () => socket.destroy()); // a request the server still waits to complete
  socket.on('data', (chunk) => { answer += chunk; });
  socket.on('error', () => resolve(answer));
  socket.on('close', () => resolve(answer));
  socket.on('connect', () => socket.write(line)); // end() would half-close before the answer
});
const live = Math.min(300, Math.max(20, Math.floor(iterations / 50)));
let leaked = 0;
for (let i = 0; i < live; ++i) {
  const t = target();
  const host = pick([`127.0.0.1:${port}`, `localhost:${port}`, 'evil.example', '']);
  const answer = await raw(Buffer.from(`GET ${t} HTTP/1.1\r\nHost: ${host}\r\nConnection: close\r\n\r\n`, 'latin1'));
  if (answer.includes('secret') || answer.includes('root:')) leaked++;
}
if (leaked) fail(`${leaked} live answers held the secret or /etc`);
const alive = await raw(`GET /data/hello.json HTTP/1.1\r\nHost: 127.0.0.1:${port}\r\nConnection: close\r\n\r\n`);
if (!alive.startsWith('HTTP/1.1 200')) fail(`the server no longer serves after ${live} raw requests: ${alive.slice(0, 80)}`);
console.log(`live server: ${live} raw requests, still serving: ${alive.startsWith('HTTP/1.1 200')}`);
server.close();
console.log(failures ? `${failures} failures` : 'ok: no crash, nothing outside the served folders');
process.exit(failures ? 1 : 0);
