// Batched Levenberg-Marquardt for the spherical-Gaussian fit of glossy.h: one work item per problem, the same
// residuals as objective.cpp. Built with -D NL=lobes -D real=float|double.
#pragma OPENCL FP_CONTRACT OFF
#if defined(USE_DOUBLE)
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#endif
#define NP (NL * 5)
#ifndef vreal8
#define vreal8 float8
#define vreal float
#endif
#if defined(VECTOR_DOUBLE)
#define VLOAD(p) convert_double8(vload8(0, p))
#else
#define VLOAD(p) vload8(0, p)
#endif

typedef struct {
    real cost;
    real jtj[NP * NP];
    real g[NP];
} Normal;

inline real hsum(vreal8 v) {
    return (real)(((v.s0 + v.s1) + (v.s2 + v.s3)) + ((v.s4 + v.s5) + (v.s6 + v.s7)));
}

// Adds residual r with Jacobian row j (NP values) to the normal equations.
inline void addRow(real r, const real* j, Normal* n, int build) {
    n->cost += r * r;
    if (!build) return;
    for (int a = 0; a < NP; ++a) {
        n->g[a] += j[a] * r;
        for (int b = a; b < NP; ++b) n->jtj[a * NP + b] += j[a] * j[b];
    }
}

// Data residuals run 8 grid directions at a time (float8), so the CPU device uses its vector units; count is
// a multiple of 8 (the host pads the grid with zero-weight directions).
void evaluate(const real* x, int build, int count, int p, __global const float* table,
              __global const float* dirX, __global const float* dirY, __global const float* dirZ,
              __global const float* rootSolidAngle, real energy,
              __global const float* prior, real priorWeight, real weightMean, real weightWidth, real weightFlip, Normal* n) {
    n->cost = 0;
    if (build) {
        for (int a = 0; a < NP * NP; ++a) n->jtj[a] = 0;
        for (int a = 0; a < NP; ++a) n->g[a] = 0;
    }
    real mean[NL][3], len[NL], lam[NL];
    for (int k = 0; k < NL; ++k) {
        const real* q = x + k * 5;
        len[k] = sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        for (int c = 0; c < 3; ++c) mean[k][c] = q[1 + c] / len[k];
        lam[k] = exp(q[4]);
    }
    vreal8 jtjv[NP * (NP + 1) / 2], gv[NP], costv = (vreal8)(0);
    if (build) {
        for (int a = 0; a < NP * (NP + 1) / 2; ++a) jtjv[a] = (vreal8)(0);
        for (int a = 0; a < NP; ++a) gv[a] = (vreal8)(0);
    }
    __global const float* row = table + (size_t)p * count;
    vreal8 jv[NP];
    for (int i = 0; i < count; i += 8) {
        vreal8 w0 = VLOAD(dirX + i), w1 = VLOAD(dirY + i), w2 = VLOAD(dirZ + i);
        vreal8 root = VLOAD(rootSolidAngle + i);
        vreal8 model = (vreal8)(0);
        for (int k = 0; k < NL; ++k) {
            vreal8 cosine = (vreal)mean[k][0] * w0 + (vreal)mean[k][1] * w1 + (vreal)mean[k][2] * w2;
            vreal8 e = exp((vreal)lam[k] * (cosine - 1));
            vreal8 g = (vreal)x[k * 5] * e;
            model += g;
            jv[k * 5] = root * e;
            vreal8 along = root * g * (vreal)(lam[k] / len[k]);
            jv[k * 5 + 1] = along * (w0 - cosine * (vreal)mean[k][0]);
            jv[k * 5 + 2] = along * (w1 - cosine * (vreal)mean[k][1]);
            jv[k * 5 + 3] = along * (w2 - cosine * (vreal)mean[k][2]);
            jv[k * 5 + 4] = root * g * (vreal)lam[k] * (cosine - 1);
        }
        vreal8 r = root * (model - VLOAD(row + i));
        costv += r * r;
        if (build) {
            int index = 0;
            for (int a = 0; a < NP; ++a) {
                gv[a] += jv[a] * r;
                for (int b = a; b < NP; ++b) jtjv[index++] += jv[a] * jv[b];
            }
        }
    }
    n->cost = hsum(costv);
    if (build) {
        int index = 0;
        for (int a = 0; a < NP; ++a) {
            n->g[a] = hsum(gv[a]);
            for (int b = a; b < NP; ++b) n->jtj[a * NP + b] = hsum(jtjv[index++]);
        }
    }
    real j[NP];
    real rootEnergy = sqrt(energy);
    for (int k = 0; k < NL; ++k) { // gauge
        for (int a = 0; a < NP; ++a) j[a] = 0;
        for (int c = 0; c < 3; ++c) j[k * 5 + 1 + c] = rootEnergy * (real)2 * x[k * 5 + 1 + c];
        addRow(rootEnergy * (len[k] * len[k] - (real)1), j, n, build);
    }
    if (priorWeight == (real)0) return;
    real rootBeta = sqrt(weightMean * energy), rootGamma = sqrt(weightWidth * energy), rootDelta = sqrt(weightFlip * energy);
    for (int k = 0; k < NL; ++k)
        for (int c = 0; c < 3; ++c) {
            for (int a = 0; a < NP; ++a) j[a] = 0;
            for (int d = 0; d < 3; ++d)
                j[k * 5 + 1 + d] = rootBeta * (((c == d) ? (real)1 : (real)0) - mean[k][c] * mean[k][d]) / len[k];
            addRow(rootBeta * (mean[k][c] - (real)prior[k * 4 + c]), j, n, build);
        }
    for (int k = 0; k < NL; ++k) {
        for (int a = 0; a < NP; ++a) j[a] = 0;
        j[k * 5 + 4] = rootGamma;
        addRow(rootGamma * (x[k * 5 + 4] - (real)prior[k * 4 + 3]), j, n, build);
    }
    for (int k1 = 0; k1 < NL; ++k1)
        for (int k2 = k1 + 1; k2 < NL; ++k2) {
            real q[3], s = 0;
            for (int c = 0; c < 3; ++c) {
                q[c] = (real)prior[k1 * 4 + c] - (real)prior[k2 * 4 + c];
                s -= (mean[k1][c] - mean[k2][c]) * q[c];
            }
            if (s <= (real)0) continue;
            for (int a = 0; a < NP; ++a) j[a] = 0;
            real slope = (real)1.5 * rootDelta * sqrt(s);
            for (int d = 0; d < 3; ++d) {
                real d1 = 0, d2 = 0;
                for (int c = 0; c < 3; ++c) {
                    d1 -= q[c] * (((c == d) ? (real)1 : (real)0) - mean[k1][c] * mean[k1][d]) / len[k1];
                    d2 += q[c] * (((c == d) ? (real)1 : (real)0) - mean[k2][c] * mean[k2][d]) / len[k2];
                }
                j[k1 * 5 + 1 + d] = slope * d1;
                j[k2 * 5 + 1 + d] = slope * d2;
            }
            addRow(rootDelta * s * sqrt(s), j, n, build);
        }
}

// Solves (JtJ + mu D) step = -g by Cholesky; returns 0 when the damped matrix is not positive definite.
int dampedSolve(const Normal* n, real mu, real* step) {
    real a[NP * NP];
    for (int i = 0; i < NP; ++i)
        for (int k = i; k < NP; ++k) a[i * NP + k] = n->jtj[i * NP + k];
    // Marquardt's scaling, clamped as Ceres clamps it (min_lm_diagonal, max_lm_diagonal).
    for (int i = 0; i < NP; ++i) a[i * NP + i] += mu * clamp(n->jtj[i * NP + i], (real)1e-6, (real)1e32);
    for (int i = 0; i < NP; ++i) { // upper Cholesky: A = U^T U
        real s = a[i * NP + i];
        for (int k = 0; k < i; ++k) s -= a[k * NP + i] * a[k * NP + i];
        if (!(s > (real)0)) return 0;
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
        real t = -n->g[i];
        for (int k = 0; k < i; ++k) t -= a[k * NP + i] * y[k];
        y[i] = t / a[i * NP + i];
    }
    for (int i = NP - 1; i >= 0; --i) {
        real t = y[i];
        for (int k = i + 1; k < NP; ++k) t -= a[i * NP + k] * step[k];
        step[i] = t / a[i * NP + i];
    }
    return 1;
}

__kernel void fitLobes(int problems, int count, __global const float* table, __global const float* dirX,
                       __global const float* dirY, __global const float* dirZ,
                       __global const float* rootSolidAngle,
                       __global const float* energies, __global const float* amplitudeMax,
                       __global const float* priors, __global const float* priorWeights, float weightMean, float weightWidth,
                       float weightFlip, float logLambdaMin, float logLambdaMax, int maxIterations,
                       float relativeTolerance, __global float* params, __global float* costs,
                       __global int* iterations) {
    int p = get_global_id(0);
    if (p >= problems) return;
    real energy = energies[p];
    real x[NP], trial[NP], step[NP];
    for (int a = 0; a < NP; ++a) x[a] = params[(size_t)p * NP + a];
    if (!(energy > (real)0)) {
        costs[p] = 0;
        iterations[p] = 0;
        return;
    }
    __global const float* prior = priors + (size_t)p * NL * 4;
    real priorWeight = priorWeights[p];
    Normal n, t;
    evaluate(x, 1, count, p, table, dirX, dirY, dirZ, rootSolidAngle, energy, prior, priorWeight, weightMean, weightWidth, weightFlip,
             &n);
    // Ceres's Levenberg-Marquardt trust-region schedule: radius 1e4, grown by the gain ratio on success, shrunk
    // by a doubling factor on failure; steps projected onto the bounds.
    real radius = (real)1e4, decreaseFactor = (real)2;
    int it = 0;
    for (; it < maxIterations; ++it) {
        int solved = dampedSolve(&n, (real)1 / radius, step);
        real predicted = 0, stepNorm = 0, xNorm = 0;
        if (solved) {
            for (int a = 0; a < NP; ++a) trial[a] = x[a] + step[a];
            for (int k = 0; k < NL; ++k) {
                trial[k * 5] = clamp(trial[k * 5], (real)0, (real)amplitudeMax[p]);
                trial[k * 5 + 4] = clamp(trial[k * 5 + 4], (real)logLambdaMin, (real)logLambdaMax);
            }
            // Predicted decrease of |r + J d|^2 for the projected step d.
            for (int a = 0; a < NP; ++a) {
                step[a] = trial[a] - x[a];
                stepNorm += step[a] * step[a];
                xNorm += x[a] * x[a];
            }
            for (int a = 0; a < NP; ++a) {
                real row = 0;
                for (int b = 0; b < NP; ++b)
                    row += (a <= b ? n.jtj[a * NP + b] : n.jtj[b * NP + a]) * step[b];
                predicted -= (real)2 * n.g[a] * step[a] + step[a] * row;
            }
            if (sqrt(stepNorm) <= (real)1e-7 * (sqrt(xNorm) + (real)1e-7)) { ++it; break; } // parameter tolerance
            evaluate(trial, 0, count, p, table, dirX, dirY, dirZ, rootSolidAngle, energy, prior, priorWeight, weightMean,
                     weightWidth, weightFlip, &t);
        }
        real decrease = solved ? n.cost - t.cost : (real)0;
        real rho = predicted > (real)0 ? decrease / predicted : (real)-1;
        if (solved && decrease > (real)0 && rho > (real)1e-3) {
            for (int a = 0; a < NP; ++a) x[a] = trial[a];
            real q = (real)2 * rho - (real)1;
            radius = fmin(radius / fmax((real)1 / (real)3, (real)1 - q * q * q), (real)1e16);
            decreaseFactor = (real)2;
            real before = n.cost;
            evaluate(x, 1, count, p, table, dirX, dirY, dirZ, rootSolidAngle, energy, prior, priorWeight, weightMean, weightWidth,
                     weightFlip, &n);
            if (decrease <= (real)relativeTolerance * before) { ++it; break; } // function tolerance
        } else {
            radius /= decreaseFactor;
            decreaseFactor *= (real)2;
            if (radius < (real)1e-12) { ++it; break; }
        }
    }
    for (int a = 0; a < NP; ++a) params[(size_t)p * NP + a] = (float)x[a];
    costs[p] = (float)n.cost;
    iterations[p] = it;
}
