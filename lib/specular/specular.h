// Specular through SH triple products (seed 004's Phong path, issue 12): per vertex, the cosine-weighted
// visibility O(w) = V(w) max(0, n . w) as SH; at relight time the product L O with the lighting through the sparse
// Gaunt tensor of lib/sh, a zonal convolution with the normalised Phong lobe of docs/conventions.md ("Glossy
// BRDF"), and evaluation at the mirrored view direction R = 2 (n . wo) n - wo:
//
//   glossy(v) = ks sum_{l < B} lambda_l(n_e) sum_m (L O)_lm Y_lm(R)  ~  integral L V f_phong max(0, n . w) dw
//
// lambda_l(n_e) = (n_e + 2) I_l(n_e), I_l = integral_0^1 t^n_e P_l(t) dt, is the Funk-Hecke multiplier of the lobe
// (n_e + 2) / (2 pi) max(0, R . w)^n_e. The cosine sits in O, not in a second product, so the reference's integrand
// is one triple product; the diffuse part of the same surface is albedo / pi times L . O.
// "Adaptive bands": B is the number of bands whose multiplier relative to band 0 is at least a tolerance
// (lambda_l / lambda_0 ~ exp(-l^2 / (2 n_e)), so B grows like sqrt(n_e)), capped by what the product holds.
// docs/results.md "Specular through SH triple products" has the measurements.
#pragma once

#include "bundle.h"
#include "sh.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace prt::specular {

// ---- the Phong lobe's zonal multipliers (phong_zonal.cpp) ---------------------------------------------------
// lambda_l for l = 0 .. bands-1 of the normalised lobe (n_e + 2) / (2 pi) max(0, R . w)^n_e (ks = 1): the lobe
// convolved with Y_lm, evaluated at R, is lambda_l Y_lm(R). Exact by the recurrence I_l = (n_e - l + 2) /
// (n_e + l + 1) I_{l-2}, I_0 = 1 / (n_e + 1), I_1 = 1 / (n_e + 2); lambda_0 = (n_e + 2) / (n_e + 1) (the lobe's
// integral over its hemisphere). Needs exponent > 0 and 1 <= bands <= sh::kMaxOrder; throws prt::Error(kExitUsage).
std::vector<double> phongMultipliers(double exponent, int bands);

// Tolerance of the adaptive band count (relative multiplier lambda_l / lambda_0 below it is dropped).
inline constexpr double kDefaultBandTolerance = 0.02;

// The adaptive band count: 1 + the largest l < maxBands with |lambda_l / lambda_0| >= tolerance (so at least 1,
// at most maxBands). tolerance 0 keeps all maxBands. Needs exponent > 0, 1 <= maxBands <= sh::kMaxOrder,
// tolerance >= 0.
int adaptiveBands(double exponent, int maxBands, double tolerance = kDefaultBandTolerance);

// ---- the visibility layer (visibility.cpp) ------------------------------------------------------------------
struct VisibilityOptions {
    int order = 6;        // SH bands of O, 1..sh::kMaxOrder
    int samples = 1024;   // rays per vertex, 1..kMaxTransferSamples
    uint64_t seed = 0;
    int threads = 0;      // 0: all hardware threads; results do not depend on it
    bool progress = true;
};

struct Visibility {
    int order = 0;
    std::vector<float> coefficients; // [V][order^2]: SH of V(w) max(0, n . w) about the vertex normal
    uint64_t rays = 0;
    float rayOffset = 0.0f;
    double seconds = 0.0;
};

// O for every vertex by the shadowed transfer integrator of lib/transfer (its Hammersley set, per-vertex rotation
// hashed from (seed, vertex), the lib/raycast spawn rule, Embree occlusion rays; unoccluded vertices exact), at unit
// albedo times pi. Needs a mesh with normals (throws prt::Error naming the vertex otherwise) and options in range
// (kExitUsage). Bit-identical for any thread count.
Visibility computeVisibility(const TriMesh& mesh, const VisibilityOptions& options);

// The bundle layer: name "specular_visibility", semantic "sh_cosine_visibility", domain vertex, float32, shape
// [V, order^2], params order, samples, seed, direction_set, ray_offset, rays (docs/bundle.md "Specular visibility").
inline constexpr const char* kVisibilityLayer = "specular_visibility";
Layer visibilityLayer(const Visibility& visibility, const VisibilityOptions& options);

// Reads the layer back. Throws prt::Error naming `source` when it is missing (naming `prt specular`), has another
// semantic or domain, a shape other than [mesh vertices, order^2] with order = params.order, or non-finite values.
Visibility readVisibility(const Bundle& bundle, const std::string& source);

// ---- shading (shade.cpp) ------------------------------------------------------------------------------------
struct Phong {
    double exponent = 32.0; // n_e > 0
    double ks = 1.0;        // [0, 1]
};

// Per channel, the dense matrix M_c[i][k] = sum_j G_ijk L_jc (the Gaunt tensor contracted with the lighting),
// pre-scaled by ks lambda_l(i), for output coefficients i < bands^2 and visibility coefficients k < visibility
// order^2: then glossy_c = sum_i Y_i(R) sum_k M_c[i][k] O_k. Built once per lighting and lobe.
struct LightProduct {
    int lightOrder = 0, visibilityOrder = 0, bands = 0;
    std::vector<float> matrix; // [3][bands^2][visibilityOrder^2]
};

// Needs `tensor` = sh::tripleProduct(T) with T >= lightOrder, visibilityOrder and bands (it depends on no
// lighting: build it once), RGB lighting [lightOrder^2][3], 1 <= lightOrder, visibilityOrder, 1 <= bands <=
// lightOrder + visibilityOrder - 1 (the product's own bands), phong in range. Throws prt::Error(kExitUsage)
// otherwise. The tensor is exact (lib/sh), so M is the exact projection of L times O onto the product's first bands.
LightProduct lightProduct(const sh::TripleProduct& tensor, const float* lighting, int lightOrder, int visibilityOrder,
                          int bands, const Phong& phong);

// Glossy radiance toward `eye` at vertices [0, V) of `mesh` with visibility `o`: R the mirror of the unit
// direction to the eye about the vertex normal; zero where the eye is below the surface (n . wo <= 0), as the
// reference's lobe. Needs o.order == product.visibilityOrder and o sized for the mesh (throws prt::Error(kExitInput)
// naming the mismatch otherwise). radiance is [V][3]. Vertices run in parallel (TBB), each summed alone in a fixed
// order, so the result is bit-identical for any thread count.
void glossyRadiance(const TriMesh& mesh, const Visibility& o, const LightProduct& product, const float eye[3],
                    float* radiance);

// The same for one point: glossy radiance in direction R (unit) from visibility coefficients o
// (product.visibilityOrder^2 values). rgb gets 3 values.
void glossyAt(const LightProduct& product, const float* o, const double R[3], double rgb[3]);

} // namespace prt::specular
