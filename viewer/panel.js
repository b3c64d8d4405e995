// The page's helpers around the viewer: the folder listing (GET data/index.json, listing.mjs) as links that load
// a bundle or a lighting, and mouse and keyboard orbit.

// Fills `element` with links to what the served folder holds. A bundle link keeps the current lighting (or takes
// every lighting in the folder); a lighting link keeps the bundle and takes that lighting with its map of the same
// base name (NAME.sh.json with NAME.exr) as the sky. Shows a line when the listing is not served.
export async function listingPanel(element, params) {
  let listing;
  try {
    const response = await fetch('data/index.json', { cache: 'no-store' });
    listing = await response.json();
    if (listing.format !== 'prt-listing') throw new Error('not a listing');
  } catch {
    element.textContent = 'no folder listing (prt serve answers data/index.json)';
    return;
  }
  const skyOf = (sh) => {
    const exr = sh.replace(/\.sh\.json$/, '.exr');
    return listing.maps.includes(exr) ? 'data/' + exr : '';
  };
  const link = (text, changes) => {
    const q = new URLSearchParams(params);
    for (const [key, value] of Object.entries(changes)) if (value) q.set(key, value); else q.delete(key);
    const a = document.createElement('a');
    a.textContent = text;
    a.href = '?' + q.toString().replace(/%2C/g, ',').replace(/%2F/g, '/');
    return a;
  };
  const section = (title, items) => {
    const h = document.createElement('h4');
    h.textContent = title;
    element.append(h, ...items);
  };
  const allLighting = listing.lighting.map((n) => 'data/' + n).join(',');
  const allSkies = listing.lighting.map(skyOf).join(',');
  section('bundles', listing.bundles.map((n) => link(n, {
    bundle: 'data/' + n, maps: params.get('maps') || allLighting, sky: params.get('maps') ? params.get('sky') : allSkies,
    mode: null, map: null, camera: params.get('camera'),
  })));
  section('lighting (prt envsh)', listing.lighting.map((n) => link(n, { maps: 'data/' + n, sky: skyOf(n), map: null })));
  section('maps (sky only)', listing.maps.map((n) => link(n, { sky: 'data/' + n })));
}

// Orbit about the target: drag (left button) turns, the wheel zooms; arrow keys turn by 5 degrees, + and - zoom.
// With shift held, a drag moves the selected occluder of a FIV scene (api.drag) instead.
export function attachOrbit(canvas, api) {
  let last = null;
  canvas.addEventListener('pointerdown', (e) => { last = [e.clientX, e.clientY]; canvas.setPointerCapture(e.pointerId); });
  canvas.addEventListener('pointerup', () => { last = null; });
  canvas.addEventListener('pointermove', (e) => {
    if (!last) return;
    if (e.shiftKey && api.drag) api.drag(e.clientX - last[0], e.clientY - last[1]); // a FIV scene's selected occluder
    else api.orbit(-0.4 * (e.clientX - last[0]), 0.4 * (e.clientY - last[1]));
    last = [e.clientX, e.clientY];
  });
  canvas.addEventListener('wheel', (e) => { e.preventDefault(); api.orbit(0, 0, e.deltaY > 0 ? 1.1 : 1 / 1.1); }, { passive: false });
  window.addEventListener('keydown', (e) => {
    if (e.target instanceof HTMLInputElement || e.target instanceof HTMLSelectElement) return;
    const moves = { ArrowLeft: [5, 0], ArrowRight: [-5, 0], ArrowUp: [0, 5], ArrowDown: [0, -5], '+': [0, 0, 1 / 1.1],
                    '=': [0, 0, 1 / 1.1], '-': [0, 0, 1.1] };
    if (!moves[e.key]) return;
    e.preventDefault();
    api.orbit(...moves[e.key]);
  });
}
