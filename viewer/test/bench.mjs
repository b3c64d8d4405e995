#!/usr/bin/env node
// Viewer frame time in Debian's headless Chromium (software GL): the bunny and a 1M-vertex sphere, each frame finished
// by a 1-pixel read: plain SH at orders 3, 5 and 8 (mode sh), hybrid with 4 cone lights at order 5 (mode hybrid:
// night's lights from prt envlight; the bunny with its bounce layer and prt relight's visibility, the sphere with
// stand-ins of the same cost), FIV with 3 moving sphere occluders (mode fiv, shaded on the GPU and on the CPU: a still frame, and a frame in
// which the occluders move, so the shading, and on the CPU the upload, are in it), glossy lobes per pixel with 1 and 2
// lobes (mode glossy, glossy.js: the bunny above fitted by prt glossy --iterations 20, order 3, studio's stack from
// prt render --glossy-stack; the 1M-vertex sphere takes that bundle's lobes, vertex v the row v % 1,839, so the
// per-pixel work is the same and only the lobe texture is smaller than a real 1M-vertex fit's). The glossy bunny's
// 640x480 picture is saved as WORK_DIR/glossy_bunny.png.
// usage: node viewer/test/bench.mjs PRT BUNNY.ply WORK_DIR [OUT.json] [MODES, e.g. sh,hybrid,fiv,glossy]
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { launchChromium } from './chromium.mjs';
import { serve } from '../serve.mjs';

const [prt, bunny, work, out, modeList] = process.argv.slice(2);
const modes = (modeList || 'sh,hybrid,fiv').split(',');
const envDir = path.join(path.dirname(bunny), 'env');
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

// Hybrid: 4 lights of night at order 5; the bunny's interreflected transfer with its bounce layer.
const bunnyCamera = '3.46275,7.798,18.8643,-0.00481248,4.8258,0.040403,0,1,0,35';
if (modes.includes('hybrid')) {
  if (!fs.existsSync(file('night5.lights.json')))
    run('envlight', path.join(envDir, 'night.exr'), '--order', '5', '--max-lights', '4', '-o', file('night5.lights.json'));
  if (!fs.existsSync(file('bunny.hybrid.glb')))
    run('transfer', file('bunny.glb'), '--mode', 'interreflected', '--bounces', '1', '--order', '5', '--samples', '64',
        '--albedo', '0.8', '-o', file('bunny.hybrid.glb'));
  run('relight', file('bunny.hybrid.glb'), '--lights', file('night5.lights.json'), '--visibility-out',
      file('bunny.visibility.npy'), '-o', file('bunny.hybrid.npy'));
}
// FIV: 3 instances of a radius-1 sphere's grid over the bunny and over a 1M-vertex sphere of radius 1.
if (modes.includes('fiv')) {
  const map = path.join(envDir, 'courtyard.exr');
  if (!fs.existsSync(file('occluder.fiv.glb'))) {
    run('scene', 'sphere', '-o', file('occluder.glb'));
    run('fiv', file('occluder.glb'), '--env', map, '--grid', '16,9,6', '--cube', '8', '-o', file('occluder.fiv.glb'));
  }
  if (!fs.existsSync(file('big.glb'))) run('scene', 'sphere', '--vertices', '1000000', '-o', file('big.glb'));
  const place = (at) => at.flatMap((p) => ['--occluder', file('occluder.fiv.glb'), '--at', p]);
  run('fivscene', file('bunny.glb'), ...place(['-2,11,1', '2,10,-1', '4,7,4']), '-o', file('bunny.fiv.glb'));
  run('fivscene', file('big.glb'), ...place(['0,2.5,0', '2.2,1.2,0', '-1.5,1.5,1.5']), '-o', file('big.fiv.glb'));
}

// Glossy: the bunny with 1 and 2 lobes (20 LM iterations: the frame's cost does not depend on the fit's quality).
if (modes.includes('glossy')) {
  for (const lobes of [1, 2])
    if (!fs.existsSync(file(`glossy${lobes}.glb`)))
      run('glossy', file('bunny.glb'), '--brdf', 'phong:32,0.5', '--lobes', String(lobes), '--order', '3', '--samples', '64',
          '--iterations', '20', '--threads', '2', '-o', file(`glossy${lobes}.glb`));
  if (!fs.existsSync(file('studio.sh.json'))) run('envsh', path.join(envDir, 'studio.exr'), '--order', '8', '-o', file('studio.sh.json'));
  for (const lobes of [1, 2])
    if (!fs.existsSync(file(`studio${lobes}.stack`)))
      run('render', file(`glossy${lobes}.glb`), '--env', path.join(envDir, 'studio.exr'), '--size', '64,48', '--camera', bunnyCamera,
          '-o', file(`glossy${lobes}.render.png`), '--glossy-stack', file(`studio${lobes}.stack`));
}

const server = await serve(work);
const base = `http://127.0.0.1:${server.address().port}`;
const browser = await launchChromium();
const rows = [];
try {
  const cases = [];
  if (modes.includes('sh')) {
    for (const order of orders) cases.push({ mode: 'sh', mesh: 'bunny', order, query: `bundle=data/bunny.o${order}.glb&camera=0,0.1,0.45,0,0.1,0,0,1,0,40` });
    for (const order of orders) cases.push({ mode: 'sh', mesh: 'sphere 1M vertices', order, query: `synthetic=1000000,${order}&camera=0,0,2,0,0,0,0,1,0,40` });
  }
  if (modes.includes('hybrid')) {
    cases.push({ mode: 'hybrid 4 lights', mesh: 'bunny', order: 5,
                 query: `bundle=data/bunny.hybrid.glb&lights=data/night5.lights.json&visibility=data/bunny.visibility.npy&camera=${bunnyCamera}` });
    cases.push({ mode: 'hybrid 4 lights', mesh: 'sphere 1M vertices', order: 5,
                 query: `synthetic=1000000,5&lights=data/night5.lights.json&camera=0,0,2,0,0,0,0,1,0,40` });
  }
  if (modes.includes('fiv')) {
    for (const on of ['gpu', 'cpu']) {
      cases.push({ mode: `fiv 3 occluders (${on})`, mesh: 'bunny', moving: true, query: `bundle=data/bunny.fiv.glb&albedo=0.8&camera=${bunnyCamera}&fivOn=${on}` });
      cases.push({ mode: `fiv 3 occluders (${on})`, mesh: 'sphere 1M vertices', moving: true, query: `bundle=data/big.fiv.glb&albedo=0.8&camera=0,1.5,6,0,0.5,0,0,1,0,40&fivOn=${on}` });
    }
  }
  if (modes.includes('glossy')) {
    for (const lobes of [1, 2]) {
      cases.push({ mode: `glossy ${lobes} lobe${lobes > 1 ? 's' : ''} per pixel`, mesh: 'bunny', order: 3,
                   maps: 'studio.sh.json', screenshot: lobes === 1 ? 'glossy_bunny.png' : null,
                   query: `bundle=data/glossy${lobes}.glb&glossy=data/studio${lobes}.stack&camera=${bunnyCamera}` });
      if (lobes === 1) // the same draw with the lobes off: the diffuse part's share of the frame
        cases.push({ mode: 'glossy bundle, lobes off (glossyOn=0)', mesh: 'bunny', order: 3, maps: 'studio.sh.json',
                     query: `bundle=data/glossy1.glb&glossy=data/studio1.stack&glossyOn=0&camera=${bunnyCamera}` });
      cases.push({ mode: `glossy ${lobes} lobe${lobes > 1 ? 's' : ''} per pixel`, mesh: 'sphere 1M vertices', order: 3, maps: 'studio.sh.json',
                   query: `synthetic=1000000,3&glossy=data/studio${lobes}.stack&glossyLobes=data/glossy${lobes}.glb&camera=0,0,2,0,0,0,0,1,0,40` });
    }
  }
  for (const c of cases) {
    const page = await browser.newPage({ viewport: { width: 900, height: 520 }, deviceScaleFactor: 1 });
    try {
      await page.goto(`${base}/?${c.query}&maps=data/${c.maps || 'flat.sh.json'}&size=640,480`, { timeout: 600000 });
      const result = await page.evaluate(async (moving) => {
        const api = await window.prtReady;
        // Warm up, then time: frames until at least 2 s or 50 frames.
        api.bench(2);
        let frames = 0, total = 0;
        while (frames < 50 && total < 2000) { total += api.bench(1); ++frames; }
        const row = { vertices: api.vertexCount, renderer: api.renderer, frameMs: total / frames, frames };
        if (moving) { // FIV: frames in which the occluders move (CPU shading, upload, draw)
          api.benchMoving(1);
          let movingFrames = 0, movingTotal = 0;
          while (movingFrames < 20 && movingTotal < 4000) { movingTotal += api.benchMoving(1); ++movingFrames; }
          Object.assign(row, { movingFrameMs: movingTotal / movingFrames, movingFrames });
        }
        return row;
      }, !!c.moving);
      if (c.screenshot) await page.locator('#view').screenshot({ path: file(c.screenshot) });
      rows.push({ ...c, ...result, query: undefined, maps: undefined, screenshot: undefined });
      console.log(`${c.mode} ${c.mesh} (${result.vertices} vertices)${c.order ? ` order ${c.order}` : ''}: ` +
                  `${result.frameMs.toFixed(2)} ms/frame over ${result.frames} frames` +
                  (c.moving ? `; moving: ${result.movingFrameMs.toFixed(1)} ms/frame over ${result.movingFrames}` : '') +
                  `, 640x480, ${result.renderer}`);
    } catch (error) {
      rows.push({ ...c, error: String(error.message || error).split('\n')[0], query: undefined });
      console.log(`${c.mode} ${c.mesh} order ${c.order}: FAILED ${String(error.message || error).split('\n')[0]}`);
    } finally {
      await page.close();
    }
  }
} finally {
  await browser.close();
  server.close();
}
if (out) fs.writeFileSync(out, JSON.stringify(rows, null, 2) + '\n');
