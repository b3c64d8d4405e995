// Coefficient textures on disk: one multi-channel OpenEXR, or 8-bit PNG layers with a [min, max] sidecar.
#include "bake.h"

#include "core.h"

#include <OpenImageIO/imageio.h>

#include <cstdio>

namespace prt {

TexelFormat parseTexelFormat(const std::string& name) {
    if (name == "half") return TexelFormat::Half;
    if (name == "float") return TexelFormat::Float;
    if (name == "u8") return TexelFormat::U8;
    throw Error("", "--format", "'" + name + "' is not one of half, float, u8", kExitUsage);
}

const char* texelFormatName(TexelFormat format) {
    switch (format) {
    case TexelFormat::Half: return "half";
    case TexelFormat::Float: return "float";
    case TexelFormat::U8: return "u8";
    }
    return "?";
}

std::string coefficientChannel(int coefficient, int colour) {
    char name[16];
    std::snprintf(name, sizeof name, "T%03d.%c", coefficient, "RGB"[colour]);
    return name;
}

void writeCoefficientExr(const std::string& path, const float* texels, int width, int height, int coefficients,
                         bool half) {
    writeFileAtomic(path, [&](const std::string& tmpPath) {
        auto output = OIIO::ImageOutput::create("openexr");
        if (!output) throw Error(path, "", "no OpenEXR writer (" + OIIO::geterror() + ")", kExitOutput);
        OIIO::ImageSpec spec(width, height, 3 * coefficients, half ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT);
        spec.channelnames.clear();
        for (int j = 0; j < coefficients; ++j)
            for (int c = 0; c < 3; ++c) spec.channelnames.push_back(coefficientChannel(j, c));
        spec.alpha_channel = -1;
        spec.attribute("compression", "zip");
        if (!output->open(tmpPath, spec) || !output->write_image(OIIO::TypeDesc::FLOAT, texels) || !output->close())
            throw Error(path, "", "cannot write OpenEXR (" + output->geterror() + ")", kExitOutput);
    });
}

std::vector<float> readCoefficientExr(const std::string& path, int& width, int& height, int& coefficients) {
    auto input = OIIO::ImageInput::open(path);
    if (!input) throw Error(path, "", "cannot open coefficient texture (" + OIIO::geterror() + ")");
    const OIIO::ImageSpec& spec = input->spec();
    if ((width > 0 && spec.width != width) || (height > 0 && spec.height != height))
        throw Error(path, "", std::to_string(spec.width) + "x" + std::to_string(spec.height) + " texels, expected " +
                                  std::to_string(width) + "x" + std::to_string(height));
    if (coefficients <= 0) {
        coefficients = 0;
        while (spec.channelindex(coefficientChannel(coefficients, 0)) >= 0) ++coefficients;
        if (coefficients == 0) throw Error(path, "channel " + coefficientChannel(0, 0), "is missing");
    }
    width = spec.width, height = spec.height;
    std::vector<int> channelOf(3 * size_t(coefficients));
    for (int j = 0; j < coefficients; ++j)
        for (int c = 0; c < 3; ++c) {
            channelOf[3 * j + c] = spec.channelindex(coefficientChannel(j, c));
            if (channelOf[3 * j + c] < 0) throw Error(path, "channel " + coefficientChannel(j, c), "is missing");
        }
    size_t texelCount = size_t(width) * height;
    std::vector<float> file(texelCount * spec.nchannels);
    if (!input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, file.data()))
        throw Error(path, "", "cannot read pixels (" + input->geterror() + ")");
    std::vector<float> texels(texelCount * 3 * coefficients);
    for (size_t t = 0; t < texelCount; ++t)
        for (size_t k = 0; k < channelOf.size(); ++k)
            texels[t * channelOf.size() + k] = file[t * spec.nchannels + channelOf[k]];
    return texels;
}

void writeImage8(const std::string& path, const uint8_t* bytes, int width, int height, int channels) {
    writeFileAtomic(path, [&](const std::string& tmpPath) {
        // The temporary name hides the extension, so the format comes from the final path.
        auto output = OIIO::ImageOutput::create(path);
        if (!output)
            throw Error(path, "", "no image writer for this extension (" + OIIO::geterror() + ")", kExitOutput);
        OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::UINT8);
        if (!output->open(tmpPath, spec) || !output->write_image(OIIO::TypeDesc::UINT8, bytes) || !output->close())
            throw Error(path, "", "cannot write image (" + output->geterror() + ")", kExitOutput);
    });
}

std::vector<uint8_t> readImage8(const std::string& path, int& width, int& height, int channels) {
    auto input = OIIO::ImageInput::open(path);
    if (!input) throw Error(path, "", "cannot open image (" + OIIO::geterror() + ")");
    const OIIO::ImageSpec& spec = input->spec();
    if ((width > 0 && spec.width != width) || (height > 0 && spec.height != height) || spec.nchannels < channels)
        throw Error(path, "", std::to_string(spec.width) + "x" + std::to_string(spec.height) + " texels of " +
                                  std::to_string(spec.nchannels) + " channels, expected " + std::to_string(width) +
                                  "x" + std::to_string(height) + " of " + std::to_string(channels));
    width = spec.width, height = spec.height;
    std::vector<uint8_t> bytes(size_t(width) * height * channels);
    if (!input->read_image(0, 0, 0, channels, OIIO::TypeDesc::UINT8, bytes.data()))
        throw Error(path, "", "cannot read pixels (" + input->geterror() + ")");
    return bytes;
}

} // namespace prt
