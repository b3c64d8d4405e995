#!/usr/bin/env node
// `prt serve`: serves the viewer at / and the given folder at /data/ on 127.0.0.1, refuses paths that climb out of
// the folder (symlinks inside it included), answers malformed requests 400 and keeps serving, answers a Host that
// is not loopback 421, and refuses a missing folder (exit 3), a bad port or a port in use (exit 2, one line, no
// stack trace) without starting.
// usage: node viewer/test/serve_test.mjs PRT WORK_DIR
import { spawn, spawnSync } from 'node:child_process';
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';

const [prt, work] = process.argv.slice(2);
if (!prt || !work) { console.error('usage: serve_test.mjs PRT WORK_DIR'); process.exit(2); }
fs.rmSync(work, { recursive: true, force: true });
fs.mkdirSync(path.join(work, 'out'), { recursive: true });
fs.writeFileSync(path.join(work, 'out/hello.json'), '{"hello": 1}\n');
fs.writeFileSync(path.join(work, 'secret.txt'), 'secret\n');
// Links inside the served folder that lead out of it: to a file and to a folder.
fs.symlinkSync(path.join(work, 'secret.txt'), path.join(work, 'out/link.txt'));
fs.symlinkSync(work, path.join(work, 'out/up'));
// Not regular files: a FIFO (reading one would hold a worker thread until a writer came) and a folder.
spawnSync('mkfifo', [path.join(work, 'out/fifo.glb')]);
fs.mkdirSync(path.join(work, 'out/folder.glb'));

let failed = false;
const check = (ok, what) => { console.log(`${ok ? 'ok' : 'FAILED'}: ${what}`); failed ||= !ok; };

for (const [args, code, what] of [[['serve', path.join(work, 'missing')], 3, 'a missing folder'],
                                  [['serve', path.join(work, 'out'), '--port', '70000'], 2, 'port 70000']]) {
  const result = spawnSync(prt, args, { encoding: 'utf8', timeout: 20000 });
  check(result.status === code && result.stderr.length > 0, `${what} exits ${code} with a message (got ${result.status})`);
}

// Raw requests: fetch() would normalise the dot segments away before they reach the server.
const get = (port, target, headers = {}) => new Promise((resolve, reject) => {
  http.get({ host: '127.0.0.1', port, path: target, headers }, (response) => {
    let body = '';
    response.on('data', (chunk) => { body += chunk; });
    response.on('end', () => resolve({ status: response.statusCode, body }));
  }).on('error', reject);
});

const server = spawn(prt, ['serve', path.join(work, 'out'), '--port', '0'], { stdio: ['ignore', 'pipe', 'inherit'] });
try {
  const port = await new Promise((resolve, reject) => {
    let text = '';
    server.stdout.on('data', (chunk) => {
      text += chunk;
      const match = text.match(/http:\/\/127\.0\.0\.1:(\d+)\//);
      if (match) resolve(Number(match[1]));
    });
    server.on('exit', (code) => reject(new Error(`prt serve exited ${code}`)));
    setTimeout(() => reject(new Error('prt serve printed no address in 20 s')), 20000);
  });
  const page = await get(port, '/');
  check(page.status === 200 && page.body.includes('prt viewer'), `/ is the viewer page (${page.status})`);
  const three = await get(port, '/three/three.module.js');
  check(three.status === 200, `/three/ serves three.js (${three.status})`);
  const data = await get(port, '/data/hello.json');
  check(data.status === 200 && data.body.includes('hello'), `/data/ serves the folder (${data.status})`);
  for (const target of ['/data/../secret.txt', '/data/%2E%2E/secret.txt', '/data/..%2Fsecret.txt']) {
    const escape = await get(port, target);
    check(escape.status >= 400 && !escape.body.includes('secret'), `${target} is refused (${escape.status})`);
  }
  for (const target of ['/data/link.txt', '/data/up/secret.txt']) {
    const escape = await get(port, target);
    check(escape.status === 403 && !escape.body.includes('secret'), `symlink out of the folder ${target} is refused (${escape.status})`);
  }
  for (const target of ['/data/%', '/data/%E0%A4%A', '/data/%zz', '/data/%00', '/data/a%00b.json', '/%C0%AE%C0%AE/x']) {
    const bad = await get(port, target);
    check(bad.status === 400, `malformed ${target} is answered 400 (${bad.status})`);
  }
  // Node's file-system pool has four threads: eight requests for the FIFO would hold them all if any blocked.
  for (let i = 0; i < 8; ++i) {
    const fifo = await Promise.race([get(port, '/data/fifo.glb'),
      new Promise((resolve) => setTimeout(() => resolve({ status: 'no answer in 5 s' }), 5000))]);
    if (i === 0) check(fifo.status === 403, `a FIFO is refused (${fifo.status})`);
  }
  const folder = await get(port, '/data/folder.glb');
  check(folder.status === 403, `a folder is refused (${folder.status})`);
  const alive = await get(port, '/data/hello.json');
  check(alive.status === 200, `the server still serves after malformed requests (${alive.status})`);
  for (const host of ['evil.example', `evil.example:${port}`, `127.0.0.1.evil.example:${port}`, `localhost:${port + 1}`,
                      `127.0.0.300:${port}`, `[::2]:${port}`]) {
    const rebound = await get(port, '/data/hello.json', { host });
    check(rebound.status === 421 && !rebound.body.includes('hello'), `Host ${host} is refused (${rebound.status})`);
  }
  for (const host of [`localhost:${port}`, `127.0.0.1:${port}`, `127.1.2.3:${port}`, `[::1]:${port}`]) {
    const loopback = await get(port, '/data/hello.json', { host });
    check(loopback.status === 200, `Host ${host} is served (${loopback.status})`);
  }
  // The port now in use: one line on stderr, exit 2, no stack trace.
  const busy = spawnSync(prt, ['serve', path.join(work, 'out'), '--port', String(port)], { encoding: 'utf8', timeout: 20000 });
  check(busy.status === 2 && busy.stderr.trim().split('\n').length === 1 && busy.stderr.includes('in use') &&
        !busy.stderr.includes('    at '), `port ${port} in use exits 2 with one line (got ${busy.status}: ${busy.stderr.trim()})`);
} catch (error) {
  check(false, error.message);
} finally {
  server.kill();
}
process.exit(failed ? 1 : 0);
