// Hybrid relighting: the SH residual through the whole transfer, cone lights directly in closed form with the
// caller's visibility, and the lights' interreflected light through the transfer's bounce part.
#include "runtime.h"

#include "core.h"
#include "json_input.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <numbers>

namespace prt {

namespace {

std::array<float, 3> finiteTriple(const nlohmann::json& value, const std::string& path, const std::string& place) {
    if (!value.is_array() || value.size() != 3) throw Error(path, place, "expected [x, y, z]");
    std::array<float, 3> out;
    for (int c = 0; c < 3; ++c) {
        double x = value[c].is_number() ? value[c].get<double>() : NAN;
        if (!std::isfinite(x) || !std::isfinite(float(x)))
            throw Error(path, place, "value " + jsonExcerpt(value[c]) + " is not a finite float");
        out[c] = float(x);
    }
    return out;
}

} // namespace

HybridLighting readHybridLightingJson(const std::string& path) {
    // Size and nesting bounded before the parse; members typed (json_input.h).
    nlohmann::json document = readJsonFile(path, kMaxLightsJsonBytes);
    if (jsonString(document, "format", path, "") != "prt-lights")
        throw Error(path, "format", "not prt-lights JSON (expected \"format\": \"prt-lights\", as `prt envlight` writes)");
    const nlohmann::json& order = document.contains("order") ? document["order"] : nlohmann::json();
    if (!order.is_number_integer() || order.get<int64_t>() < 1 || order.get<int64_t>() > sh::kMaxOrder)
        throw Error(path, "order", "order " + jsonExcerpt(order) + " is not an integer in 1.." + std::to_string(sh::kMaxOrder));
    HybridLighting lighting;
    lighting.order = order.get<int>();
    const nlohmann::json& rows = document.contains("residual") ? document["residual"] : nlohmann::json();
    if (!rows.is_array() || rows.size() != size_t(sh::coefficientCount(lighting.order)))
        throw Error(path, "residual", "expected an array of " + std::to_string(sh::coefficientCount(lighting.order)) +
                                          " [r, g, b] rows for order " + std::to_string(lighting.order));
    for (size_t i = 0; i < rows.size(); ++i) {
        std::array<float, 3> rgb = finiteTriple(rows[i], path, "residual[" + std::to_string(i) + "]");
        lighting.residual.insert(lighting.residual.end(), rgb.begin(), rgb.end());
    }
    const nlohmann::json& lights = document.contains("lights") ? document["lights"] : nlohmann::json();
    if (!lights.is_array()) throw Error(path, "lights", "expected an array of lights");
    if (lights.size() > 4096) throw Error(path, "lights", std::to_string(lights.size()) + " lights (at most 4096)");
    for (size_t k = 0; k < lights.size(); ++k) {
        const std::string place = "lights[" + std::to_string(k) + "]";
        const nlohmann::json& light = lights[k];
        if (!light.is_object()) throw Error(path, place, "expected an object");
        HybridConeLight cone;
        cone.direction = finiteTriple(light.value("direction", nlohmann::json()), path, place + ".direction");
        double length = std::sqrt(double(cone.direction[0]) * cone.direction[0] +
                                  double(cone.direction[1]) * cone.direction[1] +
                                  double(cone.direction[2]) * cone.direction[2]);
        if (std::abs(length - 1.0) > 1e-3)
            throw Error(path, place + ".direction", "length " + std::to_string(length) + " is not 1");
        for (float& x : cone.direction) x = float(x / length);
        cone.radiance = finiteTriple(light.value("radiance", nlohmann::json()), path, place + ".radiance");
        for (float x : cone.radiance)
            if (x < 0.0f) throw Error(path, place + ".radiance", "negative radiance " + std::to_string(x));
        const nlohmann::json& radius = light.value("angular_radius", nlohmann::json());
        double r = radius.is_number() ? radius.get<double>() : NAN;
        if (!std::isfinite(r) || !(r > 0.0 && r < std::numbers::pi / 2))
            throw Error(path, place + ".angular_radius", "value " + jsonExcerpt(radius) + " is not a finite angle in (0, pi/2)");
        cone.angularRadius = float(r);
        lighting.lights.push_back(cone);
    }
    return lighting;
}

HybridLighting rotateHybridLighting(const HybridLighting& lighting, const double rotation[9]) {
    HybridLighting rotated = lighting;
    rotated.residual = rotateLighting(lighting.residual.data(), lighting.order, rotation);
    for (HybridConeLight& light : rotated.lights) {
        std::array<float, 3> d = light.direction;
        for (int r = 0; r < 3; ++r)
            light.direction[r] = float(rotation[3 * r] * d[0] + rotation[3 * r + 1] * d[1] + rotation[3 * r + 2] * d[2]);
    }
    return rotated;
}

double coneCosineIntegral(double cosAngle, double angularRadius) {
    const double sinRadius = std::sin(angularRadius);
    return sh::capCosineIntegral(cosAngle, sinRadius * sinRadius);
}

std::vector<float> coneLightsProjection(const std::vector<HybridConeLight>& lights, int order) {
    std::vector<double> sum(size_t(sh::coefficientCount(order)) * 3, 0.0);
    for (const HybridConeLight& light : lights) {
        double d[3] = {light.direction[0], light.direction[1], light.direction[2]};
        double radiance[3] = {light.radiance[0], light.radiance[1], light.radiance[2]};
        sh::addCapRadiance(order, d, std::cos(double(light.angularRadius)), radiance, sum.data());
    }
    return std::vector<float>(sum.begin(), sum.end());
}

HybridModel hybridModel(Bundle bundle, const std::string& source) {
    HybridModel model;
    const Layer* transfer = findLayer(bundle, "transfer");
    nlohmann::json albedo = transfer ? transfer->params.value("albedo", nlohmann::json()) : nlohmann::json();
    std::vector<float> bounce;
    for (Layer& layer : bundle.layers)
        if (layer.name == "transfer_bounce") {
            if (layer.domain != "vertex" || layer.semantic != "sh_transfer_bounce_rgb" || !transfer ||
                layer.shape != transfer->shape || layer.data.size() != transfer->data.size())
                throw Error(source, "layer \"transfer_bounce\"",
                            "expected domain \"vertex\", semantic \"sh_transfer_bounce_rgb\" and the transfer's shape");
            for (float x : layer.data)
                if (!std::isfinite(x)) throw Error(source, "layer \"transfer_bounce\"", "value is not finite");
            bounce = std::move(layer.data);
        }
    TriMesh mesh = bundle.mesh;
    model.total = relightModel(std::move(bundle), source);
    const size_t rows = model.total.vertexCount;
    if (mesh.normals.size() != rows * 3)
        throw Error(source, "mesh", "has no normals for the cone lights (run `prt meshprep`)");
    model.normals = mesh.normals;
    for (size_t v = 0; v < rows; ++v) {
        float* n = &model.normals[v * 3];
        float length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(length > 0.0f) || !std::isfinite(length)) throw Error(source, "mesh, vertex " + std::to_string(v), "normal is zero or not finite");
        for (int c = 0; c < 3; ++c) n[c] /= length;
    }
    if (albedo.is_string() && albedo.get<std::string>() == "per-vertex") {
        if (mesh.albedo.size() != rows * 3) throw Error(source, "mesh", "transfer says per-vertex albedo, the mesh has none");
        model.albedo = mesh.albedo;
    } else if (albedo.is_array() && albedo.size() == 3 && albedo[0].is_number() && albedo[1].is_number() &&
               albedo[2].is_number()) {
        model.albedo.resize(rows * 3);
        for (size_t v = 0; v < rows; ++v)
            for (int c = 0; c < 3; ++c) model.albedo[v * 3 + c] = albedo[c].get<float>();
    } else if (model.total.albedoExcluded) {
        model.albedo = model.total.albedo; // a scene: its "diffuse_albedo" layer, which relight() multiplies by
    } else {
        throw Error(source, "layer \"transfer\"", "params.albedo is neither \"per-vertex\", \"excluded\" nor [r, g, b]");
    }
    model.bounce = std::move(bounce);
    return model;
}

HybridModel loadHybridModel(const std::string& bundlePath) { return hybridModel(readBundle(bundlePath), bundlePath); }

void checkHybridOrder(const HybridModel& model, const HybridLighting& lighting, const std::string& lightsSource) {
    if (lighting.order != model.total.order)
        throw Error(lightsSource, "order", "the lights' residual has order " + std::to_string(lighting.order) +
                                                ", the bundle's transfer order " + std::to_string(model.total.order) +
                                                ": run `prt envlight --order " + std::to_string(model.total.order) + "`");
}

void relightHybrid(const HybridModel& model, const HybridLighting& lighting, const ConeVisibility& visibility,
                   size_t begin, size_t end, float* radiance) {
    checkHybridOrder(model, lighting, "");
    if (begin > end || end > model.total.vertexCount)
        throw Error("", "relightHybrid", "row range outside the model", kExitFailure);
    const int coefficients = sh::coefficientCount(model.total.order);
    const size_t rowValues = size_t(coefficients) * 3, count = end - begin;
    relight(model.total, lighting.residual.data(), begin, end, radiance);
    if (lighting.lights.empty()) return;
    if (!model.bounce.empty()) {
        std::vector<float> lit = coneLightsProjection(lighting.lights, model.total.order), bounced(count * 3);
        sh::applyWindow(lighting.bounceWindow, model.total.order, lit.data(), 3);
        relight(model.bounce.data() + begin * rowValues, count, coefficients, lit.data(), bounced.data());
        // A scene's bounce layer is irradiance transfer too: times the receiver's albedo.
        if (model.total.albedoExcluded)
            for (size_t i = 0; i < count * 3; ++i) bounced[i] *= model.albedo[begin * 3 + i];
        for (size_t i = 0; i < count * 3; ++i) radiance[i] += bounced[i];
    }
    for (size_t v = begin; v < end; ++v) {
        const float* n = &model.normals[v * 3];
        const float* albedo = &model.albedo[v * 3];
        float* out = radiance + (v - begin) * 3;
        for (size_t k = 0; k < lighting.lights.size(); ++k) {
            const HybridConeLight& light = lighting.lights[k];
            float visible = visibility(v, k);
            if (!(visible > 0.0f)) continue;
            double cosAngle = double(n[0]) * light.direction[0] + double(n[1]) * light.direction[1] +
                              double(n[2]) * light.direction[2];
            double irradiance = coneCosineIntegral(cosAngle, light.angularRadius) * std::min(1.0f, visible);
            for (int c = 0; c < 3; ++c)
                out[c] += float(albedo[c] / std::numbers::pi * light.radiance[c] * irradiance);
        }
    }
}

void relightHybrid(const HybridModel& model, const HybridLighting& lighting, const float* visibility, size_t begin,
                   size_t end, float* radiance) {
    const size_t lights = lighting.lights.size();
    relightHybrid(
        model, lighting, [&](size_t row, size_t light) { return visibility[row * lights + light]; }, begin, end,
        radiance);
}

} // namespace prt
