// Relight-time specular: the lighting contracted with the Gaunt tensor once, then per vertex a product with the
// visibility, the Phong multipliers (folded into the matrix) and SH evaluation at the mirrored view direction.
#include "specular.h"

#include "core.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace prt::specular {

LightProduct lightProduct(const sh::TripleProduct& tensor, const float* lighting, int lightOrder, int visibilityOrder,
                          int bands, const Phong& phong) {
    auto usage = [](const std::string& place, const std::string& problem) {
        return Error("", place, problem, kExitUsage);
    };
    if (lightOrder < 1 || lightOrder > sh::kMaxOrder)
        throw usage("light order", "outside 1.." + std::to_string(sh::kMaxOrder));
    if (visibilityOrder < 1 || visibilityOrder > sh::kMaxOrder)
        throw usage("visibility order", "outside 1.." + std::to_string(sh::kMaxOrder));
    if (bands < 1 || bands > lightOrder + visibilityOrder - 1)
        throw usage("bands", std::to_string(bands) + " outside 1.." + std::to_string(lightOrder + visibilityOrder - 1) +
                                 ", the bands of the product of order " + std::to_string(lightOrder) + " and " +
                                 std::to_string(visibilityOrder) + " functions");
    if (tensor.order < std::max({lightOrder, visibilityOrder, bands}))
        throw usage("triple product", "tensor of order " + std::to_string(tensor.order) + " is below the order " +
                                          std::to_string(std::max({lightOrder, visibilityOrder, bands})) + " needed");
    if (!(phong.ks >= 0.0 && phong.ks <= 1.0)) throw usage("phong ks", "must lie in [0, 1]");
    std::vector<double> multiplier = phongMultipliers(phong.exponent, bands);

    const uint32_t outputs = uint32_t(bands) * bands, lights = uint32_t(lightOrder) * lightOrder,
                   visibilities = uint32_t(visibilityOrder) * visibilityOrder;
    std::vector<double> sum(size_t(3) * outputs * visibilities, 0.0);
    for (size_t e = 0; e < tensor.value.size(); ++e) {
        uint32_t i = tensor.i[e], j = tensor.j[e], k = tensor.k[e];
        if (i >= outputs || j >= lights || k >= visibilities) continue;
        for (int c = 0; c < 3; ++c)
            sum[(size_t(c) * outputs + i) * visibilities + k] += tensor.value[e] * double(lighting[3 * j + c]);
    }
    LightProduct product;
    product.lightOrder = lightOrder;
    product.visibilityOrder = visibilityOrder;
    product.bands = bands;
    product.matrix.resize(sum.size());
    for (int c = 0; c < 3; ++c)
        for (uint32_t i = 0; i < outputs; ++i) {
            double scale = phong.ks * multiplier[int(std::sqrt(double(i)))]; // band of coefficient i
            for (uint32_t k = 0; k < visibilities; ++k) {
                size_t at = (size_t(c) * outputs + i) * visibilities + k;
                product.matrix[at] = float(scale * sum[at]);
            }
        }
    return product;
}

namespace {

// glossyAt with caller-owned scratch: basis holds bands^2 values, folded visibilities^2.
void glossyWith(const LightProduct& product, const float* o, const double R[3], double* basis, double* folded,
                double rgb[3]) {
    const size_t outputs = size_t(product.bands) * product.bands,
                 visibilities = size_t(product.visibilityOrder) * product.visibilityOrder;
    sh::evaluate(product.bands, R[0], R[1], R[2], basis);
    for (int c = 0; c < 3; ++c) {
        // folded_k = sum_i Y_i(R) M_c[i][k]: rows are contiguous, so this is a run of axpys.
        std::fill(folded, folded + visibilities, 0.0);
        const float* matrix = &product.matrix[size_t(c) * outputs * visibilities];
        for (size_t i = 0; i < outputs; ++i) {
            const float* row = matrix + i * visibilities;
            for (size_t k = 0; k < visibilities; ++k) folded[k] += basis[i] * double(row[k]);
        }
        double s = 0.0;
        for (size_t k = 0; k < visibilities; ++k) s += folded[k] * double(o[k]);
        rgb[c] = s;
    }
}

} // namespace

void glossyAt(const LightProduct& product, const float* o, const double R[3], double rgb[3]) {
    std::vector<double> basis(size_t(product.bands) * product.bands),
        folded(size_t(product.visibilityOrder) * product.visibilityOrder);
    glossyWith(product, o, R, basis.data(), folded.data(), rgb);
}

void glossyRadiance(const TriMesh& mesh, const Visibility& o, const LightProduct& product, const float eye[3],
                    float* radiance) {
    const size_t vertices = mesh.vertexCount();
    const size_t coefficients = size_t(product.visibilityOrder) * product.visibilityOrder;
    if (o.order != product.visibilityOrder)
        throw Error("", "visibility order",
                    "the visibility has order " + std::to_string(o.order) + ", the light product was built for " +
                        std::to_string(product.visibilityOrder));
    if (o.coefficients.size() != vertices * coefficients)
        throw Error("", "visibility", "holds " + std::to_string(o.coefficients.size()) + " values, not " +
                                          std::to_string(vertices * coefficients) + " for the mesh");
    if (mesh.normals.size() != mesh.positions.size()) throw Error("", "mesh", "has no per-vertex normals");
    tbb::parallel_for(tbb::blocked_range<size_t>(0, vertices, 256), [&](const tbb::blocked_range<size_t>& range) {
        std::vector<double> basis(size_t(product.bands) * product.bands), folded(coefficients);
        for (size_t v = range.begin(); v < range.end(); ++v) {
            const float* p = &mesh.positions[3 * v];
            const float* m = &mesh.normals[3 * v];
            double n[3] = {m[0], m[1], m[2]};
            double wo[3] = {eye[0] - double(p[0]), eye[1] - double(p[1]), eye[2] - double(p[2])};
            double nLength = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            double woLength = std::sqrt(wo[0] * wo[0] + wo[1] * wo[1] + wo[2] * wo[2]);
            float* out = &radiance[3 * v];
            out[0] = out[1] = out[2] = 0.0f;
            if (!(nLength > 0.0) || !(woLength > 0.0)) continue;
            for (int c = 0; c < 3; ++c) n[c] /= nLength, wo[c] /= woLength;
            double cosOut = n[0] * wo[0] + n[1] * wo[1] + n[2] * wo[2];
            if (cosOut <= 0.0) continue; // the lobe is zero toward a viewer below the surface
            double R[3];
            for (int c = 0; c < 3; ++c) R[c] = 2.0 * cosOut * n[c] - wo[c];
            double length = std::sqrt(R[0] * R[0] + R[1] * R[1] + R[2] * R[2]);
            for (int c = 0; c < 3; ++c) R[c] /= length;
            double rgb[3];
            glossyWith(product, &o.coefficients[v * coefficients], R, basis.data(), folded.data(), rgb);
            for (int c = 0; c < 3; ++c) out[c] = float(rgb[c]);
        }
    });
}

} // namespace prt::specular
