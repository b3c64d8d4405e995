// Lighting for the runtime: SH coefficients from prt-sh JSON or an environment map, rotated and order-matched.
#include "runtime.h"

#include "core.h"
#include "json_input.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>

namespace prt {

std::vector<float> fitLighting(const float* lighting, int lightingCoefficientCount, int coefficientCount) {
    const int most = sh::kMaxOrder * sh::kMaxOrder;
    if (lightingCoefficientCount < 0 || lightingCoefficientCount > most || coefficientCount < 0 || coefficientCount > most)
        throw Error("", "fitLighting", "coefficient counts " + std::to_string(lightingCoefficientCount) + " and " +
                                           std::to_string(coefficientCount) + " are not both in 0.." + std::to_string(most),
                    kExitFailure);
    std::vector<float> fitted(size_t(coefficientCount) * 3, 0.0f);
    std::copy_n(lighting, size_t(std::min(lightingCoefficientCount, coefficientCount)) * 3, fitted.begin());
    return fitted;
}

std::vector<float> readLightingJson(const std::string& path, int* order) {
    nlohmann::json document = readJsonFile(path, kMaxShJsonBytes); // size and nesting bounded first
    // value() would throw a type error for a non-string "format": compare as JSON instead.
    if (!document.is_object() || !document.contains("format") || document["format"] != "prt-sh")
        throw Error(path, "format", "not prt-sh JSON (expected \"format\": \"prt-sh\", as `prt envsh` writes)");
    const nlohmann::json& orderValue = document.contains("order") ? document["order"] : nlohmann::json();
    if (!orderValue.is_number_integer() || orderValue.get<int64_t>() < 1 ||
        orderValue.get<int64_t>() > sh::kMaxOrder)
        throw Error(path, "order", "order " + jsonExcerpt(orderValue) + " is not an integer in 1.." +
                                       std::to_string(sh::kMaxOrder));
    int bands = orderValue.get<int>();
    const nlohmann::json& rows = document.contains("coefficients") ? document["coefficients"] : nlohmann::json();
    if (!rows.is_array() || rows.size() != size_t(sh::coefficientCount(bands)))
        throw Error(path, "coefficients", "expected an array of " + std::to_string(sh::coefficientCount(bands)) +
                                              " [r, g, b] rows for order " + std::to_string(bands));

    std::vector<float> lighting;
    lighting.reserve(rows.size() * 3);
    for (size_t i = 0; i < rows.size(); ++i) {
        const nlohmann::json& row = rows[i];
        if (!row.is_array() || row.size() != 3)
            throw Error(path, "coefficients[" + std::to_string(i) + "]", "expected [r, g, b]");
        for (const nlohmann::json& value : row) {
            float radiance = value.is_number() ? value.get<float>() : NAN;
            if (!std::isfinite(radiance))
                throw Error(path, "coefficients[" + std::to_string(i) + "]",
                            "value " + jsonExcerpt(value) + " is not a finite float");
            lighting.push_back(radiance);
        }
    }
    *order = bands;
    return lighting;
}

std::vector<float> rotateLighting(const float* lighting, int order, const double rotation[9]) {
    std::vector<float> rotated(size_t(sh::coefficientCount(order)) * 3);
    sh::rotate(sh::rotation(order, rotation), lighting, rotated.data(), 3);
    return rotated;
}

std::vector<float> environmentLighting(const EnvironmentMap& env, int order, const double* rotation,
                                       sh::Window window) {
    std::vector<float> lighting = sh::projectEnvironment(env, order);
    if (rotation) lighting = rotateLighting(lighting.data(), order, rotation);
    sh::applyWindow(window, order, lighting.data(), 3);
    return lighting;
}

} // namespace prt
