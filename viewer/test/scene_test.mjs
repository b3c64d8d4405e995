#!/usr/bin/env node
// Scene bundles, the sky and the usability features in Debian's headless Chromium (playwright-core):
//   - a textured glTF scene written here (test/scene_fixture.mjs: two instances of a box, one mirrored, COLOR_0,
//     metallic, a bilinear checker through KHR_texture_transform, a MASK fence, a primitive without material) goes
//     through prt meshprep and transfer (interreflected, 1 bounce); the viewer's canvas must match `prt render` of
//     the same bundle and camera at sampled interior pixels, for two cameras and a turned environment;
//   - with the map drawn behind (sky=URL), background pixels must match the map's radiance along prt's pinhole rays,
//     turned with the lighting, bilinear between texel centres, tone-mapped as compare.h; computed here in double
//     precision from the map decoded by three.js's EXRLoader, and `prt render --background` of the same camera and
//     turn at every second background pixel;
//   - orbit, the URL state (a view reloaded from api.query() draws the same pixels), the folder listing panel, the
//     frame-time readout and the screenshot button.
// Screenshots and agreement.json land in WORK_DIR.
// usage: node viewer/test/scene_test.mjs PRT DATA_DIR WORK_DIR
import fs from 'node:fs';
import path from 'node:path';
import { launchChromium } from './chromium.mjs';
import { againstPng } from './pixels.mjs';
import { EXRLoader } from 'three/addons/loaders/EXRLoader.js';
import * as THREE from 'three';
import { serve } from '../serve.mjs';
import { writeTexturedScene } from './scene_fixture.mjs';
import { testWorkspace } from './workspace.mjs';

// 8-bit levels. Surface: as viewer_test.mjs (sums in another order, GPU interpolation), plus the GPU's bilinear
// texture filter, whose weights have fewer bits than prt's float weights.
const kMaxLevels = 3, kMeanLevels = 0.4;
// A pixel is interior when its 3x3 neighbourhood in prt's picture is all surface and within kEdgeLevels of it: hard
// edges (nearest texels, cut-out holes, silhouettes, instance boundaries) are left out, where the GPU's and prt's
// sub-pixel positions may pick different sides. Smooth shading changes by at most about 3 levels per pixel in these
// pictures; the dimmest geometric edge (a box's side against its top, seen from the side camera) steps 14 levels.
const kEdgeLevels = 8;
// Sky: EXRLoader's half floats decoded to float, the direction and bilinear weights in float on the GPU.
const kSkyMaxLevels = 2, kSkyMeanLevels = 0.5;

const { prt, data, work, file, run } = testWorkspace('scene_test.mjs');
const mapFile = path.join(data, 'env/courtyard.exr');

writeTexturedScene(file('scene.gltf'));
run('meshprep', file('scene.gltf'), '-o', file('prepped.glb'));
run('transfer', file('prepped.glb'), '-o', file('scene.prt.glb'), '--mode', 'interreflected', '--bounces', '1',
    '--order', '3', '--samples', '64');
run('envsh', mapFile, '--order', '8', '-o', file('courtyard.sh.json'));
fs.copyFileSync(mapFile, file('courtyard.exr'));

const size = [160, 120];
const cameras = { front: '0,1.4,2.6,0,0.3,0,0,1,0,40', side: '2.2,0.9,1.2,0,0.3,0,0,1,0,45' };
const cases = [
  { camera: 'front', rotate: 0, order: 3 },
  { camera: 'front', rotate: 100, order: 3 },
  { camera: 'side', rotate: 0, order: 2 },
];
let renderError = null; // a failing prt render fails the test, after the sky and usability checks have run
for (const [i, c] of cases.entries())
  try { run('render', file('scene.prt.glb'), '--env', mapFile, '--camera', cameras[c.camera], '--size', size.join(','),
      '--rotate-y', String(c.rotate), '--order', String(c.order), '-o', file(`render_scene${i}.png`)); }
  catch (error) { renderError = error; }
// The sky in prt render too (--background), turned with the lighting: the PNG to compare, the EXR for its coverage.
const skyTurns = [0, 100];
for (const rotate of skyTurns)
  for (const ext of ['png', 'exr'])
    try { run('render', file('scene.prt.glb'), '--env', mapFile, '--camera', cameras.front, '--size', size.join(','),
        '--rotate-y', String(rotate), '--background', '-o', file(`render_sky${rotate}.${ext}`)); }
    catch (error) { renderError = error; }

// The sky's expected 8-bit values at pixel (x, y): prt's pinhole ray (raycast.cpp), the map at R^T d
// (docs/conventions.md), bilinear between texel centres (u repeats, v clamps), then compare.h's tone map.
const exr = new EXRLoader();
exr.setDataType(THREE.FloatType);
const map = exr.parse(fs.readFileSync(mapFile).buffer.slice(0));
function skyExpected(camera, degrees, x, y) {
  const v = camera.split(',').map(Number);
  const sub = (a, b) => a.map((_, k) => a[k] - b[k]);
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const normalize = (a) => { const l = Math.hypot(...a); return a.map((c) => c / l); };
  const forward = normalize(sub(v.slice(3, 6), v.slice(0, 3))), right = normalize(cross(forward, v.slice(6, 9)));
  const up = normalize(cross(right, forward));
  const halfHeight = Math.tan(v[9] * Math.PI / 360), halfWidth = halfHeight * size[0] / size[1];
  const sx = (2 * (x + 0.5) / size[0] - 1) * halfWidth, sy = (1 - 2 * (y + 0.5) / size[1]) * halfHeight;
  const d = normalize([0, 1, 2].map((k) => forward[k] + sx * right[k] + sy * up[k]));
  const t = degrees * Math.PI / 180, c = Math.cos(t), s = Math.sin(t);
  const e = [c * d[0] - s * d[2], d[1], s * d[0] + c * d[2]];
  const theta = Math.acos(Math.max(-1, Math.min(1, e[1]))), phi = Math.atan2(e[0], -e[2]);
  const u = (phi + Math.PI) / (2 * Math.PI) * map.width - 0.5, w = theta / Math.PI * map.height - 0.5;
  const i = Math.floor(u), j = Math.floor(w), fu = u - i, fw = w - j;
  const texel = (a, b, ch) => {
    a = ((a % map.width) + map.width) % map.width;
    b = Math.max(0, Math.min(map.height - 1, b));
    return map.data[((map.height - 1 - b) * map.width + a) * 4 + ch]; // EXRLoader's rows run bottom-up
  };
  return [0, 1, 2].map((ch) => {
    const radiance = (1 - fw) * ((1 - fu) * texel(i, j, ch) + fu * texel(i + 1, j, ch)) +
                     fw * ((1 - fu) * texel(i, j + 1, ch) + fu * texel(i + 1, j + 1, ch));
    const xr = Math.max(radiance, 0), dd = xr / (1 + xr);
    const srgb = dd <= 0.0031308 ? 12.92 * dd : 1.055 * dd ** (1 / 2.4) - 0.055;
    return Math.round(255 * Math.max(0, Math.min(1, srgb)));
  });
}

const server = await serve(work);
const base = `http://127.0.0.1:${server.address().port}`;
const browser = await launchChromium();
let failed = false;
const check = (ok, line) => { console.log(`${line} ${ok ? 'ok' : 'FAILED'}`); failed ||= !ok; return ok; };
const results = {};
try {
  const page = await browser.newPage({ viewport: { width: 900, height: 400 }, deviceScaleFactor: 1, acceptDownloads: true });
  page.on('pageerror', (error) => console.error('page error:', error.message));
  page.on('console', (message) => { if (message.type() === 'error') console.error('page console:', message.text()); });
  const open = async (query) => {
    await page.goto(`${base}/?${query}`);
    return page.evaluate(async () => { const api = await window.prtReady; return { renderer: api.renderer, kind: api.kind, receivers: api.receivers }; });
  };
  const query = (camera, extra = '') => `bundle=data/scene.prt.glb&maps=data/courtyard.sh.json&camera=${camera}&size=${size.join(',')}${extra}`;

  // 1. The scene, relit and textured, against prt render.
  results.surface = [];
  let loadedCamera = null;
  if (renderError) check(false, `prt render of the scene bundle: ${renderError.message.split('\n')[0]}`);
  for (const [i, c] of renderError ? [] : cases.entries()) {
    if (loadedCamera !== c.camera) {
      const info = await open(query(cameras[c.camera], '&showSky=0'));
      if (!loadedCamera) console.log(`viewer: ${info.renderer}; ${info.kind} bundle of ${info.receivers} receivers`);
      check(info.kind === 'scene' && info.receivers === 5, `scene bundle read as ${info.kind} with ${info.receivers} receivers (expected scene, 5)`);
      loadedCamera = c.camera;
    }
    // Every second pixel whose 3x3 neighbourhood in prt's picture is surface and within kEdgeLevels (pixels.mjs).
    const result = await againstPng(page, fs.readFileSync(file(`render_scene${i}.png`)), size,
                                    { rotate: c.rotate, order: c.order }, { step: 2, edge: kEdgeLevels });
    await page.locator('#view').screenshot({ path: file(`viewer_scene${i}.png`) });
    check(result.points >= 400 && result.max <= kMaxLevels && result.mean <= kMeanLevels,
          `scene ${c.camera} rotate ${c.rotate} order ${c.order}: ${result.points} interior pixels, max ${result.max} ` +
          `mean ${result.mean.toFixed(3)} levels (tolerance max ${kMaxLevels}, mean ${kMeanLevels}; ` +
          `pixels by worst channel ${JSON.stringify(result.histogram)}; worst ${JSON.stringify(result.where)})`);
    results.surface.push({ ...c, ...result, state: undefined });
  }

  // 2. The sky behind it, turned with the lighting.
  results.sky = [];
  await open(query(cameras.front, '&sky=data/courtyard.exr'));
  for (const rotate of skyTurns) {
    const points = [];
    for (const [x, y] of [[5, 3], [40, 6], [80, 4], [120, 8], [155, 2], [20, 14], [100, 12], [140, 16]]) points.push([x, y]);
    const viewer = await page.evaluate(({ rotate, points }) => { window.prt.set({ rotate }); return window.prt.read(points); },
                                       { rotate, points });
    // Against prt render --background: every second background pixel whose 3x3 neighbourhood escapes in prt's
    // render (its EXR's A channel is 0 there), so silhouettes, where the rasteriser and the rays may differ, are out.
    if (!renderError) {
      const coverage = exr.parse(fs.readFileSync(file(`render_sky${rotate}.exr`)).buffer.slice(0));
      const escapes = (x, y) => coverage.data[((size[1] - 1 - y) * size[0] + x) * 4 + 3] === 0; // rows bottom-up
      const background = [];
      for (let y = 1; y < size[1] - 1; y += 2)
        for (let x = 1; x < size[0] - 1; x += 2) {
          let all = true;
          for (let dy = -1; dy <= 1; ++dy) for (let dx = -1; dx <= 1; ++dx) all &&= escapes(x + dx, y + dy);
          if (all) background.push([x, y]);
        }
      const png = fs.readFileSync(file(`render_sky${rotate}.png`)).toString('base64');
      const r = await page.evaluate(async ({ png, size, background }) => {
        const blob = await (await fetch(`data:image/png;base64,${png}`)).blob();
        const bitmap = await createImageBitmap(blob, { colorSpaceConversion: 'none', premultiplyAlpha: 'none' });
        const context = new OffscreenCanvas(size[0], size[1]).getContext('2d');
        context.drawImage(bitmap, 0, 0);
        const rendered = context.getImageData(0, 0, size[0], size[1]).data;
        const viewer = window.prt.read(background);
        let max = 0, sum = 0;
        background.forEach(([x, y], k) => {
          for (let ch = 0; ch < 3; ++ch) {
            const d = Math.abs(viewer[k][ch] - rendered[(y * size[0] + x) * 4 + ch]);
            max = Math.max(max, d);
            sum += d;
          }
        });
        return { points: background.length, max, mean: sum / (3 * background.length) };
      }, { png, size, background });
      check(r.points >= 500 && r.max <= kSkyMaxLevels && r.mean <= kSkyMeanLevels,
            `sky rotate ${rotate}: ${r.points} background pixels, max ${r.max} mean ${r.mean.toFixed(3)} levels against ` +
            `prt render --background (tolerance max ${kSkyMaxLevels}, mean ${kSkyMeanLevels})`);
      results.skyAgainstRender = [...(results.skyAgainstRender || []), { rotate, ...r }];
    }
    let max = 0, sum = 0;
    points.forEach(([x, y], k) => {
      const expected = skyExpected(cameras.front, rotate, x, y);
      for (let ch = 0; ch < 3; ++ch) { const d = Math.abs(expected[ch] - viewer[k][ch]); max = Math.max(max, d); sum += d; }
    });
    const mean = sum / (3 * points.length);
    await page.locator('#view').screenshot({ path: file(`viewer_sky${rotate}.png`) });
    check(max <= kSkyMaxLevels && mean <= kSkyMeanLevels,
          `sky rotate ${rotate}: ${points.length} background pixels, max ${max} mean ${mean.toFixed(3)} levels against the map ` +
          `(tolerance max ${kSkyMaxLevels}, mean ${kSkyMeanLevels})`);
    results.sky.push({ rotate, points: points.length, max, mean });
  }

  // 3. Usability: orbit moves the camera, the URL state reloads the same view, the panel lists the folder, the
  // frame time shows, the screenshot button downloads a PNG.
  const orbited = await page.evaluate(() => {
    const before = window.prt.camera();
    window.prt.orbit(30, 10, 0.9);
    return { before, after: window.prt.camera(), query: window.prt.query(), pixels: window.prt.read([[40, 60], [80, 70], [120, 90]]),
             frame: document.getElementById('frame').textContent, url: location.search };
  });
  const moved = Math.hypot(...orbited.after.slice(0, 3).map((v, k) => v - orbited.before[k]));
  check(moved > 0.5 && orbited.url.slice(1) === orbited.query, `orbit moves the eye by ${moved.toFixed(3)} and the address bar holds the view`);
  check(/\d+(\.\d+)? ms/.test(orbited.frame), `frame-time readout shows "${orbited.frame}"`);
  await page.keyboard.press('ArrowLeft'); // the keyboard orbits too
  const keyed = await page.evaluate(() => window.prt.camera());
  check(Math.hypot(...keyed.slice(0, 3).map((v, k) => v - orbited.after[k])) > 1e-3, 'the arrow keys orbit');
  await page.goto(`${base}/?${orbited.query}`);
  const reloaded = await page.evaluate(async () => { await window.prtReady; return window.prt.read([[40, 60], [80, 70], [120, 90]]); });
  const reloadDiff = Math.max(...reloaded.flat().map((v, k) => Math.abs(v - orbited.pixels.flat()[k])));
  check(reloadDiff <= 1, `a view reloaded from its URL draws the same pixels (max ${reloadDiff} levels)`);
  const listing = await page.evaluate(() => [...document.querySelectorAll('#files a')].map((a) => a.textContent));
  check(listing.includes('scene.prt.glb') && listing.includes('courtyard.sh.json'),
        `the panel lists the folder: ${listing.join(', ')}`);
  const [download] = await Promise.all([page.waitForEvent('download'), page.click('#screenshot')]);
  await download.saveAs(file('viewer_button.png'));
  const head = fs.readFileSync(file('viewer_button.png')).subarray(0, 8);
  check(head.equals(Buffer.from([137, 80, 78, 71, 13, 10, 26, 10])), `the screenshot button saves a PNG (${download.suggestedFilename()})`);
  await page.screenshot({ path: file('viewer_page.png') });
  results.renderer = (await page.evaluate(() => window.prt.renderer));
  fs.writeFileSync(file('agreement.json'), JSON.stringify(results, null, 2) + '\n');
} finally {
  await browser.close();
  server.close();
}
process.exit(failed ? 1 : 0);
