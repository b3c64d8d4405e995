// Specular through SH triple products against brute-force quadrature of integral L O f_phong dw, closed forms, the
// visibility layer and bad input.
#include "core.h"
#include "sh.h"
#include "specular.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace {

using prt::specular::Phong;

double evaluateSh(int order, const std::vector<double>& coefficients, const double w[3], int stride = 1,
                  int channel = 0) {
    std::vector<double> basis(size_t(order) * order);
    prt::sh::evaluate(order, w[0], w[1], w[2], basis.data());
    double sum = 0.0;
    for (size_t i = 0; i < basis.size(); ++i) sum += basis[i] * coefficients[i * stride + channel];
    return sum;
}

// integral over the sphere of f(w) ks (n + 2) / (2 pi) max(0, R . w)^n dw, in a frame about R: Gauss-Legendre in
// t = R . w over [0, 1] times uniform azimuth. Exact (to rounding) when f is a polynomial of degree < azimuths
// and n + degree f <= 2 nodes - 1; otherwise a converging rule.
template <class F>
double bruteForce(const F& f, const double R[3], const Phong& phong, int nodes, int azimuths) {
    double t1[3], t2[3];
    double sign = std::copysign(1.0, R[2]), a = -1.0 / (sign + R[2]), b = R[0] * R[1] * a;
    t1[0] = 1.0 + sign * R[0] * R[0] * a, t1[1] = sign * b, t1[2] = -sign * R[0];
    t2[0] = b, t2[1] = sign + R[1] * R[1] * a, t2[2] = -R[1];
    std::vector<double> x(nodes), weight(nodes);
    prt::sh::gaussLegendre(nodes, x.data(), weight.data());
    double sum = 0.0;
    for (int q = 0; q < nodes; ++q) {
        double t = 0.5 * (x[q] + 1.0), s = std::sqrt(std::max(0.0, 1.0 - t * t));
        double lobe = phong.ks * (phong.exponent + 2.0) / (2.0 * std::numbers::pi) * std::pow(t, phong.exponent);
        for (int p = 0; p < azimuths; ++p) {
            double phi = 2.0 * std::numbers::pi * (p + 0.5) / azimuths;
            double w[3];
            for (int c = 0; c < 3; ++c) w[c] = s * (std::cos(phi) * t1[c] + std::sin(phi) * t2[c]) + t * R[c];
            sum += 0.5 * weight[q] * (2.0 * std::numbers::pi / azimuths) * lobe * f(w);
        }
    }
    return sum;
}

void unit(double d[3]) {
    double length = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int c = 0; c < 3; ++c) d[c] /= length;
}

// The done-when test: band-limited lighting (order 3, RGB) and visibility (order 4) whose product (6 bands) the
// tensor holds exactly, so the Gaunt product, the zonal convolution and the evaluation at R must equal the
// pointwise integral of L O times the lobe.
TEST(SpecularShade, TripleProductMatchesBruteForceQuadrature) {
    std::mt19937 random(7);
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    const int lightOrder = 3, visibilityOrder = 4, bands = 6;
    std::vector<double> light(lightOrder * lightOrder * 3), visibility(visibilityOrder * visibilityOrder);
    for (double& value : light) value = uniform(random);
    for (double& value : visibility) value = uniform(random);
    std::vector<float> lightFloat(light.begin(), light.end()), visibilityFloat(visibility.begin(), visibility.end());
    for (size_t i = 0; i < light.size(); ++i) light[i] = lightFloat[i];
    for (size_t i = 0; i < visibility.size(); ++i) visibility[i] = visibilityFloat[i];

    prt::sh::TripleProduct tensor = prt::sh::tripleProduct(bands);
    for (Phong phong : {Phong{8.0, 0.7}, Phong{20.0, 0.5}, Phong{3.0, 1.0}}) {
        prt::specular::LightProduct product =
            prt::specular::lightProduct(tensor, lightFloat.data(), lightOrder, visibilityOrder, bands, phong);
        for (int trial = 0; trial < 4; ++trial) {
            double R[3] = {uniform(random), uniform(random), uniform(random)};
            unit(R);
            double rgb[3];
            prt::specular::glossyAt(product, visibilityFloat.data(), R, rgb);
            for (int c = 0; c < 3; ++c) {
                auto integrand = [&](const double w[3]) {
                    return evaluateSh(lightOrder, light, w, 3, c) * evaluateSh(visibilityOrder, visibility, w);
                };
                double expected = bruteForce(integrand, R, phong, 40, 32);
                EXPECT_NEAR(rgb[c], expected, 2e-5 * (1.0 + std::abs(expected)))
                    << "n " << phong.exponent << " trial " << trial << " channel " << c;
            }
        }
    }
}

// The light product is the sparse tensor of lib/sh contracted once: the same as sh::multiply, then the lobe.
TEST(SpecularShade, LightProductEqualsSparseMultiplyThenConvolution) {
    std::mt19937 random(3);
    std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
    const int order = 5;
    const Phong phong{12.0, 0.6};
    prt::sh::TripleProduct tensor = prt::sh::tripleProduct(order);
    std::vector<float> lighting(order * order * 3), o(order * order);
    for (float& value : lighting) value = uniform(random);
    for (float& value : o) value = uniform(random);
    prt::specular::LightProduct product =
        prt::specular::lightProduct(tensor, lighting.data(), order, order, order, phong);
    std::vector<double> multiplier = prt::specular::phongMultipliers(phong.exponent, order);
    double R[3] = {0.3, -0.5, 0.8};
    unit(R);
    std::vector<double> basis(order * order);
    prt::sh::evaluate(order, R[0], R[1], R[2], basis.data());
    double rgb[3];
    prt::specular::glossyAt(product, o.data(), R, rgb);
    for (int c = 0; c < 3; ++c) {
        std::vector<float> channel(order * order), incoming(order * order);
        for (int j = 0; j < order * order; ++j) channel[j] = lighting[3 * j + c];
        prt::sh::multiply(tensor, channel.data(), o.data(), incoming.data());
        double expected = 0.0;
        for (int l = 0; l < order; ++l)
            for (int m = -l; m <= l; ++m)
                expected += phong.ks * multiplier[l] * incoming[prt::sh::index(l, m)] * basis[prt::sh::index(l, m)];
        EXPECT_NEAR(rgb[c], expected, 1e-5 * (1.0 + std::abs(expected))) << c;
    }
}

// A flat square: every vertex sees the whole upper hemisphere, so its visibility is the exact clamped cosine.
prt::TriMesh flatSquare() {
    prt::TriMesh mesh;
    mesh.positions = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
    mesh.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
    mesh.indices = {0, 1, 2, 0, 2, 3};
    return mesh;
}

std::vector<float> constantLighting(int order, float radiance) {
    std::vector<float> lighting(size_t(order) * order * 3, 0.0f);
    for (int c = 0; c < 3; ++c) lighting[c] = float(radiance * 2.0 * std::sqrt(std::numbers::pi));
    return lighting;
}

// Closed form: unoccluded (V = 1), constant radiance c, seen along the normal: the normalised lobe returns ks c.
// For an even integer n the SH sum is exact at order n + 2 (the cosine's odd bands above 1 and the lobe's even
// bands above n + 1 vanish), so this holds to float precision.
TEST(SpecularShade, UnoccludedNormalViewReflectsKsTimesRadiance) {
    prt::TriMesh mesh = flatSquare();
    prt::specular::VisibilityOptions options;
    options.order = 10;
    options.samples = 64;
    options.progress = false;
    prt::specular::Visibility o = prt::specular::computeVisibility(mesh, options);
    const Phong phong{8.0, 0.5};
    const float radiance = 2.0f;
    prt::sh::TripleProduct tensor = prt::sh::tripleProduct(10);
    std::vector<float> lighting = constantLighting(1, radiance);
    prt::specular::LightProduct product = prt::specular::lightProduct(tensor, lighting.data(), 1, 10, 10, phong);
    std::vector<float> out(mesh.vertexCount() * 3);
    for (int v = 0; v < 4; ++v) {
        float eye[3] = {mesh.positions[3 * v], mesh.positions[3 * v + 1], 5.0f};
        prt::specular::glossyRadiance(mesh, o, product, eye, out.data());
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(out[3 * v + c], phong.ks * radiance, 2e-5) << v;
    }
    // A viewer below the surface sees no lobe.
    float below[3] = {0.0f, 0.0f, -3.0f};
    prt::specular::glossyRadiance(mesh, o, product, below, out.data());
    for (float value : out) EXPECT_EQ(value, 0.0f);
}

// The same vertex seen obliquely: the integral of c max(0, n . w) times the lobe about R, by brute force.
TEST(SpecularShade, UnoccludedObliqueViewMatchesQuadrature) {
    prt::TriMesh mesh = flatSquare();
    prt::specular::VisibilityOptions options;
    options.order = 10;
    options.samples = 16;
    options.progress = false;
    prt::specular::Visibility o = prt::specular::computeVisibility(mesh, options);
    const Phong phong{8.0, 1.0};
    prt::sh::TripleProduct tensor = prt::sh::tripleProduct(10);
    std::vector<float> lighting = constantLighting(1, 1.0f);
    prt::specular::LightProduct product = prt::specular::lightProduct(tensor, lighting.data(), 1, 10, 10, phong);
    std::vector<float> out(mesh.vertexCount() * 3);
    for (double angle : {20.0, 50.0, 75.0}) {
        double a = angle * std::numbers::pi / 180.0;
        float eye[3] = {float(-1.0 + 4.0 * std::sin(a)), -1.0f, float(4.0 * std::cos(a))};
        prt::specular::glossyRadiance(mesh, o, product, eye, out.data());
        double R[3] = {-std::sin(a), 0.0, std::cos(a)}; // the mirror of the view at vertex 0
        auto cosine = [](const double w[3]) { return std::max(0.0, w[2]); };
        double expected = bruteForce(cosine, R, phong, 400, 400);
        EXPECT_NEAR(out[0], expected, 1e-3 * expected) << angle;
    }
}

TEST(SpecularShade, ResultDoesNotDependOnThreadCount) {
    prt::TriMesh mesh = flatSquare();
    prt::specular::Visibility o;
    o.order = 4;
    std::mt19937 random(11);
    std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
    // Many vertices over several TBB blocks: the square's corners repeated.
    prt::TriMesh many;
    for (int copy = 0; copy < 600; ++copy) {
        for (size_t i = 0; i < mesh.positions.size(); ++i) {
            many.positions.push_back(mesh.positions[i] + 0.01f * copy);
            many.normals.push_back(mesh.normals[i]);
        }
        for (uint32_t index : mesh.indices) many.indices.push_back(index + 4 * copy);
    }
    o.coefficients.resize(many.vertexCount() * 16);
    for (float& value : o.coefficients) value = uniform(random);
    std::vector<float> lighting(16 * 3);
    for (float& value : lighting) value = uniform(random);
    prt::sh::TripleProduct tensor = prt::sh::tripleProduct(4);
    prt::specular::LightProduct product =
        prt::specular::lightProduct(tensor, lighting.data(), 4, 4, 4, Phong{16.0, 0.5});
    float eye[3] = {0.3f, 0.2f, 4.0f};
    std::vector<float> one(many.vertexCount() * 3), all(many.vertexCount() * 3);
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        prt::specular::glossyRadiance(many, o, product, eye, one.data());
    }
    prt::specular::glossyRadiance(many, o, product, eye, all.data());
    EXPECT_EQ(one, all);
}

TEST(SpecularShade, BadInputIsRefused) {
    prt::sh::TripleProduct tensor = prt::sh::tripleProduct(6);
    std::vector<float> lighting(16 * 3, 0.1f);
    // More bands than a product of order 2 and order 3 functions has (4).
    EXPECT_THROW(prt::specular::lightProduct(tensor, lighting.data(), 2, 3, 5, Phong{8.0, 0.5}), prt::Error);
    EXPECT_THROW(prt::specular::lightProduct(tensor, lighting.data(), 4, 4, 4, Phong{0.0, 0.5}), prt::Error);
    EXPECT_THROW(prt::specular::lightProduct(tensor, lighting.data(), 4, 4, 4, Phong{8.0, 1.5}), prt::Error);
    EXPECT_THROW(prt::specular::lightProduct(prt::sh::tripleProduct(3), lighting.data(), 4, 4, 4, Phong{8.0, 0.5}),
                 prt::Error);
    // Visibility of another order than the light product's.
    prt::TriMesh mesh = flatSquare();
    prt::specular::Visibility o;
    o.order = 3;
    o.coefficients.assign(mesh.vertexCount() * 9, 0.0f);
    prt::specular::LightProduct product =
        prt::specular::lightProduct(tensor, lighting.data(), 4, 4, 4, Phong{8.0, 0.5});
    std::vector<float> out(mesh.vertexCount() * 3);
    float eye[3] = {0, 0, 3};
    try {
        prt::specular::glossyRadiance(mesh, o, product, eye, out.data());
        FAIL();
    } catch (const prt::Error& e) {
        EXPECT_NE(std::string(e.what()).find("order 3"), std::string::npos) << e.what();
    }
}

TEST(SpecularVisibility, LayerRoundTripsAndBadLayersAreRefused) {
    prt::Bundle bundle;
    bundle.mesh = flatSquare();
    try {
        prt::specular::readVisibility(bundle, "square.glb");
        FAIL();
    } catch (const prt::Error& e) {
        EXPECT_NE(std::string(e.what()).find("square.glb"), std::string::npos);
        EXPECT_NE(std::string(e.what()).find("prt specular"), std::string::npos) << e.what();
    }
    prt::specular::VisibilityOptions options;
    options.order = 3;
    options.samples = 32;
    options.progress = false;
    prt::specular::Visibility o = prt::specular::computeVisibility(bundle.mesh, options);
    // The clamped cosine about +z: O_00 = pi Y_00 ... = sqrt(pi) / 2 exactly for an unoccluded vertex.
    EXPECT_NEAR(o.coefficients[0], std::sqrt(std::numbers::pi) / 2.0, 1e-6);
    bundle.layers.push_back(prt::specular::visibilityLayer(o, options));
    prt::specular::Visibility back = prt::specular::readVisibility(bundle, "square.glb");
    EXPECT_EQ(back.order, 3);
    EXPECT_EQ(back.coefficients, o.coefficients);
    bundle.layers[0].params["order"] = 4; // shape [4, 9] no longer matches order 4
    EXPECT_THROW(prt::specular::readVisibility(bundle, "square.glb"), prt::Error);
    bundle.layers[0].params["order"] = 3;
    bundle.layers[0].data[5] = std::nanf("");
    EXPECT_THROW(prt::specular::readVisibility(bundle, "square.glb"), prt::Error);
    options.order = 0;
    EXPECT_THROW(prt::specular::computeVisibility(bundle.mesh, options), prt::Error);
}

} // namespace
