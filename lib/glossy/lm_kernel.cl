// Batched Levenberg-Marquardt for the spherical-Gaussian fit of glossy.h: one work item per problem, the same
// residuals as objective.cpp, in double, following the trust-region rules of Ceres 2.1's TrustRegionMinimizer
// with LEVENBERG_MARQUARDT (solve_ceres.cpp sets Ceres up the same way), so that from one start both take the
// same steps and stop at the same point. Built with -D NL=lobes.
#pragma OPENCL FP_CONTRACT OFF
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#define NP (NL * 5)
typedef double real;
typedef double8 real8;
#define LOADF(p) convert_double8(vload8(0, p))

typedef struct {
    real cost;          // sum of squared residuals (the objective of glossy.h)
    real jtj[NP * NP];  // upper triangle of J^T J
    real g[NP];         // J^T r
} Normal;

inline real hsum(real8 v) { return ((v.s0 + v.s1) + (v.s2 + v.s3)) + ((v.s4 + v.s5) + (v.s6 + v.s7)); }

// Adds residual r with Jacobian row j (NP values) to the normal equations.
inline void addRow(real r, const real* j, Normal* n) {
    n->cost += r * r;
    for (int a = 0; a < NP; ++a) {
        n->g[a] += j[a] * r;
        for (int b = a; b < NP; ++b) n->jtj[a * NP + b] += j[a] * j[b];
    }
}

// The data term, 8 grid directions at a time (double8, so the CPU device uses its vector units). With
// w^ = (1, w) and c = mean . w, lobe k's Jacobian row at direction i is root_i e_ki L_k w^_i, where L_k (5x4)
// holds only the problem's parameters (rows: amplitude (1, 0), mean a (0, I - m m^T) with a = amplitude lam / len,
// log sharpness b (-1, m) with b = amplitude lam). So J^T J's lobe block (k, l) is L_k S_kl L_l^T with
// S_kl = sum_i solidAngle_i e_ki e_li w^ w^T: 10 moments per lobe pair against the grid's moments `moments`
// (host-precomputed, shared by every problem; solidAngle times 1, x, y, z, xx, xy, xz, yy, yz, zz, for every 8
// directions i the 10 moments' 8 values at moments + 10 i), 30 products per 8 directions at 2 lobes instead of 55 plus the Jacobian. J^T r stays a sum of
// per-direction tangential terms, (a, b) x sum_i solidAngle_i e_ki d_i (1, w - c m, c - 1) with d = model -
// kernel: through the moments its mean part is a difference of nearly equal terms for sharp lobes, which moved
// the end points (measured: one fit of 2000 into a 3.4x worse minimum). Count is a multiple of 8 (the host pads
// the grid with zero-weight directions).
#define PAIRS (NL * (NL + 1) / 2)
#define BLOCK 8
__constant int kMoment[4][4] = {{0, 1, 2, 3}, {1, 4, 5, 6}, {2, 5, 7, 8}, {3, 6, 8, 9}};
void evaluate(const real* x, int count, int p, __global const float* table,
              __global const float* dirX, __global const float* dirY, __global const float* dirZ,
              __global const double* moments, real energy,
              __global const float* prior, real priorWeight, real weightMean, real weightWidth, real weightFlip, Normal* n) {
    n->cost = 0;
    for (int a = 0; a < NP * NP; ++a) n->jtj[a] = 0;
    for (int a = 0; a < NP; ++a) n->g[a] = 0;
    real mean[NL][3], len[NL], lam[NL];
    for (int k = 0; k < NL; ++k) {
        const real* q = x + k * 5;
        len[k] = sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        for (int c = 0; c < 3; ++c) mean[k][c] = q[1 + c] / len[k];
        lam[k] = exp(q[4]);
    }
    real8 sv[PAIRS][10], gv[NL][5], costv = (real8)(0);
    for (int a = 0; a < PAIRS; ++a)
        for (int m = 0; m < 10; ++m) sv[a][m] = (real8)(0);
    for (int k = 0; k < NL; ++k)
        for (int m = 0; m < 5; ++m) gv[k][m] = (real8)(0);
    __global const float* row = table + (size_t)p * count;
    // Blocks of BLOCK x 8 directions: first the lobes, cost and J^T r over the block (e kept), then each lobe
    // pair's 10 moments over it, so that few accumulators are live at a time (all 30 + 10 at once spill to the
    // stack); every accumulator still sums its directions in grid order.
    for (int i0 = 0; i0 < count; i0 += 8 * BLOCK) {
        const int chunks = min(BLOCK, (count - i0) / 8);
        real8 eb[NL][BLOCK];
        for (int c = 0; c < chunks; ++c) {
            const int i = i0 + 8 * c;
            real8 w0 = LOADF(dirX + i), w1 = LOADF(dirY + i), w2 = LOADF(dirZ + i);
            real8 model = (real8)(0), e[NL], cosine[NL];
            #pragma unroll
            for (int k = 0; k < NL; ++k) {
                cosine[k] = mean[k][0] * w0 + mean[k][1] * w1 + mean[k][2] * w2;
                e[k] = exp(lam[k] * (cosine[k] - 1));
                eb[k][c] = e[k];
                model += x[k * 5] * e[k];
            }
            real8 d = model - LOADF(row + i);
            real8 solidAngle = vload8(0, moments + (size_t)i * 10);
            costv = fma(solidAngle * d, d, costv);
            #pragma unroll
            for (int k = 0; k < NL; ++k) {
                real8 ed = solidAngle * e[k] * d, c = cosine[k];
                gv[k][0] += ed;
                gv[k][1] += ed * (w0 - c * mean[k][0]);
                gv[k][2] += ed * (w1 - c * mean[k][1]);
                gv[k][3] += ed * (w2 - c * mean[k][2]);
                gv[k][4] += ed * (c - 1);
            }
        }
        int pair = 0;
        for (int k = 0; k < NL; ++k)
            for (int l = k; l < NL; ++l, ++pair) {
                real8 acc[10];
                #pragma unroll
                for (int m = 0; m < 10; ++m) acc[m] = sv[pair][m];
                for (int c = 0; c < chunks; ++c) {
                    const int i = i0 + 8 * c;
                    real8 s = eb[k][c] * eb[l][c];
                    #pragma unroll
                    for (int m = 0; m < 10; ++m) acc[m] = fma(s, vload8(m, moments + (size_t)i * 10), acc[m]);
                }
                #pragma unroll
                for (int m = 0; m < 10; ++m) sv[pair][m] = acc[m];
            }
    }
    n->cost = hsum(costv);
    {
        real lift[NL][5][4]; // L_k
        for (int k = 0; k < NL; ++k) {
            real a = x[k * 5] * lam[k] / len[k], b = x[k * 5] * lam[k];
            for (int m = 0; m < 4; ++m) lift[k][0][m] = m == 0 ? 1.0 : 0.0;
            for (int c = 0; c < 3; ++c) {
                lift[k][1 + c][0] = 0;
                for (int m = 0; m < 3; ++m) lift[k][1 + c][1 + m] = a * (((c == m) ? 1.0 : 0.0) - mean[k][c] * mean[k][m]);
            }
            lift[k][4][0] = -b;
            for (int m = 0; m < 3; ++m) lift[k][4][1 + m] = b * mean[k][m];
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
    }
    real j[NP];
    real rootEnergy = sqrt(energy);
    for (int k = 0; k < NL; ++k) { // gauge: only lobe k's mean entries are non-zero (adding the zeros is exact)
        real r = rootEnergy * (len[k] * len[k] - 1), jm[3];
        for (int c = 0; c < 3; ++c) jm[c] = rootEnergy * 2 * x[k * 5 + 1 + c];
        n->cost += r * r;
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
            for (int d = 0; d < 3; ++d) j[k * 5 + 1 + d] = rootBeta * (((c == d) ? 1.0 : 0.0) - mean[k][c] * mean[k][d]) / len[k];
            addRow(rootBeta * (mean[k][c] - (real)prior[k * 4 + c]), j, n);
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
                s -= (mean[k1][c] - mean[k2][c]) * q[c];
            }
            if (s <= 0) continue;
            for (int a = 0; a < NP; ++a) j[a] = 0;
            real slope = 1.5 * rootDelta * sqrt(s);
            for (int d = 0; d < 3; ++d) {
                real d1 = 0, d2 = 0;
                for (int c = 0; c < 3; ++c) {
                    d1 -= q[c] * (((c == d) ? 1.0 : 0.0) - mean[k1][c] * mean[k1][d]) / len[k1];
                    d2 += q[c] * (((c == d) ? 1.0 : 0.0) - mean[k2][c] * mean[k2][d]) / len[k2];
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
    for (int i = 0; i < NP; ++i)
        for (int k = i; k < NP; ++k) a[i * NP + k] = scale[i] * n->jtj[i * NP + k] * scale[k];
    for (int i = 0; i < NP; ++i) a[i * NP + i] += clamp(a[i * NP + i], 1e-6, 1e32) / radius;
    for (int i = 0; i < NP; ++i) { // upper Cholesky: A = U^T U
        real s = a[i * NP + i];
        for (int k = 0; k < i; ++k) s -= a[k * NP + i] * a[k * NP + i];
        if (!(s > 0)) return 0;
        real d = sqrt(s);
        a[i * NP + i] = d;
        for (int c = i + 1; c < NP; ++c) {
            real t = a[i * NP + c];
            for (int k = 0; k < i; ++k) t -= a[k * NP + i] * a[k * NP + c];
            a[i * NP + c] = t / d;
        }
    }
    real y[NP];
    for (int i = 0; i < NP; ++i) {
        real t = -scale[i] * n->g[i];
        for (int k = 0; k < i; ++k) t -= a[k * NP + i] * y[k];
        y[i] = t / a[i * NP + i];
    }
    for (int i = NP - 1; i >= 0; --i) {
        real t = y[i];
        for (int k = i + 1; k < NP; ++k) t -= a[i * NP + k] * y[k];
        y[i] = t / a[i * NP + i];
    }
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
__kernel void fitLobes(int problems, int count, __global const float* table, __global const float* dirX,
                       __global const float* dirY, __global const float* dirZ,
                       __global const double* moments,
                       __global const double* energies, __global const float* amplitudeMaxima,
                       __global const float* priors, __global const float* priorWeights, double weightMean,
                       double weightWidth, double weightFlip, double logMin, double logMax, int maxIterations,
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
    Normal n, t;
    project(x, amplitudeMax, logMin, logMax);
    evaluate(x, count, p, table, dirX, dirY, dirZ, moments, energy, prior, priorWeight, weightMean, weightWidth,
             weightFlip, &n);
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
        // The normal equations at the candidate too: an accepted step then needs no second pass over the grid
        // (the cost comes out bit-identical either way; a rejected step wastes the J^T J part).
        evaluate(trial, count, p, table, dirX, dirY, dirZ, moments, energy, prior, priorWeight, weightMean,
                 weightWidth, weightFlip, &t);
        real decrease = n.cost - t.cost;
        if (fabs(decrease) <= functionTolerance * n.cost) { --it; break; }
        real rho = decrease / modelDecrease;
        if (rho > 1e-3) { // min_relative_decrease
            for (int a = 0; a < NP; ++a) x[a] = trial[a];
            n = t;
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
__kernel void normalEquations(int problems, int count, __global const float* table, __global const float* dirX,
                              __global const float* dirY, __global const float* dirZ,
                              __global const double* moments,
                              __global const double* energies, __global const float* amplitudeMaxima,
                              __global const float* priors, __global const float* priorWeights, double weightMean,
                              double weightWidth, double weightFlip, double logMin, double logMax, int maxIterations,
                              double functionTolerance, double parameterTolerance, double gradientTolerance,
                              __global float* params, __global double* costs, __global int* iterations,
                              __global double* normals) {
    int p = get_global_id(0);
    if (p >= problems) return;
    real x[NP];
    for (int a = 0; a < NP; ++a) x[a] = params[(size_t)p * NP + a];
    project(x, amplitudeMaxima[p], logMin, logMax);
    Normal n;
    evaluate(x, count, p, table, dirX, dirY, dirZ, moments, energies[p], priors + (size_t)p * NL * 4,
             priorWeights[p], weightMean, weightWidth, weightFlip, &n);
    __global double* out = normals + (size_t)p * (1 + NP + NP * NP);
    out[0] = n.cost;
    for (int a = 0; a < NP; ++a) {
        out[1 + a] = n.g[a];
        for (int b = 0; b < NP; ++b) out[1 + NP + a * NP + b] = a <= b ? n.jtj[a * NP + b] : n.jtj[b * NP + a];
    }
    costs[p] = n.cost;
    iterations[p] = 0;
}
