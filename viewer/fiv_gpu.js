// Moving occluders on the GPU: fiv.js's shading (lib/runtime/fiv_shade.cpp fivIrradiance, partial and overlap
// "cap") as a fragment shader that writes every receiver vertex's irradiance into a float render target, one texel
// per vertex (vertex v at (v % 1024, v / 1024)); the receiver's vertex shader then fetches its texel. In float, as
// the runtime is. Grids, the DifMap and the receiver's points live in RGBA32F textures read by texelFetch. A grid's
// source grid (`prt fiv --sources --source-grid`) lives in a texture of its own, one texel per sample after a short
// header, and shares the main grid's lookup; the receiver's fiv_self rides with its points.
import * as THREE from 'three';

const kWidth = 1024;
export const kMaxGrids = 8, kMaxShells = 16, kMaxInstances = 16, kMaxSourceShells = 64;
const kLoopShells = Math.max(kMaxShells, kMaxSourceShells);
const kSourceHeader = 4; // texels before a source grid's shell radii: sharpen, then N . FIV_sources of r, g, b

// A limit of the GPU shading: fiv_view.js shades such a scene on the CPU (fiv.js) instead, saying why.
function limit(message) {
  const error = new Error(message);
  error.gpuLimit = true;
  return error;
}

function floatTexture(values, texels) {
  const lines = Math.max(1, Math.ceil(texels / kWidth));
  const data = new Float32Array(kWidth * lines * 4);
  data.set(values);
  const texture = new THREE.DataTexture(data, kWidth, lines, THREE.RGBAFormat, THREE.FloatType);
  texture.minFilter = texture.magFilter = THREE.NearestFilter;
  texture.generateMipmaps = false;
  texture.needsUpdate = true;
  return texture;
}

const fragmentShader = /* glsl */ `
precision highp float;
precision highp int;
precision highp sampler2D;
uniform sampler2D grids;    // per grid g from gridBase[g]: row r at 4 r + (fiv r xyz + valid, fiv g, fiv b, power)
uniform sampler2D difmap;   // 6 size^2 texels, cube strip order
uniform sampler2D points;   // vertex v: 3 v position, 3 v + 1 unit normal, 3 v + 2 E_self (fiv_self)
uniform sampler2D sources;  // source grid s from sourceDims[s].x: sharpen, the sources' FIV r, g, b, shell radii, then
                            // row r at base + ${kSourceHeader} + shells + r (fraction, valid)
uniform ivec4 sourceDims[${kMaxGrids}]; // base, azimuth (0: the grid has no source grid), polar, shells
uniform bool selfExact;     // the receiver's E_self replaces its grid's N . FIV(Env) - N . FIV_self
uniform int gridBase[${kMaxGrids}], gridAzimuth[${kMaxGrids}], gridPolar[${kMaxGrids}], gridShells[${kMaxGrids}];
uniform float gridRadius[${kMaxGrids}];
uniform vec3 gridCentre[${kMaxGrids}];
uniform float shellRadii[${kMaxGrids * kMaxShells}];
uniform int instanceCount;
uniform int instanceGrid[${kMaxInstances}];
uniform vec3 instanceTranslation[${kMaxInstances}];
uniform int selfGrid;       // -1: no self-shadowing
uniform int difmapSize;
uniform vec3 fivEnv[3];
uniform int pointCount;
out vec4 irradiance;
const float pi = 3.14159265358979;
vec4 fetch(sampler2D t, int i) { return texelFetch(t, ivec2(i % ${kWidth}, i / ${kWidth}), 0); }

const vec3 faceRight[6] = vec3[6](vec3(0, 0, 1), vec3(0, 0, -1), vec3(1, 0, 0), vec3(1, 0, 0), vec3(-1, 0, 0), vec3(1, 0, 0));
const vec3 faceUp[6] = vec3[6](vec3(0, 1, 0), vec3(0, 1, 0), vec3(0, 0, 1), vec3(0, 0, -1), vec3(0, 1, 0), vec3(0, 1, 0));
vec3 difmapAt(vec3 n) {
  int axis = 0;
  if (abs(n.y) > abs(n[axis])) axis = 1;
  if (abs(n.z) > abs(n[axis])) axis = 2;
  int face = 2 * axis + (n[axis] < 0.0 ? 1 : 0);
  float depth = abs(n[axis]);
  if (!(depth > 0.0)) return vec3(0.0);
  int size = difmapSize;
  float a = dot(faceRight[face], n) / depth, b = dot(faceUp[face], n) / depth;
  float x = clamp((a + 1.0) * 0.5 * float(size) - 0.5, 0.0, float(size - 1));
  float y = clamp((1.0 - b) * 0.5 * float(size) - 0.5, 0.0, float(size - 1));
  int x0 = min(int(x), size - 1), y0 = min(int(y), size - 1), x1 = min(x0 + 1, size - 1), y1 = min(y0 + 1, size - 1);
  float tx = x - float(x0), ty = y - float(y0);
  int base = face * size * size;
  vec3 top = (1.0 - tx) * fetch(difmap, base + y0 * size + x0).rgb + tx * fetch(difmap, base + y0 * size + x1).rgb;
  vec3 bottom = (1.0 - tx) * fetch(difmap, base + y1 * size + x0).rgb + tx * fetch(difmap, base + y1 * size + x1).rgb;
  return (1.0 - ty) * top + ty * bottom;
}

int cornerRow[8];
float cornerWeight[8];
mat3 F;   // columns: the FIV of channel r, g, b
vec3 P;   // power
float fraction; // a source grid's hidden fraction
bool sourceKind; // lookup reads the source grid of slot g, not its main grid
float gatherCorners(int g, int count) {
  float total = 0.0;
  if (sourceKind) {
    fraction = 0.0;
    int rows = sourceDims[g].x + ${kSourceHeader} + sourceDims[g].w;
    for (int c = 0; c < 8; ++c) {
      if (c >= count) break;
      float w = cornerWeight[c];
      vec4 r = fetch(sources, rows + cornerRow[c]);
      if (w <= 0.0 || r.y < 0.5) continue;
      fraction += w * r.x;
      total += w;
    }
    return total;
  }
  F = mat3(0.0);
  P = vec3(0.0);
  for (int c = 0; c < 8; ++c) {
    if (c >= count) break;
    float w = cornerWeight[c];
    int at = gridBase[g] + 4 * cornerRow[c];
    vec4 r = fetch(grids, at);
    if (w <= 0.0 || r.a < 0.5) continue;
    F[0] += w * r.xyz;
    F[1] += w * fetch(grids, at + 1).xyz;
    F[2] += w * fetch(grids, at + 2).xyz;
    P += w * fetch(grids, at + 3).xyz;
    total += w;
  }
  return total;
}
float shellRadius(int g, int k) {
  return sourceKind ? fetch(sources, sourceDims[g].x + ${kSourceHeader} + k).x : shellRadii[g * ${kMaxShells} + k];
}
// The lookup both grids share (gridLookup): fivLookup, F and P at offset = centre - point, or with sourceKind
// fivSourceLookup's unclamped fraction; false when no usable sample exists.
bool lookup(int g, vec3 offset) {
  float len = length(offset);
  vec3 u = len > 0.0 ? offset / len : vec3(0.0, 1.0, 0.0);
  float theta = acos(clamp(u.y, -1.0, 1.0));
  float phi = atan(u.x, -u.z);
  if (phi < 0.0) phi += 2.0 * pi;
  int polar = sourceKind ? sourceDims[g].z : gridPolar[g], azimuth = sourceKind ? sourceDims[g].y : gridAzimuth[g];
  int shells = sourceKind ? sourceDims[g].w : gridShells[g];
  float fj = theta / pi * float(polar - 1);
  int j0 = clamp(int(floor(fj)), 0, polar - 2);
  float tj = clamp(fj - float(j0), 0.0, 1.0);
  float fi = phi / (2.0 * pi) * float(azimuth);
  int i0 = int(floor(fi));
  float ti = clamp(fi - float(i0), 0.0, 1.0);
  i0 = i0 % azimuth;
  int i1 = (i0 + 1) % azimuth;
  int k0 = 0, k1 = 0;
  float tk = 0.0;
  if (len >= shellRadius(g, shells - 1)) { k0 = k1 = shells - 1; }
  else if (len > shellRadius(g, 0)) {
    for (int k = 1; k < ${kLoopShells}; ++k) if (k < shells && shellRadius(g, k) > len) { k1 = k; break; }
    k0 = k1 - 1;
    tk = (len - shellRadius(g, k0)) / (shellRadius(g, k1) - shellRadius(g, k0));
  }
  float r0 = shellRadius(g, 0);
  float inverse2 = len > r0 ? 1.0 / (len * len) : 1.0 / (r0 * r0);
  float a[4] = float[4]((1.0 - ti) * (1.0 - tj), ti * (1.0 - tj), (1.0 - ti) * tj, ti * tj);
  float w0 = (1.0 - tk) * shellRadius(g, k0) * shellRadius(g, k0), w1 = tk * shellRadius(g, k1) * shellRadius(g, k1);
  for (int c = 0; c < 4; ++c) {
    int j = c < 2 ? j0 : j0 + 1, i = c % 2 == 1 ? i1 : i0;
    cornerRow[c] = (k0 * polar + j) * azimuth + i;
    cornerWeight[c] = w0 * a[c];
    cornerRow[4 + c] = (k1 * polar + j) * azimuth + i;
    cornerWeight[4 + c] = w1 * a[c];
  }
  float full = w0 + w1;
  float used = gatherCorners(g, 8);
  if (used <= 1e-6 * full) {
    used = 0.0;
    for (int k = 0; k < ${kLoopShells}; ++k) {
      if (k >= shells || used > 0.0) break;
      if (k <= k1) continue;
      full = shellRadius(g, k) * shellRadius(g, k);
      for (int c = 0; c < 4; ++c) {
        cornerRow[c] = (k * polar + (c < 2 ? j0 : j0 + 1)) * azimuth + (c % 2 == 1 ? i1 : i0);
        cornerWeight[c] = full * a[c];
      }
      used = gatherCorners(g, 4);
    }
    if (used <= 0.0) return false;
  }
  float scale = full / used * inverse2;
  if (sourceKind) {
    fraction *= scale;
    return true;
  }
  F *= scale;
  P *= scale;
  return true;
}
// The source grid's sharpened fraction g = clamp(0.5 + K (f - 0.5), 0, 1) at offset; 1 without a usable sample.
float sourceHidden(int g, vec3 offset) {
  sourceKind = true;
  bool hit = lookup(g, offset);
  sourceKind = false;
  if (!hit) return 1.0;
  float f = clamp(fraction, 0.0, 1.0);
  return clamp(0.5 + fetch(sources, sourceDims[g].x).x * (f - 0.5), 0.0, 1.0);
}
// N . FIV_sources per channel, the sources' own irradiance.
vec3 sourceIrradianceAt(int g, vec3 n) {
  int b = sourceDims[g].x;
  return vec3(dot(n, fetch(sources, b + 1).xyz), dot(n, fetch(sources, b + 2).xyz), dot(n, fetch(sources, b + 3).xyz));
}
float capCosineIntegral(float cosTheta, float sinSigmaSquared) {
  cosTheta = clamp(cosTheta, -1.0, 1.0);
  sinSigmaSquared = clamp(sinSigmaSquared, 0.0, 1.0);
  if (cosTheta * cosTheta >= sinSigmaSquared) return pi * sinSigmaSquared * max(0.0, cosTheta);
  float sinTheta = sqrt(1.0 - cosTheta * cosTheta), x = sqrt(max(1.0 / sinSigmaSquared - 1.0, 0.0));
  float y = clamp(-x * cosTheta / sinTheta, -1.0, 1.0), s = sinTheta * sqrt(max(0.0, 1.0 - y * y));
  return max(0.0, (cosTheta * acos(y) - x * s) * sinSigmaSquared + (x > 0.0 ? atan(s / x) : pi / 2.0));
}
float discOverlap(float r1, float r2, float s) {
  if (s >= r1 + r2) return 0.0;
  if (s <= abs(r1 - r2)) return pi * min(r1, r2) * min(r1, r2);
  float a = clamp((s * s + r1 * r1 - r2 * r2) / (2.0 * s * r1), -1.0, 1.0);
  float b = clamp((s * s + r2 * r2 - r1 * r1) / (2.0 * s * r2), -1.0, 1.0);
  float k = (-s + r1 + r2) * (s + r1 - r2) * (s - r1 + r2) * (s + r1 + r2);
  return r1 * r1 * acos(a) + r2 * r2 * acos(b) - 0.5 * sqrt(max(0.0, k));
}
float angleBetween(vec3 a, vec3 b) { return 2.0 * asin(min(1.0, 0.5 * length(a - b))); }

vec3 hiddenValue[${kMaxInstances}], hiddenDirection[${kMaxInstances}];
float hiddenRadius[${kMaxInstances}], hiddenDisc[${kMaxInstances}];
void main() {
  int v = int(gl_FragCoord.y) * ${kWidth} + int(gl_FragCoord.x);
  if (v >= pointCount) { irradiance = vec4(0.0); return; }
  vec3 p = fetch(points, 3 * v).xyz, n = fetch(points, 3 * v + 1).xyz;
  vec3 total = difmapAt(n), unoccluded = total;
  sourceKind = false;
  if (selfGrid >= 0 && selfExact) {
    unoccluded = fetch(points, 3 * v + 2).rgb;
  } else if (selfGrid >= 0 && lookup(selfGrid, gridCentre[selfGrid] - p)) {
    unoccluded = vec3(dot(n, fivEnv[0]), dot(n, fivEnv[1]), dot(n, fivEnv[2])) - vec3(dot(n, F[0]), dot(n, F[1]), dot(n, F[2]));
    // The grid holds the rest of the map: its sources come back signed, as FIV_self held them.
    if (sourceDims[selfGrid].y > 0)
      unoccluded -= sourceHidden(selfGrid, gridCentre[selfGrid] - p) * sourceIrradianceAt(selfGrid, n);
  }
  float visible = 1.0;
  vec3 sourceIrradiance = vec3(0.0); // the largest max(0, N . FIV_sources) over the instances' types
  int used = 0;
  for (int j = 0; j < ${kMaxInstances}; ++j) {
    if (j >= instanceCount) break;
    int g = instanceGrid[j];
    float radius = gridRadius[g];
    vec3 offset = gridCentre[g] + instanceTranslation[j] - p;
    float d = dot(n, offset);
    if (d <= -radius) continue; // case C
    if (sourceDims[g].y > 0) { // rays decided it: no partial correction
      visible *= 1.0 - sourceHidden(g, offset);
      sourceIrradiance = max(sourceIrradiance, sourceIrradianceAt(g, n));
    }
    bool hit = lookup(g, offset);
    vec3 value = total; // inside the occluder: all of it
    if (hit) {
      for (int c = 0; c < 3; ++c) {
        float raw = dot(n, F[c]);
        if (d >= radius) { value[c] = max(0.0, raw); continue; }
        float len = length(F[c]);
        if (!(len > 0.0) || !(P[c] > 0.0)) { value[c] = 0.0; continue; }
        float cosSigma = clamp(2.0 * len / P[c] - 1.0, 0.0, 1.0 - 1e-7);
        value[c] = max(0.0, P[c] / (2.0 * pi * (1.0 - cosSigma)) * capCosineIntegral(raw / len, 1.0 - cosSigma * cosSigma));
      }
    } else {
      F = mat3(0.0);
      P = vec3(0.0);
    }
    if (value.r <= 0.0 && value.g <= 0.0 && value.b <= 0.0) continue;
    float distance = length(offset);
    vec3 direction = distance > 0.0 ? offset / distance : vec3(0.0);
    float angular = distance > radius ? asin(radius / distance) : pi / 2.0;
    float green = length(F[1]);
    if (green > 0.0 && P.g > 0.0) {
      angular = max(acos(clamp(2.0 * green / P.g - 1.0, 0.0, 1.0)), 1e-4);
      direction = F[1] / green;
    }
    hiddenValue[used] = value;
    hiddenDirection[used] = direction;
    hiddenRadius[used] = angular;
    hiddenDisc[used] = pi * angular * angular;
    ++used;
  }
  vec3 occluded = vec3(0.0), largest = vec3(0.0);
  for (int a = 0; a < ${kMaxInstances}; ++a) {
    if (a >= used) break;
    occluded += hiddenValue[a];
    largest = max(largest, hiddenValue[a]);
  }
  for (int a = 0; a < ${kMaxInstances}; ++a)
    for (int b = 0; b < ${kMaxInstances}; ++b) {
      if (a >= used || b >= used || b <= a) continue;
      float cosine = clamp(dot(hiddenDirection[a], hiddenDirection[b]), -1.0, 1.0);
      float reach = hiddenRadius[a] + hiddenRadius[b];
      if (reach < pi && cosine <= cos(reach)) continue;
      float share = discOverlap(hiddenRadius[a], hiddenRadius[b], angleBetween(hiddenDirection[a], hiddenDirection[b])) /
                    (hiddenDisc[a] + hiddenDisc[b]);
      occluded -= share * (hiddenValue[a] + hiddenValue[b]);
    }
  occluded = max(occluded, largest) + (1.0 - visible) * sourceIrradiance;
  irradiance = vec4(clamp(unoccluded - occluded, vec3(0.0), max(total, vec3(0.0))), 1.0);
}`;

const vertexShader = /* glsl */ `
in vec3 position;
void main() { gl_Position = vec4(position.xy, 0.0, 1.0); }`;

// The GPU shading pass for readFivScene's `fiv`, the receiver's points and unit normals ([V][3]). Returns
// {texture (the target's: vertex v's irradiance at (v % 1024, v / 1024)), shade(instances), read()}: shade
// draws the pass, finished (a 1-texel read), for [{grid: object index, translation}], read() returns the irradiance [V][3] as floats.
// Throws Error with gpuLimit set for more grids, shells, source-grid shells or instances than the shader holds, or
// a texture taller than the renderer's maximum.
export function fivGpu(renderer, fiv, positions, normals) {
  const count = positions.length / 3;
  const gridObjects = fiv.grids.map((g, k) => (g ? k : -1)).filter((k) => k >= 0);
  if (gridObjects.length > kMaxGrids) throw limit(`FIV scene: ${gridObjects.length} grids (the GPU shading takes ${kMaxGrids})`);
  if (fiv.instances.length > kMaxInstances) throw limit(`FIV scene: ${fiv.instances.length} instances (the GPU shading takes ${kMaxInstances})`);
  const slot = {}; // object -> grid slot
  let texels = 0;
  const base = [], values = [];
  gridObjects.forEach((object, s) => {
    const g = fiv.grids[object];
    if (g.shells > kMaxShells) throw limit(`FIV scene: grid of object ${object} has ${g.shells} shells (the GPU shading takes ${kMaxShells})`);
    if (g.sources && g.sources.shells > kMaxSourceShells)
      throw limit(`FIV scene: source grid of object ${object} has ${g.sources.shells} shells (the GPU shading takes ${kMaxSourceShells})`);
    slot[object] = s;
    base.push(texels);
    const rows = g.azimuth * g.polar * g.shells;
    for (let r = 0; r < rows; ++r) {
      for (let c = 0; c < 3; ++c) values.push(g.fiv[9 * r + 3 * c], g.fiv[9 * r + 3 * c + 1], g.fiv[9 * r + 3 * c + 2], c === 0 ? g.valid[r] : 0);
      values.push(g.power[3 * r], g.power[3 * r + 1], g.power[3 * r + 2], 0);
    }
    texels += 4 * rows;
  });
  // The source grids: per slot a header (sharpen; N . FIV_sources's rows), the shell radii, then (fraction, valid).
  const sourceDims = new Array(4 * kMaxGrids).fill(0);
  let sourceTexels = 0;
  const sourceSlots = gridObjects.map((object, s) => {
    const g = fiv.grids[object].sources;
    if (!g) return null;
    sourceDims.splice(4 * s, 4, sourceTexels, g.azimuth, g.polar, g.shells);
    const start = sourceTexels;
    sourceTexels += kSourceHeader + g.shells + g.azimuth * g.polar * g.shells;
    return { g, start };
  });
  const sourceValues = new Float32Array(Math.max(1, sourceTexels) * 4);
  for (const slot of sourceSlots) {
    if (!slot) continue;
    const { g, start } = slot;
    sourceValues[4 * start] = g.sharpen;
    for (let c = 0; c < 3; ++c) sourceValues.set(g.fiv.slice(3 * c, 3 * c + 3), 4 * (start + 1 + c));
    g.shellRadii.forEach((r, k) => { sourceValues[4 * (start + kSourceHeader + k)] = r; });
    const rows = start + kSourceHeader + g.shells;
    for (let r = 0; r < g.fraction.length; ++r) {
      sourceValues[4 * (rows + r)] = g.fraction[r];
      sourceValues[4 * (rows + r) + 1] = g.valid[r];
    }
  }
  const maxLines = renderer.capabilities.maxTextureSize;
  for (const [what, n] of [['grids', texels], ['source grids', sourceTexels], ['points', 3 * count]])
    if (Math.ceil(n / kWidth) > maxLines)
      throw limit(`FIV scene: the ${what} need a ${kWidth} x ${Math.ceil(n / kWidth)} texture, beyond this GPU's ${maxLines}`);
  const pad = (array, length, fill = 0) => [...array, ...Array(Math.max(0, length - array.length)).fill(fill)];
  const grids = gridObjects.map((object) => fiv.grids[object]);
  const shellRadii = new Array(kMaxGrids * kMaxShells).fill(0);
  grids.forEach((g, s) => g.shellRadii.forEach((r, k) => { shellRadii[s * kMaxShells + k] = r; }));
  const difmapValues = new Float32Array(fiv.lighting.difmap.length / 3 * 4);
  for (let t = 0; t < fiv.lighting.difmap.length / 3; ++t) difmapValues.set(fiv.lighting.difmap.subarray(3 * t, 3 * t + 3), 4 * t);
  const selfIrradiance = fiv.self ? fiv.self.selfIrradiance : null;
  const pointValues = new Float32Array(count * 12);
  for (let v = 0; v < count; ++v) {
    for (let c = 0; c < 3; ++c) pointValues[12 * v + c] = positions[3 * v + c];
    for (let c = 0; c < 3; ++c) pointValues[12 * v + 4 + c] = normals[3 * v + c];
    if (selfIrradiance) for (let c = 0; c < 3; ++c) pointValues[12 * v + 8 + c] = selfIrradiance[3 * v + c];
  }
  const uniforms = {
    grids: { value: floatTexture(values, texels) },
    difmap: { value: floatTexture(difmapValues, difmapValues.length / 4) },
    points: { value: floatTexture(pointValues, 3 * count) },
    sources: { value: floatTexture(sourceValues, Math.max(1, sourceTexels)) },
    sourceDims: { value: Int32Array.from(sourceDims) }, // flat: three.js hands an ivec4 array to uniform4iv as is
    selfExact: { value: !!selfIrradiance },
    gridBase: { value: pad(base, kMaxGrids) },
    gridAzimuth: { value: pad(grids.map((g) => g.azimuth), kMaxGrids, 3) },
    gridPolar: { value: pad(grids.map((g) => g.polar), kMaxGrids, 2) },
    gridShells: { value: pad(grids.map((g) => g.shells), kMaxGrids, 1) },
    gridRadius: { value: pad(grids.map((g) => g.radius), kMaxGrids, 1) },
    gridCentre: { value: Array.from({ length: kMaxGrids }, (_, s) => new THREE.Vector3(...(grids[s] ? grids[s].centre : [0, 0, 0]))) },
    shellRadii: { value: shellRadii },
    instanceCount: { value: 0 },
    instanceGrid: { value: new Array(kMaxInstances).fill(0) },
    instanceTranslation: { value: Array.from({ length: kMaxInstances }, () => new THREE.Vector3()) },
    selfGrid: { value: fiv.self ? slot[0] : -1 },
    difmapSize: { value: fiv.lighting.size },
    fivEnv: { value: [0, 1, 2].map((c) => new THREE.Vector3(...fiv.lighting.fivEnv.slice(3 * c, 3 * c + 3))) },
    pointCount: { value: count },
  };
  const lines = Math.max(1, Math.ceil(count / kWidth));
  const target = new THREE.WebGLRenderTarget(kWidth, lines, { type: THREE.FloatType, format: THREE.RGBAFormat,
                                                              minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter,
                                                              depthBuffer: false });
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array([-1, -1, 0, 3, -1, 0, -1, 3, 0]), 3));
  const quad = new THREE.Mesh(geometry, new THREE.RawShaderMaterial({ vertexShader, fragmentShader, uniforms, glslVersion: THREE.GLSL3,
                                                                     depthTest: false, depthWrite: false }));
  quad.frustumCulled = false;
  const pass = new THREE.Scene();
  pass.add(quad);
  const camera = new THREE.Camera();
  const readback = new Float32Array(kWidth * lines * 4), finished = new Float32Array(4);
  return {
    texture: target.texture,
    width: kWidth,
    shade(instances) {
      uniforms.instanceCount.value = instances.length;
      instances.forEach((instance, j) => {
        uniforms.instanceGrid.value[j] = slot[instance.object];
        uniforms.instanceTranslation.value[j].fromArray(instance.translation);
      });
      const previous = renderer.getRenderTarget();
      renderer.setRenderTarget(target);
      renderer.render(pass, camera);
      renderer.setRenderTarget(previous);
      renderer.readRenderTargetPixels(target, 0, 0, 1, 1, finished); // waits for the pass, so its time is measured
    },
    read() {
      renderer.readRenderTargetPixels(target, 0, 0, kWidth, lines, readback);
      const out = new Float32Array(count * 3);
      for (let v = 0; v < count; ++v) out.set(readback.subarray(4 * v, 4 * v + 3), 3 * v);
      return out;
    },
  };
}
