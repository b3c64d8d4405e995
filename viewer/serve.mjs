#!/usr/bin/env node
// Serves the viewer on a local port: `node viewer/serve.mjs OUT_DIR [PORT]` (`prt serve OUT_DIR [--port PORT]`;
// default 8000, 0: a free one), then open the printed address. / is this folder, /three/ is three.js from npm, /data/ is OUT_DIR (bundles, prt-sh
// lighting, reference radiance). Only reads files under those three folders, links resolved: a symlink inside a
// folder that points outside it is refused (403). Requests are untrusted: a bad %-escape, a NUL byte or any other
// malformed request is answered 400 and the server keeps running; a Host header that is not a loopback name with
// this server's port (localhost, 127.x.x.x, [::1]) is answered 421, which closes DNS rebinding. A port in use is
// one line on stderr and exit 2 (kExitUsage, as `prt serve --port` takes it).
import http from 'node:http';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { answerListing } from './listing.mjs';

const here = path.dirname(fileURLToPath(import.meta.url));
const types = { '.html': 'text/html', '.js': 'text/javascript', '.mjs': 'text/javascript', '.json': 'application/json',
                '.glb': 'model/gltf-binary', '.png': 'image/png', '.npy': 'application/octet-stream',
                '.exr': 'image/x-exr' };
const kExitUsage = 2; // README "Exit codes": the command line's --port cannot be used

// The served folders by URL prefix, longest first, each with its real path (links resolved) when it exists.
export function servedRoots(dataDir) {
  const roots = [['/three/', path.join(here, 'node_modules/three/build')], ['/data/', path.resolve(dataDir)], ['/', here]];
  return roots.map(([prefix, root]) => {
    let real = null;
    try { real = fs.realpathSync(root); } catch { /* a missing folder serves nothing */ }
    return { prefix, root, real };
  });
}

const inside = (file, root) => file === root || file.startsWith(root.endsWith(path.sep) ? root : root + path.sep);

// What a request target maps to: { status: 200, file } with `file` a real path inside its folder's real path, or
// { status } 400 (malformed: bad %-escape, NUL, not a path), 403 (outside the folders, links included) or 404.
// Never throws; reads the file system only through realpath.
export function resolveTarget(roots, target) {
  let url;
  try {
    url = decodeURIComponent(new URL(target, 'http://x').pathname);
  } catch {
    return { status: 400 };
  }
  if (url.includes('\0') || !url.startsWith('/')) return { status: 400 };
  const served = roots.find((r) => url.startsWith(r.prefix));
  if (!served || !served.real) return { status: 404 };
  const rest = url.slice(served.prefix.length - 1);
  const file = path.resolve(served.root, '.' + (rest === '/' ? '/index.html' : rest));
  if (!inside(file, served.root)) return { status: 403 };
  let real;
  try {
    real = fs.realpathSync(file);
  } catch {
    return { status: 404 };
  }
  if (!inside(real, served.real)) return { status: 403 };
  return { status: 200, file: real };
}

// A Host header naming this machine's loopback interface with `port`: localhost, 127.x.x.x or [::1].
export function loopbackHost(host, port) {
  if (typeof host !== 'string') return false;
  const match = host.toLowerCase().match(/^(localhost|127(?:\.\d{1,3}){3}|\[::1\])(?::(\d{1,5}))?$/);
  if (!match) return false;
  if (match[1].startsWith('127') && match[1].split('.').some((part) => Number(part) > 255)) return false;
  return match[2] === undefined ? port === 80 : Number(match[2]) === port;
}

export function serve(dataDir, port = 0) {
  const roots = servedRoots(dataDir);
  const server = http.createServer((request, response) => {
    const refuse = (status) => { if (!response.headersSent) response.writeHead(status); response.end(); };
    try {
      response.on('error', () => {});
      if (!loopbackHost(request.headers.host, server.address().port)) { refuse(421); return; }
      if (request.method !== 'GET' && request.method !== 'HEAD') { refuse(405); return; }
      // The viewer's panel (listing.mjs) answers its own path; everything else is a file under the roots.
      if (answerListing(request.url, dataDir, response)) return;
      const { status, file } = resolveTarget(roots, request.url);
      if (status !== 200) { refuse(status); return; }
      // Regular files only (a FIFO would hold a worker thread forever, a device never end), streamed, so a large
      // file costs no more memory than a small one. O_NONBLOCK: opening a FIFO returns at once; fstat then refuses it.
      fs.open(file, fs.constants.O_RDONLY | fs.constants.O_NONBLOCK, (openError, fd) => {
        if (openError) { refuse(openError.code === 'EISDIR' ? 403 : 404); return; }
        fs.fstat(fd, (statError, stats) => {
          try {
            if (statError || !stats.isFile()) {
              fs.close(fd, () => {});
              refuse(statError ? 404 : 403);
              return;
            }
            response.writeHead(200, {
              'content-type': types[path.extname(file)] || 'application/octet-stream',
              'content-length': stats.size,
            });
            if (request.method === 'HEAD') { fs.close(fd, () => {}); response.end(); return; }
            const stream = fs.createReadStream(null, { fd, autoClose: true });
            stream.on('error', () => response.destroy());
            response.on('close', () => stream.destroy());
            stream.pipe(response);
          } catch { fs.close(fd, () => {}); refuse(500); }
        });
      });
    } catch {
      refuse(400);
    }
  });
  // A request Node cannot parse never reaches the handler: answer it and drop the connection.
  server.on('clientError', (error, socket) => {
    if (socket.writable) socket.end('HTTP/1.1 400 Bad Request\r\nConnection: close\r\n\r\n');
    else socket.destroy();
  });
  return new Promise((resolve, reject) => {
    server.once('error', reject);
    server.listen(port, '127.0.0.1', () => { server.off('error', reject); resolve(server); });
  });
}

if (process.argv[1] === fileURLToPath(import.meta.url)) {
  if (process.argv.length < 3) { console.error('usage: node viewer/serve.mjs OUT_DIR [PORT]'); process.exit(kExitUsage); }
  const port = process.argv[3] === undefined ? 8000 : Number(process.argv[3]);
  let server;
  try {
    server = await serve(process.argv[2], port);
  } catch (error) {
    const why = error.code === 'EADDRINUSE' ? 'is in use (give another --port, or --port 0 for a free one)'
      : error.code === 'EACCES' ? 'needs privileges (give a port above 1023, or --port 0 for a free one)'
        : `cannot be opened (${error.code || error.message})`;
    console.error(`prt serve: --port: port ${port} on 127.0.0.1 ${why}`);
    process.exit(kExitUsage);
  }
  const { port: bound } = server.address();
  const glbs = fs.readdirSync(process.argv[2]).filter((f) => f.endsWith('.glb'));
  const maps = fs.readdirSync(process.argv[2]).filter((f) => f.endsWith('.sh.json')).map((f) => 'data/' + f);
  console.log(`prt viewer on http://127.0.0.1:${bound}/`);
  for (const glb of glbs) console.log(`  http://127.0.0.1:${bound}/?bundle=data/${glb}&maps=${maps.join(',')}`);
}
