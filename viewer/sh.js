// Real spherical harmonics exactly as prt's lib/sh defines them (docs/conventions.md): orthonormal, no
// Condon-Shortley phase, index l*l+l+m, evaluated by the same associated-Legendre recurrence in (x, y, z), and
// lighting rotation about +Y as `prt relight --rotate-y` turns it.

const kMaxOrder = 16;

// N_m^m = N_{m-1}^{m-1} * diagonal[m]; N_l^m = a[l][m] z N_{l-1}^m - b[l][m] N_{l-2}^m (lib/sh/evaluate.cpp).
const diagonal = new Float64Array(kMaxOrder);
const a = [], b = [];
diagonal[0] = 0.5 / Math.sqrt(Math.PI);
for (let m = 1; m < kMaxOrder; ++m) diagonal[m] = Math.sqrt((2 * m + 1) / (2 * m));
for (let l = 0; l < kMaxOrder; ++l) {
  a.push(new Float64Array(kMaxOrder));
  b.push(new Float64Array(kMaxOrder));
  for (let m = 0; m < l; ++m) {
    const l2 = l * l, m2 = m * m, lm1 = (l - 1) * (l - 1);
    a[l][m] = Math.sqrt((4 * l2 - 1) / (l2 - m2));
    b[l][m] = a[l][m] * Math.sqrt((lm1 - m2) / (4 * lm1 - 1));
  }
}

// All order*order basis values at the unit direction (x, y, z).
export function evaluate(order, x, y, z, out = new Float64Array(order * order)) {
  let diag = diagonal[0], cosine = 1, sine = 0; // Re and Im of (x + i y)^m
  for (let m = 0; m < order; ++m) {
    if (m > 0) {
      diag *= diagonal[m];
      const c = x * cosine - y * sine;
      sine = x * sine + y * cosine;
      cosine = c;
    }
    let previous = 0, current = m > 0 ? Math.SQRT2 * diag : diag;
    for (let l = m; l < order; ++l) {
      if (l > m) {
        const next = a[l][m] * z * current - b[l][m] * previous;
        previous = current;
        current = next;
      }
      out[l * l + l + m] = current * cosine;
      if (m > 0) out[l * l + l - m] = current * sine;
    }
  }
  return out;
}

// Gauss-Legendre nodes and weights on [-1, 1] (Newton on P_n).
function gaussLegendre(n) {
  const nodes = new Float64Array(n), weights = new Float64Array(n);
  for (let i = 0; i < n; ++i) {
    let x = Math.cos(Math.PI * (i + 0.75) / (n + 0.5)), dp = 0;
    for (let iteration = 0; iteration < 100; ++iteration) {
      let p0 = 1, p1 = x;
      for (let k = 2; k <= n; ++k) [p0, p1] = [p1, ((2 * k - 1) * x * p1 - (k - 1) * p0) / k];
      if (n === 1) p1 = x, p0 = 1;
      dp = n * (x * p1 - p0) / (x * x - 1);
      const dx = p1 / dp;
      x -= dx;
      if (Math.abs(dx) < 1e-16) break;
    }
    nodes[n - 1 - i] = x;
    weights[n - 1 - i] = 2 / ((1 - x * x) * dp * dp);
  }
  return { nodes, weights };
}

// RGB lighting ([order^2][3], Float32Array) turned by `degrees` about +Y, right-handed (90 degrees takes +Z to +X),
// so f'(d) = f(R^T d). Each band rotates on its own, so a quadrature exact for the product of two band-(order-1)
// functions (Gauss-Legendre in z times uniform azimuth) gives the coefficients to rounding.
export function rotateLightingY(lighting, order, degrees) {
  const count = order * order;
  if (degrees === 0) return Float32Array.from(lighting.subarray(0, count * 3));
  const t = degrees * Math.PI / 180, c = Math.cos(t), s = Math.sin(t);
  const { nodes, weights } = gaussLegendre(order + 1);
  const azimuths = 2 * order + 2;
  const out = new Float64Array(count * 3), basis = new Float64Array(count), turned = new Float64Array(count);
  for (let i = 0; i < nodes.length; ++i) {
    const z = nodes[i], r = Math.sqrt(Math.max(0, 1 - z * z));
    for (let k = 0; k < azimuths; ++k) {
      const phi = 2 * Math.PI * (k + 0.5) / azimuths, x = r * Math.cos(phi), y = r * Math.sin(phi);
      const w = weights[i] * 2 * Math.PI / azimuths;
      evaluate(order, x, y, z, basis);
      // R^T d with R = [[c, 0, s], [0, 1, 0], [-s, 0, c]].
      evaluate(order, c * x - s * z, y, s * x + c * z, turned);
      const f = [0, 0, 0];
      for (let j = 0; j < count; ++j) for (let ch = 0; ch < 3; ++ch) f[ch] += lighting[j * 3 + ch] * turned[j];
      for (let j = 0; j < count; ++j) for (let ch = 0; ch < 3; ++ch) out[j * 3 + ch] += w * basis[j] * f[ch];
    }
  }
  return Float32Array.from(out);
}

// The first `count` RGB coefficients of `lighting`, zero where it has fewer (runtime.h fitLighting).
export function fitLighting(lighting, count) {
  const out = new Float32Array(count * 3);
  out.set(lighting.subarray(0, Math.min(lighting.length, count * 3)));
  return out;
}
