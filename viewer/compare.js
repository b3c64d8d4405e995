// The reference beside the result (`referenceImage=URL`: `prt reference --image`'s OpenEXR from the same camera and
// size): result | reference | false-colour error side by side, with the error's relative RMSE, as `prt compare
// --image` computes them (lib/compare/images.cpp compareImages): over the result's coverage (pixels the mesh
// covers, front or back faces, as `prt render`'s A channel), relative RMSE sqrt(sum (a - b)^2 / sum b^2) over every
// channel, per pixel |Y(a) - Y(b)| / max(Y(b), floor) with Rec.709 luminance and floor 1e-3 of the reference's mean
// luminance over the coverage, drawn in viridis from 0 to `scaleTop` (0.2, compare's default --scale), grey (48)
// outside the coverage. The result is the viewer's own linear radiance, read back from a float render target.
import * as THREE from 'three';

// Rec. 709 luminance weights, as lib/core/luminance.h.
export const kLuminance = [0.2126, 0.7152, 0.0722];
const kViridis = [[0.267, 0.005, 0.329], [0.229, 0.322, 0.546], [0.128, 0.567, 0.551], [0.369, 0.789, 0.383],
                  [0.993, 0.906, 0.144]];
const kOutsideMask = 48;

// compare.h toneMap to 8 bits: x = radiance 2^exposure, Reinhard, sRGB, rounded; negative and NaN give 0.
export function toneMap8(radiance, exposure) {
  const x = radiance * 2 ** exposure;
  if (!(x > 0)) return 0;
  const d = x / (1 + x);
  const srgb = d <= 0.0031308 ? 12.92 * d : 1.055 * d ** (1 / 2.4) - 0.055;
  return Math.round(255 * Math.min(1, Math.max(0, srgb)));
}

// images.cpp falseColour: viridis at five stops, t in [0, 1] (clamped), each channel rounded.
export function falseColour(t) {
  t = Math.min(1, Math.max(0, t)) * 4;
  const i = Math.min(3, Math.floor(t)), f = t - i;
  return [0, 1, 2].map((c) => Math.round(255 * (kViridis[i][c] * (1 - f) + kViridis[i + 1][c] * f)));
}

// result: linear RGBA [pixel][4] row 0 at the top, A > 0.5 where covered; reference: linear RGB(A) with `stride`
// floats per pixel, row 0 at the top. Returns {count, relativeRmse, meanRelativeError, relativeFloor,
// relativeError (Float32Array, -1 outside the coverage)}.
export function compareWithReference(result, reference, stride, width, height) {
  const pixels = width * height;
  let squared = 0, referenceSquared = 0, referenceLuminance = 0, count = 0;
  const luminance = (a, p, s) => kLuminance[0] * a[p * s] + kLuminance[1] * a[p * s + 1] + kLuminance[2] * a[p * s + 2];
  for (let p = 0; p < pixels; ++p) {
    if (!(result[p * 4 + 3] > 0.5)) continue;
    ++count;
    for (let c = 0; c < 3; ++c) {
      const d = result[p * 4 + c] - reference[p * stride + c];
      squared += d * d;
      referenceSquared += reference[p * stride + c] ** 2;
    }
    referenceLuminance += luminance(reference, p, stride);
  }
  const relativeFloor = count ? 1e-3 * referenceLuminance / count : 0;
  const relativeError = new Float32Array(pixels).fill(-1);
  let sum = 0;
  for (let p = 0; p < pixels; ++p) {
    if (!(result[p * 4 + 3] > 0.5)) continue;
    const ya = luminance(result, p, 4), yb = luminance(reference, p, stride);
    const e = relativeFloor > 0 ? Math.abs(ya - yb) / Math.max(yb, relativeFloor) : (ya === yb ? 0 : 1);
    relativeError[p] = e;
    sum += e;
  }
  const relativeRmse = referenceSquared > 0 ? Math.sqrt(squared / referenceSquared) : (squared > 0 ? Infinity : 0);
  return { count, relativeRmse, meanRelativeError: count ? sum / count : 0, relativeFloor, relativeError };
}

// The two panels beside the canvas: the reference tone-mapped, the error in false colour. `reference` as
// compareWithReference takes it.
function drawPanels(referenceCanvas, errorCanvas, reference, stride, comparison, width, height, exposure, scaleTop) {
  const picture = new ImageData(width, height), error = new ImageData(width, height);
  for (let p = 0; p < width * height; ++p) {
    for (let c = 0; c < 3; ++c) picture.data[p * 4 + c] = toneMap8(reference[p * stride + c], exposure);
    picture.data[p * 4 + 3] = 255;
    const e = comparison.relativeError[p];
    const rgb = e < 0 ? [kOutsideMask, kOutsideMask, kOutsideMask] : falseColour(e / scaleTop);
    error.data.set([...rgb, 255], p * 4);
  }
  referenceCanvas.getContext('2d').putImageData(picture, 0, 0);
  errorCanvas.getContext('2d').putImageData(error, 0, 0);
}

// The comparison beside `canvas` (the result): two 2D canvases of the same size appended to its parent, hidden until
// shown. `image` is sky.js loadSky's result for the reference EXR (RGBA float, rows bottom-up). Returns
// {show(visible), update(renderLinear, exposure) -> comparison, metrics(), elements}; renderLinear() draws the
// result into the float target and returns its RGBA floats row 0 at the top.
export function referencePanels(canvas, image, width, height, scaleTop = 0.2) {
  if (image.width !== width || image.height !== height)
    throw new Error(`referenceImage: ${image.width} x ${image.height} pixels, the view is ${width} x ${height} (size=)`);
  // The reference's rows top-down, RGBA.
  const reference = new Float32Array(width * height * 4);
  for (let y = 0; y < height; ++y)
    reference.set(image.data.subarray((height - 1 - y) * width * 4, (height - y) * width * 4), y * width * 4);
  const make = (id) => {
    const c = document.createElement('canvas');
    c.id = id;
    c.width = width;
    c.height = height;
    c.style.display = 'none';
    canvas.parentElement.appendChild(c);
    return c;
  };
  const referenceCanvas = make('referenceView'), errorCanvas = make('errorView');
  let comparison = null;
  return {
    elements: [referenceCanvas, errorCanvas],
    show(visible) { for (const c of [referenceCanvas, errorCanvas]) c.style.display = visible ? 'block' : 'none'; },
    update(result, exposure) {
      comparison = compareWithReference(result, reference, 4, width, height);
      drawPanels(referenceCanvas, errorCanvas, reference, 4, comparison, width, height, exposure, scaleTop);
      return comparison;
    },
    metrics: () => comparison && { count: comparison.count, relativeRmse: comparison.relativeRmse,
                                   meanRelativeError: comparison.meanRelativeError },
  };
}

// A float RGBA render target of the view's size and a function that draws `scene` into it and returns its pixels,
// row 0 at the top. `linearUniform` (toneMapGlsl's linearOutput) is set while it draws, so shaders write radiance.
export function linearReadback(renderer, width, height, linearUniform) {
  const target = new THREE.WebGLRenderTarget(width, height, { type: THREE.FloatType, format: THREE.RGBAFormat,
                                                              minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter,
                                                              depthBuffer: true });
  const bottomUp = new Float32Array(width * height * 4), topDown = new Float32Array(width * height * 4);
  return (scene, camera) => {
    const clear = new THREE.Color();
    renderer.getClearColor(clear);
    const alpha = renderer.getClearAlpha();
    linearUniform.value = true;
    renderer.setRenderTarget(target);
    renderer.setClearColor(0x000000, 0); // A = 0 where nothing is drawn: the coverage
    renderer.clear();
    renderer.render(scene, camera);
    renderer.readRenderTargetPixels(target, 0, 0, width, height, bottomUp);
    renderer.setRenderTarget(null);
    renderer.setClearColor(clear, alpha);
    linearUniform.value = false;
    for (let y = 0; y < height; ++y)
      topDown.set(bottomUp.subarray((height - 1 - y) * width * 4, (height - y) * width * 4), y * width * 4);
    return topDown;
  };
}
