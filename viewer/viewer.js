// The prt viewer: loads a bundle, relights its SH transfer on the GPU under any environment's SH lighting, and
// lets the user turn the environment and change the order. Shading agrees with `prt relight` (the same sum) and
// pictures with `prt render` (the same pinhole camera and tone map, compare.h toneMap).
import * as THREE from 'three';
import { rgbFloatNearest } from './textures.js';
import { isSceneBundle, loadBundle, parseGlb, readSceneTransfer, syntheticBundle } from './bundle.js';
import { relightRowGlsl, toneMapGlsl } from './glsl.js';
import { hybridGlsl, hybridUniforms, loadLights, parseVisibilityNpy, readHybridLayers, readSceneBounce,
         readTexelHybridLayers, setHybridUniforms, texelSurfaceTexture, turnedHybridLighting, visibilityTexture,
         visibilityTurnBlend } from './hybrid.js';
import { sceneMeshes } from './scene.js';
import { fitLighting, rotateLightingY } from './sh.js';
import { loadSky, skyMesh } from './sky.js';
import { kLuminance, linearReadback, referencePanels } from './compare.js';
import { orbitCamera, parseNumbers } from './camera.js';
import { isFivSceneJson } from './fiv.js';
import { startFivViewer } from './fiv_view.js';
import { glossySetup, glossyVertexShader, parseStack, readGlossyLobes, setMapTurn, setStack, stackAtlas } from './glossy.js';

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
${relightRowGlsl(kMaxCoefficients)}
${hybridGlsl(kMaxCoefficients)}
void main() {
  vUv = uv;
  vError = relativeError;
  vRadiance = vec3(0.0);
  if (perVertex) vRadiance = relightRow(gl_VertexID) + (hybrid ? hybridLights(gl_VertexID) : vec3(0.0));
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
uniform int rowsPerLine;
uniform sampler2DArray texelSurface; // a bake's hybrid: layer 0 the texels' normals, layer 1 their albedo
in vec3 vRadiance;
in vec2 vUv;
in float vError;
out vec4 colour;
${toneMapGlsl}
${hybridGlsl(kMaxCoefficients, false)}
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
    // A bake's hybrid: the same texel's cone lights and bounce part, as prt relight --texels --lights.
    if (hybrid)
      radiance += hybridLightsAt(texel.y * atlasSize.x + texel.x, texelFetch(texelSurface, ivec3(texel, 0), 0).rgb,
                                 texelFetch(texelSurface, ivec3(texel, 1), 0).rgb);
  }
  colour = vec4(toneMap(radiance), 1.0);
}`;

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
  rgbFloatNearest(texture);
  return texture;
}

// Loads what `params` (the page's query, README "Query parameters") names and draws it. Returns the api the page
// and the tests drive: set(changes), read(points), bench(frames), metrics(), state(), query().
// lights=URL (prt-lights JSON, `prt envlight`) and visibility=URL (its cone visibility per vertex, `prt relight
// --lights ... --visibility-out`): the hybrid's inputs (hybrid.js), or null without lights. Plain and scene bundles
// per vertex only. The synthetic sphere (frame times) takes its normals from its positions, albedo 1, its transfer as a
// stand-in bounce layer of the same cost, and a visibility of ones.
// A scene bundle (sceneTransfer given): its rows (receivers in node order, then their vertices, as `prt relight`
// writes the visibility), its bounce layer, and per receiver its world normals and materials (scene.js).
// A bake (kind texel): its texels are the rows (`prt relight --texels --lights --visibility-out` writes their
// visibility), with the bounce layer and the texel surface (normals, albedo) from readTexelHybridLayers.
async function loadHybrid(params, { isScene, kind, synthetic, mesh, bytes, sceneTransfer, sceneJson, sceneBin, bundleUrl }) {
  const url = params.get('lights');
  if (!url) return null;
  if (kind === 'texel' && synthetic) throw new Error('lights: a synthetic mesh is relit per vertex');
  const lights = await loadLights(url);
  const transfer = isScene ? sceneTransfer.transfer : mesh.transfer;
  if (lights.order !== transfer.order)
    throw new Error(`${url}: the lights' residual has order ${lights.order}, the bundle's transfer order ${transfer.order}: ` +
                    `run prt envlight --order ${transfer.order}`);
  const vertexCount = isScene || kind === 'texel' ? transfer.rows : mesh.positions.length / 3;
  let layers;
  let visibility = null;
  if (kind === 'texel') {
    layers = await readTexelHybridLayers(bytes, bundleUrl, transfer);
  } else if (isScene) {
    layers = { bounce: readSceneBounce(sceneJson, sceneBin) }; // normals and albedo: scene.js, per receiver and pixel
  } else if (synthetic) {
    layers = { bounce: mesh.transfer.data, albedo: new Float32Array(vertexCount * 3).fill(1),
               normals: mesh.positions.map((x) => 2 * x) };
    // A visibility of ones, so that its texture fetches are in the frame time.
    visibility = { rows: vertexCount, lights: lights.lights.length, data: new Float32Array(vertexCount * lights.lights.length).fill(1) };
  } else {
    layers = readHybridLayers(bytes, vertexCount);
  }
  const visibilityUrl = params.get('visibility');
  if (visibilityUrl) {
    const response = await fetch(visibilityUrl);
    if (!response.ok) throw new Error(`${visibilityUrl}: HTTP ${response.status}`);
    visibility = parseVisibilityNpy(await response.arrayBuffer(), visibilityUrl);
    if (visibility.rows !== vertexCount || visibility.lights !== lights.lights.length)
      throw new Error(`${visibilityUrl}: visibility of ${visibility.rows} rows x ${visibility.lights} lights, the bundle has ` +
                      `${vertexCount} ${isScene ? 'rows' : 'vertices'} and ${url} ${lights.lights.length} lights`);
  }
  return { lights, layers, visibility };
}

// glossy=URL,URL (`prt render --glossy-stack`, the prefiltered stack of each entry of maps=; empty: no lobes under
// that map): a glossy bundle's lobes per pixel (glossy.js), or null. The synthetic sphere (frame times) takes its lobes from the bundle glossyLobes=URL,
// vertex v from that bundle's row v % its vertex count, and its normals from its positions.
async function loadGlossy(params, { isScene, kind, synthetic, mesh, bytes, mapCount }) {
  const urls = (params.get('glossy') || '').split(',');
  if (!urls.some(Boolean)) return null;
  if (urls.length > mapCount) throw new Error(`glossy: ${urls.length} stacks for ${mapCount} maps (one per entry of maps=)`);
  if (isScene || kind === 'texel' || params.get('lights'))
    throw new Error('glossy: the lobes go with a plain glossy bundle per vertex (not scenes, texels or lights)');
  const fetchBytes = async (what) => {
    const response = await fetch(what);
    if (!response.ok) throw new Error(`${what}: HTTP ${response.status}`);
    return response.arrayBuffer();
  };
  const atlases = await Promise.all(Array.from({ length: mapCount }, async (_, i) =>
    (urls[i] ? stackAtlas(parseStack(await fetchBytes(urls[i]), urls[i])) : null)));
  const first = atlases.find(Boolean);
  const vertexCount = mesh.positions.length / 3;
  let setup;
  if (synthetic) {
    if (!params.get('glossyLobes')) throw new Error('glossy: a synthetic mesh takes its lobes from glossyLobes=URL');
    const lobes = readGlossyLobes(await fetchBytes(params.get('glossyLobes')));
    setup = glossySetup(mesh, lobes, first, mesh.positions.map((x) => 2 * x));
  } else {
    const lobes = readGlossyLobes(bytes);
    if (lobes.vertexCount !== vertexCount) throw new Error(`glossy: ${lobes.vertexCount} lobe rows for ${vertexCount} vertices`);
    setup = glossySetup(mesh, lobes, first);
  }
  return { ...setup, atlases };
}

export async function startViewer(canvas, panel, params) {
  const [width, height] = parseNumbers(params.get('size') || '640,480', 2, 'size');
  const kind = params.get('mode') === 'texel' ? 'texel' : 'vertex';
  const bundleUrl = params.get('bundle'), synthetic = params.get('synthetic'); // synthetic=VERTICES,ORDER
  if (!bundleUrl && !synthetic) throw new Error('give ?bundle=URL of a .glb');
  let bytes = null, sceneJson = null, sceneBin = null;
  if (bundleUrl) {
    const response = await fetch(bundleUrl);
    if (!response.ok) throw new Error(`${bundleUrl}: HTTP ${response.status}`);
    bytes = await response.arrayBuffer();
    const { json, bin } = parseGlb(bytes);
    if (isFivSceneJson(json)) return startFivViewer(canvas, panel, params, bytes); // moving occluders: fiv_view.js
    if (isSceneBundle(json)) [sceneJson, sceneBin] = [json, bin];
  }
  const isScene = !!sceneJson;
  if (isScene && kind === 'texel') throw new Error('a scene bundle is relit per vertex (mode=texel is for bakes)');
  const sceneTransfer = isScene ? readSceneTransfer(sceneJson, sceneBin) : null;
  const mesh = isScene ? null : synthetic ? await syntheticBundle(...parseNumbers(synthetic, 2, 'synthetic'))
                                          : await loadBundle(bundleUrl, kind, bytes);
  const maps = (params.get('maps') || '').split(',').filter(Boolean);
  if (!maps.length) throw new Error('give ?maps=URL,URL of prt-sh JSON lighting (prt envsh)');
  const lightings = await Promise.all(maps.map(async (url) => {
    const sh = await (await fetch(url)).json();
    if (sh.format !== 'prt-sh') throw new Error(`${url}: not prt-sh JSON`);
    return { name: url.split('/').pop().replace(/\.sh\.json$|\.json$/, ''), order: sh.order,
             coefficients: Float32Array.from(sh.coefficients.flat()) };
  }));
  // sky=URL,URL: the OpenEXR maps behind the lighting, one per entry of maps (empty: black for that one).
  const skyUrls = (params.get('sky') || '').split(',');
  const skies = await Promise.all(maps.map((_, i) => (skyUrls[i] ? loadSky(skyUrls[i]) : null)));
  const hybrid = await loadHybrid(params, { isScene, kind, synthetic, mesh, bytes, sceneTransfer, sceneJson, sceneBin, bundleUrl });
  const glossy = await loadGlossy(params, { isScene, kind, synthetic, mesh, bytes, mapCount: maps.length });
  const reference = !isScene && params.get('reference') ? parseNpy(await (await fetch(params.get('reference'))).arrayBuffer()) : null;

  const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: true, alpha: false });
  renderer.setPixelRatio(1);
  renderer.setSize(width, height, false);
  renderer.setClearColor(0x000000, 1);
  const gl = renderer.getContext();

  const t = isScene ? sceneTransfer.transfer : mesh.transfer;
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
    linearOutput: { value: false },
    texelSurface: { value: null },
    ...hybridUniforms(kMaxCoefficients),
  };
  if (hybrid && kind === 'texel') uniforms.texelSurface.value = texelSurfaceTexture(hybrid.layers.surface, t.width, t.height);
  if (hybrid && hybrid.layers.bounce) {
    uniforms.bounce.value = transferTexture({ ...t, data: hybrid.layers.bounce }, rowsPerLine, lines);
    uniforms.hasBounce.value = true;
  }
  if (hybrid && hybrid.visibility) {
    uniforms.visibility.value = visibilityTexture(hybrid.visibility, rowsPerLine, lines);
    uniforms.hasVisibility.value = true;
  }
  const scene = new THREE.Scene();
  const sky = skyMesh(uniforms.exposure);
  scene.add(sky);
  let vertexCount, errors = null, geometry = null, receiverCount = 0;
  if (isScene) {
    const shared = { transfer: uniforms.transfer, coefficients: uniforms.coefficients, rowsPerLine: uniforms.rowsPerLine,
                     lighting: uniforms.lighting, exposure: uniforms.exposure, linearOutput: uniforms.linearOutput };
    // The hybrid's uniforms too (hybrid.js), by reference: every receiver relights its rows with the same lights.
    for (const name of Object.keys(hybridUniforms(kMaxCoefficients))) shared[name] = uniforms[name];
    const built = await sceneMeshes(bytes, sceneJson, sceneTransfer.receivers, shared, !!hybrid);
    scene.add(built.group);
    vertexCount = t.rows;
    receiverCount = built.receivers;
  } else {
    geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(mesh.positions, 3));
    vertexCount = mesh.positions.length / 3;
    geometry.setAttribute('uv', new THREE.BufferAttribute(mesh.texcoords || new Float32Array(vertexCount * 2), 2));
    errors = new Float32Array(vertexCount);
    geometry.setAttribute('relativeError', new THREE.BufferAttribute(errors, 1));
    geometry.setIndex(new THREE.BufferAttribute(mesh.indices, 1));
    if (hybrid && kind === 'vertex') {
      geometry.setAttribute('normal', new THREE.BufferAttribute(hybrid.layers.normals, 3));
      geometry.setAttribute('albedo', new THREE.BufferAttribute(hybrid.layers.albedo, 3));
    }
    const material = new THREE.RawShaderMaterial({
      vertexShader, fragmentShader, uniforms, glslVersion: THREE.GLSL3, side: THREE.DoubleSide,
    });
    if (glossy) {
      // The lobes per pixel (glossy.js): the same transfer, lighting and tone map, drawn without an index buffer.
      const shared = { transfer: uniforms.transfer, coefficients: uniforms.coefficients, rowsPerLine: uniforms.rowsPerLine,
                       lighting: uniforms.lighting, exposure: uniforms.exposure, linearOutput: uniforms.linearOutput };
      Object.assign(glossy.uniforms, shared, { glossyOn: { value: true } });
      const glossyMaterial = new THREE.RawShaderMaterial({
        vertexShader: glossyVertexShader(kMaxCoefficients), fragmentShader: glossy.fragmentShader,
        uniforms: glossy.uniforms, glslVersion: THREE.GLSL3, side: THREE.DoubleSide,
      });
      const glossyMesh = new THREE.Mesh(glossy.geometry, glossyMaterial);
      glossyMesh.frustumCulled = false;
      scene.add(glossyMesh);
    } else {
      scene.add(new THREE.Mesh(geometry, material));
    }
  }

  const view = parseNumbers(params.get('camera') || '0,0.1,0.4,0,0.1,0,0,1,0,40', 10, 'camera');
  const view3d = orbitCamera(view, width, height);
  const { camera, orbit } = view3d;
  const placeCamera = () => view3d.place();

  // referenceImage=URL: `prt reference --image` of this camera and size, shown beside the result (compare.js); the
  // camera is locked to the reference's (the URL's camera, or referenceCamera=) while it is shown.
  const referenceUrl = params.get('referenceImage');
  const comparison = referenceUrl ? referencePanels(canvas, await loadSky(referenceUrl), width, height) : null;
  const renderLinear = comparison ? linearReadback(renderer, width, height, uniforms.linearOutput) : null;
  const referenceView = params.get('referenceCamera') ? parseNumbers(params.get('referenceCamera'), 10, 'referenceCamera') : view;
  let referenceMetrics = null;

  const state = {
    map: Math.min(lightings.length - 1, Math.max(0, Number(params.get('map') || 0))),
    order: Math.min(t.order, Number(params.get('order') || t.order)), rotate: Number(params.get('rotate') || 0),
    showError: false, showSky: params.get('showSky') !== '0', hybrid: !!hybrid && params.get('hybrid') !== '0',
    showReference: !!comparison && params.get('compare') === '1',
    glossy: !!glossy && params.get('glossyOn') !== '0',
  };
  // With a visibility file the turn stays where the visibility was cast (hybrid.js): the URL's rotate.
  // A table of turns (--visibility-turns) leaves it free.
  const lockedTurn = hybrid && hybrid.visibility && !(hybrid.visibility.turns > 1) ? state.rotate : null;
  let metrics = null;
  let lighting = null;
  let frameMs = null;

  // The relit radiance on the CPU, only for the error against a reference (per vertex).
  function errorAgainstReference() {
    if (!reference || kind !== 'vertex' || reference.length !== vertexCount * 3) return null;
    const C = t.order * t.order, weights = kLuminance;
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

  // The result's linear radiance (no sky, no error colours) against the reference image; draws the two panels.
  function compareWithReference() {
    const [showError, skyVisible] = [uniforms.showError.value, sky.visible];
    uniforms.showError.value = false;
    sky.visible = false;
    const result = renderLinear(scene, camera);
    uniforms.showError.value = showError;
    sky.visible = skyVisible;
    comparison.update(result, uniforms.exposure.value);
    return comparison.metrics();
  }

  // One frame, finished (a 1-pixel read waits for the GPU): its milliseconds are the panel's frame time.
  const pixel = new Uint8Array(4);
  function draw() {
    placeCamera();
    if (glossy) glossy.uniforms.eye.value.copy(camera.position); // each pixel's direction to the eye
    sky.userData.set(state.showSky ? skies[state.map] : null, width, height, orbit.eye, orbit.target, orbit.up,
                     orbit.fovy, state.rotate);
    const start = performance.now();
    renderer.render(scene, camera);
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
    frameMs = performance.now() - start;
  }

  function update() {
    const source = lightings[state.map];
    const order = state.order, count = order * order;
    if (lockedTurn !== null) state.rotate = lockedTurn;
    const hybridOn = state.hybrid && !!hybrid;
    if (hybridOn) {
      // As prt relight --lights: the residual turned in SH, the cones' directions turned, their projection windowed.
      const turned = turnedHybridLighting(hybrid.lights, state.rotate, order);
      lighting = turned.residual;
      setHybridUniforms(uniforms, turned, kMaxCoefficients);
      const blend = visibilityTurnBlend(state.rotate, (hybrid.visibility && hybrid.visibility.turns) || 1);
      [uniforms.visibilityTurnA.value, uniforms.visibilityTurnB.value, uniforms.visibilityWeight.value] = [blend.a, blend.b, blend.weight];
    } else {
      // As prt relight: the lighting's bands shared with the transfer, turned about +Y; bands above `order` are off.
      const fitted = fitLighting(source.coefficients, Math.min(source.order, t.order) ** 2);
      const turned = rotateLightingY(fitted, Math.min(source.order, t.order), state.rotate);
      lighting = new Float32Array(t.order * t.order * 3);
      lighting.set(turned.subarray(0, Math.min(turned.length, count * 3)));
    }
    uniforms.hybrid.value = hybridOn;
    if (glossy) {
      const atlas = glossy.atlases[state.map];
      glossy.uniforms.glossyOn.value = state.glossy && !!atlas; // no stack for this map: the diffuse part only
      if (atlas) setStack(glossy.uniforms, atlas);
      setMapTurn(glossy.uniforms, state.rotate); // the lobes see the map turned as the SH lighting is
    }
    for (let j = 0; j < kMaxCoefficients; ++j)
      uniforms.lighting.value[j].set(lighting[j * 3] || 0, lighting[j * 3 + 1] || 0, lighting[j * 3 + 2] || 0);
    uniforms.coefficients.value = count;
    uniforms.showError.value = state.showError && !!reference;
    metrics = hybridOn ? null : errorAgainstReference(); // the CPU error sums plain SH only
    if (state.showReference) {
      view3d.set(referenceView);
    }
    if (comparison) comparison.show(state.showReference);
    draw();
    referenceMetrics = state.showReference ? compareWithReference() : null;
    report();
  }
  function report() {
    if (panel) panel.update(state, metrics, { kind: isScene ? 'scene' : kind, vertexCount, receivers: receiverCount,
                                               renderer: api.renderer, frameMs, hasSky: !!skies[state.map],
                                               lights: hybrid ? hybrid.lights.lights.length : 0,
                                               glossy: glossy ? (glossy.atlases[state.map] ? 'on' : 'no stack for this map') : null,
                                               turnLocked: lockedTurn !== null, referenceMetrics });
  }

  // The view as a query string: what was loaded, and the state (README "Query parameters"), to share a view.
  function query() {
    const q = new URLSearchParams(params);
    const round = (v) => Number(v.toPrecision(6));
    q.set('camera', [...orbit.eye.toArray(), ...orbit.target.toArray(), ...orbit.up.toArray(), orbit.fovy].map(round).join(','));
    q.set('map', String(state.map));
    q.set('order', String(state.order));
    q.set('rotate', String(state.rotate));
    q.set('exposure', String(uniforms.exposure.value));
    if (!state.showSky) q.set('showSky', '0'); else q.delete('showSky');
    if (hybrid && !state.hybrid) q.set('hybrid', '0'); else q.delete('hybrid');
    if (state.showReference) q.set('compare', '1'); else q.delete('compare');
    if (glossy && !state.glossy) q.set('glossyOn', '0'); else q.delete('glossyOn');
    return q.toString().replace(/%2C/g, ',').replace(/%2F/g, '/');
  }

  const api = {
    lightings: lightings.map((l) => l.name),
    transferOrder: t.order,
    kind: isScene ? 'scene' : kind,
    vertexCount,
    receivers: receiverCount,
    lights: hybrid ? hybrid.lights.lights.length : 0,
    glossy: !!glossy,
    glossyMaps: glossy ? glossy.atlases.map(Boolean) : [],
    turnLocked: lockedTurn !== null,
    hasReferenceImage: !!comparison,
    referenceMetrics: () => referenceMetrics,
    // With a reference image: the result's linear RGBA (A = coverage), row 0 at the top, as the comparison reads it.
    linearPixels: () => (renderLinear ? Array.from(renderLinear(scene, camera)) : null),
    renderer: (() => {
      const debug = gl.getExtension('WEBGL_debug_renderer_info'); // the real GL behind Chromium's mask
      return debug ? gl.getParameter(debug.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER);
    })(),
    set(changes) {
      if ('exposure' in changes) uniforms.exposure.value = Number(changes.exposure);
      const { exposure, ...rest } = changes;
      Object.assign(state, rest);
      update();
      return { ...state };
    },
    // Orbit about the target: `yaw` and `pitch` in degrees about the up axis and the camera's right axis, `zoom`
    // a factor on the distance. The pitch stops 1 degree short of the poles.
    orbit(yaw, pitch, zoom = 1) {
      if (state.showReference) return; // the camera is the reference's while it is shown
      view3d.turn(yaw, pitch, zoom);
      draw();
      report();
    },
    camera: () => view3d.array(),
    metrics: () => metrics,
    frameMs: () => frameMs,
    state: () => ({ ...state, exposure: uniforms.exposure.value }),
    query,
    // 8-bit RGB of the canvas at pixels [[x, y], ...], row 0 at the top as in prt's images.
    read(points) {
      draw();
      return points.map(([x, y]) => {
        gl.readPixels(x, height - 1 - y, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
        return [pixel[0], pixel[1], pixel[2]];
      });
    },
    // Mean milliseconds per frame over `frames` frames, each finished (a 1-pixel read waits for the GPU).
    bench(frames) {
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
