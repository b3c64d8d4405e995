// lib/runtime's hybrid: the cone cosine integral against quadrature, and relighting in closed form on unoccluded
// points (transfer (albedo / pi) A_l Y_lm(n)), where every part of the answer is known.
#include "runtime.h"

#include "core.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include <unistd.h>

namespace {

double quadratureCosine(double cosAngle, double radius) {
    // Integral over the cap about d = (sin a, 0, cos a) of max(0, z): polar grid about d.
    double a = std::acos(cosAngle), sum = 0.0;
    const int nt = 400, np = 400;
    for (int i = 0; i < nt; ++i) {
        double t = (i + 0.5) / nt * radius;
        for (int j = 0; j < np; ++j) {
            double p = (j + 0.5) / np * 2.0 * std::numbers::pi;
            // w = cos t d + sin t (cos p e1 + sin p e2), e1 = (cos a, 0, -sin a), e2 = (0, 1, 0).
            double z = std::cos(t) * std::cos(a) - std::sin(t) * std::cos(p) * std::sin(a);
            sum += std::max(0.0, z) * std::sin(t) * (radius / nt) * (2.0 * std::numbers::pi / np);
        }
    }
    return sum;
}

prt::HybridModel unoccludedModel(const std::vector<std::array<float, 3>>& normals, int order, float albedo,
                                 bool withBounce) {
    prt::HybridModel model;
    model.total.vertexCount = uint32_t(normals.size());
    model.total.order = order;
    const int n = order * order;
    std::vector<float> basis(n);
    for (const auto& normal : normals) {
        prt::sh::evaluate(order, normal[0], normal[1], normal[2], basis.data());
        for (int j = 0; j < n; ++j) {
            int l = int(std::sqrt(double(j)));
            for (int c = 0; c < 3; ++c)
                model.total.transfer.push_back(float(albedo / std::numbers::pi * prt::sh::clampedCosine(l) * basis[j]));
        }
        model.normals.insert(model.normals.end(), normal.begin(), normal.end());
        for (int c = 0; c < 3; ++c) model.albedo.push_back(albedo);
    }
    // A made-up bounce part: a constant 0.1 response to the DC coefficient only.
    if (withBounce) {
        model.bounce.assign(model.total.transfer.size(), 0.0f);
        for (size_t v = 0; v < normals.size(); ++v)
            for (int c = 0; c < 3; ++c) model.bounce[v * n * 3 + c] = 0.1f;
    }
    return model;
}

} // namespace

TEST(ConeCosineIntegral, MatchesQuadratureAcrossTheHorizon) {
    for (double radiusDegrees : {2.0, 10.0, 30.0})
        for (double cosAngle : {1.0, 0.7, 0.3, 0.1, 0.0, -0.1, -0.3, -0.6}) {
            double r = radiusDegrees * std::numbers::pi / 180.0;
            double exact = prt::coneCosineIntegral(cosAngle, r), numeric = quadratureCosine(cosAngle, r);
            EXPECT_NEAR(exact, numeric, 1e-4 * (1.0 - std::cos(r)) * 2.0 * std::numbers::pi + 1e-9)
                << radiusDegrees << " " << cosAngle;
        }
    // Far above the horizon: pi sin^2 r cos a.
    EXPECT_NEAR(prt::coneCosineIntegral(0.8, 0.1), std::numbers::pi * std::sin(0.1) * std::sin(0.1) * 0.8, 1e-12);
    EXPECT_EQ(prt::coneCosineIntegral(-0.9, 0.1), 0.0);
}

TEST(RelightHybrid, UnoccludedPointsInClosedForm) {
    std::vector<std::array<float, 3>> normals = {{0, 1, 0}, {1, 0, 0}, {0, 0.6f, -0.8f}, {0, -1, 0}};
    const float albedo = 0.8f;
    prt::HybridModel model = unoccludedModel(normals, 3, albedo, false);
    prt::HybridLighting lighting;
    lighting.order = 3;
    lighting.residual.assign(27, 0.0f);
    for (int c = 0; c < 3; ++c) lighting.residual[c] = float(2.0 * std::sqrt(4.0 * std::numbers::pi)); // constant 2
    prt::HybridConeLight light;
    light.direction = {0, 0.8f, -0.6f};
    light.radiance = {100, 50, 25};
    light.angularRadius = 0.05f;
    lighting.lights = {light};
    std::vector<float> visibility = {1.0f, 1.0f, 0.5f, 1.0f}, radiance(12);
    prt::relightHybrid(model, lighting, visibility.data(), 0, 4, radiance.data());
    for (size_t v = 0; v < 4; ++v) {
        const auto& n = normals[v];
        double cosAngle = n[0] * light.direction[0] + n[1] * light.direction[1] + n[2] * light.direction[2];
        double cone = prt::coneCosineIntegral(cosAngle, light.angularRadius);
        for (int c = 0; c < 3; ++c) {
            // Constant 2 lights an unoccluded point to albedo * 2; the cone adds albedo / pi L V C.
            double expected = albedo * 2.0 + albedo / std::numbers::pi * light.radiance[c] * visibility[v] * cone;
            EXPECT_NEAR(radiance[v * 3 + c], expected, 1e-4 * expected + 1e-5) << v << " " << c;
        }
    }
    // Rows are independent of how the range is split, bit for bit, and the callback form agrees.
    std::vector<float> part(3);
    prt::relightHybrid(model, lighting, visibility.data(), 2, 3, part.data());
    for (int c = 0; c < 3; ++c) EXPECT_EQ(part[c], radiance[6 + c]);
    std::vector<float> viaCallback(12);
    prt::relightHybrid(model, lighting, [&](size_t row, size_t) { return visibility[row]; }, 0, 4, viaCallback.data());
    EXPECT_EQ(viaCallback, radiance);
}

TEST(RelightHybrid, LightsBounceThroughTheBouncePart) {
    std::vector<std::array<float, 3>> normals = {{0, 1, 0}};
    prt::HybridModel model = unoccludedModel(normals, 2, 0.5f, true);
    prt::HybridLighting lighting;
    lighting.order = 2;
    lighting.residual.assign(12, 0.0f);
    prt::HybridConeLight light;
    light.direction = {0, -1, 0}; // below the horizon: no direct light, only the bounce
    light.radiance = {10, 10, 10};
    light.angularRadius = 0.2f;
    lighting.lights = {light};
    float visibility = 1.0f, radiance[3];
    prt::relightHybrid(model, lighting, &visibility, 0, 1, radiance);
    // The bounce part answers 0.1 per unit DC coefficient; the cone's DC is L * solid angle * Y_00.
    double dc = 10.0 * 2.0 * std::numbers::pi * (1.0 - std::cos(0.2)) * 0.5 / std::sqrt(std::numbers::pi);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(radiance[c], 0.1 * dc, 1e-5);
}

TEST(HybridLightingJson, RejectsBadLights) {
    namespace fs = std::filesystem;
    fs::path path = fs::temp_directory_path() / ("prt_hybrid_json_" + std::to_string(::getpid()) + ".json");
    auto write = [&](const std::string& lights) {
        std::ofstream(path) << R"({"format":"prt-lights","order":1,"residual":[[1,1,1]],"lights":[)" << lights
                            << "]}";
    };
    write(R"({"direction":[0,1,0],"radiance":[1,2,3],"angular_radius":0.1})");
    prt::HybridLighting ok = prt::readHybridLightingJson(path.string());
    ASSERT_EQ(ok.lights.size(), 1u);
    EXPECT_FLOAT_EQ(ok.lights[0].radiance[2], 3.0f);
    for (const char* bad : {R"({"direction":[0,1,0],"radiance":[1,"nan",3],"angular_radius":0.1})",
                            R"({"direction":[0,1,0],"radiance":[1,4e38,3],"angular_radius":0.1})",
                            R"({"direction":[0,2,0],"radiance":[1,2,3],"angular_radius":0.1})",
                            R"({"direction":[0,1,0],"radiance":[1,-2,3],"angular_radius":0.1})",
                            R"({"direction":[0,1,0],"radiance":[1,2,3],"angular_radius":2.0})",
                            R"({"direction":[0,1,0],"radiance":[1,2,3]})"}) {
        write(bad);
        try {
            prt::readHybridLightingJson(path.string());
            ADD_FAILURE() << "accepted " << bad;
        } catch (const prt::Error& e) {
            EXPECT_EQ(e.exitCode(), prt::kExitInput);
            EXPECT_NE(e.place().find("lights[0]"), std::string::npos) << e.what();
        }
    }
    fs::remove(path);
}
