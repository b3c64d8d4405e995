// The folder listing behind the viewer's panel: GET /data/index.json answers what the served folder holds, so no
// URL needs to be typed. Only names directly in the folder, never a path outside it; `prt serve` hooks it in
// (serve.mjs calls answerListing first).
import fs from 'node:fs';
import path from 'node:path';

export const kListingPath = '/data/index.json';

// The folder's bundles (*.glb), SH lighting (*.sh.json) and maps (*.exr), sorted, at most 1000 of each.
export function listFolder(dataDir) {
  let names = [];
  try { names = fs.readdirSync(dataDir, { withFileTypes: true }).filter((e) => e.isFile()).map((e) => e.name).sort(); } catch { names = []; }
  const pick = (test) => names.filter(test).slice(0, 1000);
  return { format: 'prt-listing', bundles: pick((n) => n.endsWith('.glb')), lighting: pick((n) => n.endsWith('.sh.json')),
           maps: pick((n) => n.endsWith('.exr')) };
}

// Answers the request target `target` when it is the listing and returns true; returns false for anything else,
// a malformed target included (bad %-escape, NUL: serve.mjs's resolveTarget answers those 400). Never throws.
// The listing names only regular files directly in the folder: a symlink is never listed, so nothing outside the
// folder is named (serve.mjs refuses links out of it anyway).
export function answerListing(target, dataDir, response) {
  let url;
  try { url = decodeURIComponent(new URL(target, 'http://x').pathname); } catch { return false; }
  if (url !== kListingPath) return false;
  response.writeHead(200, { 'content-type': 'application/json', 'cache-control': 'no-store' })
    .end(JSON.stringify(listFolder(path.resolve(dataDir))));
  return true;
}
