// Indirect glossy (optional, `prt glossy --indirect-glossy`): light that reaches a vertex after one diffuse bounce
// off the mesh. A kernel direction w_i that the mesh blocks sees the hit point's diffuse radiance, which is the
// hit's shadowed SH transfer t_hit dotted with the SH lighting: L_hit = sum_k t_hit,k L_k, L_k = int L Y_k. So the
// glossy light of the blocked directions is sum_i f cos(w_i) dw_i L_hit(w_i) = int (sum_k s_k Y_k(w)) L(w) dw with
// s_k = sum_i f cos(w_i) dw_i t_hit,k(w_i): an extra kernel sum_k s_k Y_k(w) over environment directions, which
// the spherical Gaussians fit together with the direct kernel (and the runtime needs nothing new).
#include "glossy.h"

#include "sh.h"

#include <algorithm>

namespace prt::glossy {

std::vector<float> gridBasis(const DirectionGrid& grid, int order) {
    const size_t coefficients = size_t(order) * order;
    std::vector<float> basis(grid.count() * coefficients);
    for (size_t t = 0; t < grid.count(); ++t)
        sh::evaluate(order, grid.directions[t * 3], grid.directions[t * 3 + 1], grid.directions[t * 3 + 2],
                     &basis[t * coefficients]);
    return basis;
}

void hitTransfer(const TriMesh& mesh, const std::vector<float>& transfer, int order, uint32_t triangle, float u,
                 float v, float* out) {
    const size_t coefficients = size_t(order) * order;
    const float weights[3] = {1.0f - u - v, u, v}; // Embree: hit = (1 - u - v) p0 + u p1 + v p2
    std::fill(out, out + coefficients, 0.0f);
    for (int corner = 0; corner < 3; ++corner) {
        const float* row = &transfer[size_t(mesh.indices[size_t(triangle) * 3 + corner]) * coefficients];
        for (size_t k = 0; k < coefficients; ++k) out[k] += weights[corner] * row[k];
    }
}

void addIndirectKernel(const DirectionGrid& grid, const float* basis, int order, const float normal[3],
                       const float outgoing[3], const Phong& phong, const uint8_t* visibility,
                       const float* hitTransfers, float* kernel) {
    const size_t count = grid.count(), coefficients = size_t(order) * order;
    // f cos over the blocked directions alone: tabulateKernel with the visibility inverted.
    std::vector<uint8_t> blocked(count);
    for (size_t t = 0; t < count; ++t) blocked[t] = visibility[t] ? 0 : 1;
    std::vector<float> reflect(count);
    tabulateKernel(grid, normal, outgoing, phong, blocked.data(), reflect.data());
    std::vector<double> s(coefficients, 0.0);
    bool any = false;
    for (size_t t = 0; t < count; ++t) {
        if (reflect[t] <= 0.0f) continue;
        any = true;
        const double weight = double(reflect[t]) * grid.solidAngle[t];
        for (size_t k = 0; k < coefficients; ++k) s[k] += weight * hitTransfers[t * coefficients + k];
    }
    if (!any) return;
    // Truncated SH can ring below zero; a negative kernel would subtract light, so it is clamped at zero.
    for (size_t t = 0; t < count; ++t) {
        double value = 0.0;
        for (size_t k = 0; k < coefficients; ++k) value += s[k] * basis[t * coefficients + k];
        kernel[t] += float(std::max(0.0, value));
    }
}

} // namespace prt::glossy
