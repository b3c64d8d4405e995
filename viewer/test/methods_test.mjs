#!/usr/bin/env node
// The viewer's other methods in Debian's headless Chromium (playwright-core), each against the CLI's own output:
//   - hybrid lights (hybrid.js): the bunny's interreflected transfer (order 4, one bounce, so it has the bounce
//     layer) under studio's cone lights and SH residual from `prt envlight`; the canvas must match the picture of
//     `prt relight --lights --image` at sampled interior pixels, with the cone visibility `--visibility-out` wrote
//     (turned 0 and 60 degrees, the turn locked to the visibility's), and unshadowed (`--light-samples 0`) turned
//     freely to 120 degrees; the toggle to plain SH must match `prt render` of the same bundle and camera;
//   - the reference beside the result (compare.js): `prt reference --image` of the same camera; the relative RMSE the
//     page prints must be `prt compare --image`'s (of `prt render`'s EXR against the same reference) within
//     kRmseTolerance, the reference panel must be compare's strip's reference panel, the error panel compare's
//     false-colour picture at interior pixels, and the camera must stay locked while the comparison is shown;
//   - moving occluders (fiv_gpu.js on the GPU, and fiv.js on the CPU): a `prt fivscene` bundle of the bunny under three sphere instances, with and
//     without the bunny's own grid (self-shadowing); the viewer's per-vertex radiance must be `prt fivshade`'s of the
//     same placements at every vertex, for three sets of instance positions reached by moving the instances in the
//     page (kFivTolerance); a view reloaded from its URL keeps the positions; and the same under sunrise with the
//     small sources' own grids (`prt fiv --sources --source-grid`) on the spheres and the bunny, the bunny's exact
//     self-shadowing at its vertices (`--self-vertices`, fiv_self) or through its grid, at three placements that put
//     the spheres' sun shadows on the bunny; a source grid past the GPU pass's shells falls back to the CPU, saying so;
//     malformed source grids and fiv_self (copies of the sunrise scene with one member changed) are refused.
// Screenshots and agreement.json land in WORK_DIR.
// usage: node viewer/test/methods_test.mjs PRT DATA_DIR WORK_DIR
import fs from 'node:fs';
import path from 'node:path';
import { launchChromium } from './chromium.mjs';
import { againstPng } from './pixels.mjs';
import { serve } from '../serve.mjs';
import { EXRLoader } from 'three/addons/loaders/EXRLoader.js';
import * as THREE from 'three';
import { testWorkspace } from './workspace.mjs';

// 8-bit levels at interior pixels (3x3 neighbourhood all surface): as viewer_test.mjs (sums in another order, the
// GPU's interpolation), plus the cone integral in float on the GPU against double in the runtime.
const kMaxLevels = 2, kMeanLevels = 0.3;
// The printed relative RMSE against prt compare's: the viewer's result is its own float radiance (GPU sums and
// interpolation) and its coverage the rasteriser's, which may differ from the ray caster's at silhouette pixels.
// Measured: 20 of 6,500 pixels see another triangle than prt render's ray at silhouettes and ear edges (up to 60%
// apart), 3 more are covered, so the two RMSEs differ by about 1%.
const kRmseTolerance = 0.02; // relative
// Error panel against compare's picture, at pixels covered in both where the viewer's linear result is prt render's
// within 0.1% (the GPU's interpolation agrees there; elsewhere a silhouette or an edge where the rasteriser picks
// another triangle, or interpolation rounding above 0.1%), in colour levels: a relative error e moved by 0.1% (1 + e)
// moves viridis's t = e / 0.2 by at most 0.006, up to 4 levels on its steepest stop, plus rounding.
const kErrorPanelLevels = 5;
// Over every pixel covered in both, this share must lie within kErrorPanelLevels.
const kErrorPanelShare = 0.97;
// FIV radiance per vertex, |a - b| <= abs + rel |b|. CPU (fiv.js, double) against the runtime's float: rounding.
// GPU (fiv_gpu.js, float in another order): with self-shadowing the receiver's unoccluded light is N . FIV(Env) -
// N . FIV_self, two terms several times the result, so float cancellation reaches about 2e-4 (0.1% of the mean).
// Under sunrise the GPU's largest differences (6e-4, 0.65 of the tolerance) lie in the spheres' sun penumbrae, where
// the sharpened source fraction is steep in angle and the GPU's acos / atan round otherwise (3.5e-5 elsewhere).
const kFivTolerance = { cpu: { abs: 1e-5, rel: 1e-4 }, gpu: { abs: 5e-4, rel: 1e-3 } };
// The sunrise scenes must show the spheres' sun shadows: at each placement at least this many vertices are darker
// by 20% than with the spheres far away (measured: about 100 of 1839).
const kSunShadowVertices = 50;

const { prt, data, work, file, run } = testWorkspace('methods_test.mjs');
const map = path.join(data, 'env/studio.exr'); // three cone lights of 2.5 to 3.1 degrees
const size = [160, 120];
const camera = '3.46275,7.798,18.8643,-0.00481248,4.8258,0.040403,0,1,0,35'; // docs/strips' bunny camera
const view = ['--camera', camera, '--size', size.join(',')];

run('meshprep', path.join(data, 'bunny.ply'), '-o', file('bunny.glb'));
run('transfer', file('bunny.glb'), '--mode', 'interreflected', '--bounces', '1', '--order', '4', '--samples', '64',
    '--albedo', '0.8', '-o', file('bunny.prt.glb'));
run('envsh', map, '--order', '8', '-o', file('studio.sh.json'));
run('envlight', map, '--order', '4', '--max-lights', '4', '-o', file('studio.lights.json'));
const lightCount = JSON.parse(fs.readFileSync(file('studio.lights.json'), 'utf8')).lights.length;
run('envlight', map, '--order', '3', '--max-lights', '4', '-o', file('order3.lights.json')); // bad inputs below
{ // a visibility of 10 rows x 3 lights
  const header = "{'descr': '<f4', 'fortran_order': False, 'shape': (10, 3), }".padEnd(117, ' ') + '\n';
  fs.writeFileSync(file('short.npy'), Buffer.concat([Buffer.from([0x93]), Buffer.from('NUMPY'), Buffer.from([1, 0, 118, 0]),
                                                       Buffer.from(header), Buffer.alloc(120)]));
}
const hybridCases = [
  { rotate: 0, visibility: 'visibility0.npy' },
  { rotate: 60, visibility: 'visibility60.npy' },
  { rotate: 120, visibility: null }, // unshadowed cones, turned freely
];
for (const c of hybridCases)
  run('relight', file('bunny.prt.glb'), '--lights', file('studio.lights.json'), '--env', map, '--rotate-y', String(c.rotate),
      ...(c.visibility ? ['--visibility-out', file(c.visibility)] : ['--light-samples', '0']),
      '--image', size.join(','), '--camera', camera, '-o', file(`hybrid${c.rotate}.png`));
run('render', file('bunny.prt.glb'), '--env', map, ...view, '-o', file('plain.png'));
run('render', file('bunny.prt.glb'), '--env', map, ...view, '-o', file('plain.exr'));
run('reference', file('bunny.glb'), '--env', map, '--image', size.join(','), '--camera', camera, '--bounces', '1',
    '--albedo', '0.8', '--samples', '256', '-o', file('reference.exr'));
run('compare', '--image', file('plain.exr'), file('reference.exr'), '-o', file('compare_error.png'), '--strip',
    file('compare_strip.png'), '--metrics', file('compare.json'));
const compared = JSON.parse(fs.readFileSync(file('compare.json'), 'utf8'));

// Moving occluders: sphere grids (radius 1) around the bunny, and the bunny's own grid.
const fivMap = path.join(data, 'env/courtyard.exr');
run('scene', 'sphere', '-o', file('sphere.glb'));
for (const mesh of ['sphere', 'bunny'])
  run('fiv', file(`${mesh}.glb`), '--env', fivMap, '--grid', '16,9,6', '--cube', '8', '-o', file(`${mesh}.fiv.glb`));
// Three placements: above the bunny (case A), one sphere sunk into its back (B and inside), one beside it (C for
// the far side); each of three spheres.
const placements = [
  [[-2, 11, 1], [2, 10, -1], [4, 7, 4]],
  [[0, 8.2, -1.5], [-3, 6, 3], [5, 3, 0]],
  [[1, 12, 3], [-4, 2, 4], [0, 5, -5]],
];
const fivArgs = (at) => at.flatMap((p) => ['--occluder', file('sphere.fiv.glb'), '--at', p.join(',')]);
run('fivscene', file('bunny.glb'), ...fivArgs(placements[0]), '-o', file('fivscene.glb'));
run('fivscene', file('bunny.glb'), '--self', file('bunny.fiv.glb'), ...fivArgs(placements[0]), '-o', file('fivscene_self.glb'));
for (const [k, at] of placements.entries()) {
  run('fivshade', file('bunny.glb'), '--env', fivMap, ...fivArgs(at), '--albedo', '0.8', '-o', file(`fiv${k}.npy`));
  run('fivshade', file('bunny.glb'), '--env', fivMap, '--self', file('bunny.fiv.glb'), ...fivArgs(at), '--albedo', '0.8',
      '-o', file(`fiv_self${k}.npy`));
}
// Under sunrise (one small source, 59% of the map's power): the sources' own grid 32x17x12 on each (twice the main
// grid's 16x9x6), the bunny's E_self at its vertices in one scene and its grid alone in the other.
const sunMap = path.join(data, 'env/sunrise.exr');
const sunFiv = ['--env', sunMap, '--grid', '16,9,6', '--cube', '8', '--sources', '--source-grid', '32,17,12'];
run('fiv', file('sphere.glb'), ...sunFiv, '-o', file('sphere_sun.fiv.glb'));
run('fiv', file('bunny.glb'), ...sunFiv, '--self-vertices', '-o', file('bunny_sun.fiv.glb'));
run('fiv', file('bunny.glb'), ...sunFiv, '-o', file('bunny_sungrid.fiv.glb'));
// A source grid of 65 shells, past fiv_gpu.js's kMaxSourceShells: the GPU view falls back to fiv.js.
run('fiv', file('sphere.glb'), '--env', sunMap, '--grid', '16,9,6', '--cube', '8', '--sources', '--source-grid', '8,5,65',
    '-o', file('sphere_sun65.fiv.glb'));
// Spheres between the low sun (direction about (0.58, 0.14, -0.80)) and the bunny.
const sunPlacements = [
  [[2.9, 5.7, -4], [-1, 9, -4.5], [3, 2, -3.5]],
  [[1.5, 7, -3.5], [4, 4, -2], [-2, 4, -4]],
  [[0, 8.2, -1.5], [3.5, 3, -4], [-3, 6, 3]],
];
const sunArgs = (at, sphere = 'sphere_sun') => at.flatMap((p) => ['--occluder', file(`${sphere}.fiv.glb`), '--at', p.join(',')]);
for (const self of ['sun', 'sungrid']) {
  run('fivscene', file('bunny.glb'), '--self', file(`bunny_${self}.fiv.glb`), ...sunArgs(sunPlacements[0]), '-o', file(`fivscene_${self}.glb`));
  // Placement 0 from the scene itself (fivscene's layers as fivshade reads them), the others from the FIV files.
  run('fivshade', file(`fivscene_${self}.glb`), '--env', sunMap, '--albedo', '0.8', '-o', file(`fiv_${self}0.npy`));
  for (const [k, at] of sunPlacements.entries())
    if (k > 0) run('fivshade', file('bunny.glb'), '--env', sunMap, '--self', file(`bunny_${self}.fiv.glb`), ...sunArgs(at),
                   '--albedo', '0.8', '-o', file(`fiv_${self}${k}.npy`));
}
for (const self of ['sun', 'sungrid']) // the spheres far away: the bunny's own shadows only
  run('fivshade', file('bunny.glb'), '--env', sunMap, '--self', file(`bunny_${self}.fiv.glb`), ...sunArgs([[1e3, 1e3, 1e3]]),
      '--albedo', '0.8', '-o', file(`fiv_${self}_unshadowed.npy`));
run('fivscene', file('bunny.glb'), ...sunArgs(sunPlacements[0], 'sphere_sun65'), '-o', file('fivscene_sun65.glb'));
run('fivshade', file('fivscene_sun65.glb'), '--env', sunMap, '--albedo', '0.8', '-o', file('fiv_sun650.npy'));
// Malformed copies of the sunrise scene for the reader's refusals: `edit` changes the glTF JSON, the BIN chunk is kept.
const rewriteGlb = (from, to, edit) => {
  const bytes = fs.readFileSync(file(from)), jsonLength = bytes.readUInt32LE(12);
  const json = JSON.parse(bytes.subarray(20, 20 + jsonLength).toString('utf8'));
  edit(json);
  const text = Buffer.from(JSON.stringify(json)), padded = Buffer.concat([text, Buffer.alloc((4 - text.length % 4) % 4, 0x20)]);
  const bin = bytes.subarray(20 + jsonLength), header = Buffer.alloc(20);
  header.writeUInt32LE(0x46546c67, 0);
  header.writeUInt32LE(2, 4);
  header.writeUInt32LE(20 + padded.length + bin.length, 8);
  header.writeUInt32LE(padded.length, 12);
  header.writeUInt32LE(0x4e4f534a, 16);
  fs.writeFileSync(file(to), Buffer.concat([header, padded, bin]));
};
const sunLayer = (json, name) => json.extensions.PRT_bundle.layers.find((l) => l.name === name);
const badSunScenes = [
  ['bad_no_valid', (j) => { j.extensions.PRT_bundle.layers = j.extensions.PRT_bundle.layers.filter((l) => l.name !== 'fiv_source_valid.1'); },
   /object 1 has fiv_source_grid without fiv_source_valid/],
  ['bad_sharpen', (j) => { sunLayer(j, 'fiv_source_grid.1').params.sharpen = 0.5; }, /fiv_source_grid\.1 params\.sharpen is outside 1\.\.100/],
  ['bad_source_fiv', (j) => { const p = sunLayer(j, 'fiv_source_grid.1').params; p.source_fiv[0] = p.source_fiv[0].map((x) => 2 * x); },
   /source_fiv\[0\] is longer than source_power/],
  ['bad_radius', (j) => { sunLayer(j, 'fiv_source_grid.1').params.radius *= 1.01; }, /params\.radius is missing or differs from the main grid's/],
  ['bad_env', (j) => { sunLayer(j, 'fiv_source_grid.1').params.env = 'xxh128:0'; }, /params\.env differs from the main grid's environment/],
  ['bad_self_shape', (j) => { sunLayer(j, 'fiv_self').shape = [1838, 3]; }, /layer fiv_self has shape \[1838,3\], expected \[1839,3\]/],
];
for (const [name, edit] of badSunScenes) rewriteGlb('fivscene_sun.glb', `${name}.glb`, edit);
const readNpy = (name) => {
  const bytes = fs.readFileSync(file(name)), header = bytes.readUInt16LE(8);
  return Array.from(new Float32Array(bytes.buffer.slice(bytes.byteOffset + 10 + header, bytes.byteOffset + bytes.length)));
};

const server = await serve(work);
const base = `http://127.0.0.1:${server.address().port}`;
const browser = await launchChromium();
let failed = false;
const check = (ok, line) => { console.log(`${line} ${ok ? 'ok' : 'FAILED'}`); failed ||= !ok; return ok; };
const results = { lights: lightCount, hybrid: [] };
try {
  const page = await browser.newPage({ viewport: { width: 1100, height: 420 }, deviceScaleFactor: 1 });
  page.on('pageerror', (error) => console.error('page error:', error.message));
  page.on('console', (message) => { if (message.type() === 'error') console.error('page console:', message.text()); });
  const open = async (query) => {
    await page.goto(`${base}/?bundle=data/bunny.prt.glb&maps=data/studio.sh.json&camera=${camera}&size=${size.join(',')}${query}`);
    return page.evaluate(async () => { const api = await window.prtReady; return { renderer: api.renderer, lights: api.lights, locked: api.turnLocked }; });
  };
  // The canvas against a prt PNG at every 4th pixel whose 3x3 neighbourhood is lit in the PNG (pixels.mjs).
  const against = (png, changes) => againstPng(page, fs.readFileSync(file(png)), size, changes);

  // 1. Hybrid lights against prt relight --lights --image.
  for (const c of hybridCases) {
    const info = await open(`&lights=data/studio.lights.json&rotate=${c.rotate}` + (c.visibility ? `&visibility=data/${c.visibility}` : ''));
    if (c.rotate === 0) console.log(`viewer: ${info.renderer}; ${info.lights} cone lights`);
    const r = await against(`hybrid${c.rotate}.png`, { rotate: c.rotate, hybrid: true });
    await page.locator('#view').screenshot({ path: file(`viewer_hybrid${c.rotate}.png`) });
    check(info.lights === lightCount && r.points >= 200 && r.max <= kMaxLevels && r.mean <= kMeanLevels,
          `hybrid, ${lightCount} lights, turned ${c.rotate}, ${c.visibility ? 'visibility from prt relight' : 'unshadowed'}: ` +
          `${r.points} pixels, max ${r.max} mean ${r.mean.toFixed(3)} levels against prt relight --lights --image ` +
          `(tolerance max ${kMaxLevels}, mean ${kMeanLevels})`);
    results.hybrid.push({ ...c, ...r, state: undefined });
    if (c.rotate === 60) {
      const locked = await page.evaluate(() => { window.prt.set({ rotate: 10 }); return window.prt.state().rotate; });
      check(info.locked && locked === 60, `with a visibility file the turn stays at the visibility's (asked 10, shows ${locked})`);
    }
    if (c.rotate === 0) {
      // The toggle: plain SH from the same page is prt render's picture, and differs from the hybrid's.
      const plain = await against('plain.png', { hybrid: false });
      await page.locator('#view').screenshot({ path: file('viewer_plain.png') });
      const hybridVsPlain = await against('plain.png', { hybrid: true });
      check(plain.points >= 200 && plain.max <= kMaxLevels && plain.mean <= kMeanLevels && hybridVsPlain.mean > 1,
            `toggle to plain SH: ${plain.points} pixels, max ${plain.max} mean ${plain.mean.toFixed(3)} levels against ` +
            `prt render (tolerance max ${kMaxLevels}, mean ${kMeanLevels}); hybrid against prt render: mean ` +
            `${hybridVsPlain.mean.toFixed(2)} levels (must exceed 1: the toggle changes the picture)`);
      results.toggle = { plain, hybridVsPlain };
    }
  }

  // 2. The reference beside the result, against prt compare --image.
  await open('&referenceImage=data/reference.exr&compare=1');
  const shown = await page.evaluate(async ({ size }) => {
    const before = window.prt.camera();
    window.prt.orbit(40, 10, 0.8); // locked: nothing moves
    const after = window.prt.camera();
    const panel = (id) => Array.from(document.getElementById(id).getContext('2d').getImageData(0, 0, size[0], size[1]).data);
    return { before, after, metrics: window.prt.referenceMetrics(), status: document.getElementById('status').textContent,
             reference: panel('referenceView'), error: panel('errorView'), linear: window.prt.linearPixels() };
  }, { size });
  await page.locator('#views').screenshot({ path: file('viewer_compare.png') });
  const printed = shown.status.match(/vs reference image: relative RMSE ([0-9.]+)%/);
  const printedRmse = printed ? Number(printed[1]) / 100 : NaN;
  const rmseOff = Math.abs(printedRmse - compared.relative_rmse) / compared.relative_rmse;
  check(rmseOff <= kRmseTolerance && Math.abs(shown.metrics.relativeRmse - printedRmse) < 1e-5,
        `reference beside the result: printed relative RMSE ${printed ? printed[1] : 'missing'}% over ` +
        `${shown.metrics.count} pixels, prt compare --image ${(100 * compared.relative_rmse).toFixed(3)}% over ` +
        `${compared.count} (off by ${(100 * rmseOff).toFixed(3)}% of it, tolerance ${100 * kRmseTolerance}%)`);
  check(shown.before.every((v, k) => v === shown.after[k]), 'the camera stays locked to the reference\'s while shown');
  // Panels: the strip's reference panel (below its label row) and compare's error picture (above its legend).
  const decode = (name) => page.evaluate(async (png) => {
    const blob = await (await fetch(`data:image/png;base64,${png}`)).blob();
    const bitmap = await createImageBitmap(blob, { colorSpaceConversion: 'none', premultiplyAlpha: 'none' });
    const context = new OffscreenCanvas(bitmap.width, bitmap.height).getContext('2d');
    context.drawImage(bitmap, 0, 0);
    return { width: bitmap.width, height: bitmap.height, data: Array.from(context.getImageData(0, 0, bitmap.width, bitmap.height).data) };
  }, fs.readFileSync(file(name)).toString('base64'));
  const strip = await decode('compare_strip.png'), errorPicture = await decode('compare_error.png');
  const labelHeight = strip.height - errorPicture.height, referenceLeft = size[0] + 4; // the error has a legend below
  let referenceMax = 0;
  for (let y = 0; y < size[1]; ++y)
    for (let x = 0; x < size[0]; ++x)
      for (let ch = 0; ch < 3; ++ch)
        referenceMax = Math.max(referenceMax, Math.abs(shown.reference[(y * size[0] + x) * 4 + ch] -
                                                       strip.data[((y + labelHeight) * strip.width + referenceLeft + x) * 4 + ch]));
  check(referenceMax <= 1, `reference panel against prt compare's strip: max ${referenceMax} levels over every pixel (tolerance 1)`);
  const grey = (d, w, x, y) => d[(y * w + x) * 4] === 48 && d[(y * w + x) * 4 + 1] === 48 && d[(y * w + x) * 4 + 2] === 48;
  const exr = new EXRLoader();
  exr.setDataType(THREE.FloatType);
  const rendered = exr.parse(fs.readFileSync(file('plain.exr')).buffer.slice(0)); // RGBA, rows bottom-up
  const samePoint = (x, y) => {
    const p = (y * size[0] + x) * 4, q = ((size[1] - 1 - y) * size[0] + x) * 4;
    if (!(shown.linear[p + 3] > 0.5) || !(rendered.data[q + 3] > 0.5)) return false;
    return [0, 1, 2].every((c) => Math.abs(shown.linear[p + c] - rendered.data[q + c]) <= 1e-3 * Math.max(rendered.data[q + c], 1e-3));
  };
  let errorMax = 0, errorPoints = 0, otherPoint = 0, coverageDiffers = 0, bothCovered = 0, within = 0;
  for (let y = 0; y < size[1]; ++y)
    for (let x = 0; x < size[0]; ++x) {
      const viewerGrey = grey(shown.error, size[0], x, y), compareGrey = grey(errorPicture.data, errorPicture.width, x, y);
      coverageDiffers += viewerGrey !== compareGrey;
      if (viewerGrey || compareGrey) continue;
      let worst = 0;
      for (let ch = 0; ch < 3; ++ch)
        worst = Math.max(worst, Math.abs(shown.error[(y * size[0] + x) * 4 + ch] - errorPicture.data[(y * errorPicture.width + x) * 4 + ch]));
      ++bothCovered;
      within += worst <= kErrorPanelLevels;
      if (!samePoint(x, y)) { ++otherPoint; continue; }
      ++errorPoints;
      errorMax = Math.max(errorMax, worst);
    }
  check(errorPoints >= 4000 && errorMax <= kErrorPanelLevels && within >= kErrorPanelShare * bothCovered,
        `error panel against prt compare's picture: ${errorPoints} pixels where the results agree to 0.1%, max ` +
        `${errorMax} levels (tolerance ${kErrorPanelLevels}); over all ${bothCovered} covered in both, ${within} within ` +
        `${kErrorPanelLevels} levels (at least ${100 * kErrorPanelShare}%); ${coverageDiffers} differ in coverage`);
  results.reference = { printedRmse, compareRmse: compared.relative_rmse, viewerCount: shown.metrics.count,
                        compareCount: compared.count, referenceMax, errorMax, errorPoints, otherPoint, bothCovered, within, coverageDiffers };

  // 3. Moving occluders against prt fivshade, the instances moved in the page.
  results.fiv = [];
  const luminance = (a, v) => (a[3 * v] + a[3 * v + 1] + a[3 * v + 2]) / 3;
  const fivScenes = [
    { bundle: 'fivscene', expected: 'fiv', label: '', self: false, at: placements },
    { bundle: 'fivscene_self', expected: 'fiv_self', label: ' + self', self: true, at: placements },
    { bundle: 'fivscene_sun', expected: 'fiv_sun', label: ' sunrise, source grids + fiv_self', self: true, sun: true, at: sunPlacements },
    { bundle: 'fivscene_sungrid', expected: 'fiv_sungrid', label: ' sunrise, source grids + self grid', self: true, sun: true, at: sunPlacements },
    { bundle: 'fivscene_sun65', expected: 'fiv_sun65', label: ' sunrise, 65-shell source grids', self: false, sun: true,
      at: sunPlacements.slice(0, 1), fallback: true },
  ];
  for (const device of ['gpu', 'cpu'])
  for (const scene of fivScenes) {
    const { self } = scene;
    if (scene.fallback && device === 'cpu') continue;
    const on = scene.fallback ? 'cpu' : device, tolerance = kFivTolerance[on];
    await page.goto(`${base}/?bundle=data/${scene.bundle}.glb&albedo=0.8&camera=${camera}` +
                    `&size=${size.join(',')}&fivOn=${device}`);
    const info = await page.evaluate(async () => { const api = await window.prtReady; return { kind: api.kind, instances: api.instances.length, on: api.fivOn, note: api.fivNote }; });
    check(info.kind === 'fiv' && info.instances === 3 && info.on === on,
          `FIV scene${scene.label} read as ${info.kind} with ${info.instances} instances, shaded on the ${info.on}` +
          (info.note ? ` (${info.note})` : ''));
    if (scene.fallback)
      check(/source grid of object 1 has 65 shells .*shaded on the CPU instead/.test(info.note || ''),
            `a source grid past the GPU pass's shells falls back to the CPU with a message`);
    for (const [k, at] of scene.at.entries()) {
      const shaded = await page.evaluate((at) => {
        at.forEach((p, j) => window.prt.moveInstance(j, p));
        return { radiance: window.prt.fivRadiance(), shadeMs: window.prt.shadeMs(), query: window.prt.query() };
      }, at);
      const expected = readNpy(`${scene.expected}${k}.npy`);
      if (scene.sun && device === 'gpu' && !scene.fallback) {
        const unshadowed = readNpy(`${scene.expected}_unshadowed.npy`);
        let darker = 0;
        for (let v = 0; v < expected.length / 3; ++v) darker += luminance(expected, v) < 0.8 * luminance(unshadowed, v);
        check(darker >= kSunShadowVertices, `FIV${scene.label} placement ${k}: the spheres darken ${darker} vertices by over 20% ` +
                                            `(at least ${kSunShadowVertices})`);
      }
      let worst = 0, maxAbs = 0;
      expected.forEach((b, i) => {
        const d = Math.abs(shaded.radiance[i] - b);
        maxAbs = Math.max(maxAbs, d);
        worst = Math.max(worst, d / (tolerance.abs + tolerance.rel * Math.abs(b)));
      });
      await page.locator('#view').screenshot({ path: file(`viewer_${scene.expected}_${device}${k}.png`) });
      check(expected.length === shaded.radiance.length && worst <= 1,
            `FIV ${on}${scene.label} placement ${k}: ${expected.length / 3} vertices, max |viewer - prt fivshade| ` +
            `${maxAbs.toExponential(2)} (${worst.toFixed(3)} of the tolerance ${tolerance.abs} + ${tolerance.rel} x value); shading ` +
            `${shaded.shadeMs.toFixed(1)} ms`);
      results.fiv.push({ device: on, scene: scene.bundle, self, placement: k, vertices: expected.length / 3, maxAbs, ofTolerance: worst,
                         shadeMs: shaded.shadeMs });
      if (k === 1 && scene.bundle === 'fivscene' && device === 'cpu') {
        await page.goto(`${base}/?${shaded.query}`);
        const reloaded = await page.evaluate(async () => { await window.prtReady; return window.prt.translations(); });
        const off = Math.max(...reloaded.flat().map((v, i) => Math.abs(v - at.flat()[i])));
        check(off < 1e-4, `a FIV view reloaded from its URL keeps the positions (off by ${off})`);
      }
    }
  }
  fs.copyFileSync(sunMap, file('sunrise.exr'));
  // Malformed source grids and fiv_self are refused with a message naming the layer, never drawn.
  for (const [name, , expected] of badSunScenes) {
    await page.goto(`${base}/?bundle=data/${name}.glb&albedo=0.8&size=${size.join(',')}`);
    const message = await page.evaluate(async () => { try { await window.prtReady; return null; } catch (error) { return error.message; } });
    check(!!message && expected.test(message), `refused ${name}.glb: ${message}`);
  }

  // The sunrise scene from the sun's side, where the spheres' shadows fall (a picture for docs/viewer/fiv_sun.png).
  await page.goto(`${base}/?bundle=data/fivscene_sun.glb&albedo=0.8&camera=22,8,-4,0,4.8,0,0,1,0,35&size=320,240&exposure=-1&sky=data/sunrise.exr`);
  await page.evaluate(async () => { await window.prtReady; });
  await page.locator('#view').screenshot({ path: file('viewer_fiv_sun_view.png') });
  results.renderer = await page.evaluate(() => window.prt.renderer);

  // 4. Bad inputs are refused with a message naming the file and the problem, never drawn.
  const refused = async (query) => {
    const sized = query.includes('&size=') ? query : `${query}&size=${size.join(',')}`;
    await page.goto(`${base}/?bundle=data/bunny.prt.glb&maps=data/studio.sh.json&camera=${camera}${sized}`);
    return page.evaluate(async () => { try { await window.prtReady; return null; } catch (error) { return error.message; } });
  };
  const badInputs = [
    ['&lights=data/order3.lights.json', /order3\.lights\.json.*order 3.*order 4/],
    ['&lights=data/studio.lights.json&visibility=data/short.npy', /short\.npy: visibility of 10 rows x 3 lights, the bundle has 1839 vertices/],
    ['&lights=data/studio.lights.json&visibility=data/studio.lights.json', /studio\.lights\.json: not a \.npy file/],
    ['&referenceImage=data/reference.exr&size=80,60', /referenceImage: 160 x 120 pixels, the view is 80 x 60/],
    ['&lights=data/studio.sh.json', /studio\.sh\.json: format/],
  ];
  for (const [query, expected] of badInputs) {
    const message = await refused(query);
    check(!!message && expected.test(message), `refused ${query.slice(1)}: ${message}`);
  }

} finally {
  await browser.close();
  server.close();
}
fs.writeFileSync(file('agreement.json'), JSON.stringify(results, null, 2) + '\n');
process.exit(failed ? 1 : 0);
