// Glossy bundles (`prt glossy`, docs/glossy.md) in the viewer: the diffuse SH transfer per vertex (Gouraud, as every
// relit bundle) plus the spherical-Gaussian lobes evaluated PER PIXEL toward the pixel's own view direction, as
// `prt render` does (lib/render renderGlossyRadiance, glossyRadianceToward in lib/runtime/prt/glossy.h):
//   d = the unit direction from the pixel's surface point to the eye; the view triangle around d and its weights
//   (viewWeights); per triangle corner v with d above its tangent plane, each of the 3 views' lobes turned onto d's
//   mirror direction about n_v (turnViewLobes), looked up in the prefiltered stack (lookupLobe: bilinear at the mean
//   in the two levels around lambda, geometric between them, times a 2 pi / lambda (1 - exp(-2 lambda))), the views
//   blended with the view weights, the corners with the pixel's barycentrics.
// The stack is the very one prt render looks its lobes up in: `prt render B.glb --env E.exr ... --glossy-stack S`
// writes it (lib/render/glossy_stack.cpp, "prt-sg-stack"). The mesh is drawn without an index buffer (corner c of
// triangle c / 3, gl_VertexID), so every fragment knows its triangle's three vertices and its barycentrics.
import * as THREE from 'three';
import { rgbFloatNearest } from './textures.js';
import { layerData, parseGlb } from './bundle.js';
import { relightRowGlsl, toneMapGlsl } from './glsl.js';

export const kMaxStackLevels = 32;
const kTextureWidth = 4096; // every data texture: item i at (i % width, i / width)
const kMaxTextureRows = 8192; // what the viewer asks of a float texture's height (SwiftShader's limit; WebGL2 guarantees 2048)
const kMaxViewUniforms = 600; // views + view triangles held as fragment uniforms (WebGL2 guarantees 224 vectors; ANGLE has 1024+)

// Parses a prt-sg-stack file (writeSharpnessStack). Returns {levelsPerOctave, first, levels: [{width, height,
// sharpness, rgb}]}. Throws Error naming `url` and the problem.
export function parseStack(arrayBuffer, url) {
  const view = new DataView(arrayBuffer), fail = (what) => { throw new Error(`${url}: ${what}`); };
  if (arrayBuffer.byteLength < 24 || new TextDecoder().decode(new Uint8Array(arrayBuffer, 0, 8)) !== 'PRTSGSTK')
    fail('not a prt-sg-stack file (prt render --glossy-stack writes one)');
  const u32 = (at) => view.getUint32(at, true);
  if (u32(8) !== 1) fail(`version ${u32(8)}, the viewer reads 1`);
  const levelsPerOctave = u32(12), first = u32(16), count = u32(20);
  if (levelsPerOctave < 1 || levelsPerOctave > 8 || count < 2 || count > kMaxStackLevels) fail('header out of range');
  const levels = [];
  let at = 24;
  for (let l = 0; l < count; ++l) {
    if (at + 16 > arrayBuffer.byteLength) fail(`level ${l}: truncated`);
    const width = u32(at), height = u32(at + 4), sharpness = view.getFloat64(at + 8, true);
    if (width !== 2 * height || height < 1 || width > kTextureWidth || !(sharpness > 0)) fail(`level ${l}: ${width} x ${height}`);
    const bytes = width * height * 12;
    if (at + 16 + bytes > arrayBuffer.byteLength) fail(`level ${l}: truncated`);
    levels.push({ width, height, sharpness, rgb: new Float32Array(arrayBuffer.slice(at + 16, at + 16 + bytes)) });
    at += 16 + bytes;
  }
  if (at !== arrayBuffer.byteLength) fail('trailing bytes');
  return { levelsPerOctave, first, levels };
}

// The glossy lobes of a bundle: {vertexCount, lobes, viewCount, views [viewCount][3], triangles [T][3], values
// [V][views][N][5], normals [V][3]}. Checks what glossyModel checks of the shape. Throws Error otherwise.
export function readGlossyLobes(bytes) {
  const { json, bin } = parseGlb(bytes);
  const layer = (json.extensions.PRT_bundle.layers || []).find((l) => l.name === 'glossy_lobes');
  if (!layer) throw new Error('glossy: the bundle has no "glossy_lobes" layer (prt glossy writes one)');
  if (layer.semantic !== 'sg_lobes' || layer.domain !== 'vertex' || layer.shape.length !== 4 || layer.shape[3] !== 5 ||
      layer.shape[2] < 1 || layer.shape[2] > 4)
    throw new Error('glossy: layer glossy_lobes must be per-vertex sg_lobes of shape [V, views, N (1..4), 5]');
  const params = layer.params || {};
  const views = params.views, triangles = params.view_triangles;
  if (!Array.isArray(views) || views.length !== layer.shape[1] || !Array.isArray(triangles) || !triangles.length)
    throw new Error('glossy: params.views / params.view_triangles disagree with the layer');
  const primitive = json.meshes[0].primitives[0];
  if (primitive.attributes.NORMAL === undefined) throw new Error('glossy: the mesh has no normals');
  const a = json.accessors[primitive.attributes.NORMAL], bv = json.bufferViews[a.bufferView];
  if (a.componentType !== 5126 || a.type !== 'VEC3' || a.count !== layer.shape[0] || (bv.byteStride && bv.byteStride !== 12))
    throw new Error('glossy: the normals are not tightly packed float VEC3 per vertex of the lobes');
  const offset = (bv.byteOffset || 0) + (a.byteOffset || 0);
  return {
    vertexCount: layer.shape[0], viewCount: layer.shape[1], lobes: layer.shape[2],
    views: Float32Array.from(views.flat()), triangles: Uint32Array.from(triangles.flat()),
    values: layerData(json, bin, layer), normals: new Float32Array(bin.slice(offset, offset + a.count * 12)),
  };
}

// A float texture of `items` texels of `channels` floats (1 or 4), item i at (i % 4096, i / 4096).
function dataTexture(items, channels, fill) {
  const rows = Math.max(1, Math.ceil(items / kTextureWidth)), width = Math.min(kTextureWidth, Math.max(1, items));
  if (rows > kMaxTextureRows)
    throw new Error(`glossy: ${items} texels exceed the viewer's ${kTextureWidth} x ${kMaxTextureRows} data textures`);
  const data = new Float32Array(width * rows * channels);
  fill(data);
  const texture = new THREE.DataTexture(data, width, rows);
  texture.format = channels === 4 ? THREE.RGBAFormat : THREE.RedFormat;
  texture.type = THREE.FloatType;
  texture.internalFormat = channels === 4 ? 'RGBA32F' : 'R32F';
  texture.minFilter = texture.magFilter = THREE.NearestFilter;
  texture.generateMipmaps = false;
  texture.needsUpdate = true;
  return texture;
}

// The stack's levels packed left to right on shelves of a kTextureWidth-wide RGB32F atlas (levels ascend in size):
// {texture, rects [[x, y, width, height]] per level, count, first, levelsPerOctave}, for setStack.
export function stackAtlas(stack) {
  const rects = [];
  let x = 0, y = 0, shelf = 0;
  for (const level of stack.levels) {
    if (x + level.width > kTextureWidth || level.height !== shelf) { y += shelf; x = 0; shelf = level.height; }
    rects.push([x, y, level.width, level.height]);
    x += level.width;
  }
  const height = y + shelf, width = Math.max(...rects.map((r) => r[0] + r[2]));
  if (height > kMaxTextureRows) throw new Error(`glossy: the stack's atlas would be ${height} texels high (at most ${kMaxTextureRows})`);
  const data = new Float32Array(width * height * 3);
  stack.levels.forEach((level, l) => {
    const [x0, y0, w, h] = rects[l];
    for (let row = 0; row < h; ++row) data.set(level.rgb.subarray(row * w * 3, (row + 1) * w * 3), ((y0 + row) * width + x0) * 3);
  });
  const texture = new THREE.DataTexture(data, width, height);
  rgbFloatNearest(texture);
  return { texture, rects, count: stack.levels.length, first: stack.first, levelsPerOctave: stack.levelsPerOctave };
}

// Points the shader at `atlas` (stackAtlas's result): the stack of the map now shown.
export function setStack(uniforms, atlas) {
  uniforms.stackAtlas.value = atlas.texture;
  uniforms.stackCount.value = atlas.count;
  uniforms.stackFirst.value = atlas.first;
  uniforms.stackPerOctave.value = atlas.levelsPerOctave;
  for (let l = 0; l < kMaxStackLevels; ++l) uniforms.stackRect.value[l].set(...(atlas.rects[l] || [0, 0, 1, 1]));
}

// Uniforms and the non-indexed geometry of a glossy mesh. `mesh` {positions, indices} (the bundle's), `lobes` as
// readGlossyLobes (lobes.vertexCount may be smaller than the mesh's for the synthetic frame-time stand-in: vertex v
// then takes lobe row v % lobes.vertexCount, and `normals` its own), `atlas` as stackAtlas (setStack changes it).
export function glossySetup(mesh, lobes, atlas, normals = lobes.normals) {
  const V = mesh.positions.length / 3, T = mesh.indices.length / 3, views = lobes.viewCount, N = lobes.lobes;
  if (views + lobes.triangles.length / 3 > kMaxViewUniforms)
    throw new Error(`glossy: ${views} views and ${lobes.triangles.length / 3} view triangles exceed the viewer's ${kMaxViewUniforms} uniforms`);
  const lobeItems = lobes.vertexCount * views * N;
  const shape = dataTexture(lobeItems, 4, (data) => {
    for (let i = 0; i < lobeItems; ++i) data.set(lobes.values.subarray(i * 5 + 1, i * 5 + 5), i * 4);
  });
  const amplitude = dataTexture(lobeItems, 1, (data) => { for (let i = 0; i < lobeItems; ++i) data[i] = lobes.values[i * 5]; });
  const vec4s = (count, source) => dataTexture(count, 4, (data) => {
    for (let i = 0; i < count; ++i) data.set(source.subarray(i * 3, i * 3 + 3), i * 4);
  });
  // indexViewTriangles: per view its triangles ascending; offsets first (viewCount + 1), then the lists.
  const around = Array.from({ length: views }, () => []);
  for (let t = 0; t < lobes.triangles.length / 3; ++t) for (let k = 0; k < 3; ++k) around[lobes.triangles[t * 3 + k]].push(t);
  const index = [0];
  for (const list of around) index.push(index[index.length - 1] + list.length);
  const viewIndex = Float32Array.from([...index, ...around.flat()]);
  const uniforms = {
    glossyCorners: { value: vec4s(T, Float32Array.from(mesh.indices)) },
    glossyPositions: { value: vec4s(V, mesh.positions) },
    glossyNormals: { value: vec4s(V, normals) },
    lobeShape: { value: shape },
    lobeAmplitude: { value: amplitude },
    lobeRows: { value: lobes.vertexCount },
    lobeCount: { value: N },
    viewCount: { value: views },
    viewTriangleCount: { value: lobes.triangles.length / 3 },
    viewDirections: { value: Array.from({ length: views }, (_, i) => new THREE.Vector3().fromArray(lobes.views, i * 3)) },
    viewTriangles: { value: Array.from({ length: lobes.triangles.length / 3 }, (_, t) => new THREE.Vector3().fromArray(lobes.triangles, t * 3)) },
    viewIndex: { value: dataTexture(viewIndex.length, 1, (data) => data.set(viewIndex)) },
    stackAtlas: { value: null },
    stackCount: { value: 0 },
    stackFirst: { value: 0 },
    stackPerOctave: { value: 1 },
    stackRect: { value: Array.from({ length: kMaxStackLevels }, () => new THREE.Vector4()) },
    mapTurn: { value: new THREE.Matrix3() },
    eye: { value: new THREE.Vector3() },
  };
  setStack(uniforms, atlas);
  const geometry = new THREE.BufferGeometry();
  // Only a count for the draw (3 T corners); the shader reads positions by vertex id from glossyPositions.
  geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(3 * T), 1));
  return { uniforms, geometry, fragmentShader: glossyFragmentShader(views, lobes.triangles.length / 3) };
}

// R^T of sh::rotationY(degrees) (90 degrees takes +Z to +X): the lobe mean in the stored map's frame.
export function setMapTurn(uniforms, degrees) {
  const t = degrees * Math.PI / 180, c = Math.cos(t), s = Math.sin(t);
  uniforms.mapTurn.value.set(c, 0, -s, 0, 1, 0, s, 0, c);
}

const dataGlsl = /* glsl */ `
ivec2 itemAt(int i) { return ivec2(i % ${kTextureWidth}, i / ${kTextureWidth}); }`;

export const glossyVertexShader = (maxCoefficients) => /* glsl */ `
precision highp float;
precision highp int;
precision highp sampler2DArray;
uniform mat4 modelViewMatrix;
uniform mat4 projectionMatrix;
uniform sampler2DArray transfer;
uniform int coefficients;
uniform int rowsPerLine;
uniform vec3 lighting[${maxCoefficients}];
uniform highp sampler2D glossyCorners;
uniform highp sampler2D glossyPositions;
flat out ivec3 vCorners;
out vec3 vBarycentric;
out vec3 vPosition;
out vec3 vRadiance;
${dataGlsl}
${relightRowGlsl(maxCoefficients)}
void main() {
  int triangle = gl_VertexID / 3, k = gl_VertexID - 3 * triangle;
  ivec3 corners = ivec3(texelFetch(glossyCorners, itemAt(triangle), 0).xyz);
  int vertex = corners[k];
  vec3 position = texelFetch(glossyPositions, itemAt(vertex), 0).xyz;
  vCorners = corners;
  vBarycentric = vec3(k == 0, k == 1, k == 2);
  vPosition = position;
  vRadiance = relightRow(vertex);
  gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
}`;

// The fragment shader for a view set of `views` directions and `triangles` view triangles (uniform arrays: cheaper
// than texture fetches for the per-pixel search of the view triangle).
export const glossyFragmentShader = (views, triangles) => /* glsl */ `
precision highp float;
precision highp int;
uniform float exposure;
uniform bool glossyOn;
uniform vec3 eye;
uniform highp sampler2D glossyNormals;
uniform highp sampler2D lobeShape;     // (mu xyz, lambda) of lobe k of vertex v at view j: item (v views + j) N + k
uniform highp sampler2D lobeAmplitude; // a, the same items
uniform int lobeRows;
uniform int lobeCount;
uniform int viewCount;
uniform int viewTriangleCount;
uniform vec3 viewDirections[${views}];
uniform vec3 viewTriangles[${triangles}]; // view indices (exact in float)
uniform highp sampler2D viewIndex;     // per view the first of its triangles (viewCount + 1), then the lists
uniform highp sampler2D stackAtlas;
uniform int stackCount;
uniform int stackFirst;
uniform int stackPerOctave;
uniform vec4 stackRect[${kMaxStackLevels}];
uniform mat3 mapTurn;
flat in ivec3 vCorners;
in vec3 vBarycentric;
in vec3 vPosition;
in vec3 vRadiance;
out vec4 colour;
${toneMapGlsl}
${dataGlsl}
const float pi = 3.14159265358979;
vec3 viewAt(int i) { return viewDirections[i]; }

// triangleWeights: d's weights in view triangle t and their least over their sum (-1e30 on the far side).
float triangleWeights(int t, vec3 d, out ivec3 ids, out vec3 w) {
  ids = ivec3(viewTriangles[t]);
  vec3 a = viewAt(ids.x), b = viewAt(ids.y), c = viewAt(ids.z);
  float det = dot(a, cross(b, c));
  w = vec3(dot(d, cross(b, c)), dot(a, cross(d, c)), dot(a, cross(b, d))) / det;
  float sum = w.x + w.y + w.z;
  if (!(sum > 0.0)) return -1e30;
  return min(w.x, min(w.y, w.z)) / sum;
}

// viewWeights: the triangles around the nearest view first, else every triangle (the best if rounding hides d).
void viewWeights(vec3 d, out ivec3 ids, out vec3 weights) {
  int nearest = 0;
  float bestDot = -2.0;
  for (int v = 0; v < viewCount; ++v) {
    float c = dot(viewAt(v), d);
    if (c > bestDot) { bestDot = c; nearest = v; }
  }
  ids = ivec3(0);
  weights = vec3(1.0, 0.0, 0.0);
  bool found = false;
  int begin = int(texelFetch(viewIndex, itemAt(nearest), 0).r), end = int(texelFetch(viewIndex, itemAt(nearest + 1), 0).r);
  for (int i = begin; i < end; ++i) {
    int t = int(texelFetch(viewIndex, itemAt(viewCount + 1 + i), 0).r);
    ivec3 tri; vec3 w;
    if (triangleWeights(t, d, tri, w) >= 0.0) { ids = tri; weights = max(w, 0.0); found = true; break; }
  }
  float best = -1e30;
  for (int t = 0; !found && t < viewTriangleCount; ++t) {
    ivec3 tri; vec3 w;
    float low = triangleWeights(t, d, tri, w);
    if (low > best) { best = low; ids = tri; weights = max(w, 0.0); if (low >= 0.0) break; }
  }
  weights /= weights.x + weights.y + weights.z;
}

// Bilinear radiance of stack level l at map direction w (unit): across a pole the edge row half a turn round,
// across the seam the columns wrap (glossy_prefilter.cpp bilinear).
vec3 stackTexel(vec4 rect, int y, int x) {
  int W = int(rect.z), H = int(rect.w);
  if (y < 0) { y = -1 - y; x += W / 2; }
  if (y >= H) { y = 2 * H - 1 - y; x += W / 2; }
  x -= W * int(floor(float(x) / float(W)));
  return texelFetch(stackAtlas, ivec2(int(rect.x) + x, int(rect.y) + y), 0).rgb;
}
vec3 stackBilinear(int l, vec3 w) {
  vec4 rect = stackRect[l];
  float theta = acos(clamp(w.y, -1.0, 1.0)), phi = atan(w.x, -w.z);
  float u = (phi + pi) / (2.0 * pi) * rect.z - 0.5, v = theta / pi * rect.w - 0.5;
  float x0 = floor(u), y0 = floor(v), fx = u - x0, fy = v - y0;
  int xi = int(x0), yi = int(y0);
  return (1.0 - fy) * ((1.0 - fx) * stackTexel(rect, yi, xi) + fx * stackTexel(rect, yi, xi + 1)) +
         fy * ((1.0 - fx) * stackTexel(rect, yi + 1, xi) + fx * stackTexel(rect, yi + 1, xi + 1));
}

// lookupLobe: a times the kernel's integral times the kernel-weighted mean radiance, geometric in log lambda.
vec3 lookupLobe(float a, vec3 mu, float sharpness) {
  if (!(a > 0.0)) return vec3(0.0);
  float s = log2(sharpness / 0.5) * float(stackPerOctave) - float(stackFirst);
  int k = min(int(max(0.0, floor(s))), stackCount - 2);
  float t = clamp(s - float(k), 0.0, 1.0);
  vec3 w = mapTurn * mu;
  vec3 below = stackBilinear(k, w), above = stackBilinear(k + 1, w);
  float scale = a * 2.0 * pi / sharpness * (1.0 - exp(-2.0 * sharpness));
  vec3 blend = mix(below, above, t);
  for (int c = 0; c < 3; ++c)
    if (below[c] > 0.0 && above[c] > 0.0) blend[c] = below[c] * exp(t * log(above[c] / below[c]));
  return scale * blend;
}

// glossyRadianceToward for corner vertex v, with the view triangle of d already found.
vec3 cornerGlossy(int vertex, vec3 d, ivec3 views, vec3 weights) {
  vec3 n = texelFetch(glossyNormals, itemAt(vertex), 0).xyz;
  if (dot(d, n) <= 0.0) return vec3(0.0);
  float nn = dot(n, n);
  vec3 mirror = 2.0 * dot(d, n) / nn * n - d;
  int row = vertex % lobeRows;
  vec3 sum = vec3(0.0);
  for (int j = 0; j < 3; ++j) {
    if (!(weights[j] > 0.0)) continue;
    vec3 view = viewAt(views[j]);
    vec3 from = 2.0 * dot(view, n) / nn * n - view;
    vec3 axis = cross(from, mirror);
    float sine = length(axis), cosine = dot(from, mirror);
    bool turn = sine > 1e-9;
    axis = turn ? axis / sine : axis;
    for (int k = 0; k < 4; ++k) {
      if (k >= lobeCount) break;
      int item = (row * viewCount + views[j]) * lobeCount + k;
      vec4 shape = texelFetch(lobeShape, itemAt(item), 0);
      float a = texelFetch(lobeAmplitude, itemAt(item), 0).r;
      vec3 mu = shape.xyz;
      if (turn) mu = mu * cosine + cross(axis, mu) * sine + axis * dot(axis, mu) * (1.0 - cosine);
      sum += weights[j] * lookupLobe(a, mu, shape.w);
    }
  }
  return sum;
}

void main() {
  if (!gl_FrontFacing) { colour = vec4(0.0, 0.0, 0.0, 1.0); return; } // a back face is black, as in prt render
  vec3 radiance = vRadiance;
  vec3 toEye = eye - vPosition;
  if (glossyOn && length(toEye) > 0.0) {
    vec3 d = normalize(toEye);
    ivec3 views; vec3 weights;
    viewWeights(d, views, weights);
    for (int k = 0; k < 3; ++k) radiance += vBarycentric[k] * cornerGlossy(vCorners[k], d, views, weights);
  }
  colour = vec4(toneMap(radiance), 1.0);
}`;
