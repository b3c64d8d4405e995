// The environment map as the background: every pixel's ray of `prt render`'s pinhole camera, turned with the
// lighting, looks the map up (docs/conventions.md, equirectangular) and is tone-mapped as the surface is.
// The map is decoded by three.js's EXRLoader (any compression OpenEXR has, DWAB included) to float RGBA.
import * as THREE from 'three';
import { EXRLoader } from 'three/addons/loaders/EXRLoader.js';
import { toneMapGlsl } from './glsl.js';

const vertexShader = /* glsl */ `
precision highp float;
in vec3 position;
void main() { gl_Position = vec4(position.xy, 0.0, 1.0); }`;

// Pixel centre (x + 0.5, y + 0.5), row 0 at the top, as raycast.cpp pinholeRayDirection: sx = (2 (x + 0.5) / W - 1)
// halfWidth, sy = (1 - 2 (y + 0.5) / H) halfHeight, d = normalize(forward + sx right + sy up). The lighting turned by
// R about +Y shows the map at R^T d. Bilinear between texel centres, repeating in u and clamped in v.
const fragmentShader = /* glsl */ `
precision highp float;
precision highp int;
precision highp sampler2D;
uniform sampler2D sky;     // RGBA float, EXRLoader's rows: row 0 is the image's bottom row
uniform ivec2 skySize;
uniform vec2 viewport;     // W, H
uniform vec3 forward;
uniform vec3 right;
uniform vec3 up;
uniform vec2 halfExtent;   // halfWidth, halfHeight
uniform vec2 turn;         // cos, sin of the lighting's turn about +Y
uniform float exposure;
out vec4 colour;
${toneMapGlsl}
vec3 texel(int x, int y) {
  x = (x % skySize.x + skySize.x) % skySize.x;
  y = clamp(y, 0, skySize.y - 1);
  return texelFetch(sky, ivec2(x, skySize.y - 1 - y), 0).rgb;
}
void main() {
  vec2 s = (2.0 * gl_FragCoord.xy / viewport - 1.0) * halfExtent;
  vec3 d = normalize(forward + s.x * right + s.y * up);
  vec3 e = vec3(turn.x * d.x - turn.y * d.z, d.y, turn.y * d.x + turn.x * d.z);
  const float pi = 3.14159265358979;
  float theta = acos(clamp(e.y, -1.0, 1.0)), phi = atan(e.x, -e.z);
  vec2 at = vec2((phi + pi) / (2.0 * pi) * float(skySize.x), theta / pi * float(skySize.y)) - 0.5;
  ivec2 i = ivec2(floor(at));
  vec2 f = at - vec2(i);
  vec3 radiance = mix(mix(texel(i.x, i.y), texel(i.x + 1, i.y), f.x),
                      mix(texel(i.x, i.y + 1), texel(i.x + 1, i.y + 1), f.x), f.y);
  colour = vec4(toneMap(radiance), 1.0);
}`;

// Fetches and decodes the OpenEXR map at `url`. Returns {texture, width, height, data (Float32Array RGBA, rows
// bottom-up)}. Throws Error naming the URL.
export async function loadSky(url) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
  const loader = new EXRLoader();
  loader.setDataType(THREE.FloatType);
  let parsed;
  try { parsed = loader.parse(await response.arrayBuffer()); } catch (error) { throw new Error(`${url}: ${error.message}`); }
  const texture = new THREE.DataTexture(parsed.data, parsed.width, parsed.height, THREE.RGBAFormat, THREE.FloatType);
  texture.minFilter = texture.magFilter = THREE.NearestFilter;
  texture.generateMipmaps = false;
  texture.needsUpdate = true;
  return { texture, width: parsed.width, height: parsed.height, data: parsed.data };
}

// A full-screen triangle drawing the sky behind everything; set(sky, camera basis, turn) updates its uniforms.
export function skyMesh(exposureUniform) {
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array([-1, -1, 0, 3, -1, 0, -1, 3, 0]), 3));
  const uniforms = {
    sky: { value: null }, skySize: { value: new THREE.Vector2(1, 1) }, viewport: { value: new THREE.Vector2(1, 1) },
    forward: { value: new THREE.Vector3() }, right: { value: new THREE.Vector3() }, up: { value: new THREE.Vector3() },
    halfExtent: { value: new THREE.Vector2() }, turn: { value: new THREE.Vector2(1, 0) }, exposure: exposureUniform,
  };
  const material = new THREE.RawShaderMaterial({ vertexShader, fragmentShader, uniforms, glslVersion: THREE.GLSL3,
                                                 depthTest: false, depthWrite: false });
  const mesh = new THREE.Mesh(geometry, material);
  mesh.frustumCulled = false;
  mesh.renderOrder = -1;
  mesh.visible = false;
  // sky: loadSky's result or null (black); eye, target, up, fovy: the camera; degrees: the lighting's turn.
  mesh.userData.set = (sky, width, height, eye, target, upHint, fovy, degrees) => {
    mesh.visible = !!sky;
    if (!sky) return;
    uniforms.sky.value = sky.texture;
    uniforms.skySize.value.set(sky.width, sky.height);
    uniforms.viewport.value.set(width, height);
    const forward = target.clone().sub(eye).normalize();
    const right = forward.clone().cross(upHint).normalize();
    uniforms.forward.value.copy(forward);
    uniforms.right.value.copy(right);
    uniforms.up.value.copy(right.clone().cross(forward).normalize());
    const halfHeight = Math.tan(fovy * Math.PI / 360);
    uniforms.halfExtent.value.set(halfHeight * width / height, halfHeight);
    const t = degrees * Math.PI / 180;
    uniforms.turn.value.set(Math.cos(t), Math.sin(t));
  };
  return mesh;
}
