// The viewer tests' pixel sampling: the page's canvas against a prt PNG of the same camera and size, at sampled
// interior pixels. Shared by hybrid_turns_test.mjs, methods_test.mjs and scene_hybrid_test.mjs.

// Applies `changes` (api.set) in the page, then reads the canvas at every `step`th pixel (from (1, 1)) whose 3x3
// neighbourhood in the PNG is all lit (some channel above 0) and, when `edge` is a number, all within `edge` levels
// of the centre in every channel (hard texel, cut-out, silhouette and instance edges out, where the rasteriser and
// prt's rays may pick different sides). `png` is the PNG file's bytes (a Buffer), `size` [width, height].
// Returns {points, max, mean, within1, histogram, where, state}: the largest and mean absolute difference in 8-bit
// levels over every channel of every sampled pixel, the share of channel values within 1 level, the sampled pixels
// counted by their worst channel's difference, the worst pixel {x, y, prt, viewer}, and the page's state after.
export function againstPng(page, png, size, changes, { step = 4, edge = null } = {}) {
  return page.evaluate(async ({ png, size, changes, step, edge }) => {
    const blob = await (await fetch(`data:image/png;base64,${png}`)).blob();
    const bitmap = await createImageBitmap(blob, { colorSpaceConversion: 'none', premultiplyAlpha: 'none' });
    const context = new OffscreenCanvas(size[0], size[1]).getContext('2d');
    context.drawImage(bitmap, 0, 0);
    const rendered = context.getImageData(0, 0, size[0], size[1]).data;
    const at = (x, y, ch) => rendered[(y * size[0] + x) * 4 + ch];
    const lit = (x, y) => at(x, y, 0) + at(x, y, 1) + at(x, y, 2) > 0;
    const points = [];
    for (let y = 1; y < size[1] - 1; y += step)
      for (let x = 1; x < size[0] - 1; x += step) {
        let inside = true;
        for (let dy = -1; dy <= 1; ++dy)
          for (let dx = -1; dx <= 1; ++dx) {
            inside &&= lit(x + dx, y + dy);
            if (edge !== null)
              for (let ch = 0; ch < 3; ++ch) inside &&= Math.abs(at(x + dx, y + dy, ch) - at(x, y, ch)) <= edge;
          }
        if (inside) points.push([x, y]);
      }
    window.prt.set(changes);
    const viewer = window.prt.read(points);
    let max = 0, sum = 0, within1 = 0, where = null;
    const histogram = {};
    points.forEach(([x, y], k) => {
      let worst = 0;
      for (let ch = 0; ch < 3; ++ch) {
        const d = Math.abs(viewer[k][ch] - at(x, y, ch));
        worst = Math.max(worst, d);
        sum += d;
        within1 += d <= 1;
      }
      histogram[worst] = (histogram[worst] || 0) + 1;
      if (worst > max) where = { x, y, prt: [0, 1, 2].map((ch) => at(x, y, ch)), viewer: viewer[k].slice(0, 3) };
      max = Math.max(max, worst);
    });
    const n = Math.max(1, 3 * points.length);
    return { points: points.length, max, mean: sum / n, within1: within1 / n, histogram, where, state: window.prt.state() };
  }, { png: png.toString('base64'), size, changes, step, edge });
}
