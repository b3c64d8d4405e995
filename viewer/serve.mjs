#!/usr/bin/env node
// Serves the viewer on a local port: `node viewer/serve.mjs OUT_DIR [PORT]` (`prt serve OUT_DIR [--port PORT]`;
// default 8000, 0: a free one), then open the printed address. / is this folder, /three/ is three.js from npm, /data/ is OUT_DIR (bundles, prt-sh
// lighting, reference radiance). Only reads files under those three folders.
import http from 'node:http';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { answerListing } from './listing.mjs';

const here = path.dirname(fileURLToPath(import.meta.url));
const types = { '.html': 'text/html', '.js': 'text/javascript', '.mjs': 'text/javascript', '.json': 'application/json',
                '.glb': 'model/gltf-binary', '.png': 'image/png', '.npy': 'application/octet-stream',
                '.exr': 'image/x-exr' };

export function serve(dataDir, port = 0) {
  const roots = { '/three/': path.join(here, 'node_modules/three/build'), '/data/': path.resolve(dataDir), '/': here };
  const server = http.createServer((request, response) => {
    const url = decodeURIComponent(new URL(request.url, 'http://x').pathname);
    if (answerListing(url, dataDir, response)) return; // the viewer's panel: listing.mjs
    const prefix = Object.keys(roots).find((p) => url.startsWith(p));
    const root = roots[prefix];
    const file = path.resolve(root, '.' + (url.slice(prefix.length - 1) === '/' ? '/index.html' : url.slice(prefix.length - 1)));
    if (!file.startsWith(root + path.sep) && file !== root) { response.writeHead(403).end(); return; }
    fs.readFile(file, (error, bytes) => {
      if (error) { response.writeHead(404).end('not found'); return; }
      response.writeHead(200, { 'content-type': types[path.extname(file)] || 'application/octet-stream' }).end(bytes);
    });
  });
  return new Promise((resolve) => server.listen(port, '127.0.0.1', () => resolve(server)));
}

if (process.argv[1] === fileURLToPath(import.meta.url)) {
  if (process.argv.length < 3) { console.error('usage: node viewer/serve.mjs OUT_DIR [PORT]'); process.exit(2); }
  const server = await serve(process.argv[2], process.argv[3] === undefined ? 8000 : Number(process.argv[3]));
  const { port } = server.address();
  const glbs = fs.readdirSync(process.argv[2]).filter((f) => f.endsWith('.glb'));
  const maps = fs.readdirSync(process.argv[2]).filter((f) => f.endsWith('.sh.json')).map((f) => 'data/' + f);
  console.log(`prt viewer on http://127.0.0.1:${port}/`);
  for (const glb of glbs) console.log(`  http://127.0.0.1:${port}/?bundle=data/${glb}&maps=${maps.join(',')}`);
}
