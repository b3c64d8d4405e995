// The prt viewer: loads a bundle, relights its SH transfer on the GPU under any environment's SH lighting, and
// lets the user turn the environment and change the order. Shading agrees with `prt relight` (the same sum) and
// pictures with `prt render` (the same pinhole camera and tone map, compare.h toneMap).
import * as THREE from 'three';
import { loadBundle, syntheticBundle } from './bundle.js';
import { fitLighting, rotateLightingY } from './sh.js';

const kMaxCoefficients = 64; // order 8

const vertexShader = /* glsl */ `
precision highp float;
precision highp int;
precision highp sampler2DArray;
uniform mat4 modelViewMatrix;
uniform mat4 projectionMatrix;
uniform sampler2DArray transfer; // layer j: coefficient j's RGB transfer, one texel per row (vertex or atlas texel)
uniform int coefficients;
uniform int rowsPerLine;
uniform vec3 lighting[${kMaxCoefficients}];
uniform bool perVertex;
in vec3 position;
in vec2 uv;
in float relativeError;
out vec3 vRadiance;
out vec2 vUv;
out float vError;
void main() {
  vUv = uv;
  vError = relativeError;
  vRadiance = vec3(0.0);
  if (perVertex) {
    ivec2 at = ivec2(gl_VertexID % rowsPerLine, gl_VertexID / rowsPerLine);
    for (int j = 0; j < ${kMaxCoefficients}; ++j) {
      if (j >= coefficients) break;
      vRadiance += texelFetch(transfer, ivec3(at, j), 0).rgb * lighting[j];
    }
  }
  gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
}`;

const fragmentShader = /* glsl */ `
precision highp float;
precision highp int;
precision highp sampler2DArray;
uniform sampler2DArray transfer;
uniform int coefficients;
uniform vec3 lighting[${kMaxCoefficients}];
uniform bool perVertex;
uniform bool showError;
uniform float errorScale;
uniform ivec2 atlasSize;
uniform float exposure;
in vec3 vRadiance;
in vec2 vUv;
in float vError;
out vec4 colour;
// compare.h toneMap: x = radiance 2^exposure, Reinhard x / (1 + x), sRGB; the framebuffer rounds to 8 bits.
vec3 toneMap(vec3 radiance) {
  vec3 x = max(radiance * exp2(exposure), 0.0);
  vec3 d = x / (1.0 + x);
  return mix(12.92 * d, 1.055 * pow(d, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), d));
}
// Viridis at five stops, as prt compare --image draws relative error.
vec3 falseColour(float t) {
  vec3 stops[5] = vec3[5](vec3(0.267, 0.005, 0.329), vec3(0.229, 0.322, 0.546), vec3(0.128, 0.567, 0.551),
                          vec3(0.369, 0.789, 0.383), vec3(0.993, 0.906, 0.144));
  t = clamp(t, 0.0, 1.0) * 4.0;
  int i = min(3, int(t));
  return mix(stops[i], stops[i + 1], t - float(i));
}
void main() {
  if (!gl_FrontFacing) { colour = vec4(0.0, 0.0, 0.0, 1.0); return; } // a back face is black, as in prt render
  if (showError) { colour = vec4(falseColour(vError / errorScale), 1.0); return; }
  vec3 radiance = vRadiance;
  if (!perVertex) {
    // The nearest atlas texel at TEXCOORD_0 (u right, v down, row 0 at the top), as prt render --texels.
    ivec2 texel = clamp(ivec2(floor(vUv * vec2(atlasSize))), ivec2(0), atlasSize - 1);
    radiance = vec3(0.0);
    for (int j = 0; j < ${kMaxCoefficients}; ++j) {
      if (j >= coefficients) break;
      radiance += texelFetch(transfer, ivec3(texel, j), 0).rgb * lighting[j];
    }
  }
  colour = vec4(toneMap(radiance), 1.0);
}`;

function parseNumbers(text, count, name) {
  const values = text.split(',').map(Number);
  if (values.length !== count || values.some((v) => !Number.isFinite(v))) throw new Error(`${name}: need ${count} numbers`);
  return values;
}

// A prt .npy of float32 [N, 3] (prt reference's per-vertex radiance) as a Float32Array.
function parseNpy(arrayBuffer) {
  const bytes = new Uint8Array(arrayBuffer);
  const headerLength = bytes[8] | (bytes[9] << 8);
  const header = new TextDecoder().decode(bytes.subarray(10, 10 + headerLength));
  if (!header.includes("'<f4'") || header.includes("'fortran_order': True")) throw new Error('need a float32 C-order .npy');
  return new Float32Array(arrayBuffer.slice(10 + headerLength));
}

// The transfer rows [rows][C][3] rearranged into C layers of rowsPerLine x lines RGB texels.
function transferTexture(transfer, rowsPerLine, lines) {
  const C = transfer.order * transfer.order, rows = transfer.rows;
  const layer = rowsPerLine * lines;
  const data = new Float32Array(layer * C * 3);
  const source = transfer.data;
  for (let r = 0; r < rows; ++r)
    for (let j = 0; j < C; ++j) {
      const from = (r * C + j) * 3, to = (j * layer + r) * 3;
      data[to] = source[from];
      data[to + 1] = source[from + 1];
      data[to + 2] = source[from + 2];
    }
  const texture = new THREE.DataArrayTexture(data, rowsPerLine, lines, C);
  texture.format = THREE.RGBFormat;
  texture.type = THREE.FloatType;
  texture.internalFormat = 'RGB32F';
  texture.minFilter = texture.magFilter = THREE.NearestFilter;
  texture.generateMipmaps = false;
  texture.needsUpdate = true;
  return texture;
}

export async function startViewer(canvas, panel, params) {
  const [width, height] = parseNumbers(params.get('size') || '640,480', 2, 'size');
  const kind = params.get('mode') === 'texel' ? 'texel' : 'vertex';
  const bundleUrl = params.get('bundle'), synthetic = params.get('synthetic'); // synthetic=VERTICES,ORDER
  if (!bundleUrl && !synthetic) throw new Error('give ?bundle=URL of a .glb');
  const mesh = synthetic ? await syntheticBundle(...parseNumbers(synthetic, 2, 'synthetic'))
                         : await loadBundle(bundleUrl, kind);
  const maps = (params.get('maps') || '').split(',').filter(Boolean);
  if (!maps.length) throw new Error('give ?maps=URL,URL of prt-sh JSON lighting (prt envsh)');
  const lightings = await Promise.all(maps.map(async (url) => {
    const sh = await (await fetch(url)).json();
    if (sh.format !== 'prt-sh') throw new Error(`${url}: not prt-sh JSON`);
    return { name: url.split('/').pop().replace(/\.sh\.json$|\.json$/, ''), order: sh.order,
             coefficients: Float32Array.from(sh.coefficients.flat()) };
  }));
  const reference = params.get('reference') ? parseNpy(await (await fetch(params.get('reference'))).arrayBuffer()) : null;

  const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: true, alpha: false });
  renderer.setPixelRatio(1);
  renderer.setSize(width, height, false);
  renderer.setClearColor(0x000000, 1);
  const gl = renderer.getContext();

  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(mesh.positions, 3));
  const vertexCount = mesh.positions.length / 3;
  geometry.setAttribute('uv', new THREE.BufferAttribute(mesh.texcoords || new Float32Array(vertexCount * 2), 2));
  const errors = new Float32Array(vertexCount);
  geometry.setAttribute('relativeError', new THREE.BufferAttribute(errors, 1));
  geometry.setIndex(new THREE.BufferAttribute(mesh.indices, 1));

  const t = mesh.transfer;
  let rowsPerLine, lines;
  if (kind === 'texel') [rowsPerLine, lines] = [t.width, t.height];
  else [rowsPerLine, lines] = [Math.min(t.rows, 2048), Math.ceil(t.rows / Math.min(t.rows, 2048))];
  const uniforms = {
    transfer: { value: transferTexture(t, rowsPerLine, lines) },
    coefficients: { value: t.order * t.order },
    rowsPerLine: { value: rowsPerLine },
    lighting: { value: Array.from({ length: kMaxCoefficients }, () => new THREE.Vector3()) },
    perVertex: { value: kind === 'vertex' },
    showError: { value: false },
    errorScale: { value: 0.2 },
    atlasSize: { value: new THREE.Vector2(t.width || 1, t.height || 1) },
    exposure: { value: Number(params.get('exposure') || 0) },
  };
  const material = new THREE.RawShaderMaterial({
    vertexShader, fragmentShader, uniforms, glslVersion: THREE.GLSL3, side: THREE.DoubleSide,
  });
  const scene = new THREE.Scene();
  scene.add(new THREE.Mesh(geometry, material));

  const view = parseNumbers(params.get('camera') || '0,0.1,0.4,0,0.1,0,0,1,0,40', 10, 'camera');
  const eye = new THREE.Vector3(view[0], view[1], view[2]), target = new THREE.Vector3(view[3], view[4], view[5]);
  const distance = eye.distanceTo(target);
  const camera = new THREE.PerspectiveCamera(view[9], width / height, distance * 1e-3, distance * 1e3);
  camera.position.copy(eye);
  camera.up.set(view[6], view[7], view[8]);
  camera.lookAt(target);

  const state = {
    map: 0, order: Math.min(t.order, Number(params.get('order') || t.order)), rotate: Number(params.get('rotate') || 0),
    showError: false,
  };
  let metrics = null;
  let lighting = null;

  // The relit radiance on the CPU, only for the error against a reference (per vertex).
  function errorAgainstReference() {
    if (!reference || kind !== 'vertex' || reference.length !== vertexCount * 3) return null;
    const C = t.order * t.order, weights = [0.2126, 0.7152, 0.0722];
    let squared = 0, referenceSquared = 0, relativeSum = 0, referenceLuminance = 0;
    for (let v = 0; v < vertexCount; ++v)
      referenceLuminance += weights[0] * reference[v * 3] + weights[1] * reference[v * 3 + 1] + weights[2] * reference[v * 3 + 2];
    const floor = 1e-3 * referenceLuminance / vertexCount;
    for (let v = 0; v < vertexCount; ++v) {
      const radiance = [0, 0, 0];
      for (let j = 0; j < C; ++j) for (let c = 0; c < 3; ++c) radiance[c] += t.data[(v * C + j) * 3 + c] * lighting[j * 3 + c];
      let ya = 0, yb = 0;
      for (let c = 0; c < 3; ++c) {
        const d = radiance[c] - reference[v * 3 + c];
        squared += d * d;
        referenceSquared += reference[v * 3 + c] ** 2;
        ya += weights[c] * radiance[c];
        yb += weights[c] * reference[v * 3 + c];
      }
      errors[v] = Math.abs(ya - yb) / Math.max(yb, floor);
      relativeSum += errors[v];
    }
    geometry.attributes.relativeError.needsUpdate = true;
    return { relativeRmse: Math.sqrt(squared / referenceSquared), meanRelativeError: relativeSum / vertexCount };
  }

  function update() {
    const source = lightings[state.map];
    const order = state.order, count = order * order;
    // As prt relight: the lighting's bands shared with the transfer, turned about +Y; bands above `order` are off.
    const fitted = fitLighting(source.coefficients, Math.min(source.order, t.order) ** 2);
    const turned = rotateLightingY(fitted, Math.min(source.order, t.order), state.rotate);
    lighting = new Float32Array(t.order * t.order * 3);
    lighting.set(turned.subarray(0, Math.min(turned.length, count * 3)));
    for (let j = 0; j < kMaxCoefficients; ++j)
      uniforms.lighting.value[j].set(lighting[j * 3] || 0, lighting[j * 3 + 1] || 0, lighting[j * 3 + 2] || 0);
    uniforms.coefficients.value = count;
    uniforms.showError.value = state.showError && !!reference;
    metrics = errorAgainstReference();
    renderer.render(scene, camera);
    if (panel) panel.update(state, metrics, { kind, vertexCount, renderer: api.renderer });
  }

  const api = {
    lightings: lightings.map((l) => l.name),
    transferOrder: t.order,
    kind,
    vertexCount,
    renderer: (() => {
      const debug = gl.getExtension('WEBGL_debug_renderer_info'); // the real GL behind Chromium's mask
      return debug ? gl.getParameter(debug.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER);
    })(),
    set(changes) { Object.assign(state, changes); update(); return { ...state }; },
    metrics: () => metrics,
    // 8-bit RGB of the canvas at pixels [[x, y], ...], row 0 at the top as in prt's images.
    read(points) {
      renderer.render(scene, camera);
      const pixel = new Uint8Array(4);
      return points.map(([x, y]) => {
        gl.readPixels(x, height - 1 - y, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
        return [pixel[0], pixel[1], pixel[2]];
      });
    },
    // Mean milliseconds per frame over `frames` frames, each finished (a 1-pixel read waits for the GPU).
    bench(frames) {
      const pixel = new Uint8Array(4);
      renderer.render(scene, camera);
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
      const start = performance.now();
      for (let i = 0; i < frames; ++i) {
        renderer.render(scene, camera);
        gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
      }
      return (performance.now() - start) / frames;
    },
  };
  update();
  return api;
}
