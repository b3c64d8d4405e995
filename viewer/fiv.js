// Moving occluders (docs/fiv.md): a `prt fivscene` bundle read without any glTF library, and the receiver shaded
// from the FIV grids as `prt fivshade` does (lib/runtime/fiv_shade.cpp fivIrradiance with its defaults, partial
// "cap" and overlap "cap"), on the CPU in JavaScript, per vertex, in double precision: the page recomputes the
// receiver's radiance whenever an instance moves and uploads it as a vertex attribute. Cases A (bounding sphere
// above the tangent plane, exact), B (straddling, the cap correction) and C (below, ignored), the self-shadowing
// grid of object 0, and the overlap correction between instances are all the runtime's; so are the small sources'
// own grids (`prt fiv --sources --source-grid`, decision 13: the sharpened fraction g, combined over instances as
// 1 - prod(1 - g)) and the receiver's exact self-shadowing (`prt fiv --self-vertices`, layer fiv_self, decision 14:
// I = E_self - sum_j I_occ,j).
import { layerData, parseGlb } from './bundle.js';

// Cube faces +X -X +Y -Y +Z -Z: axis, right (increasing column), up (decreasing row), as lib/sh's kCubeFaces.
const kCubeFaces = [
  [[1, 0, 0], [0, 0, 1], [0, 1, 0]], [[-1, 0, 0], [0, 0, -1], [0, 1, 0]], [[0, 1, 0], [1, 0, 0], [0, 0, 1]],
  [[0, -1, 0], [1, 0, 0], [0, 0, -1]], [[0, 0, 1], [-1, 0, 0], [0, 1, 0]], [[0, 0, -1], [1, 0, 0], [0, 1, 0]],
];
const dot = (a, b, i = 0, j = 0) => a[i] * b[j] + a[i + 1] * b[j + 1] + a[i + 2] * b[j + 2];

// A layer of object `object` by name (object 0's grid layers are `name`, object k's `name.k`; difmap and fiv_env keep
// their names on whichever object holds them), checked for its shape.
function layer(extension, name, object, shape) {
  const full = object === 0 ? name : `${name}.${object}`;
  const found = (extension.layers || []).find((l) => (l.name === full || l.name === name) && (l.object || 0) === object);
  if (!found) return null;
  if (shape && JSON.stringify(found.shape) !== JSON.stringify(shape))
    throw new Error(`FIV scene: layer ${full} has shape ${JSON.stringify(found.shape)}, expected ${JSON.stringify(shape)}`);
  return found;
}

function integers(json, bin, l) {
  if (l.componentType !== 'uint8') throw new Error(`FIV scene: layer ${l.name} is not uint8`);
  const view = json.bufferViews[l.bufferView];
  return new Uint8Array(bin.slice(view.byteOffset || 0, (view.byteOffset || 0) + l.shape[0]));
}

function finite(values, name) {
  for (const v of values) if (!Number.isFinite(v)) throw new Error(`FIV scene: layer ${name} holds a value that is not finite`);
  return values;
}

// Primitive 0 of glTF mesh `index`: {positions, normals, indices} (float positions and normals, any index type).
function meshOf(json, bin, index) {
  const primitive = json.meshes[index].primitives[0];
  const read = (accessorIndex, Type, width) => {
    const a = json.accessors[accessorIndex], view = json.bufferViews[a.bufferView];
    const offset = (view.byteOffset || 0) + (a.byteOffset || 0), size = Type.BYTES_PER_ELEMENT;
    return new Type(bin.slice(offset, offset + a.count * width * size));
  };
  const indexType = { 5125: Uint32Array, 5123: Uint16Array, 5121: Uint8Array }[json.accessors[primitive.indices].componentType];
  if (primitive.attributes.NORMAL === undefined) throw new Error(`FIV scene: mesh ${index} has no normals (prt meshprep)`);
  return { positions: read(primitive.attributes.POSITION, Float32Array, 3), normals: read(primitive.attributes.NORMAL, Float32Array, 3),
           indices: Uint32Array.from(read(primitive.indices, indexType, 1)) };
}

// Whether the glTF JSON is a FIV scene, as lib/runtime's isFivScene: some object >= 1 carries a grid, or object 0
// is a receiver with its own grid (a bundle from `prt fiv` names its one object an occluder).
export function isFivSceneJson(json) {
  const extension = json.extensions && json.extensions.PRT_bundle;
  if (!extension) return false;
  const layers = extension.layers || [];
  if (layers.some((l) => (l.object || 0) >= 1 && l.name === `fiv.${l.object}`)) return true;
  const objects = extension.objects || [];
  return !!objects[0] && objects[0].role === 'receiver' && layers.some((l) => l.name === 'fiv' && !l.object);
}

// An integer param of layer `l` within lo..hi (intParam).
function intParam(l, key, lo, hi) {
  const v = (l.params || {})[key];
  if (!Number.isInteger(v)) throw new Error(`FIV scene: ${l.name} params.${key} is missing or not an integer`);
  if (v < lo || v > hi) throw new Error(`FIV scene: ${l.name} params.${key} = ${v} is outside ${lo}..${hi}`);
  return v;
}

// A number param as a float32 that is finite (coordinateParam, whose bound +-1e9 is kFivMaxCoordinate).
function coordinate(value, place) {
  const f = Math.fround(value);
  if (typeof value !== 'number' || !Number.isFinite(value) || !Number.isFinite(f) || Math.abs(value) > 1e9)
    throw new Error(`FIV scene: ${place} is not a finite number within +-1000000000`);
  return f;
}

// Layers fiv_source_grid / fiv_source_valid of object k (`prt fiv --sources --source-grid`, decision 13), checked
// as fiv_shade.cpp's sourceGrid does and against the main grid `o` (same sphere, same map): {azimuth, polar, shells,
// shellRadii, sharpen, power [3], fiv [9] (N . fiv[3c..] the sources' irradiance in channel c), fraction, valid}.
function sourceGrid(json, bin, extension, k, o, env) {
  const header = layer(extension, 'fiv_source_grid', k), validLayer = layer(extension, 'fiv_source_valid', k);
  if (!header !== !validLayer)
    throw new Error(`FIV scene: object ${k} has ${header ? 'fiv_source_grid without fiv_source_valid' : 'fiv_source_valid without fiv_source_grid'} (they come together)`);
  if (!header) return null;
  const name = header.name;
  const g = { azimuth: intParam(header, 'azimuth', 3, 4096), polar: intParam(header, 'polar', 2, 2049), shells: intParam(header, 'shells', 1, 1024) };
  const rows = g.azimuth * g.polar * g.shells;
  if (rows > 2 ** 26) throw new Error(`FIV scene: ${name} holds more than 2^26 samples`);
  layer(extension, 'fiv_source_grid', k, [rows]);
  layer(extension, 'fiv_source_valid', k, [rows]);
  if (header.semantic !== 'fiv_source_hidden_fraction' || validLayer.semantic !== 'fiv_valid')
    throw new Error(`FIV scene: ${name} or its fiv_source_valid has another semantic than fiv_source_hidden_fraction, fiv_valid`);
  g.fraction = finite(layerData(json, bin, header), name);
  g.valid = integers(json, bin, validLayer);
  if (g.fraction.length !== rows || g.valid.length !== rows)
    throw new Error(`FIV scene: ${name} or its fiv_source_valid holds fewer values than its shape [${rows}] needs`);
  for (const f of g.fraction) if (!(f >= 0 && f <= 1)) throw new Error(`FIV scene: ${name} holds a fraction outside 0..1`);
  for (const v of g.valid) if (v > 1) throw new Error(`FIV scene: ${validLayer.name} holds a value other than 0 and 1`);
  const p = header.params, place = `${name} params.`;
  if (p.radius === undefined || coordinate(p.radius, `${place}radius`) !== o.radius)
    throw new Error(`FIV scene: ${place}radius is missing or differs from the main grid's (not the same occluder)`);
  if (!Array.isArray(p.centre) || p.centre.length !== 3) throw new Error(`FIV scene: ${place}centre is not an array of 3 numbers`);
  p.centre.forEach((x, c) => {
    if (coordinate(x, `${place}centre[${c}]`) !== o.centre[c])
      throw new Error(`FIV scene: ${place}centre differs from the main grid's (not the same occluder)`);
  });
  if (!Array.isArray(p.shell_radii) || p.shell_radii.length !== g.shells)
    throw new Error(`FIV scene: ${place}shell_radii is not an array of \`shells\` numbers`);
  g.shellRadii = [];
  for (const [i, rho] of p.shell_radii.entries()) {
    const at = `${place}shell_radii[${i}]`, r = coordinate(coordinate(rho, at) * o.radius, `${at} times params.radius`);
    if (!(rho > 0) || (g.shellRadii.length && !(r > g.shellRadii[g.shellRadii.length - 1])))
      throw new Error(`FIV scene: ${at}: shell radii are not positive and ascending`);
    g.shellRadii.push(r);
  }
  if (p.sharpen === undefined) throw new Error(`FIV scene: ${place}sharpen is missing`);
  g.sharpen = coordinate(p.sharpen, `${place}sharpen`);
  if (!(g.sharpen >= 1 && g.sharpen <= 100)) throw new Error(`FIV scene: ${place}sharpen is outside 1..100`);
  if (!Array.isArray(p.source_power) || p.source_power.length !== 3) throw new Error(`FIV scene: ${place}source_power is not an array of 3 numbers`);
  if (!Array.isArray(p.source_fiv) || p.source_fiv.length !== 3) throw new Error(`FIV scene: ${place}source_fiv is not an array of 3 arrays of 3 numbers`);
  g.power = [0, 0, 0];
  g.fiv = new Array(9).fill(0);
  for (let c = 0; c < 3; ++c) {
    g.power[c] = coordinate(p.source_power[c], `${place}source_power[${c}]`);
    if (!(g.power[c] >= 0)) throw new Error(`FIV scene: ${place}source_power[${c}] is negative`);
    const row = p.source_fiv[c];
    if (!Array.isArray(row) || row.length !== 3) throw new Error(`FIV scene: ${place}source_fiv[${c}] is not an array of 3 numbers`);
    let length2 = 0;
    for (let a = 0; a < 3; ++a) {
      g.fiv[3 * c + a] = coordinate(row[a], `${place}source_fiv[${c}][${a}]`);
      length2 += g.fiv[3 * c + a] ** 2;
    }
    // A sum of power times unit directions is no longer than the power.
    if (Math.sqrt(length2) > 1.001 * g.power[c] + 1e-30) throw new Error(`FIV scene: ${place}source_fiv[${c}] is longer than source_power`);
  }
  if ((typeof p.env === 'string' ? p.env : '') !== env) throw new Error(`FIV scene: ${place}env differs from the main grid's environment`);
  return g;
}

// Reads a `prt fivscene` bundle: {receiver: mesh, grids: [object] (null without a grid), lighting: {size, difmap,
// fivEnv}, instances: [{object, translation, mesh}], self: grid or null, occluderMeshes: {object: mesh}}. A grid
// may carry `sources` (its source grid, or null) and object 0's `selfIrradiance` ([V][3], layer fiv_self, or null).
// Throws Error naming the layer or member for anything the runtime's fivScene refuses.
export function readFivScene(arrayBuffer) {
  const { json, bin } = parseGlb(arrayBuffer);
  const extension = json.extensions.PRT_bundle;
  const objects = extension.objects || [{ mesh: 0 }];
  const receiver = meshOf(json, bin, objects[0].mesh);
  const grids = objects.map((_, k) => {
    const header = layer(extension, 'fiv', k);
    if (!header) return null;
    const p = header.params || {};
    for (const key of ['azimuth', 'polar', 'shells'])
      if (!Number.isInteger(p[key]) || p[key] < 1) throw new Error(`FIV scene: fiv.${k} params.${key} is not a positive integer`);
    const rows = p.azimuth * p.polar * p.shells;
    if (!(p.radius > 0) || !Array.isArray(p.centre) || p.centre.length !== 3 || !Array.isArray(p.shell_radii) ||
        p.shell_radii.length !== p.shells)
      throw new Error(`FIV scene: fiv.${k} params radius, centre or shell_radii are missing or malformed`);
    layer(extension, 'fiv', k, [rows, 3, 3]);
    const shellRadii = p.shell_radii.map((rho) => Math.fround(Math.fround(rho) * Math.fround(p.radius))); // as the runtime's floats
    const grid = {
      azimuth: p.azimuth, polar: p.polar, shells: p.shells, radius: Math.fround(p.radius), centre: p.centre.map(Math.fround),
      shellRadii, fiv: finite(layerData(json, bin, header), `fiv.${k}`),
      power: finite(layerData(json, bin, layer(extension, 'fiv_power', k, [rows, 3])), `fiv_power.${k}`),
      valid: integers(json, bin, layer(extension, 'fiv_valid', k, [rows])),
    };
    grid.sources = sourceGrid(json, bin, extension, k, grid, typeof p.env === 'string' ? p.env : '');
    // The receiver's exact self-shadowed irradiance at its own vertices (`prt fiv --self-vertices`, carried by
    // `prt fivscene --self`), used instead of its grid's N . FIV(Env) - N . FIV_self.
    const self = k === 0 ? layer(extension, 'fiv_self', 0) : null;
    grid.selfIrradiance = null;
    if (self) {
      layer(extension, 'fiv_self', 0, [receiver.positions.length / 3, 3]);
      if (self.semantic !== 'self_shadowed_irradiance_rgb') throw new Error('FIV scene: fiv_self has another semantic than self_shadowed_irradiance_rgb');
      grid.selfIrradiance = finite(layerData(json, bin, self), 'fiv_self');
      if (grid.selfIrradiance.length !== receiver.positions.length) throw new Error('FIV scene: fiv_self holds fewer values than its shape needs');
      if (grid.selfIrradiance.some((e) => e < 0)) throw new Error('FIV scene: fiv_self holds a negative irradiance');
    }
    return grid;
  });
  let lighting = null;
  for (let k = 0; k < objects.length && !lighting; ++k) {
    const difmap = layer(extension, 'difmap', k);
    if (!difmap) continue;
    const size = difmap.params.size;
    layer(extension, 'difmap', k, [6 * size * size, 3]);
    lighting = { size, difmap: finite(layerData(json, bin, difmap), 'difmap'),
                 fivEnv: finite(layerData(json, bin, layer(extension, 'fiv_env', k, [1, 3, 3])), 'fiv_env') };
  }
  if (!lighting) throw new Error('FIV scene: no difmap layer (not a scene from prt fivscene)');
  const instances = [];
  for (const [i, instance] of (extension.instances || []).entries()) {
    if (instance.object === 0) continue; // the receiver; its own grid is `self`
    if (!grids[instance.object]) throw new Error(`FIV scene: instance ${i} places object ${instance.object}, which has no grid`);
    const t = instance.translation;
    if (!Array.isArray(t) || t.length !== 3 || t.some((x) => !Number.isFinite(x)))
      throw new Error(`FIV scene: instance ${i} has no finite translation`);
    instances.push({ object: instance.object, translation: t.map(Math.fround), name: instance.name || `instance ${i}` });
  }
  if (!instances.length && !grids[0]) throw new Error('FIV scene: no instance places an occluder, and the receiver has no grid');
  const occluderMeshes = {};
  for (const instance of instances)
    if (!occluderMeshes[instance.object]) occluderMeshes[instance.object] = meshOf(json, bin, objects[instance.object].mesh);
  return { receiver, grids, lighting, instances, self: grids[0], occluderMeshes };
}

// DifMap(n), bilinear within a face (fivDifmap).
export function fivDifmap(lighting, n) {
  let axis = 0;
  for (let c = 1; c < 3; ++c) if (Math.abs(n[c]) > Math.abs(n[axis])) axis = c;
  const face = 2 * axis + (n[axis] < 0 ? 1 : 0), depth = Math.abs(n[axis]);
  if (!(depth > 0)) return [0, 0, 0];
  const size = lighting.size, [, right, up] = kCubeFaces[face];
  const a = dot(right, n) / depth, b = dot(up, n) / depth;
  const x = Math.min(Math.max((a + 1) * 0.5 * size - 0.5, 0), size - 1), y = Math.min(Math.max((1 - b) * 0.5 * size - 0.5, 0), size - 1);
  const x0 = Math.min(Math.floor(x), size - 1), y0 = Math.min(Math.floor(y), size - 1);
  const x1 = Math.min(x0 + 1, size - 1), y1 = Math.min(y0 + 1, size - 1), tx = x - x0, ty = y - y0;
  const base = 3 * face * size * size, d = lighting.difmap;
  return [0, 1, 2].map((c) => {
    const top = (1 - tx) * d[base + 3 * (y0 * size + x0) + c] + tx * d[base + 3 * (y0 * size + x1) + c];
    const bottom = (1 - tx) * d[base + 3 * (y1 * size + x0) + c] + tx * d[base + 3 * (y1 * size + x1) + c];
    return (1 - ty) * top + ty * bottom;
  });
}

// The lookup both grids share (gridLookup in fiv_shade.cpp): the eight corners around offset = centre - point
// (angles bilinear, periodic in azimuth; shells linear in r with r_k^2 weights) go to scratch.rows / weights and
// `gatherCorners(count)` sums the usable ones and returns their weight; when none is usable, the nearest shells
// further out, four corners at a time. Returns the factor that renormalises the sum and divides by rho^2, or -1
// when no usable sample exists along the way out. Allocation-free (it runs per vertex and occluder).
const scratch = { fiv: new Float64Array(9), power: new Float64Array(3), rows: new Int32Array(8), weights: new Float64Array(8) };
function gridLookup(o, offset, gatherCorners) {
  const length = Math.hypot(offset[0], offset[1], offset[2]);
  const u1 = length > 0 ? offset[1] / length : 1, u0 = length > 0 ? offset[0] / length : 0;
  const u2 = length > 0 ? offset[2] / length : 0;
  const theta = Math.acos(Math.min(1, Math.max(-1, u1)));
  let phi = Math.atan2(u0, -u2);
  if (phi < 0) phi += 2 * Math.PI;
  const fj = theta / Math.PI * (o.polar - 1);
  const j0 = Math.min(Math.max(Math.floor(fj), 0), o.polar - 2), tj = Math.min(Math.max(fj - j0, 0), 1);
  const fi = phi / (2 * Math.PI) * o.azimuth;
  let i0 = Math.floor(fi);
  const ti = Math.min(Math.max(fi - i0, 0), 1);
  i0 %= o.azimuth;
  const i1 = (i0 + 1) % o.azimuth, r = o.shellRadii;
  let k0, k1, tk;
  if (length <= r[0]) [k0, k1, tk] = [0, 0, 0];
  else if (length >= r[r.length - 1]) [k0, k1, tk] = [o.shells - 1, o.shells - 1, 0];
  else {
    k1 = r.findIndex((radius) => radius > length);
    k0 = k1 - 1;
    tk = (length - r[k0]) / (r[k1] - r[k0]);
  }
  const inverse2 = length > r[0] ? 1 / (length * length) : 1 / (r[0] * r[0]);
  const P = o.polar, A = o.azimuth;
  const a0 = (1 - ti) * (1 - tj), a1 = ti * (1 - tj), a2 = (1 - ti) * tj, a3 = ti * tj;
  const { rows, weights } = scratch;
  const corner = (c, k, j, i, w) => { rows[c] = (k * P + j) * A + i; weights[c] = w; };
  const w0 = (1 - tk) * r[k0] * r[k0], w1 = tk * r[k1] * r[k1];
  corner(0, k0, j0, i0, w0 * a0); corner(1, k0, j0, i1, w0 * a1); corner(2, k0, j0 + 1, i0, w0 * a2); corner(3, k0, j0 + 1, i1, w0 * a3);
  corner(4, k1, j0, i0, w1 * a0); corner(5, k1, j0, i1, w1 * a1); corner(6, k1, j0 + 1, i0, w1 * a2); corner(7, k1, j0 + 1, i1, w1 * a3);
  let full = w0 + w1;
  let used = gatherCorners(8);
  if (used <= 1e-6 * full) {
    used = 0;
    for (let k = k1 + 1; k < o.shells && used <= 0; ++k) {
      full = r[k] * r[k];
      corner(0, k, j0, i0, full * a0); corner(1, k, j0, i1, full * a1); corner(2, k, j0 + 1, i0, full * a2); corner(3, k, j0 + 1, i1, full * a3);
      used = gatherCorners(4);
    }
    if (used <= 0) return -1;
  }
  return full / used * inverse2;
}

// The main grid's FIV [9] and power [3] at offset = centre - point (fivLookup), or null when no usable sample
// exists. The result lives in scratch arrays that the next call overwrites.
function gatherGrid(o, count) {
  const { fiv, power, rows, weights } = scratch;
  fiv.fill(0);
  power.fill(0);
  let total = 0;
  for (let c = 0; c < count; ++c) {
    const row = rows[c], w = weights[c];
    if (w <= 0 || !o.valid[row]) continue;
    for (let e = 0; e < 9; ++e) fiv[e] += w * o.fiv[9 * row + e];
    for (let e = 0; e < 3; ++e) power[e] += w * o.power[3 * row + e];
    total += w;
  }
  return total;
}
export function fivLookup(o, offset) {
  const scale = gridLookup(o, offset, (count) => gatherGrid(o, count));
  if (scale < 0) return null;
  for (let e = 0; e < 9; ++e) scratch.fiv[e] *= scale;
  for (let e = 0; e < 3; ++e) scratch.power[e] *= scale;
  return scratch;
}

// The source grid's hidden fraction f in 0..1 at offset (fivSourceLookup), or null when no usable sample exists.
export function fivSourceLookup(g, offset) {
  let sum = 0;
  const scale = gridLookup(g, offset, (count) => {
    const { rows, weights } = scratch;
    let total = 0;
    sum = 0;
    for (let c = 0; c < count; ++c) {
      if (weights[c] <= 0 || !g.valid[rows[c]]) continue;
      sum += weights[c] * g.fraction[rows[c]];
      total += weights[c];
    }
    return total;
  });
  return scale < 0 ? null : Math.min(Math.max(sum * scale, 0), 1);
}

// The sharpened fraction g = clamp(0.5 + K (f - 0.5), 0, 1) (sharpened); 1 (all hidden) without a usable sample,
// as the runtime.
export function sourceHidden(g, offset) {
  const f = fivSourceLookup(g, offset);
  return f === null ? 1 : Math.min(Math.max(0.5 + g.sharpen * (f - 0.5), 0), 1);
}

// sh::capCosineIntegral (clippedCapIrradiance): integral of max(0, n . w) over a cap at cosine cosTheta from n.
export function capCosineIntegral(cosTheta, sinSigmaSquared) {
  cosTheta = Math.min(1, Math.max(-1, cosTheta));
  sinSigmaSquared = Math.min(1, Math.max(0, sinSigmaSquared));
  if (cosTheta * cosTheta >= sinSigmaSquared) return Math.PI * sinSigmaSquared * Math.max(0, cosTheta);
  const sinTheta = Math.sqrt(1 - cosTheta * cosTheta), x = Math.sqrt(Math.max(1 / sinSigmaSquared - 1, 0));
  const y = Math.min(1, Math.max(-1, -x * cosTheta / sinTheta)), s = sinTheta * Math.sqrt(Math.max(0, 1 - y * y));
  return Math.max(0, (cosTheta * Math.acos(y) - x * s) * sinSigmaSquared + (x > 0 ? Math.atan(s / x) : Math.PI / 2));
}

function discOverlap(r1, r2, s) {
  if (s >= r1 + r2) return 0;
  if (s <= Math.abs(r1 - r2)) return Math.PI * Math.min(r1, r2) ** 2;
  const a = Math.min(1, Math.max(-1, (s * s + r1 * r1 - r2 * r2) / (2 * s * r1)));
  const b = Math.min(1, Math.max(-1, (s * s + r2 * r2 - r1 * r1) / (2 * s * r2)));
  const k = (-s + r1 + r2) * (s + r1 - r2) * (s - r1 + r2) * (s + r1 + r2);
  return r1 * r1 * Math.acos(a) + r2 * r2 * Math.acos(b) - 0.5 * Math.sqrt(Math.max(0, k));
}

const angleBetween = (a, b) => 2 * Math.asin(Math.min(1, 0.5 * Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2])));

// The hidden irradiance of one occluder (occludedIrradiance with partial "cap").
function occluded(n, fiv, power, d, radius) {
  return [0, 1, 2].map((c) => {
    const raw = dot(n, fiv, 0, 3 * c);
    if (d >= radius) return Math.max(0, raw);
    const length = Math.sqrt(dot(fiv, fiv, 3 * c, 3 * c));
    if (!(length > 0) || !(power[c] > 0)) return 0;
    const cosSigma = Math.min(Math.max(2 * length / power[c] - 1, 0), 1 - 1e-7);
    const radiance = power[c] / (2 * Math.PI * (1 - cosSigma));
    return Math.max(0, radiance * capCosineIntegral(raw / length, 1 - cosSigma * cosSigma));
  });
}

// Irradiance [count][3] at the receiver's vertices (fivIrradiance, partial "cap", overlap "cap"): `instances`
// [{grid, translation}], `self` a grid or null (its selfIrradiance, when it has one, is the receiver's E_self:
// positions must be the receiver's own vertices). A grid's source grid hides (1 - prod_j (1 - g_j)) of the
// largest max(0, N . FIV_sources) over the instances' types, on top of the overlap-corrected sum.
export function fivIrradiance(lighting, instances, self, positions, normals) {
  const count = positions.length / 3, out = new Float64Array(count * 3);
  for (let v = 0; v < count; ++v) {
    const p = positions.subarray(3 * v, 3 * v + 3), n = normals.subarray(3 * v, 3 * v + 3);
    const total = fivDifmap(lighting, n);
    let unoccluded = total.slice();
    if (self && self.selfIrradiance) {
      unoccluded = Array.from(self.selfIrradiance.subarray(3 * v, 3 * v + 3)); // E_self, exact at the vertex
    } else if (self) {
      const offset = [self.centre[0] - p[0], self.centre[1] - p[1], self.centre[2] - p[2]];
      const hit = fivLookup(self, offset);
      if (hit) {
        unoccluded = [0, 1, 2].map((c) => dot(n, lighting.fivEnv, 0, 3 * c) - dot(n, hit.fiv, 0, 3 * c));
        // The grid holds the rest of the map: its sources come back signed, as FIV_self held them.
        if (self.sources) {
          const g = sourceHidden(self.sources, offset);
          for (let c = 0; c < 3; ++c) unoccluded[c] -= g * dot(n, self.sources.fiv, 0, 3 * c);
        }
      }
    }
    let visible = 1;
    const sourceIrradiance = [0, 0, 0]; // the sources' term: the largest max(0, N . FIV_sources) over the types
    const hidden = [];
    for (const { grid: o, translation } of instances) {
      const offset = [0, 1, 2].map((c) => o.centre[c] + translation[c] - p[c]);
      const d = dot(n, offset);
      if (d <= -o.radius) continue; // case C
      if (o.sources) { // rays decided it: no partial correction
        visible *= 1 - sourceHidden(o.sources, offset);
        for (let c = 0; c < 3; ++c) sourceIrradiance[c] = Math.max(sourceIrradiance[c], dot(n, o.sources.fiv, 0, 3 * c));
      }
      const hit = fivLookup(o, offset);
      const value = hit ? occluded(n, hit.fiv, hit.power, d, o.radius) : total.slice(); // inside: all of it
      if (value.every((x) => x <= 0)) continue;
      const distance = Math.hypot(...offset);
      let direction = offset.map((x) => (distance > 0 ? x / distance : 0));
      let angularRadius = distance > o.radius ? Math.asin(o.radius / distance) : Math.PI / 2;
      const fiv = hit ? Array.from(hit.fiv) : null, power = hit ? Array.from(hit.power) : null;
      const green = fiv ? Math.sqrt(dot(fiv, fiv, 3, 3)) : 0;
      if (green > 0 && power[1] > 0) {
        const cosSigma = Math.min(Math.max(2 * green / power[1] - 1, 0), 1);
        angularRadius = Math.max(Math.acos(cosSigma), 1e-4);
        direction = [fiv[3] / green, fiv[4] / green, fiv[5] / green];
      }
      hidden.push({ value, direction, angularRadius, disc: Math.PI * angularRadius * angularRadius });
    }
    const hiddenTotal = [0, 0, 0], largest = [0, 0, 0];
    for (const h of hidden) for (let c = 0; c < 3; ++c) hiddenTotal[c] += h.value[c], largest[c] = Math.max(largest[c], h.value[c]);
    for (let a = 0; a < hidden.length; ++a)
      for (let b = a + 1; b < hidden.length; ++b) {
        const [ha, hb] = [hidden[a], hidden[b]];
        const cosine = Math.min(1, Math.max(-1, dot(ha.direction, hb.direction)));
        const reach = ha.angularRadius + hb.angularRadius;
        if (reach < Math.PI && cosine <= Math.cos(reach)) continue;
        const share = discOverlap(ha.angularRadius, hb.angularRadius, angleBetween(ha.direction, hb.direction)) / (ha.disc + hb.disc);
        for (let c = 0; c < 3; ++c) hiddenTotal[c] -= share * (ha.value[c] + hb.value[c]);
      }
    for (let c = 0; c < 3; ++c)
      out[3 * v + c] = Math.min(Math.max(unoccluded[c] - (Math.max(hiddenTotal[c], largest[c]) + (1 - visible) * sourceIrradiance[c]), 0),
                                Math.max(total[c], 0));
  }
  return out;
}
