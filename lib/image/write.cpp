// Writing images atomically through OpenImageIO.
#include "image.h"

#include "core.h"

#include <OpenImageIO/imageio.h>

namespace prt {

namespace {

void writePixels(const std::string& path, int width, int height, const std::vector<std::string>& channelNames,
                 const void* pixels, OIIO::TypeDesc pixelType, PixelStorage storage) {
    if (width <= 0 || height <= 0 || channelNames.empty())
        throw Error(path, "", "image to write has no pixels or no channels", kExitFailure);
    writeFileAtomic(path, [&](const std::string& tmpPath) {
        // The temporary name hides the extension, so the format comes from the final path.
        auto output = OIIO::ImageOutput::create(path);
        if (!output)
            throw Error(path, "", "no image writer for this extension (" + OIIO::geterror() + ")", kExitOutput);
        bool exr = std::string(output->format_name()) == "openexr";
        OIIO::TypeDesc stored = storage == PixelStorage::U8    ? OIIO::TypeDesc::UINT8
                                : storage == PixelStorage::Half ? OIIO::TypeDesc::HALF
                                                                 : OIIO::TypeDesc::FLOAT;
        OIIO::ImageSpec spec(width, height, int(channelNames.size()), stored);
        spec.channelnames = channelNames;
        spec.alpha_channel = -1; // named channels, none of them alpha, whatever their count
        if (exr) {
            spec.attribute("compression", "zip");
            // OIIO would stamp the current time as capDate: a fixed one keeps same pixels, same bytes. (PNG gets
            // no time chunk unless asked.)
            spec.attribute("DateTime", "1970:01:01 00:00:00");
        }
        if (!output->open(tmpPath, spec) || !output->write_image(pixelType, pixels) || !output->close())
            throw Error(path, "", "cannot write image (" + output->geterror() + ")", kExitOutput);
    });
}

} // namespace

void writeImagePixels(const std::string& path, int width, int height, const std::vector<std::string>& channelNames,
                      const float* pixels, PixelStorage storage) {
    writePixels(path, width, height, channelNames, pixels, OIIO::TypeDesc::FLOAT, storage);
}

void writeImagePixels(const std::string& path, int width, int height, const std::vector<std::string>& channelNames,
                      const uint8_t* pixels) {
    writePixels(path, width, height, channelNames, pixels, OIIO::TypeDesc::UINT8, PixelStorage::U8);
}

void writeImage(const std::string& path, const Image& image, bool half) {
    if (image.width <= 0 || image.height <= 0 || image.rgb.size() != size_t(image.width) * image.height * 3)
        throw Error(path, "", "image to write has inconsistent size", kExitFailure);
    writeImagePixels(path, image.width, image.height, {"R", "G", "B"}, image.rgb.data(),
                     half ? PixelStorage::Half : PixelStorage::Float);
}

} // namespace prt
