// The glossy runtime: the 3 views around the eye direction, each view's lobes turned onto the eye's mirror
// direction and looked up in the prefiltered environment (glossy_prefilter.cpp), their radiances blended. Needs only the bundle reader and the standard library.
#include "runtime.h"
#include "runtime_internal.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace prt {

namespace {

constexpr double kPi = std::numbers::pi;

float dot3(const float* a, const float* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

double triple(const float* x, const float* y, const float* z) {
    return double(x[0]) * (double(y[1]) * z[2] - double(y[2]) * z[1]) -
           double(x[1]) * (double(y[0]) * z[2] - double(y[2]) * z[0]) +
           double(x[2]) * (double(y[0]) * z[1] - double(y[1]) * z[0]);
}

// Whether the view triangles tile the sphere exactly once, which viewWeights needs to find, for every direction,
// a triangle holding it with weights >= 0: each triangle counter-clockwise seen from outside (positive triple
// product), each directed edge once and its reverse once (a closed surface), and their solid angles (Van
// Oosterom-Strackee) summing to 4 pi. A closed surface has one covering degree everywhere, total / 4 pi, and with
// every triangle positive that degree counts the triangles over each direction. Returns the problem, or "".
std::string viewTilingProblem(const std::vector<float>& views, const std::vector<uint32_t>& triangles) {
    const size_t count = triangles.size() / 3;
    std::vector<uint64_t> edges;
    edges.reserve(triangles.size());
    double total = 0.0;
    for (size_t t = 0; t < count; ++t) {
        const uint32_t* tri = &triangles[3 * t];
        const float *a = &views[3 * size_t(tri[0])], *b = &views[3 * size_t(tri[1])], *c = &views[3 * size_t(tri[2])];
        double det = triple(a, b, c);
        if (!(det > 0.0))
            return "view triangle " + std::to_string(t) + " is degenerate or not counter-clockwise from outside";
        total += 2.0 * std::atan2(det, 1.0 + double(dot3(a, b)) + dot3(b, c) + dot3(c, a));
        for (int e = 0; e < 3; ++e) edges.push_back(uint64_t(tri[e]) << 32 | tri[(e + 1) % 3]);
    }
    std::sort(edges.begin(), edges.end());
    for (size_t e = 0; e < edges.size(); ++e) {
        if (e > 0 && edges[e] == edges[e - 1]) return "two view triangles share a directed edge";
        uint64_t reverse = (edges[e] & 0xffffffffu) << 32 | edges[e] >> 32;
        if (!std::binary_search(edges.begin(), edges.end(), reverse))
            return "an edge of the view triangles has no triangle on its other side (they leave a hole)";
    }
    if (!(std::abs(total - 4.0 * kPi) < 1e-3)) return "the view triangles do not cover the sphere once";
    return "";
}

} // namespace

GlossyModel glossyModel(const Bundle& bundle, const std::string& source) {
    const Layer* layer = findLayer(bundle, "glossy_lobes");
    if (!layer) throw Error(source, "layers", "has no \"glossy_lobes\" layer (prt glossy writes one)");
    auto bad = [&](const std::string& problem) { return Error(source, "layer glossy_lobes", problem); };
    if (layer->domain != "vertex" || layer->semantic != "sg_lobes")
        throw bad("needs domain vertex and semantic sg_lobes");
    if (layer->shape.size() != 4 || layer->shape[3] != 5 || layer->shape[2] < 1 || layer->shape[2] > 4)
        throw bad("shape must be [V, views, N (1..4), 5]");
    if (layer->shape[0] != bundle.mesh.vertexCount())
        throw bad("has " + std::to_string(layer->shape[0]) + " rows for " + std::to_string(bundle.mesh.vertexCount()) +
                  " vertices");
    if (bundle.mesh.normals.size() != bundle.mesh.positions.size()) throw Error(source, "mesh", "has no normals");
    GlossyModel model;
    const nlohmann::json& views = layer->params.value("views", nlohmann::json());
    const nlohmann::json& triangles = layer->params.value("view_triangles", nlohmann::json());
    if (!views.is_array() || views.size() != layer->shape[1])
        throw bad("its view set (params.views, " + std::to_string(views.is_array() ? views.size() : 0) +
                  " directions) disagrees with its " + std::to_string(layer->shape[1]) + " views per vertex");
    for (const auto& v : views) {
        if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
            throw bad("params.views must hold x,y,z triples");
        float d[3] = {v[0].get<float>(), v[1].get<float>(), v[2].get<float>()};
        if (!(std::abs(std::sqrt(dot3(d, d)) - 1.0f) < 1e-3f)) throw bad("params.views must be unit directions");
        model.views.insert(model.views.end(), d, d + 3);
    }
    if (!triangles.is_array() || triangles.empty()) throw bad("params.view_triangles is missing");
    for (const auto& t : triangles) {
        if (!t.is_array() || t.size() != 3) throw bad("params.view_triangles must hold index triples");
        for (const auto& i : t) {
            if (!i.is_number_unsigned() || i.get<uint64_t>() >= views.size())
                throw bad("params.view_triangles indexes a view that does not exist");
            model.triangles.push_back(i.get<uint32_t>());
        }
    }
    if (std::string problem = viewTilingProblem(model.views, model.triangles); !problem.empty())
        throw bad("params.view_triangles: " + problem);
    // Read from the float storage only: a layer of another component type holds its values elsewhere.
    if (layer->componentType != "float32" && layer->componentType != "float16")
        throw bad("component type is " + layer->componentType + ", not float16 or float32");
    if (layer->data.size() != layer->shape[0] * layer->shape[1] * layer->shape[2] * 5)
        throw bad("holds " + std::to_string(layer->data.size()) + " values, not the V x views x N x 5 of its shape");
    model.vertexCount = uint32_t(layer->shape[0]);
    model.lobes = int(layer->shape[2]);
    model.values = layer->data;
    for (size_t i = 0; i < model.values.size(); ++i) {
        if (!std::isfinite(model.values[i])) throw bad("holds a value that is not finite");
        // (a, mu, lambda): a negative sharpness is a lobe that grows away from its mean.
        if (i % 5 == 4 && model.values[i] < 0.0f)
            throw bad("lobe sharpness (lambda) " + std::to_string(model.values[i]) + " at value " + std::to_string(i) +
                      " is negative");
    }
    model.positions = bundle.mesh.positions;
    model.normals = bundle.mesh.normals;
    indexViewTriangles(model);
    const nlohmann::json& brdf = layer->params.value("brdf", nlohmann::json());
    if (brdf.is_object() && brdf.value("model", "") == "phong") {
        const nlohmann::json& exponent = brdf.value("exponent", nlohmann::json());
        const nlohmann::json& ks = brdf.value("ks", nlohmann::json());
        if (!exponent.is_number() || !ks.is_number() || !(exponent.get<double>() > 0.0) ||
            !std::isfinite(exponent.get<double>()) || !(ks.get<double>() >= 0.0 && ks.get<double>() <= 1.0))
            throw bad("params.brdf needs an exponent > 0 and ks in [0, 1]");
        model.exponent = exponent.get<double>();
        model.ks = ks.get<double>();
    }
    return model;
}

namespace {

// The weights of d in view triangle t (Cramer's rule with triple products) and the smallest of them over their
// sum; -inf when d lies on the far side.
double triangleWeights(const GlossyModel& model, size_t t, const float d[3], double w[3]) {
    const uint32_t* tri = &model.triangles[t * 3];
    const float* a = &model.views[tri[0] * 3];
    const float* b = &model.views[tri[1] * 3];
    const float* c = &model.views[tri[2] * 3];
    double det = triple(a, b, c);
    w[0] = triple(d, b, c) / det, w[1] = triple(a, d, c) / det, w[2] = triple(a, b, d) / det;
    double sum = w[0] + w[1] + w[2];
    if (!(sum > 0)) return -1e300;
    return std::min({w[0], w[1], w[2]}) / sum;
}

} // namespace

void indexViewTriangles(GlossyModel& model) {
    const size_t viewCount = model.viewCount();
    model.viewTriangleOffsets.assign(viewCount + 1, 0);
    for (uint32_t v : model.triangles) ++model.viewTriangleOffsets[v + 1];
    for (size_t v = 0; v < viewCount; ++v) model.viewTriangleOffsets[v + 1] += model.viewTriangleOffsets[v];
    model.viewTriangles.assign(model.triangles.size(), 0);
    std::vector<uint32_t> fill(model.viewTriangleOffsets.begin(), model.viewTriangleOffsets.end() - 1);
    for (size_t t = 0; t < model.triangles.size() / 3; ++t) // ascending triangles per view
        for (int k = 0; k < 3; ++k) model.viewTriangles[fill[model.triangles[t * 3 + k]]++] = uint32_t(t);
}

void viewWeights(const GlossyModel& model, const float d[3], uint32_t views[3], float weights[3]) {
    double bestMin = -1e30;
    // glossyModel guarantees a tiling, so some triangle holds d; these only keep the outputs defined if none does.
    views[0] = views[1] = views[2] = 0;
    weights[0] = 1.0f, weights[1] = weights[2] = 0.0f;
    auto keep = [&](size_t t, double low, const double* w) {
        bestMin = low;
        const uint32_t* tri = &model.triangles[t * 3];
        views[0] = tri[0], views[1] = tri[1], views[2] = tri[2];
        weights[0] = float(std::max(0.0, w[0])), weights[1] = float(std::max(0.0, w[1]));
        weights[2] = float(std::max(0.0, w[2]));
    };
    bool found = false;
    if (model.viewTriangleOffsets.size() == model.viewCount() + 1 && model.viewCount() > 0) {
        // The triangles around the nearest view hold d but where d lies within rounding of an edge they do not
        // share; the full scan below catches those.
        size_t nearest = 0;
        float bestDot = -2.0f;
        for (size_t v = 0; v < model.viewCount(); ++v) {
            float c = dot3(&model.views[v * 3], d);
            if (c > bestDot) bestDot = c, nearest = v;
        }
        for (uint32_t i = model.viewTriangleOffsets[nearest]; i < model.viewTriangleOffsets[nearest + 1]; ++i) {
            double w[3];
            double low = triangleWeights(model, model.viewTriangles[i], d, w);
            if (low >= 0) {
                keep(model.viewTriangles[i], low, w);
                found = true;
                break;
            }
        }
    }
    for (size_t t = 0; !found && t < model.triangles.size() / 3; ++t) {
        double w[3];
        double low = triangleWeights(model, t, d, w);
        if (low > bestMin) { // the containing triangle has all weights >= 0; keep the best if rounding hides it
            keep(t, low, w);
            if (low >= 0) break;
        }
    }
    float total = weights[0] + weights[1] + weights[2];
    for (int i = 0; i < 3; ++i) weights[i] /= total;
}

void interpolateLobe(const GlossyModel& model, uint32_t vertex, int lobe, const uint32_t views[3],
                     const float weights[3], float out[5]) {
    double a = 0.0, mean[3] = {0, 0, 0}, logSharpness = 0.0;
    for (int j = 0; j < 3; ++j) {
        const float* v = &model.values[((size_t(vertex) * model.viewCount() + views[j]) * model.lobes + lobe) * 5];
        a += weights[j] * double(v[0]);
        for (int c = 0; c < 3; ++c) mean[c] += weights[j] * double(v[1 + c]);
        logSharpness += weights[j] * std::log(std::max(double(v[4]), 1e-6));
    }
    double length = std::sqrt(mean[0] * mean[0] + mean[1] * mean[1] + mean[2] * mean[2]);
    out[0] = float(a);
    for (int c = 0; c < 3; ++c) out[1 + c] = length > 0 ? float(mean[c] / length) : (c == 1 ? 1.0f : 0.0f);
    out[4] = float(std::exp(logSharpness));
}

void turnViewLobes(const GlossyModel& model, uint32_t vertex, uint32_t view, const float mirror[3], float* out) {
    const float* n = &model.normals[size_t(vertex) * 3];
    const float* w = &model.views[size_t(view) * 3];
    double ln2 = double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2];
    double c = (double(w[0]) * n[0] + double(w[1]) * n[1] + double(w[2]) * n[2]) / ln2;
    double from[3], to[3] = {mirror[0], mirror[1], mirror[2]};
    for (int i = 0; i < 3; ++i) from[i] = 2.0 * c * n[i] - w[i];
    // Rodrigues' rotation about from x to, by the angle between them (unit vectors).
    double axis[3] = {from[1] * to[2] - from[2] * to[1], from[2] * to[0] - from[0] * to[2],
                      from[0] * to[1] - from[1] * to[0]};
    double sine = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    double cosine = from[0] * to[0] + from[1] * to[1] + from[2] * to[2];
    const float* lobes = &model.values[(size_t(vertex) * model.viewCount() + view) * size_t(model.lobes) * 5];
    std::copy_n(lobes, size_t(model.lobes) * 5, out);
    if (!(sine > 1e-9)) return;
    for (double& a : axis) a /= sine;
    for (int k = 0; k < model.lobes; ++k) {
        float* lobe = out + k * 5;
        double m[3] = {lobe[1], lobe[2], lobe[3]};
        double cross[3] = {axis[1] * m[2] - axis[2] * m[1], axis[2] * m[0] - axis[0] * m[2], axis[0] * m[1] - axis[1] * m[0]};
        double along = axis[0] * m[0] + axis[1] * m[1] + axis[2] * m[2];
        for (int i = 0; i < 3; ++i) lobe[1 + i] = float(m[i] * cosine + cross[i] * sine + axis[i] * along * (1.0 - cosine));
    }
}

void glossySharpnessRange(const GlossyModel& model, double& sharpnessMin, double& sharpnessMax) {
    sharpnessMin = 1.0, sharpnessMax = 0.0;
    bool any = false;
    for (size_t i = 0; i + 4 < model.values.size(); i += 5) {
        if (!(model.values[i] > 0.0f)) continue;
        const double sharpness = model.values[i + 4];
        sharpnessMin = any ? std::min(sharpnessMin, sharpness) : sharpness;
        sharpnessMax = any ? std::max(sharpnessMax, sharpness) : sharpness;
        any = true;
    }
}

void choosePrefilterRange(const GlossyModel& model, size_t lobeEvaluations, PrefilterOptions& options) {
    if (lobeEvaluations >= kStackBreakEvenLobes) {
        glossySharpnessRange(model, options.sharpnessMin, options.sharpnessMax);
    } else {
        options.sharpnessMin = 1.0, options.sharpnessMax = 0.0; // no stack
    }
}

void glossyRadianceToward(const GlossyModel& model, const PrefilteredEnvironment& env, uint32_t vertex,
                          const float d[3], float radiance[3]) {
    glossyRadianceToward(model, env, vertex, d, radiance, LobeEvaluation::Prefiltered);
}

void glossyRadianceToward(const GlossyModel& model, const PrefilteredEnvironment& env, uint32_t vertex,
                          const float d[3], float radiance[3], LobeEvaluation evaluation) {
    radiance[0] = radiance[1] = radiance[2] = 0.0f;
    const float* n = &model.normals[size_t(vertex) * 3];
    if (dot3(d, n) <= 0.0f) return; // the lobe sends nothing below the surface
    uint32_t views[3];
    float weights[3];
    viewWeights(model, d, views, weights);
    // The view's mirror direction about the (unit) normal; each view's lobes turned onto it, then the three views'
    // radiances blended: no lobe of one view is paired with a lobe of another.
    double ln2 = double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2];
    double c = (double(d[0]) * n[0] + double(d[1]) * n[1] + double(d[2]) * n[2]) / ln2;
    float mirror[3];
    for (int i = 0; i < 3; ++i) mirror[i] = float(2.0 * c * n[i] - d[i]);
    float turned[4 * 5];
    const int lobes = std::min(model.lobes, 4); // glossyModel allows 1..4
    for (int j = 0; j < 3; ++j) {
        if (!(weights[j] > 0.0f)) continue;
        turnViewLobes(model, vertex, views[j], mirror, turned);
        for (int k = 0; k < lobes; ++k) {
            float lit[3];
            if (evaluation == LobeEvaluation::ExactSum)
                integrateLobe(env, &turned[size_t(k) * 5], lit);
            else
                lookupLobe(env, &turned[size_t(k) * 5], lit);
            for (int i = 0; i < 3; ++i) radiance[i] += weights[j] * lit[i];
        }
    }
}

bool directionToEye(const GlossyModel& model, uint32_t vertex, const float eye[3], float d[3]) {
    const float* p = &model.positions[size_t(vertex) * 3];
    float toward[3] = {eye[0] - p[0], eye[1] - p[1], eye[2] - p[2]};
    float length = std::sqrt(dot3(toward, toward));
    if (!(length > 0.0f)) return false;
    for (int i = 0; i < 3; ++i) d[i] = toward[i] / length;
    return true;
}

void glossyRadiance(const GlossyModel& model, const PrefilteredEnvironment& env, const float eye[3],
                    float* radiance, LobeEvaluation evaluation) {
    for (uint32_t v = 0; v < model.vertexCount; ++v) {
        float* out = radiance + size_t(v) * 3;
        out[0] = out[1] = out[2] = 0.0f;
        float d[3];
        if (directionToEye(model, v, eye, d)) glossyRadianceToward(model, env, v, d, out, evaluation);
    }
}

} // namespace prt
