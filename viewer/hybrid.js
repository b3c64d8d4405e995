// Hybrid lights (docs/envlight.md, "Hybrid relight"): the cone lights of a prt-lights JSON from `prt envlight` plus
// their SH residual, relit on the GPU as `prt relight --lights` does (lib/runtime/hybrid.cpp relightHybrid):
//   radiance(v) = T_v . residual + B_v . hann(sum_k proj(light_k)) + sum_k (albedo_v / pi) L_k V_vk C(n_v . d_k, r_k)
// T the transfer, B its bounce part (layer "transfer_bounce"; without it the lights light only directly), proj the
// exact SH projection of a cone (sh::capProjection), C the horizon-clipped cone cosine integral
// (sh::capCosineIntegral), V_vk the cone visibility that `prt relight --lights ... --visibility-out V.npy` wrote
// ([rows][lights] float32), or with `--visibility-turns N` a table for N turns about +Y ([N][rows][lights] uint8,
// round(255 V), turn t at t 360/N degrees). A single-turn file belongs to the lights as they were turned when it
// was cast, so with one the turn is locked to the URL's `rotate` (the --rotate-y it was made with); with a table the
// turn is free: at a turn theta the visibility is blended linearly between the two nearest table turns
// (visibilityTurnBlend); without a file the cones are unshadowed (V = 1, as `--light-samples 0`).
import * as THREE from 'three';
import { rgbFloatNearest } from './textures.js';
import { layerData, parseGlb } from './bundle.js';
import { readExr } from './exr.js';
import { relightRowGlsl } from './glsl.js';
import { evaluate, rotateLightingY } from './sh.js';

export const kMaxLights = 16;

// Fetches and checks the prt-lights JSON at `url` (as lib/runtime's readHybridLightingJson: format, order, a
// residual of order^2 finite RGB rows, lights with a unit direction, radiance >= 0 and a radius in (0, pi/2)).
// Returns {order, residual: Float32Array [order^2][3], lights: [{direction, radiance, angularRadius}]}.
export async function loadLights(url) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
  const json = await response.json();
  const fail = (place, what) => { throw new Error(`${url}: ${place}: ${what}`); };
  if (json.format !== 'prt-lights') fail('format', 'not prt-lights JSON (prt envlight writes it)');
  if (!Number.isInteger(json.order) || json.order < 1 || json.order > 8) fail('order', 'not an integer in 1..8 (the viewer relights up to order 8)');
  const triple = (value, place) => {
    if (!Array.isArray(value) || value.length !== 3 || value.some((x) => typeof x !== 'number' || !Number.isFinite(x)))
      fail(place, 'expected 3 finite numbers');
    return value;
  };
  if (!Array.isArray(json.residual) || json.residual.length !== json.order ** 2) fail('residual', `expected ${json.order ** 2} rows`);
  const residual = Float32Array.from(json.residual.flatMap((row, i) => triple(row, `residual[${i}]`)));
  if (!Array.isArray(json.lights)) fail('lights', 'expected an array');
  if (json.lights.length > kMaxLights) fail('lights', `${json.lights.length} lights (the viewer draws at most ${kMaxLights})`);
  const lights = json.lights.map((light, k) => {
    const direction = triple(light.direction, `lights[${k}].direction`), length = Math.hypot(...direction);
    if (Math.abs(length - 1) > 1e-3) fail(`lights[${k}].direction`, `length ${length} is not 1`);
    const radiance = triple(light.radiance, `lights[${k}].radiance`);
    if (radiance.some((x) => x < 0)) fail(`lights[${k}].radiance`, 'negative');
    const r = light.angular_radius;
    if (typeof r !== 'number' || !(r > 0 && r < Math.PI / 2)) fail(`lights[${k}].angular_radius`, 'not in (0, pi/2)');
    return { direction: direction.map((x) => x / length), radiance, angularRadius: r };
  });
  return { order: json.order, residual, lights };
}

// SH coefficients of the cap {w : w . d >= cosRadius}: out_lm = 2 pi I_l Y_lm(d), I_l = integral of P_l over
// [cosRadius, 1] (lib/sh/cap.cpp capProjection, the same recurrence).
export function capProjection(order, d, cosRadius) {
  const x = cosRadius, legendre = new Float64Array(order + 1);
  legendre[0] = 1;
  if (order >= 1) legendre[1] = x;
  for (let l = 1; l < order; ++l) legendre[l + 1] = ((2 * l + 1) * x * legendre[l] - l * legendre[l - 1]) / (l + 1);
  const out = evaluate(order, d[0], d[1], d[2]);
  for (let l = 0; l < order; ++l) {
    const integral = l === 0 ? 1 - x : (legendre[l - 1] - legendre[l + 1]) / (2 * l + 1);
    for (let j = l * l; j < (l + 1) * (l + 1); ++j) out[j] *= 2 * Math.PI * integral;
  }
  return out;
}

// The hybrid's lighting turned by `degrees` about +Y (R, 90 degrees takes +Z to +X) at `order` bands (bands above
// are off): {residual [order^2][3] turned in SH (as rotateHybridLighting), bounce = Hann-windowed projection of the
// turned lights (relightHybrid's lit with lighting.bounceWindow = Hann), lights with turned directions}.
export function turnedHybridLighting(hybrid, degrees, order) {
  const full = hybrid.order, count = order * order;
  const residual = rotateLightingY(hybrid.residual, full, degrees);
  const t = degrees * Math.PI / 180, c = Math.cos(t), s = Math.sin(t);
  const lights = hybrid.lights.map((light) => {
    const [x, y, z] = light.direction;
    return { ...light, direction: [c * x + s * z, y, -s * x + c * z] };
  });
  const bounce = new Float64Array(full * full * 3);
  for (const light of lights) {
    const cap = capProjection(full, light.direction, Math.cos(light.angularRadius));
    for (let j = 0; j < full * full; ++j) for (let ch = 0; ch < 3; ++ch) bounce[j * 3 + ch] += light.radiance[ch] * cap[j];
  }
  // sh::applyWindow(Hann): band l times (1 + cos(pi l / order)) / 2, over the transfer's order.
  for (let l = 0; l < full; ++l) {
    const w = 0.5 * (1 + Math.cos(Math.PI * l / full));
    for (let i = l * l * 3; i < (l + 1) * (l + 1) * 3; ++i) bounce[i] *= w;
  }
  const cut = (a) => { const out = new Float32Array(full * full * 3); out.set(Float32Array.from(a).subarray(0, count * 3)); return out; };
  return { residual: cut(residual), bounce: cut(bounce), lights };
}

// What the hybrid reads from the bundle beyond the transfer: the bounce layer ("transfer_bounce", same shape as
// "transfer", or null), the albedo per vertex ([V][3]: params.albedo [r, g, b], or "per-vertex" from COLOR_0) and
// the normals. Throws Error naming the problem (a scene bundle, no normals, an albedo it cannot read).
export function readHybridLayers(bytes, vertexCount) {
  const { json, bin } = parseGlb(bytes);
  const extension = json.extensions.PRT_bundle;
  const layers = extension.layers || [];
  const transfer = layers.find((l) => l.name === 'transfer' && (l.object || 0) === 0);
  if (!transfer) throw new Error('lights: the bundle has no "transfer" layer');
  const bounceLayer = layers.find((l) => l.name === 'transfer_bounce' && (l.object || 0) === 0);
  let bounce = null;
  if (bounceLayer) {
    if (bounceLayer.semantic !== 'sh_transfer_bounce_rgb' || JSON.stringify(bounceLayer.shape) !== JSON.stringify(transfer.shape))
      throw new Error('lights: layer "transfer_bounce" is not sh_transfer_bounce_rgb of the transfer\'s shape');
    bounce = layerData(json, bin, bounceLayer);
  }
  const primitive = json.meshes[0].primitives[0];
  const accessorFloats = (index) => {
    const a = json.accessors[index], view = json.bufferViews[a.bufferView];
    if (a.componentType !== 5126 || a.count !== vertexCount) throw new Error(`lights: accessor ${index} is not float per vertex`);
    const offset = (view.byteOffset || 0) + (a.byteOffset || 0), width = { VEC3: 3, VEC4: 4 }[a.type];
    if (!width || (view.byteStride && view.byteStride !== width * 4)) throw new Error(`lights: accessor ${index} layout`);
    return { data: new Float32Array(bin.slice(offset, offset + a.count * width * 4)), width };
  };
  if (primitive.attributes.NORMAL === undefined) throw new Error('lights: the mesh has no normals for the cone lights (prt meshprep)');
  const normals = accessorFloats(primitive.attributes.NORMAL).data;
  const params = transfer.params || {};
  const albedo = new Float32Array(vertexCount * 3);
  if (Array.isArray(params.albedo) && params.albedo.length === 3) {
    for (let v = 0; v < vertexCount; ++v) albedo.set(params.albedo, v * 3);
  } else if (params.albedo === 'per-vertex' && primitive.attributes.COLOR_0 !== undefined) {
    const { data, width } = accessorFloats(primitive.attributes.COLOR_0);
    for (let v = 0; v < vertexCount; ++v) albedo.set(data.subarray(v * width, v * width + 3), v * 3);
  } else {
    throw new Error(`lights: the transfer's params.albedo ${JSON.stringify(params.albedo)} is not [r, g, b] or per-vertex COLOR_0`);
  }
  return { bounce, albedo, normals };
}

// A scene bundle's bounce layer ("transfer_bounce", irradiance transfer of the transfer's shape, or null): what the
// hybrid reads beyond the transfer for a scene. The albedo is the materials' per pixel (scene.js), the normals
// each receiver's in world space (the node's normal matrix, scene.js). Throws Error for a malformed layer.
export function readSceneBounce(json, bin) {
  const layers = json.extensions.PRT_bundle.layers || [];
  const transfer = layers.find((l) => l.name === 'transfer');
  const bounceLayer = layers.find((l) => l.name === 'transfer_bounce');
  if (!bounceLayer) return null;
  if (bounceLayer.semantic !== 'sh_transfer_bounce_rgb' || !transfer || JSON.stringify(bounceLayer.shape) !== JSON.stringify(transfer.shape))
    throw new Error('lights: layer "transfer_bounce" is not sh_transfer_bounce_rgb of the transfer\'s shape');
  const data = layerData(json, bin, bounceLayer);
  if (!data) throw new Error('lights: layer "transfer_bounce" has no data in the bundle');
  return data;
}

// A bake's texel hybrid layers (`prt bake`, docs/bundle.md): "texel_surface" ([texels][10]: position, unit normal,
// albedo, coverage, gutters filled; inline with --format bundle, else the OpenEXR params.uri with the channels
// params.channels) and "texel_transfer_bounce" (the transfer's shape; inline, or the OpenEXR params.uri with channels
// T000.R ... as the transfer's), as lib/runtime's texelHybridModel reads them. `bundleUrl` resolves the files, `bytes`
// are the bundle's, `transfer` its texel transfer ({width, height, order}). Returns {bounce: Float32Array
// [texels][C][3] or null, surface: Float32Array [2][texels][3] (normals, then albedo)}. Throws Error naming the
// problem (no surface layer: a bake made before the texel hybrid; a layer of the wrong shape).
export async function readTexelHybridLayers(bytes, bundleUrl, transfer) {
  const { json, bin } = parseGlb(bytes);
  const layers = json.extensions.PRT_bundle.layers || [];
  const texels = transfer.width * transfer.height, C = transfer.order * transfer.order;
  const fetchExr = async (uri) => {
    const url = new URL(uri, new URL(bundleUrl, location.href)).href;
    const response = await fetch(url);
    if (!response.ok) throw new Error(`${uri}: HTTP ${response.status}`);
    const image = await readExr(await response.arrayBuffer(), uri);
    if (image.width !== transfer.width || image.height !== transfer.height)
      throw new Error(`${uri}: ${image.width} x ${image.height} texels, the transfer's atlas ${transfer.width} x ${transfer.height}`);
    return image;
  };
  const channel = (image, name, uri) => {
    if (!image.channels[name]) throw new Error(`${uri}: no channel ${name}`);
    return image.channels[name];
  };
  const surfaceLayer = layers.find((l) => l.name === 'texel_surface');
  if (!surfaceLayer)
    throw new Error('lights: the bake has no "texel_surface" layer (texel normals and albedo for the cone lights): bake it again');
  if (surfaceLayer.domain !== 'texel' || JSON.stringify(surfaceLayer.shape) !== JSON.stringify([texels, 10]))
    throw new Error(`lights: layer "texel_surface" is not a texel layer of shape [${texels}, 10]`);
  let values = layerData(json, bin, surfaceLayer);
  const params = surfaceLayer.params || {};
  if (!values) {
    if (!params.uri || !Array.isArray(params.channels) || params.channels.length !== 10)
      throw new Error('lights: layer "texel_surface" has neither data nor an OpenEXR uri with 10 channels');
    const image = await fetchExr(params.uri);
    values = new Float32Array(texels * 10);
    params.channels.forEach((name, k) => {
      const data = channel(image, name, params.uri);
      for (let t = 0; t < texels; ++t) values[t * 10 + k] = data[t];
    });
  }
  const surface = new Float32Array(2 * texels * 3);
  for (let t = 0; t < texels; ++t) {
    const row = values.subarray(t * 10, t * 10 + 10), length = Math.hypot(row[3], row[4], row[5]);
    if (!(length > 0.5 && length < 1.5)) throw new Error(`lights: layer "texel_surface", texel ${t}: normal is not unit length`);
    for (let a = 0; a < 3; ++a) {
      surface[t * 3 + a] = row[3 + a] / length;
      surface[(texels + t) * 3 + a] = row[6 + a];
    }
  }
  const bounceLayer = layers.find((l) => l.name === 'texel_transfer_bounce');
  let bounce = null;
  if (bounceLayer) {
    if (bounceLayer.semantic !== 'sh_transfer_bounce_rgb' || JSON.stringify(bounceLayer.shape) !== JSON.stringify([texels, C, 3]))
      throw new Error(`lights: layer "texel_transfer_bounce" is not sh_transfer_bounce_rgb of shape [${texels}, ${C}, 3]`);
    bounce = layerData(json, bin, bounceLayer);
    if (!bounce) {
      const uri = (bounceLayer.params || {}).uri, format = (bounceLayer.params || {}).format;
      if (!uri || !(format === 'half' || format === 'float'))
        throw new Error(`lights: layer "texel_transfer_bounce" keeps its texels as ${format}: the viewer reads OpenEXR (half, float) or bundle texels`);
      const image = await fetchExr(uri);
      bounce = new Float32Array(texels * C * 3);
      for (let j = 0; j < C; ++j)
        for (let c = 0; c < 3; ++c) {
          const data = channel(image, `T${String(j).padStart(3, '0')}.${'RGB'[c]}`, uri);
          for (let t = 0; t < texels; ++t) bounce[(t * C + j) * 3 + c] = data[t];
        }
    }
  }
  return { bounce, surface };
}

// The texel surface (readTexelHybridLayers: normals, then albedo) as a 2-layer RGB32F array texture of the atlas.
export function texelSurfaceTexture(surface, width, height) {
  const texture = new THREE.DataArrayTexture(surface, width, height, 2);
  rgbFloatNearest(texture);
  return texture;
}

// A prt .npy of float32 [rows, lights] (prt relight --visibility-out) as {turns: 1, rows, lights, data}, or of uint8
// [turns, rows, lights] (with --visibility-turns) as {turns, rows, lights, bytes}. Throws Error otherwise.
export function parseVisibilityNpy(arrayBuffer, url) {
  const bytes = new Uint8Array(arrayBuffer);
  if (bytes.length < 10 || bytes[0] !== 0x93 || new TextDecoder().decode(bytes.subarray(1, 6)) !== 'NUMPY')
    throw new Error(`${url}: not a .npy file`);
  const headerLength = bytes[8] | (bytes[9] << 8);
  const header = new TextDecoder().decode(bytes.subarray(10, 10 + headerLength));
  const table = header.match(/'shape': \((\d+),\s*(\d+),\s*(\d+)\)/);
  if (header.includes("'|u1'") && table && !header.includes("'fortran_order': True")) {
    const [turns, rows, lights] = [Number(table[1]), Number(table[2]), Number(table[3])];
    const data = new Uint8Array(arrayBuffer.slice(10 + headerLength));
    if (turns < 1 || data.length !== turns * rows * lights)
      throw new Error(`${url}: ${data.length} bytes for shape (${turns}, ${rows}, ${lights})`);
    return { turns, rows, lights, bytes: data };
  }
  const shape = header.match(/'shape': \((\d+),\s*(\d+)\)/);
  if (!header.includes("'<f4'") || header.includes("'fortran_order': True") || !shape)
    throw new Error(`${url}: need a float32 C-order .npy of shape (rows, lights)`);
  const rows = Number(shape[1]), lights = Number(shape[2]);
  const data = new Float32Array(arrayBuffer.slice(10 + headerLength));
  if (data.length !== rows * lights) throw new Error(`${url}: ${data.length} values for shape (${rows}, ${lights})`);
  return { turns: 1, rows, lights, data };
}

// Where a turn of `degrees` falls in a table of `turns` turns: {a, b, weight}, V = (1 - weight) V_a + weight V_b,
// a and b the two nearest table turns (periodic over 360 degrees).
export function visibilityTurnBlend(degrees, turns) {
  const position = (((degrees % 360) + 360) % 360) * turns / 360;
  const a = Math.floor(position) % turns;
  return { a, b: (a + 1) % turns, weight: position - Math.floor(position) };
}

// The visibility [rows][lights] as `lights` layers of rowsPerLine x lines R32F texels (row r at (r % rowsPerLine,
// r / rowsPerLine)), as viewer.js lays out the transfer.
// A table (uint8, `turns` > 1 or bytes) goes as turns x lights R8 layers, layer t * lights + k (read back as byte/255).
export function visibilityTexture(visibility, rowsPerLine, lines) {
  const layer = rowsPerLine * lines, K = Math.max(1, visibility.lights), turns = visibility.turns || 1;
  const bytes = !!visibility.bytes;
  if (turns * K > 256) throw new Error(`visibility: ${turns} turns x ${K} lights = ${turns * K} texture layers, above WebGL2's 256`);
  const data = bytes ? new Uint8Array(layer * K * turns).fill(255) : new Float32Array(layer * K).fill(1);
  const source = bytes ? visibility.bytes : visibility.data;
  for (let t = 0; t < turns; ++t)
    for (let r = 0; r < visibility.rows; ++r)
      for (let k = 0; k < visibility.lights; ++k)
        data[(t * K + k) * layer + r] = source[(t * visibility.rows + r) * visibility.lights + k];
  const texture = new THREE.DataArrayTexture(data, rowsPerLine, lines, K * turns);
  texture.format = THREE.RedFormat;
  texture.type = bytes ? THREE.UnsignedByteType : THREE.FloatType;
  texture.internalFormat = bytes ? 'R8' : 'R32F';
  texture.minFilter = texture.magFilter = THREE.NearestFilter;
  texture.generateMipmaps = false;
  texture.needsUpdate = true;
  return texture;
}

// Uniforms the hybrid's GLSL reads, filled by setHybridUniforms.
export function hybridUniforms(maxCoefficients) {
  return {
    hybrid: { value: false },
    bounce: { value: null },
    hasBounce: { value: false },
    bounceLighting: { value: Array.from({ length: maxCoefficients }, () => new THREE.Vector3()) },
    lightCount: { value: 0 },
    lightDirection: { value: Array.from({ length: kMaxLights }, () => new THREE.Vector3()) },
    lightRadiance: { value: Array.from({ length: kMaxLights }, () => new THREE.Vector3()) },
    lightSinSquared: { value: new Array(kMaxLights).fill(0) },
    visibility: { value: null },
    hasVisibility: { value: false },
    visibilityTurnA: { value: 0 },
    visibilityTurnB: { value: 0 },
    visibilityWeight: { value: 0 },
  };
}

// Loads turnedHybridLighting's result into the uniforms.
export function setHybridUniforms(uniforms, turned, maxCoefficients) {
  for (let j = 0; j < maxCoefficients; ++j)
    uniforms.bounceLighting.value[j].set(turned.bounce[j * 3] || 0, turned.bounce[j * 3 + 1] || 0, turned.bounce[j * 3 + 2] || 0);
  uniforms.lightCount.value = turned.lights.length;
  turned.lights.forEach((light, k) => {
    uniforms.lightDirection.value[k].set(...light.direction);
    uniforms.lightRadiance.value[k].set(...light.radiance);
    uniforms.lightSinSquared.value[k] = Math.sin(light.angularRadius) ** 2;
  });
}

// The vertex shader's part: hybridLightsAt(row, n, albedo) is B . bounceLighting plus the cones' direct light at a
// vertex of normal n (normalised here) and albedo; with `attributes` also hybridLights(row), which takes both from
// the attributes normal and albedo (a plain bundle). A scene (scene.js) passes its world normal and albedo 1: its
// transfer and bounce layer are irradiance transfer, and the materials multiply per pixel.
// Needs relightRowGlsl's uniforms (transfer layout: rowsPerLine, coefficients).
export const hybridGlsl = (maxCoefficients, attributes = true) => /* glsl */ `
uniform bool hybrid;
uniform sampler2DArray bounce;
uniform bool hasBounce;
uniform vec3 bounceLighting[${maxCoefficients}];
uniform int lightCount;
uniform vec3 lightDirection[${kMaxLights}];
uniform vec3 lightRadiance[${kMaxLights}];
uniform float lightSinSquared[${kMaxLights}];
uniform sampler2DArray visibility;
uniform bool hasVisibility;
uniform int visibilityTurnA, visibilityTurnB; // table turns blended (visibilityTurnBlend); 0, 0 for one turn
uniform float visibilityWeight;
${relightRowGlsl(maxCoefficients, 'relightBounce', 'bounce', 'bounceLighting')}
// sh::capCosineIntegral: the integral of max(0, n . w) over the cap of half-angle sigma about an axis at cosine
// cosTheta from n (Snyder 1996, horizon-clipped form of Lagarde and de Rousiers 2014).
float capCosineIntegral(float cosTheta, float sinSigmaSquared) {
  const float pi = 3.14159265358979;
  cosTheta = clamp(cosTheta, -1.0, 1.0);
  sinSigmaSquared = clamp(sinSigmaSquared, 0.0, 1.0);
  if (cosTheta * cosTheta >= sinSigmaSquared) return pi * sinSigmaSquared * max(0.0, cosTheta);
  float sinTheta = sqrt(1.0 - cosTheta * cosTheta);
  float x = sqrt(max(1.0 / sinSigmaSquared - 1.0, 0.0));
  float y = clamp(-x * cosTheta / sinTheta, -1.0, 1.0);
  float sinThetaSqrtY = sinTheta * sqrt(max(0.0, 1.0 - y * y));
  float value = (cosTheta * acos(y) - x * sinThetaSqrtY) * sinSigmaSquared + (x > 0.0 ? atan(sinThetaSqrtY / x) : pi / 2.0);
  return max(0.0, value);
}
vec3 hybridLightsAt(int row, vec3 vertexNormal, vec3 albedo) {
  const float pi = 3.14159265358979;
  vec3 sum = hasBounce ? relightBounce(row) : vec3(0.0);
  ivec2 at = ivec2(row % rowsPerLine, row / rowsPerLine);
  vec3 n = normalize(vertexNormal);
  for (int k = 0; k < ${kMaxLights}; ++k) {
    if (k >= lightCount) break;
    float visible = 1.0;
    if (hasVisibility) {
      float va = texelFetch(visibility, ivec3(at, visibilityTurnA * lightCount + k), 0).r;
      float vb = texelFetch(visibility, ivec3(at, visibilityTurnB * lightCount + k), 0).r;
      visible = mix(va, vb, visibilityWeight);
    }
    if (!(visible > 0.0)) continue;
    float irradiance = capCosineIntegral(dot(n, lightDirection[k]), lightSinSquared[k]) * min(1.0, visible);
    sum += albedo / pi * lightRadiance[k] * irradiance;
  }
  return sum;
}
${attributes ? `in vec3 normal;
in vec3 albedo;
vec3 hybridLights(int row) { return hybridLightsAt(row, normal, albedo); }` : ''}`;
