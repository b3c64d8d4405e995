#!/usr/bin/env node
// Viewer frame time in Debian's headless Chromium (software GL): the bunny and a 1M-vertex sphere at orders 3, 5
// and 8, each frame finished by a 1-pixel read. usage: node viewer/test/bench.mjs PRT BUNNY.ply WORK_DIR [OUT.json]
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { launchChromium } from './chromium.mjs';
import { serve } from '../serve.mjs';

const [prt, bunny, work, out] = process.argv.slice(2);
if (!prt || !bunny || !work) { console.error('usage: bench.mjs PRT BUNNY.ply WORK_DIR [OUT.json]'); process.exit(2); }
fs.mkdirSync(work, { recursive: true });
const run = (...args) => {
  const result = spawnSync(prt, ['--quiet', ...args], { encoding: 'utf8' });
  if (result.status !== 0) throw new Error(`prt ${args.join(' ')} failed:\n${result.stderr}`);
};
const file = (name) => path.join(work, name);
const orders = [3, 5, 8];
if (!fs.existsSync(file('bunny.glb'))) run('meshprep', bunny, '-o', file('bunny.glb'));
for (const order of orders)
  if (!fs.existsSync(file(`bunny.o${order}.glb`)))
    run('transfer', file('bunny.glb'), '--mode', 'unshadowed', '--order', String(order), '--samples', '64', '-o',
        file(`bunny.o${order}.glb`));
// One lighting file is enough: the frame cost does not depend on the values.
fs.writeFileSync(file('flat.sh.json'), JSON.stringify({ format: 'prt-sh', order: 8,
  coefficients: Array.from({ length: 64 }, (_, j) => (j === 0 ? [3.5, 3.5, 3.5] : [0.1, 0.05, 0.02])) }));

const server = await serve(work);
const base = `http://127.0.0.1:${server.address().port}`;
const browser = await launchChromium();
const rows = [];
try {
  const cases = [];
  for (const order of orders) cases.push({ mesh: 'bunny', order, query: `bundle=data/bunny.o${order}.glb&camera=0,0.1,0.45,0,0.1,0,0,1,0,40` });
  for (const order of orders) cases.push({ mesh: 'sphere 1M vertices', order, query: `synthetic=1000000,${order}&camera=0,0,2,0,0,0,0,1,0,40` });
  for (const c of cases) {
    const page = await browser.newPage({ viewport: { width: 900, height: 520 }, deviceScaleFactor: 1 });
    try {
      await page.goto(`${base}/?${c.query}&maps=data/flat.sh.json&size=640,480`, { timeout: 600000 });
      const result = await page.evaluate(async () => {
        const api = await window.prtReady;
        // Warm up, then time: frames until at least 2 s or 50 frames.
        api.bench(2);
        let frames = 0, total = 0;
        while (frames < 50 && total < 2000) { total += api.bench(1); ++frames; }
        return { vertices: api.vertexCount, renderer: api.renderer, frameMs: total / frames, frames };
      });
      rows.push({ ...c, ...result, query: undefined });
      console.log(`${c.mesh} (${result.vertices} vertices) order ${c.order}: ${result.frameMs.toFixed(2)} ms/frame ` +
                  `over ${result.frames} frames, 640x480, ${result.renderer}`);
    } catch (error) {
      rows.push({ ...c, error: String(error.message || error).split('\n')[0], query: undefined });
      console.log(`${c.mesh} order ${c.order}: FAILED ${String(error.message || error).split('\n')[0]}`);
    } finally {
      await page.close();
    }
  }
} finally {
  await browser.close();
  server.close();
}
if (out) fs.writeFileSync(out, JSON.stringify(rows, null, 2) + '\n');
