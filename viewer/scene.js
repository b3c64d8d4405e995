// Scene bundles (docs/bundle.md, "Scene bundles (version 3)"): the glTF asset kept intact plus irradiance transfer
// per receiver. three.js's GLTFLoader decodes the asset (accessors, images, samplers, KHR_texture_transform); this
// file places every receiver (a primitive under a node of the default scene) with its node's world matrix, relights
// its rows on the GPU and multiplies per pixel by the material's diffuse albedo, as `prt render` does:
//   albedo = baseColorFactor.rgb * baseColorTexture.rgb (sRGB-decoded, bilinear between texel centres or nearest,
//            no mipmaps) * COLOR_0.rgb * (1 - metallicFactor), clamped to [0, 1];
//   MASK (and BLEND, taken as MASK) discards where factor.a * texture.a * COLOR_0.a < alphaCutoff (0.5 by default);
//   a primitive without material is white and not metallic; back faces are black.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { relightRowGlsl, toneMapGlsl } from './glsl.js';
import { hybridGlsl } from './hybrid.js';

const kMaxCoefficients = 64; // order 8, as viewer.js

const vertexShader = /* glsl */ `
precision highp float;
precision highp int;
precision highp sampler2DArray;
uniform mat4 modelViewMatrix;
uniform mat4 projectionMatrix;
uniform sampler2DArray transfer;
uniform int coefficients;
uniform int rowsPerLine;
uniform vec3 lighting[${kMaxCoefficients}];
uniform int firstRow;      // the receiver's first row in the transfer layer
uniform mat3 uvTransform;  // KHR_texture_transform of the base colour texture (identity without)
uniform int texCoord;      // the texture's TEXCOORD set
uniform bool hasColor;     // COLOR_0 present
uniform mat3 normalWorld;  // the node's normal matrix (inverse transpose of its world matrix's linear part)
in vec3 position;
in vec3 normal;
in vec2 uv;
in vec2 uv1;
in vec4 color;
out vec3 vRelit;
out vec2 vUv;
out vec4 vColor;
${relightRowGlsl(kMaxCoefficients)}
${hybridGlsl(kMaxCoefficients, false)}
void main() {
  int row = firstRow + gl_VertexID; // rows are the primitive's vertices in accessor order
  vRelit = relightRow(row);
  // Hybrid lights (hybrid.js) at albedo 1, in world space: the materials multiply per pixel, as prt relight --lights
  // --image draws a scene.
  if (hybrid) vRelit += hybridLightsAt(row, normalWorld * normal, vec3(1.0));
  vUv = (uvTransform * vec3(texCoord == 1 ? uv1 : uv, 1.0)).xy;
  vColor = hasColor ? color : vec4(1.0);
  gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
}`;

const fragmentShader = /* glsl */ `
precision highp float;
precision highp int;
uniform sampler2D map;
uniform bool hasMap;
uniform vec4 baseColorFactor;
uniform float metallic;
uniform float alphaCutoff; // negative when the material is OPAQUE
uniform float exposure;
in vec3 vRelit;
in vec2 vUv;
in vec4 vColor;
out vec4 colour;
${toneMapGlsl}
void main() {
  vec4 base = baseColorFactor * vColor;
  if (hasMap) base *= texture(map, vUv);
  if (base.a < alphaCutoff) discard; // a cut-out texel is not there, whichever side is seen
  if (!gl_FrontFacing) { colour = vec4(0.0, 0.0, 0.0, 1.0); return; }
  vec3 albedo = clamp(base.rgb * (1.0 - metallic), 0.0, 1.0);
  colour = vec4(toneMap(albedo * vRelit), 1.0);
}`;

// The world matrix of every node of the default scene (glTF: matrix, or T R S, composed down from the roots).
function nodeWorldMatrices(json) {
  const world = new Map();
  const visit = (index, parent, depth) => {
    if (depth > 256) throw new Error('scene bundle: node tree deeper than 256');
    const node = json.nodes[index];
    if (!node) throw new Error(`scene bundle: node ${index} does not exist`);
    const local = new THREE.Matrix4();
    if (node.matrix) local.fromArray(node.matrix);
    else local.compose(new THREE.Vector3().fromArray(node.translation || [0, 0, 0]),
                       new THREE.Quaternion().fromArray(node.rotation || [0, 0, 0, 1]),
                       new THREE.Vector3().fromArray(node.scale || [1, 1, 1]));
    const m = parent.clone().multiply(local);
    world.set(index, m);
    for (const child of node.children || []) visit(child, m, depth + 1);
  };
  const scene = json.scenes[json.scene || 0];
  for (const root of scene.nodes || []) visit(root, new THREE.Matrix4(), 0);
  return world;
}

// Parses the scene bundle's bytes with GLTFLoader and returns {group, materials} where group holds one THREE.Mesh
// per receiver (`receivers` from readSceneTransfer), each drawn with the relighting material above; `shared` holds
// the uniforms every receiver shares (transfer, coefficients, rowsPerLine, lighting, exposure, and hybridUniforms'
// of hybrid.js), by reference. With `hybrid` every receiver must have normals (the cone lights need them).
export async function sceneMeshes(arrayBuffer, json, receivers, shared, hybrid = false) {
  const gltf = await new Promise((resolve, reject) => new GLTFLoader().parse(arrayBuffer, '', resolve, reject));
  const parser = gltf.parser;
  const world = nodeWorldMatrices(json);
  const group = new THREE.Group();
  const materialCache = new Map();
  for (const [k, r] of receivers.entries()) {
    if (!world.has(r.node)) throw new Error(`scene bundle: receiver ${k}'s node ${r.node} is not in the default scene`);
    if (json.nodes[r.node].mesh !== r.mesh) throw new Error(`scene bundle: receiver ${k}'s node ${r.node} does not show mesh ${r.mesh}`);
    const loaded = await parser.getDependency('mesh', r.mesh);
    const primitiveMesh = loaded.isGroup ? loaded.children[r.primitive] : (r.primitive === 0 ? loaded : null);
    if (!primitiveMesh || !primitiveMesh.isMesh) throw new Error(`scene bundle: mesh ${r.mesh} has no triangle primitive ${r.primitive}`);
    const geometry = primitiveMesh.geometry;
    if (geometry.attributes.position.count !== r.rows)
      throw new Error(`scene bundle: receiver ${k} has ${r.rows} rows for ${geometry.attributes.position.count} vertices`);
    if (hybrid && !geometry.attributes.normal)
      throw new Error(`lights: receiver ${k} (mesh ${r.mesh}, primitive ${r.primitive}) has no normals for the cone ` +
                      'lights (prt meshprep)');
    const primitiveDef = json.meshes[r.mesh].primitives[r.primitive];
    const key = `${primitiveDef.material}:${!!geometry.attributes.color}`;
    if (!materialCache.has(key)) materialCache.set(key, relightMaterial(json, primitiveDef.material, primitiveMesh.material, geometry, shared));
    const template = materialCache.get(key);
    // Each receiver has its own first row: a clone shares the program and the textures, with its own uniform.
    const material = template.clone();
    for (const name of Object.keys(shared)) material.uniforms[name] = shared[name];
    material.uniforms.map.value = template.uniforms.map.value;
    material.uniforms.firstRow = { value: r.first_row };
    material.uniforms.normalWorld = { value: new THREE.Matrix3().getNormalMatrix(world.get(r.node)) };
    const mesh = new THREE.Mesh(geometry, material);
    mesh.matrixAutoUpdate = false;
    mesh.matrix.copy(world.get(r.node));
    mesh.frustumCulled = false;
    group.add(mesh);
  }
  group.updateMatrixWorld(true);
  return { group, receivers: group.children.length };
}

// The relighting material of glTF material `index` (undefined: white, not metallic). `loaded` is GLTFLoader's
// material for it, whose base colour texture (`map`) carries the image, the sampler and KHR_texture_transform.
function relightMaterial(json, index, loaded, geometry, shared) {
  const def = index === undefined ? {} : json.materials[index];
  const pbr = def.pbrMetallicRoughness || {};
  const factor = pbr.baseColorFactor || [1, 1, 1, 1];
  const metallic = index === undefined ? 0 : (pbr.metallicFactor === undefined ? 1 : pbr.metallicFactor);
  const mode = def.alphaMode || 'OPAQUE';
  const cutoff = mode === 'OPAQUE' ? -1 : (def.alphaCutoff === undefined ? 0.5 : def.alphaCutoff);
  let map = pbr.baseColorTexture && loaded && loaded.map ? loaded.map : null;
  if (map) {
    // prt's sampling (lib/material): bilinear between texel centres, or nearest for a NEAREST magnification
    // filter, never mipmaps; three's GPU upload decodes sRGB (SRGB8_ALPHA8) before filtering, as prt decodes first.
    map.colorSpace = THREE.SRGBColorSpace;
    const nearest = map.magFilter === THREE.NearestFilter;
    map.magFilter = map.minFilter = nearest ? THREE.NearestFilter : THREE.LinearFilter;
    map.generateMipmaps = false;
    map.anisotropy = 1;
    map.updateMatrix();
    map.needsUpdate = true;
  }
  return new THREE.RawShaderMaterial({
    vertexShader, fragmentShader, glslVersion: THREE.GLSL3, side: THREE.DoubleSide,
    uniforms: {
      ...shared,
      firstRow: { value: 0 },
      normalWorld: { value: new THREE.Matrix3() },
      uvTransform: { value: map ? map.matrix.clone() : new THREE.Matrix3() },
      texCoord: { value: map ? map.channel || 0 : 0 },
      hasColor: { value: !!geometry.attributes.color },
      map: { value: map },
      hasMap: { value: !!map },
      baseColorFactor: { value: new THREE.Vector4(...factor) },
      metallic: { value: metallic },
      alphaCutoff: { value: cutoff },
    },
  });
}
