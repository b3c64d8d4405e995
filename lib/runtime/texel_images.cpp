// prt::runtime_images: a bake bundle's per-texel layers ("texel_transfer", and the texel hybrid's
// "texel_transfer_bounce" and "texel_surface") read from the textures they reference, through lib/image
// (OpenImageIO). Kept out of prt_runtime so the thin runtime needs no image library.
#include "runtime.h"

#include "core.h"
#include "json_input.h"
#include "image.h"
#include "runtime_internal.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>

namespace prt {

namespace {

namespace fs = std::filesystem;

// The string params[key], or an error naming the layer.
std::string stringParam(const Layer& layer, const char* key, const std::string& source, const std::string& place) {
    if (!layer.params.contains(key) || !layer.params[key].is_string())
        throw Error(source, place, std::string("params.") + key + " is missing or not a string");
    return layer.params[key].get<std::string>();
}

// A file referenced from `owner` by a relative uri: checked against its recorded hash.
std::string referencedFile(const std::string& owner, const std::string& uri, const nlohmann::json& hash,
                           const std::string& place) {
    fs::path relative = fs::path(uri).lexically_normal();
    if (uri.empty() || relative.is_absolute() || relative.empty() || *relative.begin() == "..")
        throw Error(owner, place, "uri '" + uri + "' is not a path inside the bundle's folder");
    std::error_code error;
    fs::path resolved = fs::canonical(owner, error); // a linked bundle's textures lie next to its target
    const fs::path folder = (error ? fs::path(owner) : resolved).parent_path();
    fs::path path = folder / uri;
    if (fs::exists(fs::symlink_status(path, error)) && resolvedInside(path.string(), folder.string()).empty())
        throw Error(owner, place, "uri '" + uri + "' leads out of the bundle's folder (through a link)");
    if (!fs::is_regular_file(path, error))
        throw Error(path.string(), "", "referenced by " + owner + " (" + place + ") but not found");
    if (!hash.is_string()) throw Error(owner, place, "no content hash recorded for " + uri);
    std::string actual = hashFile(path.string());
    if (actual != hash.get<std::string>())
        throw Error(path.string(), "", "content hash " + actual + " differs from " + hash.get<std::string>() +
                                           " recorded in " + owner + ": the texture was modified or belongs to "
                                           "another bake");
    return path.string();
}

void checkSize(const ImageChannels& image, int width, int height, const std::string& path) {
    if (image.width != width || image.height != height)
        throw Error(path, "", std::to_string(image.width) + "x" + std::to_string(image.height) +
                                  " texels; the bundle's layer says " + std::to_string(width) + "x" +
                                  std::to_string(height));
}

// Format "half" / "float": one OpenEXR with every coefficient's RGB as named channels.
std::vector<float> readExrRows(const std::string& path, int width, int height, int coefficients) {
    std::vector<std::string> names;
    for (int j = 0; j < coefficients; ++j)
        for (int c = 0; c < 3; ++c) names.push_back(texelCoefficientChannel(j, c));
    ImageChannels image = readImageChannels(path, names);
    checkSize(image, width, height, path);
    return std::move(image.values);
}

// Format "u8": a JSON sidecar listing one 8-bit RGB image per coefficient with its [min, max].
std::vector<float> readU8Rows(const std::string& sidecarPath, int width, int height, int coefficients) {
    nlohmann::json sidecar = readJsonFile(sidecarPath, kMaxSidecarJsonBytes); // size and nesting bounded first
    if (!sidecar.is_object() || !sidecar.contains("format") || sidecar["format"] != "prt-texel-u8" ||
        !sidecar.contains("layers") || !sidecar["layers"].is_array())
        throw Error(sidecarPath, "", "not a prt-texel-u8 sidecar (JSON with format \"prt-texel-u8\" and layers)");
    const nlohmann::json& layers = sidecar["layers"];
    if (int(layers.size()) != coefficients)
        throw Error(sidecarPath, "layers", std::to_string(layers.size()) + " layers for " +
                                               std::to_string(coefficients) + " coefficients");
    const size_t texels = size_t(width) * height, values = 3 * size_t(coefficients);
    std::vector<float> rows; // allocated once the first image has shown the size is real
    for (int j = 0; j < coefficients; ++j) {
        const nlohmann::json& layer = layers[j];
        std::string place = "layers[" + std::to_string(j) + "]";
        if (!layer.is_object() || !layer.contains("uri") || !layer["uri"].is_string() || !layer.contains("min") ||
            !layer["min"].is_number() || !layer.contains("max") || !layer["max"].is_number())
            throw Error(sidecarPath, place, "needs uri, hash, min and max");
        std::string path = referencedFile(sidecarPath, layer["uri"].get<std::string>(),
                                          layer.value("hash", nlohmann::json()), place);
        ImageChannels image = readImageChannels(path, {"R", "G", "B"});
        checkSize(image, width, height, path);
        if (rows.empty()) rows.resize(texels * values);
        float lo = layer["min"].get<float>(), span = layer["max"].get<float>() - lo;
        // The file holds q / 255 as read; value = min + q * (max - min) / 255.
        for (size_t t = 0; t < texels; ++t)
            for (int c = 0; c < 3; ++c) rows[t * values + 3 * j + c] = lo + image.values[3 * t + c] * span;
    }
    return rows;
}

// The rows of a texel coefficient layer ([W*H][coefficients][3]): inline, or from the texture params.uri names.
std::vector<float> texelLayerRows(const std::string& bundlePath, const Layer& layer, int width, int height,
                                  int coefficients) {
    const std::string place = std::string("layer \"").append(layer.name).append("\"");
    const size_t values = size_t(width) * height * 3 * size_t(coefficients);
    // The size comes from the bundle's JSON: bounded before anything is allocated for it.
    checkedProduct({uint64_t(width) * uint64_t(height), 3 * uint64_t(coefficients)}, "texel values", bundlePath, place);
    std::vector<float> rows;
    if (!layer.params.contains("uri")) {
        if (layer.data.size() != values)
            throw Error(bundlePath, place, "holds " + std::to_string(layer.data.size()) + " values, not " +
                                               std::to_string(values));
        rows = layer.data;
    } else {
        std::string format = stringParam(layer, "format", bundlePath, place);
        std::string path = referencedFile(bundlePath, stringParam(layer, "uri", bundlePath, place),
                                          layer.params.value("hash", nlohmann::json()), place + ", params.uri");
        if (format == "half" || format == "float")
            rows = readExrRows(path, width, height, coefficients);
        else if (format == "u8")
            rows = readU8Rows(path, width, height, coefficients);
        else
            throw Error(bundlePath, place + ", params.format", "'" + format + "' is not one of half, float, u8");
        checkFiniteRows(rows, 3 * size_t(coefficients), path, "texture", "texel");
        return rows;
    }
    checkFiniteRows(rows, 3 * size_t(coefficients), bundlePath, place, "texel");
    return rows;
}

// loadTexelRelightModel on a bundle already read from bundlePath.
TexelRelightModel texelModelOf(Bundle bundle, const std::string& bundlePath) {
    if (!findLayer(bundle, "texel_transfer") && hasAdaptiveTransfer(bundle)) return adaptiveTexelModel(bundle, bundlePath);
    const Layer* layer = &transferLayer(bundle, "texel_transfer", "texel", bundlePath, "bake");
    if (!layer->params.contains("uri")) return texelRelightModel(std::move(bundle), bundlePath); // texels inline
    TexelLayerShape shape = texelLayerShape(*layer, bundlePath);
    TexelRelightModel model;
    model.width = shape.width;
    model.height = shape.height;
    model.rows.vertexCount = uint32_t(size_t(shape.width) * shape.height);
    model.rows.order = shape.order;
    model.rows.albedoExcluded = shape.albedoExcluded;
    model.rows.transfer = texelLayerRows(bundlePath, *layer, shape.width, shape.height, shape.order * shape.order);
    return model;
}

// The layer `name`, moved out of the bundle; empty when absent.
std::optional<Layer> takeLayer(Bundle& bundle, const char* name) {
    auto found = std::find_if(bundle.layers.begin(), bundle.layers.end(), [&](const Layer& l) { return l.name == name; });
    if (found == bundle.layers.end()) return std::nullopt;
    Layer layer = std::move(*found);
    bundle.layers.erase(found);
    return layer;
}

} // namespace

TexelRelightModel loadTexelRelightModel(const std::string& bundlePath) {
    return texelModelOf(readBundle(bundlePath), bundlePath);
}

TexelHybridModel loadTexelHybridModel(const std::string& bundlePath) {
    return texelHybridModel(readBundle(bundlePath), bundlePath);
}

TexelHybridModel texelHybridModel(Bundle bundle, const std::string& bundlePath) {
    std::optional<Layer> surface = takeLayer(bundle, "texel_surface");
    const std::optional<Layer> bounce = takeLayer(bundle, "texel_transfer_bounce");
    TexelRelightModel total = texelModelOf(std::move(bundle), bundlePath);
    TexelHybridModel model;
    model.width = total.width;
    model.height = total.height;
    const size_t texels = size_t(total.width) * total.height;
    const int coefficients = total.rows.order * total.rows.order;
    if (!surface)
        throw Error(bundlePath, "layers", "has no \"texel_surface\" layer (texel positions, normals and albedo for the "
                                          "cone lights): it was baked before the texel hybrid; bake it again");
    const std::string place = "layer \"texel_surface\"";
    if (surface->domain != "texel" || surface->shape != std::vector<uint64_t>{texels, uint64_t(kTexelSurfaceChannels)})
        throw Error(bundlePath, place, "expected domain \"texel\" and shape [" + std::to_string(texels) + ", " +
                                           std::to_string(kTexelSurfaceChannels) + "] (the transfer's texels)");
    std::vector<float> values;
    if (!surface->params.contains("uri")) {
        if (surface->data.size() != texels * kTexelSurfaceChannels)
            throw Error(bundlePath, place, "holds " + std::to_string(surface->data.size()) + " values, not " +
                                               std::to_string(texels * kTexelSurfaceChannels));
        values = std::move(surface->data);
    } else {
        std::string path = referencedFile(bundlePath, stringParam(*surface, "uri", bundlePath, place),
                                          surface->params.value("hash", nlohmann::json()), place + ", params.uri");
        ImageChannels image = readImageChannels(
            path, std::vector<std::string>(kTexelSurfaceChannelNames, kTexelSurfaceChannelNames + kTexelSurfaceChannels));
        checkSize(image, total.width, total.height, path);
        values = std::move(image.values);
    }
    checkFiniteRows(values, kTexelSurfaceChannels, bundlePath, place, "texel");
    model.positions.resize(texels * 3);
    model.covered.resize(texels);
    model.rows.normals.resize(texels * 3);
    model.rows.albedo.resize(texels * 3);
    for (size_t t = 0; t < texels; ++t) {
        const float* row = &values[t * kTexelSurfaceChannels];
        double length = std::sqrt(double(row[3]) * row[3] + double(row[4]) * row[4] + double(row[5]) * row[5]);
        if (!(length > 0.5 && length < 1.5))
            throw Error(bundlePath, place + ", texel " + std::to_string(t), "normal is not unit length");
        for (int a = 0; a < 3; ++a) {
            model.positions[t * 3 + a] = row[a];
            model.rows.normals[t * 3 + a] = float(row[3 + a] / length);
            model.rows.albedo[t * 3 + a] = row[6 + a];
        }
        model.covered[t] = row[9] > 0.5f;
    }
    // A scene bake's texels are irradiance transfer, relit as E / pi (an engine multiplies by its base colour per
    // pixel): the cone lights and the bounce part then shade a white surface too.
    if (total.rows.albedoExcluded) std::fill(model.rows.albedo.begin(), model.rows.albedo.end(), 1.0f);
    if (bounce) {
        if (bounce->domain != "texel" || bounce->semantic != "sh_transfer_bounce_rgb" ||
            bounce->shape != std::vector<uint64_t>{texels, uint64_t(coefficients), 3})
            throw Error(bundlePath, "layer \"texel_transfer_bounce\"",
                        "expected domain \"texel\", semantic \"sh_transfer_bounce_rgb\" and the transfer's shape");
        model.rows.bounce = texelLayerRows(bundlePath, *bounce, total.width, total.height, coefficients);
    }
    model.rows.total = std::move(total.rows);
    return model;
}

} // namespace prt
