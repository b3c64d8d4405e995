// Texture set-up the viewer's data textures share.
import * as THREE from 'three';

// Makes `texture` (a THREE.DataTexture or DataArrayTexture over a Float32Array of RGB triples) an RGB32F texture read
// texel for texel: nearest filtering, no mipmaps, uploaded on next use. Returns it.
export function rgbFloatNearest(texture) {
  texture.format = THREE.RGBFormat;
  texture.type = THREE.FloatType;
  texture.internalFormat = 'RGB32F';
  texture.minFilter = texture.magFilter = THREE.NearestFilter;
  texture.generateMipmaps = false;
  texture.needsUpdate = true;
  return texture;
}
