// Reads a prt bundle (.glb with the PRT_bundle extension, docs/bundle.md) without any glTF library: the mesh
// attributes and the layers are plain views into the one binary buffer.

import { halfToFloat, readExr } from './exr.js';

const kComponentSize = { 5126: 4, 5125: 4, 5123: 2, 5121: 1 };
const kTypeSize = { SCALAR: 1, VEC2: 2, VEC3: 3, VEC4: 4 };

// Splits a GLB into its JSON and BIN chunk. Throws Error for anything that is not a glTF 2 binary.
export function parseGlb(arrayBuffer) {
  const view = new DataView(arrayBuffer);
  if (view.getUint32(0, true) !== 0x46546c67 || view.getUint32(4, true) !== 2) throw new Error('not a glTF 2 binary');
  const jsonLength = view.getUint32(12, true);
  if (view.getUint32(16, true) !== 0x4e4f534a) throw new Error('first chunk is not JSON');
  const json = JSON.parse(new TextDecoder().decode(new Uint8Array(arrayBuffer, 20, jsonLength)));
  const binStart = 20 + jsonLength;
  const binLength = view.getUint32(binStart, true);
  if (view.getUint32(binStart + 4, true) !== 0x004e4942) throw new Error('second chunk is not BIN');
  return { json, bin: arrayBuffer.slice(binStart + 8, binStart + 8 + binLength) };
}

function accessorArray(gltf, bin, index) {
  const accessor = gltf.accessors[index];
  const bufferView = gltf.bufferViews[accessor.bufferView];
  const offset = (bufferView.byteOffset || 0) + (accessor.byteOffset || 0);
  const count = accessor.count * kTypeSize[accessor.type];
  if (bufferView.byteStride && bufferView.byteStride !== kComponentSize[accessor.componentType] * kTypeSize[accessor.type])
    throw new Error('interleaved accessors are not supported');
  switch (accessor.componentType) {
    case 5126: return new Float32Array(bin.slice(offset, offset + count * 4));
    case 5125: return new Uint32Array(bin.slice(offset, offset + count * 4));
    case 5123: return Uint32Array.from(new Uint16Array(bin.slice(offset, offset + count * 2)));
    case 5121: return Uint32Array.from(new Uint8Array(bin.slice(offset, offset + count)));
    default: throw new Error(`accessor ${index}: component type ${accessor.componentType}`);
  }
}

// A layer's values as a Float32Array (float32 or float16 layers).
export function layerData(gltf, bin, layer) {
  if (layer.bufferView === undefined) return null;
  const bufferView = gltf.bufferViews[layer.bufferView];
  const offset = bufferView.byteOffset || 0;
  const count = layer.shape.reduce((p, n) => p * n, 1);
  const type = layer.componentType || 'float32';
  if (type === 'float32') return new Float32Array(bin.slice(offset, offset + count * 4));
  if (type === 'float16') {
    const halves = new Uint16Array(bin.slice(offset, offset + count * 2));
    const out = new Float32Array(count);
    for (let i = 0; i < count; ++i) out[i] = halfToFloat(halves[i]);
    return out;
  }
  throw new Error(`layer ${layer.name}: component type ${type} is not a float`);
}

// Whether the bundle's extension describes a scene bundle (version 3, docs/bundle.md "Scene bundles"): the glTF
// asset kept intact, with the receivers' rows listed in `scene.receivers`.
export function isSceneBundle(json) {
  const extension = json.extensions && json.extensions.PRT_bundle;
  return !!(extension && extension.scene && Array.isArray(extension.scene.receivers));
}

// A scene bundle's irradiance transfer (layer "transfer", params.albedo "excluded") and its receivers, each
// {node, mesh, primitive, first_row, rows} as the extension lists them, checked against the layer's row count.
// Returns {transfer: {rows, order, data}, receivers}. Throws Error naming the problem.
export function readSceneTransfer(json, bin) {
  const extension = json.extensions.PRT_bundle;
  const layer = (extension.layers || []).find((l) => l.name === 'transfer');
  if (!layer || layer.semantic !== 'sh_transfer_rgb' || layer.domain !== 'vertex')
    throw new Error('scene bundle: no per-vertex "transfer" layer of semantic sh_transfer_rgb');
  if (!layer.params || layer.params.albedo !== 'excluded')
    throw new Error('scene bundle: layer "transfer" must be irradiance transfer (params.albedo "excluded")');
  const data = layerData(json, bin, layer);
  if (!data) throw new Error('scene bundle: layer "transfer" has no data in the bundle');
  const rows = layer.shape[0], order = Math.round(Math.sqrt(layer.shape[1]));
  if (order * order !== layer.shape[1] || layer.shape[2] !== 3) throw new Error('scene bundle: transfer shape is not [rows, L^2, 3]');
  const receivers = extension.scene.receivers;
  let next = 0;
  for (const [k, r] of receivers.entries()) {
    for (const key of ['node', 'mesh', 'primitive', 'first_row', 'rows'])
      if (!Number.isInteger(r[key]) || r[key] < 0) throw new Error(`scene bundle: receiver ${k} has no valid ${key}`);
    if (r.first_row !== next) throw new Error(`scene bundle: receiver ${k} starts at row ${r.first_row}, expected ${next}`);
    next += r.rows;
  }
  if (next !== rows) throw new Error(`scene bundle: receivers cover ${next} rows, the transfer has ${rows}`);
  return { transfer: { rows, order, data }, receivers };
}

// The bundle's mesh (object 0) and its transfer: `kind` "vertex" (layer "transfer") or "texel" (layer
// "texel_transfer"). Returns {positions, normals, texcoords, indices, transfer: {rows, order, data, uri, width,
// height}, extension}; data is null when the texels live in the OpenEXR file `uri` (loadBundle reads it).
export function readBundle(arrayBuffer, kind = 'vertex') {
  const { json, bin } = parseGlb(arrayBuffer);
  const extension = json.extensions && json.extensions.PRT_bundle;
  if (!extension) throw new Error('no PRT_bundle extension: not a prt bundle');
  const primitive = json.meshes[0].primitives[0];
  const mesh = {
    positions: accessorArray(json, bin, primitive.attributes.POSITION),
    normals: primitive.attributes.NORMAL !== undefined ? accessorArray(json, bin, primitive.attributes.NORMAL) : null,
    texcoords: primitive.attributes.TEXCOORD_0 !== undefined ? accessorArray(json, bin, primitive.attributes.TEXCOORD_0) : null,
    indices: accessorArray(json, bin, primitive.indices),
    extension,
  };
  const name = kind === 'texel' ? 'texel_transfer' : 'transfer';
  const layer = (extension.layers || []).find((l) => l.name === name && (l.object || 0) === 0);
  if (!layer || layer.semantic !== 'sh_transfer_rgb') throw new Error(`no "${name}" layer of semantic sh_transfer_rgb`);
  const data = layerData(json, bin, layer);
  const params = layer.params || {};
  if (!data && !(params.uri && (params.format === 'half' || params.format === 'float')))
    throw new Error(`layer "${name}" keeps its texels in ${params.uri} as ${params.format}: the viewer reads ` +
                    'OpenEXR texels (bake --format half or float) and texels in the bundle (--format bundle)');
  const order = Math.round(Math.sqrt(layer.shape[1]));
  mesh.transfer = { rows: layer.shape[0], order, data, uri: data ? null : params.uri, width: params.width,
                    height: params.height };
  return mesh;
}

// Fetches the bundle at `url` and, for texels kept in an OpenEXR file next to it, that file too. Returns what
// readBundle returns, with transfer.data filled in ([rows][L^2][3] from channels T000.R .. as the bake names them).
// `bytes`, when given, are the bundle's bytes already fetched.
export async function loadBundle(url, kind = 'vertex', bytes = null) {
  const fetchBytes = async (what) => {
    const response = await fetch(what);
    if (!response.ok) throw new Error(`${what}: HTTP ${response.status}`);
    return response.arrayBuffer();
  };
  const mesh = readBundle(bytes || await fetchBytes(url), kind);
  const t = mesh.transfer;
  if (t.data) return mesh;
  const imageUrl = new URL(t.uri, new URL(url, location.href)).href;
  const image = await readExr(await fetchBytes(imageUrl), t.uri);
  if (image.width !== t.width || image.height !== t.height || image.width * image.height !== t.rows)
    throw new Error(`${t.uri}: ${image.width} x ${image.height} texels, but the bundle says ${t.width} x ${t.height}`);
  const C = t.order * t.order;
  t.data = new Float32Array(t.rows * C * 3);
  for (let j = 0; j < C; ++j)
    for (let c = 0; c < 3; ++c) {
      const name = `T${String(j).padStart(3, '0')}.${'RGB'[c]}`, channel = image.channels[name];
      if (!channel) throw new Error(`${t.uri}: no channel ${name}`);
      for (let r = 0; r < t.rows; ++r) t.data[(r * C + j) * 3 + c] = channel[r];
    }
  return mesh;
}

// A stand-in bundle for frame-time figures: a UV sphere of about `vertexCount` vertices with the unshadowed
// diffuse transfer of white albedo at `order` bands, T[v][j] = A_l Y_j(n) / pi (a closed form, docs/bundle.md).
export async function syntheticBundle(vertexCount, order) {
  const { evaluate } = await import('./sh.js');
  const rings = Math.max(2, Math.round(Math.sqrt(vertexCount / 2))), segments = Math.max(3, Math.round(vertexCount / rings));
  const rows = (rings + 1) * (segments + 1), C = order * order;
  const positions = new Float32Array(rows * 3), data = new Float32Array(rows * C * 3);
  const clampedCosine = (l) => {
    if (l === 0) return Math.PI;
    if (l === 1) return 2 * Math.PI / 3;
    if (l % 2) return 0;
    let binomial = 1;
    for (let k = 0; k < l; k += 2) binomial *= (k + 1) / (k + 2);
    return 2 * Math.PI * (((l / 2 - 1) % 2) ? -1 : 1) / ((l + 2) * (l - 1)) * binomial;
  };
  const band = Float64Array.from({ length: C }, (_, j) => clampedCosine(Math.floor(Math.sqrt(j))) / Math.PI);
  const basis = new Float64Array(C);
  for (let i = 0, v = 0; i <= rings; ++i)
    for (let k = 0; k <= segments; ++k, ++v) {
      const theta = Math.PI * i / rings, phi = 2 * Math.PI * k / segments;
      const n = [Math.sin(theta) * Math.sin(phi), Math.cos(theta), Math.sin(theta) * Math.cos(phi)];
      positions.set(n.map((x) => 0.5 * x), v * 3);
      evaluate(order, n[0], n[1], n[2], basis);
      for (let j = 0; j < C; ++j) data.fill(band[j] * basis[j], (v * C + j) * 3, (v * C + j) * 3 + 3);
    }
  const indices = new Uint32Array(rings * segments * 6);
  for (let i = 0, t = 0; i < rings; ++i)
    for (let k = 0; k < segments; ++k) {
      const a = i * (segments + 1) + k, b = a + segments + 1;
      indices.set([a, b, a + 1, a + 1, b, b + 1], t);
      t += 6;
    }
  return { positions, normals: null, texcoords: null, indices, extension: {}, transfer: { rows, order, data } };
}
