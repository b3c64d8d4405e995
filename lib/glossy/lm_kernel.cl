// Batched Levenberg-Marquardt for the spherical-Gaussian fit of glossy.h: one work item per problem, the same
// residuals as objective.cpp, in double, following the trust-region rules of Ceres 2.1's TrustRegionMinimizer
// with LEVENBERG_MARQUARDT (solve_ceres.cpp sets Ceres up the same way), so that from one start both take the
// same steps and stop at the same point. Built with -D NL=lobes -D CACHED=min((padded grid count) / 8, 192).
#pragma OPENCL FP_CONTRACT OFF
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#define NP (NL * 5)
typedef double real;
typedef double8 real8;
#define LOADF(p) convert_double8(vload8(0, p))
// Below this exponent (e < 2e-22 of the lobe's amplitude, far under its half ulp) 8 directions of a lobe count as
// zero: their exp, J^T r terms and moment products are skipped (docs/glossy.md "Solvers").
#define CUTOFF (-50.0)

typedef struct {
    real cost;          // sum of squared residuals (the objective of glossy.h)
    real jtj[NP * NP];  // upper triangle of J^T J
    real g[NP];         // J^T r
} Normal;

// What the normal equations at a point need from its cost pass: the lobes' unit means, lengths and
// sharpnesses, and for the first CACHED times 8 grid directions (all of them up to grid 16: 192 x 8 = 6 x 16^2;
// more would overflow PoCL's work-item stack) each lobe's values e (zero where the whole 8 lies below CUTOFF,
// which `live` records) and the data residuals d = model - kernel (not yet times root solid angle).
typedef struct {
    real mean[NL][3], len[NL], lam[NL];
    real8 e[NL][CACHED], d[CACHED];
    int live[NL][CACHED];
} Values;

// The one-sided data weight of glossy.h per direction: `over` (1 + FitWeights::overshoot) where the model lies
// above the kernel (d > 0), else 1; with over = 1 every product by it is exact, so the plain fit keeps its bits.
inline real8 oneSided(real8 d, real over) { return select((real8)(1), (real8)(over), d > (real8)(0)); }

inline real hsum(real8 v) { return ((v.s0 + v.s1) + (v.s2 + v.s3)) + ((v.s4 + v.s5) + (v.s6 + v.s7)); }

// Adds a residual r with Jacobian row j (NP values) to J^T r and J^T J (its square is in costAt).
inline void addRow(real r, const real* j, Normal* n) {
    for (int a = 0; a < NP; ++a) {
        n->g[a] += j[a] * r;
        for (int b = a; b < NP; ++b) n->jtj[a * NP + b] += j[a] * j[b];
    }
}

// Lobe values e[NL] (live[NL]: not all 8 below CUTOFF) and the data residual at the 8 directions from i, for
// the lobes of v (mean, len, lam); the one formula of costAt and of normalAt past the cache.
inline real8 chunkValues(const real* x, const Values* v, int i, __global const double* dirX,
                         __global const double* dirY, __global const double* dirZ, __global const float* row,
                         real8* e, int* live) {
    real8 w0 = vload8(0, dirX + i), w1 = vload8(0, dirY + i), w2 = vload8(0, dirZ + i), model = (real8)(0);
    #pragma unroll
    for (int k = 0; k < NL; ++k) {
        real8 cosine = v->mean[k][0] * w0 + v->mean[k][1] * w1 + v->mean[k][2] * w2;
        real8 exponent = v->lam[k] * (cosine - 1);
        live[k] = any(exponent > CUTOFF);
        e[k] = live[k] ? exp(exponent) : (real8)(0);
        model += x[k * 5] * e[k];
    }
    return model - LOADF(row + i);
}

// The objective at x (count grid directions, a multiple of 8: the host pads the grid with zero-weight
// directions), 8 directions at a time in double8, so that the CPU device uses its vector units; fills *v for
// normalAt. Summation order: the data term's 8 lanes in grid order, then gauge, mean, width and no-flip rows.
real costAt(const real* x, int count, int p, __global const float* table, __global const double* dirX,
            __global const double* dirY, __global const double* dirZ, __global const double* moments, real energy,
            __global const float* prior, real priorWeight, real weightMean, real weightWidth, real weightFlip,
            real over, Values* v) {
    for (int k = 0; k < NL; ++k) {
        const real* q = x + k * 5;
        v->len[k] = sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        for (int c = 0; c < 3; ++c) v->mean[k][c] = q[1 + c] / v->len[k];
        v->lam[k] = exp(q[4]);
    }
    __global const float* row = table + (size_t)p * count;
    real8 costv = (real8)(0);
    for (int c = 0; c < count / 8; ++c) {
        const int i = 8 * c;
        real8 e[NL];
        int live[NL];
        real8 d = chunkValues(x, v, i, dirX, dirY, dirZ, row, e, live);
        if (c < CACHED) {
            for (int k = 0; k < NL; ++k) v->e[k][c] = e[k], v->live[k][c] = live[k];
            v->d[c] = d;
        }
        real8 solidAngle = vload8(0, moments + (size_t)i * 10);
        costv = fma(solidAngle * oneSided(d, over) * d, d, costv);
    }
    real cost = hsum(costv);
    real rootEnergy = sqrt(energy);
    for (int k = 0; k < NL; ++k) { // gauge
        real r = rootEnergy * (v->len[k] * v->len[k] - 1);
        cost += r * r;
    }
    if (priorWeight == 0) return cost;
    real rootBeta = sqrt(weightMean * energy), rootGamma = sqrt(weightWidth * energy), rootDelta = sqrt(weightFlip * energy);
    for (int k = 0; k < NL; ++k)
        for (int c = 0; c < 3; ++c) {
            real r = rootBeta * (v->mean[k][c] - (real)prior[k * 4 + c]);
            cost += r * r;
        }
    for (int k = 0; k < NL; ++k) {
        real r = rootGamma * (x[k * 5 + 4] - (real)prior[k * 4 + 3]);
        cost += r * r;
    }
    for (int k1 = 0; k1 < NL; ++k1)
        for (int k2 = k1 + 1; k2 < NL; ++k2) {
            real s = 0;
            for (int c = 0; c < 3; ++c)
                s -= (v->mean[k1][c] - v->mean[k2][c]) * ((real)prior[k1 * 4 + c] - (real)prior[k2 * 4 + c]);
            if (s <= 0) continue;
            real r = rootDelta * s * sqrt(s);
            cost += r * r;
        }
    return cost;
}

// J^T r and J^T J (n->g, n->jtj; n->cost untouched) at the x whose costAt filled *v. With w^ = (1, w) and
// c = mean . w, lobe k's Jacobian row at direction i is root_i e_ki L_k w^_i, where L_k (5x4) holds only the
// problem's parameters (rows: amplitude (1, 0), mean a (0, I - m m^T) with a = amplitude lam / len, log
// sharpness b (-1, m) with b = amplitude lam). So J^T J's lobe block (k, l) is L_k S_kl L_l^T with
// S_kl = sum_i solidAngle_i e_ki e_li w^ w^T: 10 moments per lobe pair against the grid's moments `moments`
// (host-precomputed, shared by every problem; solidAngle times 1, x, y, z, xx, xy, xz, yy, yz, zz, for every 8
// directions i the 10 moments' 8 values at moments + 10 i), 30 products per 8 directions at 2 lobes instead of
// 55 plus the Jacobian. J^T r stays a sum of per-direction tangential terms, (a, b) x sum_i solidAngle_i e_ki
// d_i (1, w - c m, c - 1): through the moments its mean part is a difference of nearly equal terms for sharp
// lobes, which moved the end points (measured: one fit of 2000 into a 3.4x worse minimum). Every accumulator
// sums its directions in grid order; 8 directions where a lobe is not live add exact zeros and are skipped.
#define PAIRS (NL * (NL + 1) / 2)
#define BLOCK 8 // chunks of 8 directions per block; CACHED is a multiple of it or the whole grid
__constant int kMoment[4][4] = {{0, 1, 2, 3}, {1, 4, 5, 6}, {2, 5, 7, 8}, {3, 6, 8, 9}};
void normalAt(const real* x, int count, int p, __global const float* table, __global const double* dirX,
              __global const double* dirY, __global const double* dirZ, __global const double* moments, real energy,
              __global const float* prior, real priorWeight, real weightMean, real weightWidth, real weightFlip,
              real over, const Values* v, Normal* n) {
    for (int a = 0; a < NP * NP; ++a) n->jtj[a] = 0;
    for (int a = 0; a < NP; ++a) n->g[a] = 0;
    const int chunks = count / 8;
    __global const float* row = table + (size_t)p * count;
    real8 gv[NL][5], sv[PAIRS][10];
    for (int k = 0; k < NL; ++k)
        for (int m = 0; m < 5; ++m) gv[k][m] = (real8)(0);
    for (int a = 0; a < PAIRS; ++a)
        for (int m = 0; m < 10; ++m) sv[a][m] = (real8)(0);
    // Blocks of BLOCK x 8 directions, from the cache or (past it) computed again by chunkValues, bit-identical:
    // first each lobe's J^T r terms over the block, then each lobe pair's 10 moments, so that few accumulators
    // are live at a time.
    for (int c0 = 0; c0 < chunks; c0 += BLOCK) {
        const int size = min(BLOCK, chunks - c0);
        real8 eb[NL][BLOCK], db[BLOCK];
        int lb[NL][BLOCK];
        const real8 *e[NL], *d;
        const int* live[NL];
        if (c0 < CACHED) {
            for (int k = 0; k < NL; ++k) e[k] = v->e[k] + c0, live[k] = v->live[k] + c0;
            d = v->d + c0;
        } else {
            for (int b = 0; b < size; ++b) {
                real8 eo[NL];
                int lo[NL];
                db[b] = chunkValues(x, v, 8 * (c0 + b), dirX, dirY, dirZ, row, eo, lo);
                for (int k = 0; k < NL; ++k) eb[k][b] = eo[k], lb[k][b] = lo[k];
            }
            for (int k = 0; k < NL; ++k) e[k] = eb[k], live[k] = lb[k];
            d = db;
        }
        for (int k = 0; k < NL; ++k) {
            const real* mean = v->mean[k];
            real8 acc[5];
            #pragma unroll
            for (int m = 0; m < 5; ++m) acc[m] = gv[k][m];
            for (int b = 0; b < size; ++b) {
                if (!live[k][b]) continue;
                const int i = 8 * (c0 + b);
                real8 w0 = vload8(0, dirX + i), w1 = vload8(0, dirY + i), w2 = vload8(0, dirZ + i);
                real8 cosine = mean[0] * w0 + mean[1] * w1 + mean[2] * w2;
                real8 ed = vload8(0, moments + (size_t)i * 10) * e[k][b] * (oneSided(d[b], over) * d[b]);
                acc[0] += ed;
                acc[1] += ed * (w0 - cosine * mean[0]);
                acc[2] += ed * (w1 - cosine * mean[1]);
                acc[3] += ed * (w2 - cosine * mean[2]);
                acc[4] += ed * (cosine - 1);
            }
            #pragma unroll
            for (int m = 0; m < 5; ++m) gv[k][m] = acc[m];
        }
        int pair = 0;
        for (int k = 0; k < NL; ++k)
            for (int l = k; l < NL; ++l, ++pair) {
                real8 acc[10];
                #pragma unroll
                for (int m = 0; m < 10; ++m) acc[m] = sv[pair][m];
                for (int b = 0; b < size; ++b) {
                    if (!(live[k][b] && live[l][b])) continue;
                    real8 s = e[k][b] * e[l][b] * oneSided(d[b], over);
                    #pragma unroll
                    for (int m = 0; m < 10; ++m) acc[m] = fma(s, vload8(m, moments + (size_t)(c0 + b) * 80), acc[m]);
                }
                #pragma unroll
                for (int m = 0; m < 10; ++m) sv[pair][m] = acc[m];
            }
    }
    real lift[NL][5][4]; // L_k
    for (int k = 0; k < NL; ++k) {
        const real* mean = v->mean[k];
        real a = x[k * 5] * v->lam[k] / v->len[k], b = x[k * 5] * v->lam[k];
        for (int m = 0; m < 4; ++m) lift[k][0][m] = m == 0 ? 1.0 : 0.0;
        for (int c = 0; c < 3; ++c) {
            lift[k][1 + c][0] = 0;
            for (int m = 0; m < 3; ++m) lift[k][1 + c][1 + m] = a * (((c == m) ? 1.0 : 0.0) - mean[c] * mean[m]);
        }
        lift[k][4][0] = -b;
        for (int m = 0; m < 3; ++m) lift[k][4][1 + m] = b * mean[m];
        real factor[5] = {1, a, a, a, b};
        for (int r = 0; r < 5; ++r) n->g[k * 5 + r] = factor[r] * hsum(gv[k][r]);
    }
    int pair = 0;
    for (int k = 0; k < NL; ++k)
        for (int l = k; l < NL; ++l, ++pair) {
            real sum[10], left[5][4]; // left = L_k S_kl
            for (int m = 0; m < 10; ++m) sum[m] = hsum(sv[pair][m]);
            for (int r = 0; r < 5; ++r)
                for (int c = 0; c < 4; ++c) {
                    real t = 0;
                    for (int m = 0; m < 4; ++m) t += lift[k][r][m] * sum[kMoment[m][c]];
                    left[r][c] = t;
                }
            for (int r = 0; r < 5; ++r)
                for (int c = (k == l ? r : 0); c < 5; ++c) {
                    real t = 0;
                    for (int m = 0; m < 4; ++m) t += left[r][m] * lift[l][c][m];
                    n->jtj[(k * 5 + r) * NP + l * 5 + c] = t;
                }
        }
    real j[NP];
    real rootEnergy = sqrt(energy);
    for (int k = 0; k < NL; ++k) { // gauge: only lobe k's mean entries are non-zero (adding the zeros is exact)
        real r = rootEnergy * (v->len[k] * v->len[k] - 1), jm[3];
        for (int c = 0; c < 3; ++c) jm[c] = rootEnergy * 2 * x[k * 5 + 1 + c];
        for (int c = 0; c < 3; ++c) {
            n->g[k * 5 + 1 + c] += jm[c] * r;
            for (int d = c; d < 3; ++d) n->jtj[(k * 5 + 1 + c) * NP + k * 5 + 1 + d] += jm[c] * jm[d];
        }
    }
    if (priorWeight == 0) return;
    real rootBeta = sqrt(weightMean * energy), rootGamma = sqrt(weightWidth * energy), rootDelta = sqrt(weightFlip * energy);
    for (int k = 0; k < NL; ++k)
        for (int c = 0; c < 3; ++c) {
            for (int a = 0; a < NP; ++a) j[a] = 0;
            for (int d = 0; d < 3; ++d)
                j[k * 5 + 1 + d] = rootBeta * (((c == d) ? 1.0 : 0.0) - v->mean[k][c] * v->mean[k][d]) / v->len[k];
            addRow(rootBeta * (v->mean[k][c] - (real)prior[k * 4 + c]), j, n);
        }
    for (int k = 0; k < NL; ++k) {
        for (int a = 0; a < NP; ++a) j[a] = 0;
        j[k * 5 + 4] = rootGamma;
        addRow(rootGamma * (x[k * 5 + 4] - (real)prior[k * 4 + 3]), j, n);
    }
    for (int k1 = 0; k1 < NL; ++k1)
        for (int k2 = k1 + 1; k2 < NL; ++k2) {
            real q[3], s = 0;
            for (int c = 0; c < 3; ++c) {
                q[c] = (real)prior[k1 * 4 + c] - (real)prior[k2 * 4 + c];
                s -= (v->mean[k1][c] - v->mean[k2][c]) * q[c];
            }
            if (s <= 0) continue;
            for (int a = 0; a < NP; ++a) j[a] = 0;
            real slope = 1.5 * rootDelta * sqrt(s);
            for (int d = 0; d < 3; ++d) {
                real d1 = 0, d2 = 0;
                for (int c = 0; c < 3; ++c) {
                    d1 -= q[c] * (((c == d) ? 1.0 : 0.0) - v->mean[k1][c] * v->mean[k1][d]) / v->len[k1];
                    d2 += q[c] * (((c == d) ? 1.0 : 0.0) - v->mean[k2][c] * v->mean[k2][d]) / v->len[k2];
                }
                j[k1 * 5 + 1 + d] = slope * d1;
                j[k2 * 5 + 1 + d] = slope * d2;
            }
            addRow(rootDelta * s * sqrt(s), j, n);
        }
}

// Ceres's LM step in the Jacobi-scaled variables y = x / scale: (S J^T J S + D / radius) y = -S g with
// D = diag(S J^T J S) clamped to [1e-6, 1e32] (min_lm_diagonal, max_lm_diagonal), by Cholesky; step = S y.
// Returns 0 when the damped matrix is not positive definite (Ceres's linear solver failure: an invalid step).
int dampedSolve(const Normal* n, const real* scale, real radius, real* step) {
    real a[NP * NP];
    #pragma unroll
    for (int i = 0; i < NP; ++i)
        #pragma unroll
        for (int k = i; k < NP; ++k) a[i * NP + k] = scale[i] * n->jtj[i * NP + k] * scale[k];
    #pragma unroll
    for (int i = 0; i < NP; ++i) a[i * NP + i] += clamp(a[i * NP + i], 1e-6, 1e32) / radius;
    #pragma unroll
    for (int i = 0; i < NP; ++i) { // upper Cholesky: A = U^T U
        real s = a[i * NP + i];
        #pragma unroll
        for (int k = 0; k < i; ++k) s -= a[k * NP + i] * a[k * NP + i];
        if (!(s > 0)) return 0;
        real d = sqrt(s);
        a[i * NP + i] = d;
        #pragma unroll
        for (int c = i + 1; c < NP; ++c) {
            real t = a[i * NP + c];
            #pragma unroll
            for (int k = 0; k < i; ++k) t -= a[k * NP + i] * a[k * NP + c];
            a[i * NP + c] = t / d;
        }
    }
    real y[NP];
    #pragma unroll
    for (int i = 0; i < NP; ++i) {
        real t = -scale[i] * n->g[i];
        #pragma unroll
        for (int k = 0; k < i; ++k) t -= a[k * NP + i] * y[k];
        y[i] = t / a[i * NP + i];
    }
    #pragma unroll
    for (int i = NP - 1; i >= 0; --i) {
        real t = y[i];
        #pragma unroll
        for (int k = i + 1; k < NP; ++k) t -= a[i * NP + k] * y[k];
        y[i] = t / a[i * NP + i];
    }
    #pragma unroll
    for (int i = 0; i < NP; ++i) {
        step[i] = scale[i] * y[i];
        if (!isfinite(step[i])) return 0;
    }
    return 1;
}

// Projects x onto the bounds: amplitude in [0, amplitudeMax], log sharpness in [logMin, logMax].
inline void project(real* x, real amplitudeMax, real logMin, real logMax) {
    for (int k = 0; k < NL; ++k) {
        x[k * 5] = clamp(x[k * 5], 0.0, amplitudeMax);
        x[k * 5 + 4] = clamp(x[k * 5 + 4], logMin, logMax);
    }
}

// Ceres's gradient test: max |x - project(x - g)| (g = J^T r, the gradient of half the objective).
inline real projectedGradientNorm(const real* x, const real* g, real amplitudeMax, real logMin, real logMax) {
    real moved[NP], largest = 0;
    for (int a = 0; a < NP; ++a) moved[a] = x[a] - g[a];
    project(moved, amplitudeMax, logMin, logMax);
    for (int a = 0; a < NP; ++a) largest = fmax(largest, fabs(x[a] - moved[a]));
    return largest;
}

// One problem per work item. Writes the result, its objective (this kernel's own sum, in double) and the
// number of iterations Ceres would record (a step that ends the fit on a tolerance is not one).
__kernel void fitLobes(int problems, int count, __global const float* table, __global const double* dirX,
                       __global const double* dirY, __global const double* dirZ,
                       __global const double* moments,
                       __global const double* energies, __global const float* amplitudeMaxima,
                       __global const float* priors, __global const float* priorWeights, double weightMean,
                       double weightWidth, double weightFlip, double over, double logMin, double logMax,
                       int maxIterations,
                       double functionTolerance, double parameterTolerance, double gradientTolerance,
                       __global float* params, __global double* costs, __global int* iterations,
                       __global double* normals) {
    int p = get_global_id(0);
    if (p >= problems) return;
    real energy = energies[p], amplitudeMax = amplitudeMaxima[p];
    real x[NP], trial[NP], step[NP], scale[NP];
    for (int a = 0; a < NP; ++a) x[a] = params[(size_t)p * NP + a];
    if (!(energy > 0)) {
        costs[p] = 0;
        iterations[p] = 0;
        return;
    }
    __global const float* prior = priors + (size_t)p * NL * 4;
    real priorWeight = priorWeights[p];
    Normal n;
    Values v;
    project(x, amplitudeMax, logMin, logMax);
    n.cost = costAt(x, count, p, table, dirX, dirY, dirZ, moments, energy, prior, priorWeight, weightMean,
                    weightWidth, weightFlip, over, &v);
    normalAt(x, count, p, table, dirX, dirY, dirZ, moments, energy, prior, priorWeight, weightMean, weightWidth,
             weightFlip, over, &v, &n);
    for (int a = 0; a < NP; ++a) scale[a] = 1 / (1 + sqrt(n.jtj[a * NP + a])); // Jacobi scaling, fixed at the start
    real radius = 1e4, decreaseFactor = 2;
    int it = 0, invalid = 0;
    int done = projectedGradientNorm(x, n.g, amplitudeMax, logMin, logMax) <= gradientTolerance;
    while (!done && it < maxIterations) {
        ++it;
        int valid = dampedSolve(&n, scale, radius, step);
        real modelDecrease = 0; // of the objective, for the unprojected step: -(2 g.d + d^T J^T J d)
        if (valid) {
            for (int a = 0; a < NP; ++a) {
                real row = 0;
                for (int b = 0; b < NP; ++b) row += (a <= b ? n.jtj[a * NP + b] : n.jtj[b * NP + a]) * step[b];
                modelDecrease -= 2 * n.g[a] * step[a] + step[a] * row;
            }
            valid = modelDecrease > 0;
        }
        if (!valid) {
            if (++invalid >= 5) break; // max_num_consecutive_invalid_steps
            radius /= decreaseFactor;
            decreaseFactor *= 2;
            if (radius <= 1e-32) break;
            continue;
        }
        invalid = 0;
        real stepNorm = 0, xNorm = 0;
        for (int a = 0; a < NP; ++a) trial[a] = x[a] + step[a];
        project(trial, amplitudeMax, logMin, logMax);
        for (int a = 0; a < NP; ++a) stepNorm += (trial[a] - x[a]) * (trial[a] - x[a]), xNorm += x[a] * x[a];
        if (sqrt(stepNorm) <= parameterTolerance * (sqrt(xNorm) + parameterTolerance)) { --it; break; }
        // The cost at the candidate; its normal equations only once it is accepted, from the lobe values the
        // cost pass kept (so neither pass takes an exp twice, and a rejected step costs only the cost pass).
        real trialCost = costAt(trial, count, p, table, dirX, dirY, dirZ, moments, energy, prior, priorWeight,
                                weightMean, weightWidth, weightFlip, over, &v);
        real decrease = n.cost - trialCost;
        if (fabs(decrease) <= functionTolerance * n.cost) { --it; break; }
        real rho = decrease / modelDecrease;
        if (rho > 1e-3) { // min_relative_decrease
            for (int a = 0; a < NP; ++a) x[a] = trial[a];
            n.cost = trialCost;
            normalAt(x, count, p, table, dirX, dirY, dirZ, moments, energy, prior, priorWeight, weightMean,
                     weightWidth, weightFlip, over, &v, &n);
            real q = 2 * rho - 1;
            radius = fmin(radius / fmax(1.0 / 3.0, 1 - q * q * q), 1e16);
            decreaseFactor = 2;
            done = projectedGradientNorm(x, n.g, amplitudeMax, logMin, logMax) <= gradientTolerance;
        } else {
            radius /= decreaseFactor;
            decreaseFactor *= 2;
        }
        if (radius <= 1e-32) break;
    }
    for (int a = 0; a < NP; ++a) params[(size_t)p * NP + a] = (float)x[a];
    costs[p] = n.cost;
    iterations[p] = it;
}

// The normal equations at the given parameters (projected onto the bounds first, as fitLobes starts), for the
// tests: cost, then g = J^T r (NP), then J^T J (NP x NP, both triangles), per problem in `normals`. Takes the
// arguments of fitLobes; changes no parameters.
__kernel void normalEquations(int problems, int count, __global const float* table, __global const double* dirX,
                              __global const double* dirY, __global const double* dirZ,
                              __global const double* moments,
                              __global const double* energies, __global const float* amplitudeMaxima,
                              __global const float* priors, __global const float* priorWeights, double weightMean,
                              double weightWidth, double weightFlip, double over, double logMin, double logMax,
                              int maxIterations,
                              double functionTolerance, double parameterTolerance, double gradientTolerance,
                              __global float* params, __global double* costs, __global int* iterations,
                              __global double* normals) {
    int p = get_global_id(0);
    if (p >= problems) return;
    real x[NP];
    for (int a = 0; a < NP; ++a) x[a] = params[(size_t)p * NP + a];
    project(x, amplitudeMaxima[p], logMin, logMax);
    Normal n;
    Values v;
    __global const float* prior = priors + (size_t)p * NL * 4;
    n.cost = costAt(x, count, p, table, dirX, dirY, dirZ, moments, energies[p], prior, priorWeights[p], weightMean,
                    weightWidth, weightFlip, over, &v);
    normalAt(x, count, p, table, dirX, dirY, dirZ, moments, energies[p], prior, priorWeights[p], weightMean,
             weightWidth, weightFlip, over, &v, &n);
    __global double* out = normals + (size_t)p * (1 + NP + NP * NP);
    out[0] = n.cost;
    for (int a = 0; a < NP; ++a) {
        out[1 + a] = n.g[a];
        for (int b = 0; b < NP; ++b) out[1 + NP + a * NP + b] = a <= b ? n.jtj[a * NP + b] : n.jtj[b * NP + a];
    }
    costs[p] = n.cost;
    iterations[p] = 0;
}
