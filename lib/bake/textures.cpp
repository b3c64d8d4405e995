// Coefficient textures on disk: one multi-channel OpenEXR, or 8-bit PNG layers with a [min, max] sidecar.
#include "bake.h"

#include "core.h"
#include "image.h"
#include "image_library.h"
#include "runtime.h"

#include <algorithm>
#include <cstdio>

namespace prt {

TexelFormat parseTexelFormat(const std::string& name) {
    if (name == "half") return TexelFormat::Half;
    if (name == "float") return TexelFormat::Float;
    if (name == "u8") return TexelFormat::U8;
    if (name == "bundle") return TexelFormat::Bundle;
    throw Error("", "--format", "'" + name + "' is not one of half, float, u8, bundle", kExitUsage);
}

const char* texelFormatName(TexelFormat format) {
    switch (format) {
    case TexelFormat::Half: return "half";
    case TexelFormat::Float: return "float";
    case TexelFormat::U8: return "u8";
    case TexelFormat::Bundle: return "bundle";
    }
    return "?";
}

void writeCoefficientExr(const std::string& path, const float* texels, int width, int height, int coefficients,
                         bool half) {
    std::vector<std::string> names;
    for (int j = 0; j < coefficients; ++j)
        for (int c = 0; c < 3; ++c) names.push_back(texelCoefficientChannel(j, c));
    writeImagePixels(path, width, height, names, texels, half ? PixelStorage::Half : PixelStorage::Float);
}

std::vector<float> readCoefficientExr(const std::string& path, int& width, int& height, int& coefficients) {
    if (coefficients <= 0) {
        std::vector<std::string> present = imageChannelNames(path);
        auto has = [&](const std::string& name) {
            return std::find(present.begin(), present.end(), name) != present.end();
        };
        coefficients = 0;
        while (has(texelCoefficientChannel(coefficients, 0))) ++coefficients;
        if (coefficients == 0) throw Error(path, "channel " + texelCoefficientChannel(0, 0), "is missing");
    }
    std::vector<std::string> names;
    for (int j = 0; j < coefficients; ++j)
        for (int c = 0; c < 3; ++c) names.push_back(texelCoefficientChannel(j, c));
    ImageChannels image = readImageChannels(path, names);
    if ((width > 0 && image.width != width) || (height > 0 && image.height != height))
        throw Error(path, "", std::to_string(image.width) + "x" + std::to_string(image.height) +
                                  " texels, expected " + std::to_string(width) + "x" + std::to_string(height));
    width = image.width, height = image.height;
    return std::move(image.values);
}

std::vector<uint8_t> readImage8(const std::string& path, int& width, int& height, int channels) {
    std::string error;
    OpenedImage spec = openImageFile(path, error);
    if (!spec.handle) throw Error(path, "", "cannot open image (" + error + ")");
    if ((width > 0 && spec.width != width) || (height > 0 && spec.height != height) || spec.channels < channels)
        throw Error(path, "", std::to_string(spec.width) + "x" + std::to_string(spec.height) + " texels of " +
                                  std::to_string(spec.channels) + " channels, expected " + std::to_string(width) +
                                  "x" + std::to_string(height) + " of " + std::to_string(channels));
    if (spec.width <= 0 || spec.height <= 0 || spec.deep) throw Error(path, "", "image has no flat pixels");
    checkedProduct({uint64_t(spec.width), uint64_t(spec.height), uint64_t(channels)}, "texel values", path, "header");
    width = spec.width, height = spec.height;
    std::vector<uint8_t> bytes(size_t(width) * height * channels);
    if (!readOpenedPixels(spec, channels, bytes.data(), error))
        throw Error(path, "", "cannot read pixels (" + error + ")");
    return bytes;
}

} // namespace prt
