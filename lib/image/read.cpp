// Reading images and environment maps through OpenImageIO (loaded on first use, image_library.h).
#include "image.h"

#include "core.h"
#include "image_library.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace prt {

// Negative radiance down to this fraction of the mean radiance is treated as compression noise.
constexpr double kCompressionNoise = 0.1;

// Reads `path` as readImage does; `cubeTagged` (when given) says whether the file is tagged as a cube map.
static Image readTagged(const std::string& path, bool* cubeTagged) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) throw Error(path, "", "file not found");
    if (std::filesystem::is_directory(path, ec)) throw Error(path, "", "is a folder, not an image");

    checkExrHeaders(path);
    std::string error;
    OpenedImage spec = openImageFile(path, error);
    if (!spec.handle) throw Error(path, "", "not a readable image (" + error + ")");
    // Deep EXRs hold per-pixel sample lists, not one value per pixel.
    if (spec.deep) throw Error(path, "", "deep image data is not a flat image");
    if (spec.width <= 0 || spec.height <= 0 || spec.channels <= 0)
        throw Error(path, "", "image has no pixels");

    int channels = spec.channels;
    checkedProduct({uint64_t(spec.width), uint64_t(spec.height), uint64_t(channels)}, "texel values", path, "header");
    std::vector<float> pixels(size_t(spec.width) * spec.height * channels);
    if (!readOpenedPixels(spec, channels, pixels.data(), error))
        throw Error(path, "pixels", "cannot read (" + error + ")");

    Image image;
    image.width = spec.width;
    image.height = spec.height;
    size_t count = size_t(spec.width) * spec.height;
    image.rgb.resize(count * 3);
    for (size_t p = 0; p < count; ++p)
        for (int c = 0; c < 3; ++c)
            image.rgb[p * 3 + c] = pixels[p * channels + (channels >= 3 ? c : 0)];
    if (cubeTagged) *cubeTagged = spec.cubeEnvironment;
    return image;
}

Image readImage(const std::string& path) { return readTagged(path, nullptr); }

EnvironmentMap readEnvironmentMap(const std::string& path) {
    bool taggedCube = false; // OpenEXR's envmap=cube attribute
    EnvironmentMap env;
    env.radiance = readTagged(path, &taggedCube);
    Image& image = env.radiance;

    if (image.height == 6 * image.width)
        env.layout = EnvLayout::CubeStrip;
    else if (image.width == 2 * image.height && !taggedCube)
        env.layout = EnvLayout::Equirectangular;
    else
        throw Error(path, "", "environment map is " + std::to_string(image.width) + "x" +
                                  std::to_string(image.height) + (taggedCube ? " and tagged as a cube map" : "") +
                                  "; need 2:1 (equirectangular) or 1:6 (cube strip)");

    // Lossy EXR compression (DWA, B44) undershoots slightly below zero next to bright texels; every map we ship
    // has such texels, down to a few percent of the mean radiance. Those are noise and become 0; anything more
    // negative means the image does not hold radiance.
    double finiteSum = 0.0;
    size_t finiteCount = 0;
    for (float radiance : image.rgb)
        if (std::isfinite(radiance)) finiteSum += radiance, ++finiteCount;
    double noiseFloor = -kCompressionNoise * (finiteCount ? finiteSum / double(finiteCount) : 0.0);
    size_t clamped = 0;
    float lowest = 0.0f;
    for (size_t i = 0; i < image.rgb.size(); ++i) {
        float& radiance = image.rgb[i];
        const char* problem = std::isnan(radiance)      ? "NaN radiance"
                              : std::isinf(radiance)    ? "infinite radiance"
                              : radiance < noiseFloor   ? "negative radiance"
                                                        : nullptr;
        if (problem) {
            size_t pixel = i / 3;
            std::string place = "texel (" + std::to_string(pixel % image.width) + ", " +
                                std::to_string(pixel / image.width) + ") channel " + std::to_string(i % 3);
            throw Error(path, place, std::string(problem) + " (" + std::to_string(radiance) + ")");
        }
        if (radiance < 0.0f) {
            lowest = std::min(lowest, radiance);
            radiance = 0.0f;
            ++clamped;
        }
    }
    if (clamped > 0)
        logInfo(path + ": " + std::to_string(clamped) + " slightly negative values (lowest " + std::to_string(lowest) +
                ", compression noise) set to 0");
    return env;
}

} // namespace prt
