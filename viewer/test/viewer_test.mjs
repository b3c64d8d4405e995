#!/usr/bin/env node
// The viewer in a real browser (Debian's headless Chromium through playwright-core): a small bundle relit on the
// GPU must match `prt render` of the same camera at sampled pixels, 8-bit tone-mapped values within a stated
// tolerance, for a turned environment and a lower order too. Saves screenshots as test artefacts.
// usage: node viewer/test/viewer_test.mjs PRT ENV.exr WORK_DIR
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { chromium } from 'playwright-core';
import { serve } from '../serve.mjs';

// Tolerance in 8-bit levels of the tone-mapped picture: the GPU sums the SH products in another order than the
// CPU kernel and interpolates in its own precision; one level is about 0.4% of radiance in the mid-tones.
const kMaxLevels = 2;
const kMeanLevels = 0.25;

const [prt, env, work] = process.argv.slice(2);
if (!prt || !env || !work) { console.error('usage: viewer_test.mjs PRT ENV.exr WORK_DIR'); process.exit(2); }
fs.rmSync(work, { recursive: true, force: true });
fs.mkdirSync(work, { recursive: true });
const run = (...args) => {
  const result = spawnSync(prt, ['--quiet', ...args], { encoding: 'utf8' });
  if (result.status !== 0) throw new Error(`prt ${args.join(' ')} failed (${result.status}):\n${result.stderr}`);
};
const file = (name) => path.join(work, name);

// Two spheres: one shadows the other, so the picture has more than a smooth gradient.
run('scene', 'two-spheres', '-o', file('scene.glb'));
run('transfer', file('scene.glb'), '--mode', 'shadowed', '--order', '4', '--samples', '256', '-o', file('bundle.glb'));
run('envsh', env, '--order', '8', '-o', file('env.sh.json'));
const size = [160, 120];
const camera = '0,1,3.6,0,0,0,0,1,0,40';
// Per texel too: a small bake whose texels live in the bundle (--format bundle), looked up nearest at TEXCOORD_0.
run('bake', file('scene.glb'), '--resolution', '64', '--order', '3', '--samples', '32', '--format', 'bundle', '-o',
    file('baked.glb'));
const cases = [{ rotate: 0, order: 4 }, { rotate: 75, order: 4 }, { rotate: 0, order: 2 },
               { rotate: 40, order: 3, texel: true }];
for (const [i, c] of cases.entries())
  run('render', file(c.texel ? 'baked.glb' : 'bundle.glb'), ...(c.texel ? ['--texels'] : []), '--env', env,
      '--camera', camera, '--size', size.join(','), '--rotate-y', String(c.rotate), '--order', String(c.order), '-o',
      file(`render${i}.png`));

const server = await serve(work);
const base = `http://127.0.0.1:${server.address().port}`;
const browser = await chromium.launch({
  executablePath: process.env.PRT_CHROMIUM || '/usr/bin/chromium',
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
         '--disable-background-networking', '--disable-component-update', '--disable-sync',
         '--enable-unsafe-swiftshader', '--use-angle=swiftshader'],
});
let failed = false;
const results = [];
try {
  const page = await browser.newPage({ viewport: { width: 640, height: 360 }, deviceScaleFactor: 1 });
  page.on('pageerror', (error) => console.error('page error:', error.message));
  let info = null, loaded = null;
  for (const [i, c] of cases.entries()) {
    const bundle = c.texel ? 'baked.glb&mode=texel' : 'bundle.glb';
    if (loaded !== bundle) {
      await page.goto(`${base}/?bundle=data/${bundle}&maps=data/env.sh.json&camera=${camera}&size=${size.join(',')}`);
      info = await page.evaluate(async () => { const api = await window.prtReady; return { renderer: api.renderer }; });
      if (!loaded) console.log(`viewer: ${info.renderer}`);
      loaded = bundle;
    }
    const png = fs.readFileSync(file(`render${i}.png`)).toString('base64');
    const result = await page.evaluate(async ({ png, c, size }) => {
      // Decode prt render's PNG in the page, with no colour management, to its stored 8-bit values.
      const blob = await (await fetch(`data:image/png;base64,${png}`)).blob();
      const bitmap = await createImageBitmap(blob, { colorSpaceConversion: 'none', premultiplyAlpha: 'none' });
      const canvas = new OffscreenCanvas(size[0], size[1]);
      const context = canvas.getContext('2d');
      context.drawImage(bitmap, 0, 0);
      const rendered = context.getImageData(0, 0, size[0], size[1]).data;
      const lit = (x, y) => rendered[(y * size[0] + x) * 4] + rendered[(y * size[0] + x) * 4 + 1] > 0;
      // Sampled pixels: every 4th pixel whose 3x3 neighbourhood is all lit surface (no silhouette, no background).
      const points = [];
      for (let y = 1; y < size[1] - 1; y += 4)
        for (let x = 1; x < size[0] - 1; x += 4) {
          let inside = true;
          for (let dy = -1; dy <= 1; ++dy) for (let dx = -1; dx <= 1; ++dx) inside &&= lit(x + dx, y + dy);
          if (inside) points.push([x, y]);
        }
      window.prt.set({ rotate: c.rotate, order: c.order });
      const viewer = window.prt.read(points);
      let max = 0, sum = 0;
      points.forEach(([x, y], k) => {
        for (let ch = 0; ch < 3; ++ch) {
          const d = Math.abs(viewer[k][ch] - rendered[(y * size[0] + x) * 4 + ch]);
          max = Math.max(max, d);
          sum += d;
        }
      });
      return { points: points.length, max, mean: sum / (3 * points.length) };
    }, { png, c, size });
    await page.locator('#view').screenshot({ path: file(`viewer${i}.png`) });
    const ok = result.points >= 100 && result.max <= kMaxLevels && result.mean <= kMeanLevels;
    console.log(`case ${c.texel ? 'per texel' : 'per vertex'} rotate ${c.rotate} order ${c.order}: ${result.points} pixels, max ${result.max} mean ` +
                `${result.mean.toFixed(3)} levels (tolerance max ${kMaxLevels}, mean ${kMeanLevels}) ${ok ? 'ok' : 'FAILED'}`);
    failed ||= !ok;
    results.push({ ...c, ...result, ok });
  }
  fs.writeFileSync(file('agreement.json'), JSON.stringify({ renderer: info.renderer, results }, null, 2) + '\n');
} finally {
  await browser.close();
  server.close();
}
process.exit(failed ? 1 : 0);
