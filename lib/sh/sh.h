// Real spherical harmonics: evaluation, rotation, windowing, triple products and environment projection.
// Convention (orthonormal, no Condon-Shortley phase, index l*l+l+m, "order L" = L bands = L*L coefficients):
// docs/conventions.md. Coefficient arrays of RGB functions are [coefficient][3].
#pragma once

#include "image.h"

#include <cstdint>
#include <string>
#include <vector>

namespace prt::sh {

// Highest supported order (bands). Evaluation is stable to at least this order.
inline constexpr int kMaxOrder = 32;

inline constexpr int coefficientCount(int order) { return order * order; }
inline constexpr int index(int l, int m) { return l * l + l + m; }

// Evaluates all order*order basis functions at the unit direction (x, y, z).
// Needs 1 <= order <= kMaxOrder and out sized order*order. Uses the associated-Legendre recurrence in
// (x, y, z) directly, with no trigonometric calls, so it is exact at the poles and stable to kMaxOrder.
void evaluate(int order, double x, double y, double z, double* out);
void evaluate(int order, float x, float y, float z, float* out);

// Gauss-Legendre rule on [-1, 1] with n nodes (ascending), exact for polynomials of degree <= 2n - 1.
void gaussLegendre(int n, double* nodes, double* weights);

// A product rule on the unit sphere: Gauss-Legendre in z (cos of the polar angle from +Z) times uniform
// azimuth. Exact for every polynomial in (x, y, z) of degree <= `degree`, so SH products of total band
// degree <= `degree` integrate exactly. Weights sum to 4 pi.
struct SphereQuadrature {
    std::vector<double> directions; // [count][3], unit
    std::vector<double> weights;    // [count]
};
SphereQuadrature sphereQuadrature(int degree);

// Clamped-cosine convolution factor A_l (Ramamoorthi-Hanrahan, multiplier form): pi, 2pi/3, pi/4, 0, -pi/24, ...
// Irradiance coefficient E_lm = A_l * L_lm.
double clampedCosine(int l);

// ---- spherical caps (lib/sh/cap.cpp) ---------------------------------------------------------------------------
// SH coefficients of the indicator of the spherical cap {w : w . d >= cosRadius} about the unit direction d:
// out_lm = 2 pi I_l Y_lm(d), with I_l = integral of the Legendre polynomial P_l over [cosRadius, 1] (exact, by
// the recurrence; out_00 = solid angle * Y_00). Needs 1 <= order <= kMaxOrder, cosRadius in [-1, 1], d unit and
// out sized order*order. A cone light of uniform radiance L projects to L * out.
void capProjection(int order, const double d[3], double cosRadius, double* out);
// out[j][c] += radiance[c] * capProjection(order, d, cosRadius)[j] for j < order^2: a uniform cone light added to
// RGB coefficients [order^2][3]. Same needs as capProjection.
void addCapRadiance(int order, const double d[3], double cosRadius, const double radiance[3], double* out);
// The solid angle 2 pi (1 - cosRadius) of the cap {w : w . d >= cosRadius}.
double capSolidAngle(double cosRadius);
// Snyder's (1996) horizon-clipped cap: the integral of max(0, n . w) over the cap of half-angle sigma about a unit
// axis at cosine cosTheta from the unit normal n, given sinSigmaSquared = sin^2 sigma (both clamped to their
// ranges): pi sin^2(sigma) cosTheta when the cap lies wholly above the horizon, 0 wholly below, the exact clipped
// form in between (Lagarde and de Rousiers 2014). Never negative.
double capCosineIntegral(double cosTheta, double sinSigmaSquared);

// ---- cube strips (lib/sh/cube.cpp) -------------------------------------------------------------------------------
// Faces in strip order +X, -X, +Y, -Y, +Z, -Z, as OpenEXR's ImfEnvmap.h lays them out seen from inside
// (docs/conventions.md): the face's axis, the direction of increasing image column (face coordinate a) and the
// direction of decreasing image row (face coordinate b). The one table every cube map in prt uses.
struct CubeFace {
    double axis[3], right[3], up[3];
};
inline constexpr CubeFace kCubeFaces[6] = {
    {{1, 0, 0}, {0, 0, 1}, {0, 1, 0}},   {{-1, 0, 0}, {0, 0, -1}, {0, 1, 0}}, {{0, 1, 0}, {1, 0, 0}, {0, 0, 1}},
    {{0, -1, 0}, {1, 0, 0}, {0, 0, -1}}, {{0, 0, 1}, {-1, 0, 0}, {0, 1, 0}}, {{0, 0, -1}, {1, 0, 0}, {0, 1, 0}},
};
// Unit direction of face coordinates (a, b) (in [-1, 1]^2 on the face) of face 0..5.
void cubeFaceDirection(int face, double a, double b, double d[3]);
// Exact solid angle of the face rectangle [a0, a1] x [b0, b1] (a0 <= a1, b0 <= b1, face coordinates) by the
// corner formula: the 6 x N^2 texels of a cube sum to 4 pi to rounding.
double cubeRectangleSolidAngle(double a0, double a1, double b0, double b1);
// The face (0..5) a non-zero direction d falls on (its largest axis; ties to the lower axis) and its face
// coordinates a, b in [-1, 1].
int cubeFaceOf(const double d[3], double& a, double& b);

// ---- rotation ----------------------------------------------------------------------------------------------
// A rotation of SH coefficient vectors: block diagonal, one (2l+1)^2 block per band, stored band after band.
struct Rotation {
    int order = 0;
    std::vector<double> blocks;
};
// Builds the SH rotation for the 3x3 rotation matrix R (row-major, acting on column vectors: d' = R d), so that
// if f'(d) = f(R^T d) (f rotated by R) then coeffs(f') = apply(rotation(R), coeffs(f)).
Rotation rotation(int order, const double R[9]);
// out = rotation * in, for `channels` interleaved channels ([coefficient][channels]). in and out may not alias.
void rotate(const Rotation& rotation, const float* in, float* out, int channels);
void rotate(const Rotation& rotation, const double* in, double* out, int channels);
// The 3x3 matrix of a right-handed rotation by `degrees` about +Y (90 degrees takes +Z to +X).
void rotationY(double degrees, double R[9]);

// ---- windowing and energy ------------------------------------------------------------------------------------
enum class Window { None, Hann, Lanczos };
// Parses "none" | "hann" | "lanczos"; throws prt::Error(kExitUsage) naming `option` (the flag it came from)
// otherwise.
Window parseWindow(const std::string& name, const char* option = "--window");
const char* windowName(Window window);
// Per-band weight w_l for a window over `order` bands: Hann (1 + cos(pi l / order)) / 2, Lanczos sinc(l / order).
double windowWeight(Window window, int l, int order);
// Scales each band by its weight, in place.
void applyWindow(Window window, int order, float* coeffs, int channels);
// Energy per band: sum over m of c_lm^2 (summed over channels). Returns `order` values.
std::vector<double> bandEnergy(int order, const float* coeffs, int channels);

// ---- triple products ----------------------------------------------------------------------------------------
// The Gaunt tensor G_ijk = integral Y_i Y_j Y_k over the sphere, stored sparse: every nonzero (i, j, k) entry
// for i, j, k < order^2 (all orderings, so products are a single pass). Selection rules: l_i + l_j + l_k even,
// triangle inequality, and the real-SH m rules. Computed by exact quadrature (Gauss-Legendre in z times uniform
// azimuth); permuted entries hold identical bits. Needs 1 <= order <= kMaxOrder; the entry count grows about as
// order^5 (order 8: 12868 entries).
struct TripleProduct {
    int order = 0;
    std::vector<uint32_t> i, j, k;
    std::vector<double> value;
};
TripleProduct tripleProduct(int order);
// Projection of the product of two single-channel functions onto the first order^2 coefficients:
// out_i = sum G_ijk a_j b_k, accumulated in double. a, b and out hold tensor.order^2 values. Exact when the
// product's bands fit in the tensor's order.
void multiply(const TripleProduct& tensor, const float* a, const float* b, float* out);

// ---- environment projection --------------------------------------------------------------------------------
// Unit direction of equirectangular pixel (x, y) (docs/conventions.md). Integer x, y give texel centres;
// fractions up to +-0.5 move within the texel.
void equirectDirection(int width, int height, double x, double y, double d[3]);
// Unit direction of pixel (x, y) of a cube strip with faces of `faceSize` texels (docs/conventions.md), with
// the same texel-centre coordinates as equirectDirection; the face is the one holding texel row round(y).
void cubeStripDirection(int faceSize, double x, double y, double d[3]);
// Exact solid angle of every pixel of the environment's layout, row-major. They sum to 4 pi.
std::vector<double> texelSolidAngles(const EnvironmentMap& env);
// Projects radiance onto `order` bands (1..kMaxOrder) with exact per-texel solid angles: the basis is evaluated
// once at each texel centre and accumulated in double. Runs on `threads` std::threads (0 = all; no TBB, so the thin
// runtime can project) over fixed row blocks summed in a fixed order, so the result is bit-identical for any
// thread count. Returns [order^2][3].
std::vector<float> projectEnvironment(const EnvironmentMap& env, int order, int threads = 0);
// Irradiance at the unit normal n from RGB radiance coefficients ([order^2][3]) via the clamped-cosine
// convolution: E(n) = sum A_l L_lm Y_lm(n).
void irradiance(int order, const float* radianceCoeffs, const double n[3], double out[3]);

} // namespace prt::sh
