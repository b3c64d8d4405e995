#!/usr/bin/env node
// The hybrid's visibility table in Debian's headless Chromium: the bunny (interreflected, order 4) under studio's
// cone lights, with `prt relight --lights --visibility-out T.npy --visibility-turns 12` (turns every 30 degrees).
// The page's turn is free; the canvas must match `prt relight --lights --rotate-y THETA --image` at sampled interior
// pixels: at table turns (0, 90, 330) within kTableLevels, between them (15, 45, 100: the linear blend of the two
// nearest turns against the visibility cast at THETA itself) within kBetweenLevels; the toggle to plain SH must
// still match `prt render`. Screenshots and agreement.json land in WORK_DIR.
// usage: node viewer/test/hybrid_turns_test.mjs PRT DATA_DIR WORK_DIR
import fs from 'node:fs';
import path from 'node:path';
import { launchChromium } from './chromium.mjs';
import { againstPng } from './pixels.mjs';
import { serve } from '../serve.mjs';
import { testWorkspace } from './workspace.mjs';

// 8-bit levels. At a table turn: the GPU's float sums and interpolation (as methods_test.mjs's hybrid) plus the
// table's byte quantisation (|dV| <= 1/510 of a light's direct term).
const kTableLevels = { max: 1, mean: 0.1 };
// Between table turns the blend of two neighbouring shadows stands for the shadow cast at THETA: edges of cone
// shadows move up to 15 degrees, so single pixels near a shadow edge differ by a share of the light's term (measured:
// max 13, mean 1.08 levels at 15 degrees, 77% of samples within 1 level; 0.24 and 0.47 mean at 45 and 100).
const kBetweenLevels = { max: 20, mean: 1.5 };
const turns = 12;

const { prt, data, work, file, run } = testWorkspace('hybrid_turns_test.mjs');
const map = path.join(data, 'env/studio.exr');
const size = [160, 120];
const camera = '3.46275,7.798,18.8643,-0.00481248,4.8258,0.040403,0,1,0,35';
run('meshprep', path.join(data, 'bunny.ply'), '-o', file('bunny.glb'));
run('transfer', file('bunny.glb'), '--mode', 'interreflected', '--bounces', '1', '--order', '4', '--samples', '64',
    '--albedo', '0.8', '-o', file('bunny.prt.glb'));
run('envsh', map, '--order', '8', '-o', file('studio.sh.json'));
run('envlight', map, '--order', '4', '--max-lights', '4', '-o', file('studio.lights.json'));
const castStart = Date.now();
run('relight', file('bunny.prt.glb'), '--lights', file('studio.lights.json'), '--env', map, '--visibility-out',
    file('table.npy'), '--visibility-turns', String(turns), '-o', file('turn0.npy'));
const castSeconds = (Date.now() - castStart) / 1000;
const tableAngles = [0, 90, 330], betweenAngles = [15, 45, 100];
for (const angle of [...tableAngles, ...betweenAngles])
  run('relight', file('bunny.prt.glb'), '--lights', file('studio.lights.json'), '--env', map, '--rotate-y', String(angle),
      '--image', size.join(','), '--camera', camera, '-o', file(`hybrid${angle}.png`));
run('render', file('bunny.prt.glb'), '--env', map, '--camera', camera, '--size', size.join(','), '-o', file('plain.png'));

const server = await serve(work);
const base = `http://127.0.0.1:${server.address().port}`;
const browser = await launchChromium();
let failed = false;
const check = (ok, line) => { console.log(`${line} ${ok ? 'ok' : 'FAILED'}`); failed ||= !ok; return ok; };
const results = { turns, tableBytes: fs.statSync(file('table.npy')).size, castSeconds, cases: [] };
try {
  const page = await browser.newPage({ viewport: { width: 1100, height: 420 }, deviceScaleFactor: 1 });
  page.on('pageerror', (error) => console.error('page error:', error.message));
  await page.goto(`${base}/?bundle=data/bunny.prt.glb&maps=data/studio.sh.json&camera=${camera}&size=${size.join(',')}` +
                  '&lights=data/studio.lights.json&visibility=data/table.npy');
  const info = await page.evaluate(async () => { const api = await window.prtReady; return { locked: api.turnLocked, lights: api.lights }; });
  check(!info.locked, `with a table of ${turns} turns the turn is free`);
  // The canvas against a prt PNG at every 4th pixel whose 3x3 neighbourhood is lit in the PNG (pixels.mjs).
  const against = (png, changes) => againstPng(page, fs.readFileSync(file(png)), size, changes);

  for (const angle of [...tableAngles, ...betweenAngles]) {
    const table = tableAngles.includes(angle), limit = table ? kTableLevels : kBetweenLevels;
    const r = await against(`hybrid${angle}.png`, { rotate: angle, hybrid: true });
    await page.locator('#view').screenshot({ path: file(`viewer_hybrid_turn${angle}.png`) });
    check(r.state.rotate === angle && r.points >= 200 && r.max <= limit.max && r.mean <= limit.mean,
          `hybrid with the table, turned ${angle} (${table ? 'a table turn' : 'between table turns'}): ${r.points} pixels, ` +
          `max ${r.max} mean ${r.mean.toFixed(3)} levels, ${(100 * r.within1).toFixed(1)}% within 1 level, against ` +
          `prt relight --lights --rotate-y ${angle} --image (tolerance max ${limit.max}, mean ${limit.mean})`);
    results.cases.push({ angle, table, ...r, state: undefined });
  }
  const plain = await against('plain.png', { rotate: 0, hybrid: false });
  await page.locator('#view').screenshot({ path: file('viewer_hybrid_turn_plain.png') });
  check(plain.points >= 200 && plain.max <= kTableLevels.max && plain.mean <= kTableLevels.mean,
        `toggle to plain SH with the table loaded: max ${plain.max} mean ${plain.mean.toFixed(3)} levels against prt render`);
  results.plain = plain;
} finally {
  await browser.close();
  server.close();
}
fs.writeFileSync(file('agreement.json'), JSON.stringify(results, null, 2));
console.log(`table: ${turns} turns, ${results.tableBytes} bytes, cast (with the turn-0 relight) in ${castSeconds.toFixed(1)} s`);
process.exit(failed ? 1 : 0);
