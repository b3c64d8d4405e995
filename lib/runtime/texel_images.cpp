// prt::runtime_images: a bundle's per-texel transfer (the "texel_transfer" layer of `prt bake`) read from the
// texture it references, through lib/image (OpenImageIO). Kept out of prt_runtime so the thin runtime needs no image
// library.
#include "runtime.h"

#include "core.h"
#include "image.h"
#include "runtime_internal.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>

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
    fs::path path = (error ? fs::path(owner) : resolved).parent_path() / uri;
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
    std::ifstream in(sidecarPath);
    nlohmann::json sidecar = nlohmann::json::parse(in, nullptr, false);
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

} // namespace

TexelRelightModel loadTexelRelightModel(const std::string& bundlePath) {
    Bundle bundle = readBundle(bundlePath);
    const Layer* layer = &transferLayer(bundle, "texel_transfer", "texel", bundlePath, "bake");
    if (!layer->params.contains("uri")) return texelRelightModel(std::move(bundle), bundlePath); // texels inline
    const std::string place = "layer \"texel_transfer\"";
    TexelLayerShape shape = texelLayerShape(*layer, bundlePath);
    // The size comes from the bundle's JSON: bounded before anything is allocated for it.
    checkedProduct({uint64_t(shape.width) * uint64_t(shape.height), 3 * uint64_t(shape.order) * uint64_t(shape.order)},
                   "texel transfer values", bundlePath, place);
    std::string format = stringParam(*layer, "format", bundlePath, place);
    std::string path = referencedFile(bundlePath, stringParam(*layer, "uri", bundlePath, place),
                                      layer->params.value("hash", nlohmann::json()), place + ", params.uri");
    const int coefficients = shape.order * shape.order;
    TexelRelightModel model;
    model.width = shape.width;
    model.height = shape.height;
    model.rows.vertexCount = uint32_t(size_t(shape.width) * shape.height);
    model.rows.order = shape.order;
    if (format == "half" || format == "float")
        model.rows.transfer = readExrRows(path, shape.width, shape.height, coefficients);
    else if (format == "u8")
        model.rows.transfer = readU8Rows(path, shape.width, shape.height, coefficients);
    else
        throw Error(bundlePath, place + ", params.format", "'" + format + "' is not one of half, float, u8");
    checkFiniteRows(model.rows.transfer, 3 * size_t(coefficients), path, "texture", "texel");
    return model;
}

} // namespace prt
