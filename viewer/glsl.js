// GLSL shared by the viewer's shaders, so each formula is written once.

// compare.h toneMap: x = radiance 2^exposure, Reinhard x / (1 + x), sRGB; the framebuffer rounds to 8 bits.
// Needs `uniform float exposure;` declared by the shader. With linearOutput (compare.js's float render target, for
// the comparison with a reference) the radiance passes through unchanged.
export const toneMapGlsl = /* glsl */ `
uniform bool linearOutput;
vec3 toneMap(vec3 radiance) {
  if (linearOutput) return radiance;
  vec3 x = max(radiance * exp2(exposure), 0.0);
  vec3 d = x / (1.0 + x);
  return mix(12.92 * d, 1.055 * pow(d, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), d));
}`;

// The SH sum of transfer row `row` (texels of a 2D array, layer j = coefficient j, rowsPerLine texels a line)
// with the lighting. Needs `transfer`, `coefficients`, `rowsPerLine`, `lighting[]` and kMaxCoefficients; `name`,
// `sampler` and `lightingName` name another such sum (the hybrid's bounce part: hybrid.js).
export const relightRowGlsl = (maxCoefficients, name = 'relightRow', sampler = 'transfer', lightingName = 'lighting') => /* glsl */ `
vec3 ${name}(int row) {
  ivec2 at = ivec2(row % rowsPerLine, row / rowsPerLine);
  vec3 sum = vec3(0.0);
  for (int j = 0; j < ${maxCoefficients}; ++j) {
    if (j >= coefficients) break;
    sum += texelFetch(${sampler}, ivec3(at, j), 0).rgb * ${lightingName}[j];
  }
  return sum;
}`;
