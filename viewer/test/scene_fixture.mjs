// A small textured glTF scene written from code, so the scene-bundle test needs no download: a checkered floor
// (bilinear texture through KHR_texture_transform, repeat wrap), one box mesh placed by two nodes under a turned
// root (one instance mirrored), with COLOR_0, a base colour factor and metallic 0.25, a cut-out fence (alphaMode
// MASK, nearest texels whose alpha is 0 or 1) and, in the fence's mesh, a second primitive without material.
// Images are PNG data URIs.
import fs from 'node:fs';
import zlib from 'node:zlib';

const crcTable = Array.from({ length: 256 }, (_, n) => {
  let c = n;
  for (let k = 0; k < 8; ++k) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
  return c >>> 0;
});
function crc32(bytes) {
  let c = 0xffffffff;
  for (const b of bytes) c = crcTable[(c ^ b) & 0xff] ^ (c >>> 8);
  return (c ^ 0xffffffff) >>> 0;
}

// An 8-bit RGBA PNG of `width` x `height` from `rgba` (row 0 at the top), as a Buffer.
export function encodePng(width, height, rgba) {
  const chunk = (type, data) => {
    const body = Buffer.concat([Buffer.from(type, 'ascii'), data]);
    const out = Buffer.alloc(body.length + 8);
    out.writeUInt32BE(data.length, 0);
    body.copy(out, 4);
    out.writeUInt32BE(crc32(body), body.length + 4);
    return out;
  };
  const header = Buffer.alloc(13);
  header.writeUInt32BE(width, 0);
  header.writeUInt32BE(height, 4);
  header.set([8, 6, 0, 0, 0], 8); // 8 bits, RGBA, deflate, no filter, no interlace
  const raw = Buffer.alloc(height * (width * 4 + 1));
  for (let y = 0; y < height; ++y) Buffer.from(rgba.subarray(y * width * 4, (y + 1) * width * 4)).copy(raw, y * (width * 4 + 1) + 1);
  return Buffer.concat([Buffer.from([137, 80, 78, 71, 13, 10, 26, 10]), chunk('IHDR', header),
                        chunk('IDAT', zlib.deflateSync(raw)), chunk('IEND', Buffer.alloc(0))]);
}

// A grid of (cells+1)^2 vertices over the unit square mapped by `place(s, t)` -> [x, y, z]; uv = (s, t) * uvScale.
function grid(cells, place, uvScale) {
  const positions = [], uvs = [], indices = [];
  for (let j = 0; j <= cells; ++j)
    for (let i = 0; i <= cells; ++i) {
      positions.push(...place(i / cells, j / cells));
      uvs.push(uvScale * i / cells, uvScale * j / cells);
    }
  for (let j = 0; j < cells; ++j)
    for (let i = 0; i < cells; ++i) {
      const a = j * (cells + 1) + i, b = a + 1, c = a + cells + 1, d = c + 1;
      indices.push(a, c, b, b, c, d);
    }
  return { positions, uvs, indices };
}

// Writes the scene as a self-contained .gltf at `file`.
export function writeTexturedScene(file) {
  const buffers = [];
  let byteLength = 0;
  const bufferViews = [], accessors = [];
  const addAccessor = (values, type, componentType, target, extra = {}) => {
    const array = componentType === 5126 ? new Float32Array(values) : new Uint32Array(values);
    const bytes = Buffer.from(array.buffer);
    bufferViews.push({ buffer: 0, byteOffset: byteLength, byteLength: bytes.length, target });
    buffers.push(bytes);
    byteLength += bytes.length;
    const width = { SCALAR: 1, VEC2: 2, VEC3: 3, VEC4: 4 }[type];
    const accessor = { bufferView: bufferViews.length - 1, componentType, count: array.length / width, type, ...extra };
    if (type === 'VEC3' && componentType === 5126 && extra.position) {
      delete accessor.position;
      accessor.min = [0, 1, 2].map((c) => Math.min(...values.filter((_, k) => k % 3 === c)));
      accessor.max = [0, 1, 2].map((c) => Math.max(...values.filter((_, k) => k % 3 === c)));
    }
    accessors.push(accessor);
    return accessors.length - 1;
  };
  const primitive = (mesh, material, color) => {
    const p = {
      attributes: { POSITION: addAccessor(mesh.positions, 'VEC3', 5126, 34962, { position: true }),
                    TEXCOORD_0: addAccessor(mesh.uvs, 'VEC2', 5126, 34962) },
      indices: addAccessor(mesh.indices, 'SCALAR', 5125, 34963),
    };
    if (color) p.attributes.COLOR_0 = addAccessor(color, 'VEC4', 5126, 34962);
    if (material !== undefined) p.material = material;
    return p;
  };

  // Floor: y = 0, x and z in [-1, 1], front +Y; uv 0..2 over it.
  const floor = grid(8, (s, t) => [2 * s - 1, 0, 2 * t - 1], 2);
  // Box: a unit cube of 24 vertices (a face per 4), fronts outward, a grey level per face in COLOR_0.
  const box = { positions: [], uvs: [], indices: [] }, boxColors = [];
  const faces = [[[1, 0, 0], [0, 0, -1], [0, 1, 0]], [[-1, 0, 0], [0, 0, 1], [0, 1, 0]], [[0, 1, 0], [1, 0, 0], [0, 0, -1]],
                 [[0, -1, 0], [1, 0, 0], [0, 0, 1]], [[0, 0, 1], [1, 0, 0], [0, 1, 0]], [[0, 0, -1], [-1, 0, 0], [0, 1, 0]]];
  faces.forEach(([n, u, v], f) => {
    for (const [a, b] of [[-1, -1], [1, -1], [1, 1], [-1, 1]]) {
      box.positions.push(...[0, 1, 2].map((c) => 0.5 * (n[c] + a * u[c] + b * v[c])));
      box.uvs.push((a + 1) / 2, (1 - b) / 2);
      const grey = 0.55 + 0.09 * f;
      boxColors.push(grey, 1.0 - 0.05 * f, grey, 1);
    }
    box.indices.push(4 * f, 4 * f + 1, 4 * f + 2, 4 * f, 4 * f + 2, 4 * f + 3);
  });
  // Fence: z = -0.55, x in [-0.8, 0.8], y in [0, 0.9], front +Z; a small plain quad beside it, front +Z.
  const fence = grid(6, (s, t) => [-0.8 + 1.6 * s, 0.9 * (1 - t), -0.55], 1);
  const plain = grid(2, (s, t) => [0.55 + 0.3 * s, 0.75 - 0.3 * t, -0.5], 1);
  // grid() winds each cell (s, t), (s, t + 1), (s + 1, t): fronts face +Y on the floor and +Z on the fence.

  const meshes = [
    { name: 'floor', primitives: [primitive(floor, 0)] },
    { name: 'box', primitives: [primitive(box, 1, boxColors)] },
    { name: 'fence', primitives: [primitive(fence, 2), primitive(plain, undefined)] },
  ];

  // Textures: a 4 x 4 checker (cream and blue), and an 8 x 8 fence of green slats with holes (alpha 0).
  const checker = new Uint8Array(4 * 4 * 4), slats = new Uint8Array(8 * 8 * 4);
  for (let y = 0; y < 4; ++y)
    for (let x = 0; x < 4; ++x)
      checker.set((x + y) % 2 ? [60, 90, 200, 255] : [235, 220, 170, 255], (y * 4 + x) * 4);
  for (let y = 0; y < 8; ++y)
    for (let x = 0; x < 8; ++x)
      slats.set([40 + 20 * y, 170, 60, (x % 3 === 2 || y === 3) ? 0 : 255], (y * 8 + x) * 4);
  const dataUri = (png) => 'data:image/png;base64,' + png.toString('base64');
  const gltf = {
    asset: { version: '2.0', generator: 'prt viewer test scene_fixture.mjs' },
    extensionsUsed: ['KHR_texture_transform'],
    scene: 0,
    scenes: [{ nodes: [0, 4] }],
    nodes: [
      { name: 'root', rotation: [0, Math.sin(0.1), 0, Math.cos(0.1)], children: [1, 2, 3] },
      { name: 'floor', mesh: 0 },
      { name: 'box left', mesh: 1, translation: [-0.4, 0.25, 0.05], scale: [0.5, 0.5, 0.5] },
      { name: 'box right (mirrored)', mesh: 1, translation: [0.42, 0.2, 0.25],
        rotation: [0, Math.sin(0.3), 0, Math.cos(0.3)], scale: [-0.4, 0.4, 0.4] },
      { name: 'fence', mesh: 2, translation: [0, 0, 0.05] },
    ],
    meshes,
    materials: [
      { name: 'checker', pbrMetallicRoughness: { baseColorFactor: [0.95, 0.95, 0.9, 1], metallicFactor: 0,
        baseColorTexture: { index: 0, extensions: { KHR_texture_transform: { offset: [0.125, 0], scale: [1.5, 1.5], rotation: 0.2 } } } } },
      { name: 'box', pbrMetallicRoughness: { baseColorFactor: [0.9, 0.55, 0.35, 1], metallicFactor: 0.25 } },
      { name: 'fence', alphaMode: 'MASK', alphaCutoff: 0.5, doubleSided: true,
        pbrMetallicRoughness: { baseColorTexture: { index: 1 }, metallicFactor: 0 } },
    ],
    textures: [{ sampler: 0, source: 0 }, { sampler: 1, source: 1 }],
    samplers: [{ magFilter: 9729, minFilter: 9729, wrapS: 10497, wrapT: 10497 },
               { magFilter: 9728, minFilter: 9728, wrapS: 33071, wrapT: 33071 }],
    images: [{ uri: dataUri(encodePng(4, 4, checker)) }, { uri: dataUri(encodePng(8, 8, slats)) }],
    accessors,
    bufferViews,
    buffers: [{ byteLength, uri: 'data:application/octet-stream;base64,' + Buffer.concat(buffers).toString('base64') }],
  };
  fs.writeFileSync(file, JSON.stringify(gltf, null, 1));
}

if (process.argv[1] && import.meta.url.endsWith(process.argv[1].split('/').pop()) && process.argv[2])
  writeTexturedScene(process.argv[2]);
