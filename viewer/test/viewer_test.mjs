#!/usr/bin/env node
// The viewer in a real browser (Debian's headless Chromium through playwright-core). Bundles relit on the GPU must
// match `prt render` of the same camera at sampled pixels, 8-bit tone-mapped values within a stated tolerance, for
// a turned environment and a lower order too:
//   - the default pipeline's own bundle (pipelines/default.toml, run here from an empty cache), whose reference
//     radiance also drives the error display: the viewer's relative RMSE must equal `prt compare`'s metrics.json,
//     and the false-colour view must draw viridis;
//   - the default pipeline's bake, per texel from its OpenEXR texture;
//   - a two-spheres bundle per vertex (one sphere shadows the other) and a small bake per texel in the bundle.
// Saves screenshots as test artefacts.
// usage: node viewer/test/viewer_test.mjs PRT PIPELINE.toml DATA_DIR WORK_DIR
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { launchChromium } from './chromium.mjs';
import { serve } from '../serve.mjs';

// Tolerance in 8-bit levels of the tone-mapped picture: the GPU sums the SH products in another order than the
// CPU kernel and interpolates in its own precision; one level is about 0.4% of radiance in the mid-tones.
const kMaxLevels = 2;
const kMeanLevels = 0.25;
const kTexelEdgeShare = 0.02, kTexelEdgeLevels = 12;

const [prt, pipeline, data, work] = process.argv.slice(2);
if (!prt || !pipeline || !data || !work) {
  console.error('usage: viewer_test.mjs PRT PIPELINE.toml DATA_DIR WORK_DIR');
  process.exit(2);
}
const env = path.join(data, 'env/courtyard.exr');
fs.rmSync(work, { recursive: true, force: true });
fs.mkdirSync(work, { recursive: true });
const run = (...args) => {
  const result = spawnSync(prt, ['--quiet', ...args], { encoding: 'utf8', cwd: work });
  if (result.status !== 0) throw new Error(`prt ${args.join(' ')} failed (${result.status}):\n${result.stderr}`);
};
const file = (name) => path.join(work, name);

// The default pipeline, run in WORK from an empty cache: its inputs are the data folder's, its outputs land in
// WORK/out/default (bunny.prt.glb per vertex at order 5, reference.npy, metrics.json from prt compare).
fs.mkdirSync(file('.cache'));
fs.symlinkSync(path.resolve(data), file('.cache/data'));
run('run', path.resolve(pipeline), '--cache-dir', file('cache'));
const metrics = JSON.parse(fs.readFileSync(file('out/default/metrics.json'), 'utf8'));

// Two spheres: one shadows the other, so the picture has more than a smooth gradient.
run('scene', 'two-spheres', '-o', file('scene.glb'));
run('transfer', file('scene.glb'), '--mode', 'shadowed', '--order', '4', '--samples', '256', '-o', file('bundle.glb'));
run('envsh', env, '--order', '8', '-o', file('env.sh.json'));
// Per texel too: a small bake whose texels live in the bundle (--format bundle), looked up nearest at TEXCOORD_0.
run('bake', file('scene.glb'), '--resolution', '64', '--order', '3', '--samples', '32', '--format', 'bundle', '-o',
    file('baked.glb'));

const size = [160, 120];
const spheres = '0,1,3.6,0,0,0,0,1,0,40';
const bunny = '3.46275,7.798,18.8643,-0.00481248,4.8258,0.040403,0,1,0,35'; // docs/strips' camera
const defaultBundle = 'out/default/bunny.prt.glb';
const cases = [
  { bundle: defaultBundle, camera: bunny, rotate: 0, order: 5 },
  { bundle: defaultBundle, camera: bunny, rotate: 120, order: 3 },
  // The default pipeline's bake: half-float texels in a multi-channel OpenEXR next to the bundle (viewer/exr.js).
  { bundle: 'out/default/bunny.baked.glb', camera: bunny, rotate: 30, order: 3, texel: true },
  { bundle: 'bundle.glb', camera: spheres, rotate: 0, order: 4 },
  { bundle: 'bundle.glb', camera: spheres, rotate: 75, order: 4 },
  { bundle: 'bundle.glb', camera: spheres, rotate: 0, order: 2 },
  { bundle: 'baked.glb', camera: spheres, rotate: 40, order: 3, texel: true },
];
for (const [i, c] of cases.entries())
  run('render', file(c.bundle), ...(c.texel ? ['--texels'] : []), '--env', env, '--camera', c.camera, '--size',
      size.join(','), '--rotate-y', String(c.rotate), '--order', String(c.order), '-o', file(`render${i}.png`));

// The false-colour error view draws viridis (fragment shader falseColour); a pixel on it lies within this many
// 8-bit levels of the piecewise-linear curve through its five stops.
const kViridis = [[0.267, 0.005, 0.329], [0.229, 0.322, 0.546], [0.128, 0.567, 0.551], [0.369, 0.789, 0.383],
                  [0.993, 0.906, 0.144]];
const kViridisLevels = 2;
function distanceToViridis(rgb) {
  let best = Infinity;
  for (let i = 0; i < 4; ++i)
    for (let k = 0; k <= 64; ++k) {
      const t = k / 64;
      const d = Math.max(...[0, 1, 2].map((ch) =>
        Math.abs(rgb[ch] - 255 * (kViridis[i][ch] + t * (kViridis[i + 1][ch] - kViridis[i][ch])))));
      best = Math.min(best, d);
    }
  return best;
}
// The viewer's relative RMSE against the reference must be prt compare's to this relative tolerance (float32 sums
// in another order, and the lighting truncated from an order-8 envsh instead of projected at order 5).
const kMetricTolerance = 1e-3;

const server = await serve(work);
const base = `http://127.0.0.1:${server.address().port}`;
const browser = await launchChromium();
let failed = false;
const results = [];
let errorView = null;
try {
  const page = await browser.newPage({ viewport: { width: 640, height: 360 }, deviceScaleFactor: 1 });
  page.on('pageerror', (error) => console.error('page error:', error.message));
  let info = null, loaded = null;
  for (const [i, c] of cases.entries()) {
    const query = `bundle=data/${c.bundle}${c.texel ? '&mode=texel' : ''}&maps=data/env.sh.json&camera=${c.camera}` +
                  `&size=${size.join(',')}` + (c.bundle === defaultBundle ? '&reference=data/out/default/reference.npy' : '');
    if (loaded !== query) {
      await page.goto(`${base}/?${query}`);
      info = await page.evaluate(async () => { const api = await window.prtReady; return { renderer: api.renderer }; });
      if (!loaded) console.log(`viewer: ${info.renderer}`);
      loaded = query;
    }
    const png = fs.readFileSync(file(`render${i}.png`)).toString('base64');
    const result = await page.evaluate(async ({ png, c, size, maxLevels }) => {
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
      window.prt.set({ rotate: c.rotate, order: c.order, showError: false });
      const viewer = window.prt.read(points);
      let max = 0, sum = 0, over = 0;
      points.forEach(([x, y], k) => {
        let worst = 0;
        for (let ch = 0; ch < 3; ++ch) {
          const d = Math.abs(viewer[k][ch] - rendered[(y * size[0] + x) * 4 + ch]);
          worst = Math.max(worst, d);
          sum += d;
        }
        max = Math.max(max, worst);
        over += worst > maxLevels;
      });
      // With a reference: the metrics at the pipeline's own setting (full order, unturned), and the error view.
      let error = null;
      if (window.prt.metrics() && c.rotate === 0 && c.order === window.prt.transferOrder) {
        window.prt.set({ showError: true });
        error = { metrics: window.prt.metrics(), pixels: window.prt.read(points),
                  status: document.getElementById('status').textContent };
        window.prt.set({ showError: false });
      }
      return { points: points.length, max, over, mean: sum / (3 * points.length), error };
    }, { png, c, size, maxLevels: kMaxLevels });
    await page.locator('#view').screenshot({ path: file(`viewer${i}.png`) });
    // Per texel, a pixel whose uv lies next to a texel edge may take the neighbouring texel (the GPU interpolates
    // uv in its own precision): such pixels may exceed the tolerance, a few of them and within kTexelEdgeLevels.
    const allowed = c.texel ? Math.floor(kTexelEdgeShare * result.points) : 0;
    const ok = result.points >= 100 && result.over <= allowed && result.max <= (c.texel ? kTexelEdgeLevels : kMaxLevels) &&
               result.mean <= kMeanLevels;
    console.log(`case ${c.bundle} ${c.texel ? 'per texel' : 'per vertex'} rotate ${c.rotate} order ${c.order}: ` +
                `${result.points} pixels, max ${result.max} mean ${result.mean.toFixed(3)} levels, ${result.over} over ` +
                `${kMaxLevels} (tolerance max ${kMaxLevels}, mean ${kMeanLevels}` +
                (c.texel ? `; at texel edges ${allowed} pixels up to ${kTexelEdgeLevels}` : '') + `) ${ok ? 'ok' : 'FAILED'}`);
    failed ||= !ok;
    if (result.error) {
      const viewerRmse = result.error.metrics.relativeRmse, compareRmse = metrics.relative_rmse;
      const metricOk = Math.abs(viewerRmse - compareRmse) <= kMetricTolerance * compareRmse;
      const offCurve = Math.max(...result.error.pixels.map(distanceToViridis));
      const changed = result.error.pixels.filter((rgb, k) => rgb.some((v, ch) => v !== 0)).length;
      const statusOk = result.error.status.includes(`relative RMSE ${(100 * viewerRmse).toFixed(2)}%`);
      const viewOk = offCurve <= kViridisLevels && changed === result.error.pixels.length && statusOk;
      console.log(`error view: relative RMSE ${viewerRmse.toFixed(6)} against prt compare's ${compareRmse.toFixed(6)} ` +
                  `(tolerance ${kMetricTolerance} relative) ${metricOk ? 'ok' : 'FAILED'}; ` +
                  `${result.error.pixels.length} pixels at most ${offCurve.toFixed(2)} levels off viridis ` +
                  `(tolerance ${kViridisLevels}), panel ${statusOk ? 'shows it' : 'does NOT show it'} ` +
                  `${viewOk ? 'ok' : 'FAILED'}`);
      await page.evaluate(() => window.prt.set({ showError: true }));
      await page.locator('#view').screenshot({ path: file('viewer_error.png') });
      await page.evaluate(() => window.prt.set({ showError: false }));
      failed ||= !metricOk || !viewOk;
      errorView = { viewerRmse, compareRmse, offCurve, pixels: result.error.pixels.length };
    }
    results.push({ ...c, points: result.points, max: result.max, over: result.over, mean: result.mean, ok });
  }
  if (!errorView) { console.log('error view: never checked FAILED'); failed = true; }
  fs.writeFileSync(file('agreement.json'),
                   JSON.stringify({ renderer: info.renderer, results, errorView }, null, 2) + '\n');
} finally {
  await browser.close();
  server.close();
}
process.exit(failed ? 1 : 0);
