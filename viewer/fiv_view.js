// The viewer for a `prt fivscene` bundle: the receiver shaded per vertex from the FIV grids on the GPU (fiv_gpu.js,
// float, the default) or on the CPU (fiv.js, double; `fivOn=cpu`), radiance =
// albedo / pi x irradiance as `prt fivshade --albedo` (albedo=R,G,B or one grey value; default 1; a scene past
// the GPU pass's limits is shaded on the CPU, the reason in api.fivNote, the panel and the console), the occluders
// drawn where their instances sit, each lit unshadowed (albedo / pi x DifMap(n)). Instances move by api.moveInstance,
// by shift-drag of the selected one in the camera's plane, or on a path (animate: each circles its start position
// at 1.5 bounding radii, once every 4 s, phases spread). The URL keeps the positions (positions=X,Y,Z,...).
import * as THREE from 'three';
import { orbitCamera, parseNumbers } from './camera.js';
import { fivDifmap, fivIrradiance, readFivScene } from './fiv.js';
import { fivGpu } from './fiv_gpu.js';
import { toneMapGlsl } from './glsl.js';
import { loadSky, skyMesh } from './sky.js';

const vertexShader = /* glsl */ `
precision highp float;
uniform mat4 modelViewMatrix;
uniform mat4 projectionMatrix;
in vec3 position;
in vec3 radiance;
out vec3 vRadiance;
void main() {
  vRadiance = radiance;
  gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
}`;

const fragmentShader = /* glsl */ `
precision highp float;
uniform float exposure;
in vec3 vRadiance;
out vec4 colour;
${toneMapGlsl}
void main() {
  if (!gl_FrontFacing) { colour = vec4(0.0, 0.0, 0.0, 1.0); return; } // back faces black, as prt render
  colour = vec4(toneMap(vRadiance), 1.0);
}`;

// The receiver when the GPU shades it: vertex v's irradiance from the shading pass's texel (v % width, v / width).
const gpuVertexShader = /* glsl */ `
precision highp float;
precision highp int;
precision highp sampler2D;
uniform mat4 modelViewMatrix;
uniform mat4 projectionMatrix;
uniform sampler2D shaded;
uniform int shadedWidth;
uniform vec3 albedoOverPi;
in vec3 position;
out vec3 vRadiance;
void main() {
  vRadiance = albedoOverPi * texelFetch(shaded, ivec2(gl_VertexID % shadedWidth, gl_VertexID / shadedWidth), 0).rgb;
  gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
}`;

function meshObject(mesh, radiance, material) {
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(mesh.positions, 3));
  geometry.setAttribute('radiance', new THREE.BufferAttribute(radiance, 3));
  geometry.setIndex(new THREE.BufferAttribute(mesh.indices, 1));
  return new THREE.Mesh(geometry, material);
}

const unit = (normals) => {
  const out = new Float64Array(normals.length);
  for (let v = 0; v < normals.length; v += 3) {
    const length = Math.hypot(normals[v], normals[v + 1], normals[v + 2]);
    if (!(length > 0)) throw new Error(`FIV scene: normal ${v / 3} is zero`);
    for (let c = 0; c < 3; ++c) out[v + c] = normals[v + c] / length;
  }
  return out;
};

// Starts the FIV viewer on `canvas` for the scene bundle's `bytes`; returns the api index.html and the tests use
// (the plain viewer's, plus moveInstance, translations, fivRadiance, animate, drag).
export async function startFivViewer(canvas, panel, params, bytes) {
  const [width, height] = parseNumbers(params.get('size') || '640,480', 2, 'size');
  const fiv = readFivScene(bytes);
  const albedoText = params.get('albedo') || '1';
  const albedo = albedoText.includes(',') ? parseNumbers(albedoText, 3, 'albedo') : Array(3).fill(parseNumbers(albedoText, 1, 'albedo')[0]);
  const positions = fiv.receiver.positions, normals = unit(fiv.receiver.normals);
  if (params.get('positions')) {
    const at = parseNumbers(params.get('positions'), 3 * fiv.instances.length, 'positions');
    fiv.instances.forEach((instance, k) => { instance.translation = at.slice(3 * k, 3 * k + 3).map(Math.fround); });
  }
  const start = fiv.instances.map((instance) => instance.translation.slice());

  const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: true, alpha: false });
  renderer.setPixelRatio(1);
  renderer.setSize(width, height, false);
  renderer.setClearColor(0x000000, 1);
  const gl = renderer.getContext();
  const uniforms = { exposure: { value: Number(params.get('exposure') || 0) }, linearOutput: { value: false } };
  const material = new THREE.RawShaderMaterial({ vertexShader, fragmentShader, uniforms, glslVersion: THREE.GLSL3,
                                                 side: THREE.DoubleSide });
  const scene = new THREE.Scene();
  const sky = skyMesh(uniforms.exposure);
  scene.add(sky);
  const skyMap = params.get('sky') ? await loadSky(params.get('sky').split(',')[0]) : null;

  const radiance = new Float32Array(positions.length);
  // The GPU pass unless fivOn=cpu, or the scene exceeds its limits (fiv_gpu.js): then fiv.js, saying why.
  let gpu = null, fivNote = null;
  if (params.get('fivOn') !== 'cpu')
    try {
      gpu = fivGpu(renderer, fiv, positions, Float32Array.from(normals));
    } catch (error) {
      if (!error.gpuLimit) throw error;
      fivNote = `${error.message}: shaded on the CPU instead`;
      console.warn(fivNote);
    }
  const onGpu = !!gpu;
  const receiverMaterial = onGpu ? new THREE.RawShaderMaterial({
    vertexShader: gpuVertexShader, fragmentShader, glslVersion: THREE.GLSL3, side: THREE.DoubleSide,
    uniforms: { ...uniforms, shaded: { value: gpu.texture }, shadedWidth: { value: gpu.width },
                albedoOverPi: { value: new THREE.Vector3(...albedo.map((a) => a / Math.PI)) } } }) : material;
  const receiver = meshObject(fiv.receiver, radiance, receiverMaterial);
  scene.add(receiver);
  // Occluders: unshadowed, albedo / pi x DifMap(n), once per type.
  const occluderRadiance = {};
  for (const [object, mesh] of Object.entries(fiv.occluderMeshes)) {
    const n = unit(mesh.normals), out = new Float32Array(n.length);
    for (let v = 0; v < n.length; v += 3) {
      const e = fivDifmap(fiv.lighting, n.subarray(v, v + 3));
      for (let c = 0; c < 3; ++c) out[v + c] = albedo[c] / Math.PI * e[c];
    }
    occluderRadiance[object] = out;
  }
  const occluders = fiv.instances.map((instance) => {
    const mesh = meshObject(fiv.occluderMeshes[instance.object], occluderRadiance[instance.object], material);
    scene.add(mesh);
    return mesh;
  });

  const view3d = orbitCamera(parseNumbers(params.get('camera') || '0,8,25,0,4,0,0,1,0,40', 10, 'camera'), width, height);
  const state = { showSky: params.get('showSky') !== '0', selected: 0, animate: false };
  let frameMs = null, shadeMs = null;
  const pixel = new Uint8Array(4);

  // The receiver's radiance from the instances where they are now: the GPU pass, or fiv.js on the CPU and uploaded.
  function shade() {
    const t0 = performance.now();
    fiv.instances.forEach((instance, k) => occluders[k].position.fromArray(instance.translation));
    if (gpu) {
      gpu.shade(fiv.instances);
      shadeMs = performance.now() - t0; // the pass finished (fiv_gpu.js reads a texel back)
      return;
    }
    const irradiance = fivIrradiance(fiv.lighting, fiv.instances.map((i) => ({ grid: fiv.grids[i.object], translation: i.translation })),
                                     fiv.self, positions, normals);
    for (let v = 0; v < irradiance.length; ++v) radiance[v] = albedo[v % 3] / Math.PI * irradiance[v];
    receiver.geometry.attributes.radiance.needsUpdate = true;
    shadeMs = performance.now() - t0;
  }
  function draw() {
    view3d.place();
    sky.userData.set(state.showSky ? skyMap : null, width, height, view3d.orbit.eye, view3d.orbit.target, view3d.orbit.up,
                     view3d.orbit.fovy, 0);
    const t0 = performance.now();
    renderer.render(scene, view3d.camera);
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
    frameMs = performance.now() - t0;
  }
  function report() {
    if (panel) panel.update({ ...state, rotate: 0 }, null, { kind: 'fiv', vertexCount: positions.length / 3, receivers: 1,
                                                              renderer: api.renderer, frameMs, shadeMs, instances: fiv.instances.length,
                                                              fivOn: onGpu ? 'gpu' : 'cpu',
                                                              selfShadowing: !!fiv.self, lights: 0, fivNote,
                                                              fivSources: fiv.grids.some((g) => g && g.sources),
                                                              fivSelfExact: !!(fiv.self && fiv.self.selfIrradiance) });
  }
  function query() {
    const q = new URLSearchParams(params);
    const round = (v) => Number(v.toPrecision(6));
    q.set('camera', view3d.array().map(round).join(','));
    q.set('positions', fiv.instances.flatMap((i) => i.translation).map(round).join(','));
    q.set('exposure', String(uniforms.exposure.value));
    if (!state.showSky) q.set('showSky', '0'); else q.delete('showSky');
    return q.toString().replace(/%2C/g, ',').replace(/%2F/g, '/');
  }
  const update = () => { shade(); draw(); report(); };
  let animation = null;

  const api = {
    lightings: [], transferOrder: 0, kind: 'fiv', fivOn: onGpu ? 'gpu' : 'cpu', fivNote, vertexCount: positions.length / 3, receivers: 1, lights: 0,
    turnLocked: false, hasReferenceImage: false,
    instances: fiv.instances.map((i) => i.name),
    renderer: (() => {
      const debug = gl.getExtension('WEBGL_debug_renderer_info');
      return debug ? gl.getParameter(debug.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER);
    })(),
    set(changes) {
      if ('exposure' in changes) uniforms.exposure.value = Number(changes.exposure);
      for (const key of ['showSky', 'selected']) if (key in changes) state[key] = changes[key];
      if ('animate' in changes) {
        state.animate = !!changes.animate;
        if (state.animate && !animation) {
          const t0 = performance.now();
          const step = () => { if (!state.animate) { animation = null; return; } api.animate((performance.now() - t0) / 1000); animation = requestAnimationFrame(step); };
          animation = requestAnimationFrame(step);
        }
      }
      update();
      return { ...state };
    },
    state: () => ({ ...state, exposure: uniforms.exposure.value, rotate: 0 }),
    query,
    orbit(yaw, pitch, zoom = 1) { view3d.turn(yaw, pitch, zoom); draw(); report(); },
    camera: () => view3d.array(),
    metrics: () => null,
    frameMs: () => frameMs,
    shadeMs: () => shadeMs,
    // Instance k (order of the bundle's instances, the receiver left out) to translation [x, y, z].
    moveInstance(k, translation) {
      if (!fiv.instances[k] || translation.length !== 3 || translation.some((x) => !Number.isFinite(x))) throw new Error(`moveInstance: no instance ${k} or not 3 numbers`);
      fiv.instances[k].translation = translation.map(Math.fround);
      update();
    },
    translations: () => fiv.instances.map((i) => i.translation.slice()),
    // The receiver's radiance [V][3] as drawn (float32: the GPU pass read back, or the CPU's upload), for the tests.
    fivRadiance: () => {
      if (!gpu) return Array.from(radiance);
      const irradiance = gpu.read();
      return Array.from(irradiance, (e, i) => Math.fround(Math.fround(albedo[i % 3] / Math.PI) * e));
    },
    // The path at `seconds`: instance k circles its start at 1.5 bounding radii in the XZ plane, phase 2 pi k / N.
    animate(seconds) {
      fiv.instances.forEach((instance, k) => {
        const r = 1.5 * fiv.grids[instance.object].radius, a = 2 * Math.PI * (seconds / 4 + k / fiv.instances.length);
        instance.translation = [start[k][0] + r * Math.cos(a), start[k][1], start[k][2] + r * Math.sin(a)].map(Math.fround);
      });
      update();
    },
    // Moves the selected instance by a mouse drag of (dx, dy) pixels in the camera's right and up directions, scaled
    // so the instance follows the cursor at the target's distance.
    drag(dx, dy) {
      const instance = fiv.instances[state.selected];
      if (!instance) return;
      const { eye, target, up, fovy } = view3d.orbit;
      const forward = target.clone().sub(eye), distance = forward.length();
      forward.normalize();
      const right = forward.clone().cross(up).normalize(), upward = right.clone().cross(forward).normalize();
      const perPixel = 2 * distance * Math.tan(fovy * Math.PI / 360) / height;
      instance.translation = instance.translation.map((x, c) => Math.fround(x + perPixel * (dx * right.getComponent(c) - dy * upward.getComponent(c))));
      update();
    },
    read(points) {
      draw();
      return points.map(([x, y]) => {
        gl.readPixels(x, height - 1 - y, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
        return [pixel[0], pixel[1], pixel[2]];
      });
    },
    bench(frames) {
      renderer.render(scene, view3d.camera);
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
      const t0 = performance.now();
      for (let i = 0; i < frames; ++i) {
        renderer.render(scene, view3d.camera);
        gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
      }
      return (performance.now() - t0) / frames;
    },
    // Mean milliseconds per frame when an instance moves every frame: the CPU shading, the upload and the draw.
    benchMoving(frames) {
      const t0 = performance.now();
      for (let i = 0; i < frames; ++i) api.animate(i / 30);
      return (performance.now() - t0) / frames;
    },
  };
  update();
  return api;
}
