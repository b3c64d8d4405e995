#!/usr/bin/env node
// Glossy bundles in the viewer (glossy.js) in Debian's headless Chromium (SwiftShader), against `prt render`: the
// bunny decimated to 1,000 triangles fitted by `prt glossy` with 1 and 2 lobes (phong:32,0.5, order 3); the stack
// from `prt render --glossy-stack` of studio; the canvas against prt render's PNG of the same bundle, map and camera
// at every 4th pixel whose 3x3 neighbourhood is lit, at two cameras 40 degrees of orbit apart, and the highlight
// must move: between the two cameras the glossy part (glossy on minus off) changes, and it changes as the CLI's
// picture does (both cameras agree with the CLI); the map turned 90 degrees against prt render --rotate-y 90; with
// a stack for the first of two maps only, the lobes are off under the second. Screenshots and agreement.json land in
// WORK_DIR.
// usage: node viewer/test/glossy_test.mjs PRT DATA_DIR WORK_DIR
import fs from 'node:fs';
import path from 'node:path';
import { launchChromium } from './chromium.mjs';
import { serve } from '../serve.mjs';
import { testWorkspace } from './workspace.mjs';

// 8-bit levels at interior pixels. The GPU evaluates the lobes in float where the runtime mixes float and double
// (the view weights' triple products, the turn, the kernel's integral) and the rasteriser's barycentrics are not
// Embree's to the last bit; where d sits on a view-triangle edge the two may pick the other triangle (the weights are
// continuous there). Measured: see agreement.json and docs/results.md.
const kMaxLevels = 3, kMeanLevels = 0.3;

const { prt, data, work, file, run } = testWorkspace('glossy_test.mjs');
const map = path.join(data, 'env/studio.exr');
const size = [160, 120];
const cameras = ['3.46275,7.798,18.8643,-0.00481248,4.8258,0.040403,0,1,0,35', // docs/strips' bunny camera
                 '14.75126,7.798,12.23144,-0.00481248,4.8258,0.040403,0,1,0,35']; // orbited 40 degrees
run('meshprep', path.join(data, 'bunny.ply'), '--decimate-to', '1000', '-o', file('bunny.glb'));
run('envsh', map, '--order', '8', '-o', file('studio.sh.json'));
for (const lobes of [1, 2]) {
  run('glossy', file('bunny.glb'), '--brdf', 'phong:32,0.5', '--lobes', String(lobes), '--order', '3', '--samples', '64',
      '--iterations', '20', '--threads', '2', '-o', file(`glossy${lobes}.glb`));
  for (const [c, camera] of cameras.entries())
    run('render', file(`glossy${lobes}.glb`), '--env', map, '--size', size.join(','), '--camera', camera,
        '-o', file(`render${lobes}_${c}.png`), ...(c === 0 ? ['--glossy-stack', file(`studio${lobes}.stack`)] : []));
}
// The map turned 90 degrees about +Y: the lookup turns (R^T mu), the stack stays.
run('render', file('glossy1.glb'), '--env', map, '--size', size.join(','), '--camera', cameras[0], '--rotate-y', '90',
    '-o', file('render1_turned.png'));

const server = await serve(work);
const base = `http://127.0.0.1:${server.address().port}`;
const browser = await launchChromium();
let failed = false;
const check = (ok, line) => { console.log(`${line} ${ok ? 'ok' : 'FAILED'}`); failed ||= !ok; return ok; };
const results = {};
try {
  const page = await browser.newPage({ viewport: { width: 1100, height: 420 }, deviceScaleFactor: 1 });
  page.on('pageerror', (error) => console.error('page error:', error.message));
  page.on('console', (message) => { if (message.type() === 'error') console.error('page console:', message.text()); });
  // Canvas against a prt PNG at every 4th interior lit pixel; also the glossy part's change (on minus off).
  const against = (png) => page.evaluate(async ({ png, size }) => {
    const blob = await (await fetch(`data:image/png;base64,${png}`)).blob();
    const bitmap = await createImageBitmap(blob, { colorSpaceConversion: 'none', premultiplyAlpha: 'none' });
    const context = new OffscreenCanvas(size[0], size[1]).getContext('2d');
    context.drawImage(bitmap, 0, 0);
    const rendered = context.getImageData(0, 0, size[0], size[1]).data;
    const at = (x, y, ch) => rendered[(y * size[0] + x) * 4 + ch];
    const lit = (x, y) => at(x, y, 0) + at(x, y, 1) + at(x, y, 2) > 0;
    const points = [];
    for (let y = 1; y < size[1] - 1; y += 4)
      for (let x = 1; x < size[0] - 1; x += 4) {
        let inside = true;
        for (let dy = -1; dy <= 1; ++dy) for (let dx = -1; dx <= 1; ++dx) inside &&= lit(x + dx, y + dy);
        if (inside) points.push([x, y]);
      }
    window.prt.set({ glossy: true });
    const viewer = window.prt.read(points);
    let max = 0, sum = 0;
    points.forEach(([x, y], k) => {
      for (let ch = 0; ch < 3; ++ch) { const d = Math.abs(viewer[k][ch] - at(x, y, ch)); max = Math.max(max, d); sum += d; }
    });
    window.prt.set({ glossy: false });
    const diffuse = window.prt.read(points);
    window.prt.set({ glossy: true });
    let glossyLevels = 0;
    points.forEach((_, k) => { for (let ch = 0; ch < 3; ++ch) glossyLevels += viewer[k][ch] - diffuse[k][ch]; });
    return { points: points.length, max, mean: sum / (3 * points.length), glossyMean: glossyLevels / (3 * points.length) };
  }, { png: fs.readFileSync(file(png)).toString('base64'), size });

  for (const lobes of [1, 2]) {
    const seen = [];
    for (const [c, camera] of cameras.entries()) {
      await page.goto(`${base}/?bundle=data/glossy${lobes}.glb&maps=data/studio.sh.json&glossy=data/studio${lobes}.stack` +
                      `&camera=${camera}&size=${size.join(',')}&showSky=0`);
      const info = await page.evaluate(async () => { const api = await window.prtReady; return { renderer: api.renderer, glossy: api.glossy }; });
      if (lobes === 1 && c === 0) console.log(`viewer: ${info.renderer}`);
      const r = await against(`render${lobes}_${c}.png`);
      await page.locator('#view').screenshot({ path: file(`viewer_glossy${lobes}_${c}.png`) });
      check(info.glossy && r.points >= 200 && r.max <= kMaxLevels && r.mean <= kMeanLevels,
            `glossy, ${lobes} lobe(s), camera ${c}: ${r.points} pixels, max ${r.max} mean ${r.mean.toFixed(3)} levels against ` +
            `prt render (tolerance max ${kMaxLevels}, mean ${kMeanLevels}); glossy part ${r.glossyMean.toFixed(2)} levels`);
      check(r.glossyMean > 2, `glossy, ${lobes} lobe(s), camera ${c}: the lobes add ${r.glossyMean.toFixed(2)} levels on average (> 2)`);
      seen.push(r);
      results[`lobes${lobes}_camera${c}`] = { points: r.points, max: r.max, mean: r.mean, glossyMean: r.glossyMean };
    }
    // Orbiting: the same page orbited 40 degrees must land on camera 1's picture (the highlight moved with it).
    await page.goto(`${base}/?bundle=data/glossy${lobes}.glb&maps=data/studio.sh.json&glossy=data/studio${lobes}.stack` +
                    `&camera=${cameras[0]}&size=${size.join(',')}&showSky=0`);
    // Before orbiting: the canvas at every 4th pixel lit in both CLI pictures, to see the picture change as the CLI's.
    const pngs = [0, 1].map((c) => fs.readFileSync(file(`render${lobes}_${c}.png`)).toString('base64'));
    const before = await page.evaluate(async ({ pngs, size }) => {
      await window.prtReady;
      const decoded = [];
      for (const png of pngs) {
        const bitmap = await createImageBitmap(await (await fetch(`data:image/png;base64,${png}`)).blob(),
                                               { colorSpaceConversion: 'none', premultiplyAlpha: 'none' });
        const context = new OffscreenCanvas(size[0], size[1]).getContext('2d');
        context.drawImage(bitmap, 0, 0);
        decoded.push(context.getImageData(0, 0, size[0], size[1]).data);
      }
      const points = [];
      for (let y = 1; y < size[1] - 1; y += 4)
        for (let x = 1; x < size[0] - 1; x += 4) {
          const at = (image, dx, dy) => image[((y + dy) * size[0] + x + dx) * 4] + image[((y + dy) * size[0] + x + dx) * 4 + 1];
          let inside = true;
          for (let dy = -1; dy <= 1; ++dy) for (let dx = -1; dx <= 1; ++dx) inside &&= at(decoded[0], dx, dy) > 0 && at(decoded[1], dx, dy) > 0;
          if (inside) points.push([x, y]);
        }
      const cli = decoded.map((image) => points.map(([x, y]) => [0, 1, 2].map((ch) => image[(y * size[0] + x) * 4 + ch])));
      return { points, cli, viewer: window.prt.read(points) };
    }, { pngs, size });
    await page.evaluate(() => window.prt.orbit(-40, 0));
    const after = await page.evaluate((points) => window.prt.read(points), before.points);
    let cliChange = 0, viewerChange = 0, worst = 0;
    before.points.forEach((_, k) => {
      for (let ch = 0; ch < 3; ++ch) {
        const cli = before.cli[1][k][ch] - before.cli[0][k][ch], viewer = after[k][ch] - before.viewer[k][ch];
        cliChange += Math.abs(cli);
        viewerChange += Math.abs(viewer);
        worst = Math.max(worst, Math.abs(viewer - cli));
      }
    });
    cliChange /= 3 * before.points.length;
    viewerChange /= 3 * before.points.length;
    check(before.points.length >= 150 && cliChange > 5 && worst <= 2 * kMaxLevels,
          `glossy, ${lobes} lobe(s), orbiting 40 degrees changes ${before.points.length} pixels by ${viewerChange.toFixed(2)} levels ` +
          `on average, prt render's two pictures by ${cliChange.toFixed(2)} (> 5); the changes differ by at most ${worst} levels ` +
          `(tolerance ${2 * kMaxLevels})`);
    results[`lobes${lobes}_change`] = { points: before.points.length, cliChange, viewerChange, worst };
    const orbited = await against(`render${lobes}_1.png`);
    check(orbited.max <= kMaxLevels + 1 && orbited.mean <= kMeanLevels,
          `glossy, ${lobes} lobe(s), orbited 40 degrees in the page: max ${orbited.max} mean ${orbited.mean.toFixed(3)} ` +
          'levels against prt render at the orbited camera');
    results[`lobes${lobes}_orbited`] = { max: orbited.max, mean: orbited.mean };
  }
  // Turned: the canvas at rotate=90 against prt render --rotate-y 90.
  await page.goto(`${base}/?bundle=data/glossy1.glb&maps=data/studio.sh.json&glossy=data/studio1.stack` +
                  `&camera=${cameras[0]}&size=${size.join(',')}&showSky=0&rotate=90`);
  await page.evaluate(async () => { await window.prtReady; });
  const turned = await against('render1_turned.png');
  check(turned.max <= kMaxLevels && turned.mean <= kMeanLevels,
        `glossy, 1 lobe, map turned 90 degrees: ${turned.points} pixels, max ${turned.max} mean ${turned.mean.toFixed(3)} levels ` +
        'against prt render --rotate-y 90');
  results.lobes1_turned90 = { points: turned.points, max: turned.max, mean: turned.mean };
  // Two maps, a stack for the first only: under the second the lobes are off (the diffuse part alone).
  await page.goto(`${base}/?bundle=data/glossy1.glb&maps=data/studio.sh.json,data/studio.sh.json&glossy=data/studio1.stack,` +
                  `&camera=${cameras[0]}&size=${size.join(',')}&showSky=0`);
  const perMap = await page.evaluate(async () => {
    const api = await window.prtReady, points = [[80, 60], [60, 50], [100, 70], [70, 40]];
    api.set({ map: 0, glossy: true });
    const lit = api.read(points);
    api.set({ map: 1 });
    const second = api.read(points);
    api.set({ map: 1, glossy: false });
    const off = api.read(points);
    return { maps: api.glossyMaps, same: JSON.stringify(second) === JSON.stringify(off), differ: JSON.stringify(lit) !== JSON.stringify(off) };
  });
  check(JSON.stringify(perMap.maps) === '[true,false]' && perMap.same && perMap.differ,
        `glossy=STACK, (a stack for the first map only): lobes under map 0, the diffuse part alone under map 1 (${JSON.stringify(perMap)})`);
  fs.writeFileSync(file('agreement.json'), JSON.stringify(results, null, 1));
} finally {
  await browser.close();
  server.close();
}
process.exit(failed ? 1 : 0);
