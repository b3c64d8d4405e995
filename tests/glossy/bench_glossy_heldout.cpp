// Issue 19 item 3, step 2: the fitted lobes of every (vertex, view) against the true glossy kernel away from the
// fit's grid, run by hand (not a ctest test):
//   build/tests/glossy/bench_glossy_heldout ENV.exr FACTOR GLOSSY.glb [GLOSSY.glb ...]
// The held-out directions are the texel centres of ENV box-filtered by FACTOR (solid-angle weighted; 1024x512 by 8:
// 128x64 texels of 1.4 deg, none on the fit's cube grid). Per bundle, over every (vertex, view) above the
// horizon, with V the same Embree visibility rule as the fit (one ray per held-out direction):
//   grid      mean sqrt(sum dw (F - T)^2 / sum dw T^2) on the fit's own cube grid (params.grid), the fit residual
//   held-out  the same on the held-out directions
//   lit       relative RMSE over problems of sum dw L (F - T) against sum dw L T (RGB), the relight of a distant eye
//             exactly along the view with the map's own lighting: the error the relight sees, without the blend
// the count of lobes with a > 0 and the share of them sharper than 4x the Phong exponent (narrower than half the
// Phong lobe, below the 6x8x8 grid's spacing), and, for every bundle after the first, the share of problems whose held-out or lit error is above the first's.
#include "bundle.h"
#include "core.h"
#include "glossy.h"
#include "image.h"
#include "raycast.h"
#include "runtime.h"
#include "sh.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

struct Directions {
    std::vector<float> directions; // [count][3]
    std::vector<float> solidAngle; // [count]
    std::vector<float> radiance;   // [count][3], empty for the cube grid
};

Directions boxFiltered(const prt::EnvironmentMap& env, int factor) {
    const std::vector<double> solidAngle = prt::sh::texelSolidAngles(env);
    const int width = env.radiance.width, height = env.radiance.height, w = width / factor, h = height / factor;
    Directions out;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            double sum[3] = {0, 0, 0}, area = 0;
            for (int dy = 0; dy < factor; ++dy)
                for (int dx = 0; dx < factor; ++dx) {
                    size_t t = size_t(y * factor + dy) * width + size_t(x * factor + dx);
                    area += solidAngle[t];
                    for (int c = 0; c < 3; ++c) sum[c] += solidAngle[t] * env.radiance.rgb[3 * t + c];
                }
            double d[3];
            prt::sh::equirectDirection(w, h, x, y, d);
            for (int c = 0; c < 3; ++c) out.directions.push_back(float(d[c]));
            out.solidAngle.push_back(float(area));
            for (int c = 0; c < 3; ++c) out.radiance.push_back(float(sum[c] / area));
        }
    return out;
}

double lobeSum(const float* lobes, int count, const float* w) {
    double f = 0;
    for (int k = 0; k < count; ++k) {
        const float* l = lobes + k * 5;
        if (!(l[0] > 0.0f)) continue;
        f += l[0] * std::exp(double(l[4]) * (double(l[1]) * w[0] + double(l[2]) * w[1] + double(l[3]) * w[2] - 1.0));
    }
    return f;
}

struct Errors {
    std::vector<double> grid, heldOut;   // per problem, relative
    std::vector<double> litFit, litTrue; // per problem [3]
};

} // namespace

int main(int argc, char** argv) {
    if (argc < 4) {
        std::fprintf(stderr, "usage: %s ENV.exr FACTOR GLOSSY.glb [GLOSSY.glb ...]\n", argv[0]);
        return 2;
    }
    prt::EnvironmentMap env = prt::readEnvironmentMap(argv[1]);
    const int factor = std::atoi(argv[2]);
    const Directions held = boxFiltered(env, factor);
    const size_t heldCount = held.solidAngle.size();
    std::vector<Errors> errors;
    for (int b = 3; b < argc; ++b) {
        prt::Bundle bundle = prt::readBundle(argv[b]);
        prt::GlossyModel model = prt::glossyModel(bundle, argv[b]);
        const prt::Layer* layer = prt::findLayer(bundle, "glossy_lobes");
        const int resolution = layer->params["grid"]["resolution"].get<int>();
        const prt::glossy::DirectionGrid grid = prt::glossy::cubeGrid(resolution);
        prt::glossy::Phong phong{model.exponent, model.ks};
        const prt::TriMesh& mesh = bundle.mesh;
        prt::EmbreeScene scene(mesh);
        const float offset = prt::rayOffset(mesh);
        const std::vector<float> spawn = prt::spawnNormals(mesh);
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        auto visibility = [&](size_t v, const float* n, const float* dirs, size_t count) {
            std::vector<uint8_t> visible(count, 0);
            float origin[3];
            prt::spawnOrigin(&mesh.positions[v * 3], &spawn[v * 3], offset, origin);
            for (size_t t = 0; t < count; ++t) {
                const float* d = &dirs[t * 3];
                if (n[0] * d[0] + n[1] * d[1] + n[2] * d[2] <= 0.0f) continue;
                RTCRay ray;
                prt::spawnRay(ray, origin, d[0], d[1], d[2]);
                rtcOccluded1(scene.scene, &context, &ray);
                visible[t] = ray.tfar >= 0.0f;
            }
            return visible;
        };
        prt::glossy::DirectionGrid heldGrid;
        heldGrid.directions = held.directions;
        heldGrid.solidAngle = held.solidAngle;
        Errors e;
        std::vector<float> kernel(grid.count()), heldKernel(heldCount);
        for (size_t v = 0; v < mesh.vertexCount(); ++v) {
            float n[3];
            const float* nn = &mesh.normals[v * 3];
            double length = std::sqrt(double(nn[0]) * nn[0] + double(nn[1]) * nn[1] + double(nn[2]) * nn[2]);
            for (int c = 0; c < 3; ++c) n[c] = float(nn[c] / length);
            std::vector<uint8_t> gridVisible = visibility(v, n, grid.directions.data(), grid.count());
            std::vector<uint8_t> heldVisible = visibility(v, n, held.directions.data(), heldCount);
            for (size_t view = 0; view < model.viewCount(); ++view) {
                const float* w = &model.views[view * 3];
                if (n[0] * w[0] + n[1] * w[1] + n[2] * w[2] <= 0.0f) continue;
                const float* lobes = &model.values[(v * model.viewCount() + view) * size_t(model.lobes) * 5];
                prt::glossy::tabulateKernel(grid, n, w, phong, gridVisible.data(), kernel.data());
                prt::glossy::tabulateKernel(heldGrid, n, w, phong, heldVisible.data(), heldKernel.data());
                double residual = 0, energy = 0;
                for (size_t t = 0; t < grid.count(); ++t) {
                    double f = lobeSum(lobes, model.lobes, &grid.directions[t * 3]);
                    residual += grid.solidAngle[t] * (f - kernel[t]) * (f - kernel[t]);
                    energy += grid.solidAngle[t] * double(kernel[t]) * kernel[t];
                }
                if (!(energy > 0)) continue;
                double heldResidual = 0, heldEnergy = 0, litFit[3] = {0, 0, 0}, litTrue[3] = {0, 0, 0};
                for (size_t t = 0; t < heldCount; ++t) {
                    double f = lobeSum(lobes, model.lobes, &held.directions[t * 3]);
                    double dw = held.solidAngle[t];
                    heldResidual += dw * (f - heldKernel[t]) * (f - heldKernel[t]);
                    heldEnergy += dw * double(heldKernel[t]) * heldKernel[t];
                    for (int c = 0; c < 3; ++c) {
                        litFit[c] += dw * f * held.radiance[3 * t + c];
                        litTrue[c] += dw * heldKernel[t] * held.radiance[3 * t + c];
                    }
                }
                e.grid.push_back(std::sqrt(residual / energy));
                e.heldOut.push_back(heldEnergy > 0 ? std::sqrt(heldResidual / heldEnergy) : 0.0);
                for (int c = 0; c < 3; ++c) e.litFit.push_back(litFit[c]), e.litTrue.push_back(litTrue[c]);
            }
        }
        size_t lit = 0, sharp = 0; // lobes with a > 0, and of those the ones sharper than 4x the Phong exponent
        for (size_t i = 0; i + 4 < model.values.size(); i += 5)
            if (model.values[i] > 0.0f) ++lit, sharp += model.values[i + 4] > 4.0 * model.exponent;
        errors.push_back(std::move(e));
        const Errors& r = errors.back();
        double grid0 = 0, held0 = 0, se = 0, st = 0;
        for (size_t p = 0; p < r.grid.size(); ++p) grid0 += r.grid[p], held0 += r.heldOut[p];
        for (size_t i = 0; i < r.litFit.size(); ++i)
            se += (r.litFit[i] - r.litTrue[i]) * (r.litFit[i] - r.litTrue[i]), st += r.litTrue[i] * r.litTrue[i];
        std::printf("%s: lobes %d, problems %zu, grid %.2f%%, held-out %.2f%%, lit %.2f%%, lobes with a > 0 %zu, "
                    "sharper than 4 n %.1f%%", argv[b], model.lobes, r.grid.size(), 100 * grid0 / double(r.grid.size()),
                    100 * held0 / double(r.grid.size()), 100 * std::sqrt(se / st), lit, 100.0 * double(sharp) / double(lit));
        if (errors.size() > 1 && errors.front().grid.size() == r.grid.size()) {
            const Errors& first = errors.front();
            size_t heldWorse = 0, litWorse = 0;
            for (size_t p = 0; p < r.grid.size(); ++p) {
                heldWorse += r.heldOut[p] > first.heldOut[p] * (1 + 1e-6);
                double a = 0, b0 = 0;
                for (int c = 0; c < 3; ++c) {
                    a += std::pow(r.litFit[3 * p + c] - r.litTrue[3 * p + c], 2);
                    b0 += std::pow(first.litFit[3 * p + c] - first.litTrue[3 * p + c], 2);
                }
                litWorse += a > b0 * (1 + 1e-6);
            }
            std::printf(", worse than the first: held-out %.1f%%, lit %.1f%% of problems",
                        100.0 * double(heldWorse) / double(r.grid.size()), 100.0 * double(litWorse) / double(r.grid.size()));
        }
        std::printf("\n");
        std::fflush(stdout);
    }
    return 0;
}
